// filtered_regressor.h — the paper's input-error filtering for a rigid-body robot, filtered consistently.
//
// Two filters of the paper's family (filters.h), each with its own job:
//  - the differentiation filter D (M, Ωg) gives q^f, q̇^f, q̈^f, and the regressor is formed from them,
//    Y(q^f, q̇^f, q̈^f). Its band must lie far above the motion: the windowed differentiators are exact
//    only near DC (the second derivative's gain is off by ~1e-3 across most of its passband, by 1.4e-5 at
//    2 % of Ωg), and a biased q̈ biases every inertial parameter;
//  - the comparison filter L (M_c, Ω_c) — the low-pass that gives τ^f = L τ — is applied to every column
//    of Y too ("parallel filtering"):
//
//        L τ = L (Y(q, q̇, q̈) π) = (L Y) π   and   L Y(q, q̇, q̈) ≈ L Y(q^f, q̇^f, q̈^f),
//
//    exact for any linear L; the only approximation is Y(q^f, ..) ≈ Y(q, ..), which D's wide band makes
//    good. L decides which frequencies the fit weighs: narrow, around the motion, it keeps the torque the
//    motion makes and drops the noise and the vibrations no rigid-body model explains. Without parallel
//    filtering, Y keeps the sharp sign(q̇) edges of Coulomb friction while τ^f has them smoothed, and least
//    squares moves Coulomb friction into viscous (measured: fv +40 %).
// The compared instants start M + M_c after the data's first sample; τ^f is taken at the same instants.
//
// The doubly filtered signals hold nothing above Ω_c, so keeping every D-th instant with
// D = max(1, ⌊π / (2 Ω_c)⌋) (twice the Nyquist rate of the band) loses no information while cutting the
// least-squares work by D. The rows are accumulated sample by sample (each Y(q^f_s) added to the
// ≈ (2M_c+1)/D outputs whose window covers s), so memory stays O(rows × dim π) whatever the number of
// samples.
#pragma once

#include "manipid/core/signal/filters.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <atomic>

namespace manipid::robot {

/// The two filters: D differentiates q, L low-passes τ and the regressor's columns alike.
struct FilterPair {
  FilterSettings differentiation;
  FilterSettings comparison;
  /// Samples the two filters consume at each end together (M + M_c), and at least the data must have.
  int margin() const { return differentiation.half_length + comparison.half_length; }
  int shortest_data() const { return 2 * margin() + 3; }
};

/// The rows least squares compares: (L Y) π against L τ, joint-major within each kept instant.
struct FilteredRegressor {
  FilterPair filters;
  int decimation = 1;        ///< D: every D-th compared instant is a row block
  int instants = 0;          ///< R: row blocks; rows = R · n
  Eigen::VectorXd t;         ///< R: the time of each row block, s
  Eigen::MatrixXd W;         ///< (R · n) × dim π: row r·n + k−1 is joint k at instant r
  Eigen::VectorXd tau;       ///< R · n: L τ at the same rows (empty when the data has no torque)
  /// Σ c² of the low-pass taps: white noise through L keeps this share of its variance.
  double lowpass_energy = 1.0;
};

/// Builds the rows for `data` (uniform samples: prepare_data first). Throws InputError when the data is
/// shorter than filters.shortest_data(), the joint counts differ, or the settings are invalid. Returns
/// with `instants` = 0 when `cancel` is set part way.
FilteredRegressor filtered_regressor(const Model& model, const ParameterLayout& layout, const Trajectory& data,
                                     const FilterPair& filters, const std::atomic<bool>* cancel = nullptr);

/// What a parameter vector predicts against the measured torque, both through the same filters.
struct TorquePrediction {
  Eigen::VectorXd t;         ///< times of the compared instants, s
  Eigen::MatrixXd measured;  ///< L τ, instants × n
  Eigen::MatrixXd model;     ///< L Y(q^f, q̇^f, q̈^f) π, instants × n
  Eigen::VectorXd rms_error;       ///< per joint, N·m (N)
  Eigen::VectorXd relative_error;  ///< per joint ‖τ̂ − τ^f‖ / ‖τ^f‖
  double overall_relative_error = 0.0;  ///< ‖τ̂ − τ^f‖_F / ‖τ^f‖_F over every joint
};

/// The torque `pi` predicts on `data` (uniform samples with torque), filtered as identification filters
/// (every compared instant, no decimation), beside the measured torque and the error figures.
TorquePrediction predict_torque(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi,
                                const Trajectory& data, const FilterPair& filters);

}  // namespace manipid::robot
