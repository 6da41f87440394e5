// rules.h — the rules that judge an estimate, defined once for both families (paper/ and robot/) and every
// layer above: when a direction of the parameters counts as determined by the data, when as weak, and how
// much less independent low-passed residuals are than white samples.
#pragma once

#include <algorithm>

namespace manipid::estimation {

/// A direction of the parameters whose singular value, in the column-scaled sensitivity (robot/: the
/// regressor's columns scaled to unit norm; paper/: the Gauss–Newton Jacobian in relative coordinates
/// δθ/θ), is below this fraction of the largest is not determined by the data: it stays at the prior
/// (the URDF's values) or is reported as unidentifiable. Exact structural dependencies measure ~1e-15, the
/// collinearities of real runs (a friction term of a joint that never reverses) ~1e-9; a run that excites
/// a direction at all gives ≥ 1e-5.
inline constexpr double kUnidentifiableRatio = 1e-6;

/// Below this fraction the data barely separate the direction: its estimate is strongly correlated and
/// its standard error large (reported as a finding; robot/ shrinks it toward the prior as cross-validation
/// says, estimation/cross_validation.h).
inline constexpr double kWeakRatio = 1e-3;

/// A regressor column whose norm is below this fraction of the largest column's is treated as zero: the
/// torque depends on its parameter no more than round-off and rounded URDF angles (3.1416 for π: 1e-6 of
/// the largest) make it, and scaled to unit norm it would pass for a direction of its own.
inline constexpr double kNegligibleColumn = 1e-5;

/// The residual variance's correction for low-passed residuals: white noise through a low-pass with taps c
/// keeps Σc² of its variance, and rows `decimation` samples apart are about 1/(decimation · Σc²) times
/// less independent than white samples would be (never counted as more independent). `lowpass_energy` is
/// Σc² (for an IIR filter, the sum of its impulse response squared).
inline double filtered_residual_factor(int decimation, double lowpass_energy) {
  return std::max(1.0, 1.0 / (static_cast<double>(decimation) * lowpass_energy));
}

}  // namespace manipid::estimation
