// controller_gains.h — the PD gains read from the data: least squares on the filtered control law.
//
// The paper's controller is τ_j = Kp_j (r_j − q_j) − Kd_j q̇_j, joint by joint. It is linear in
// (Kp_j, Kd_j), and so is its low-passed version (the filters are linear):
//     τ^f_j = Kp_j (r^f_j − q^f_j) − Kd_j q̇^f_j,
// so when the data carry τ, q and r the gains follow from a 2-unknown least-squares fit per
// joint on the filtered signals the input-error method computes anyway (low-passing removes
// the measurement noise that would otherwise sit in q̇). The fit's residual says how well the
// law explains the torque: near zero for a PD loop without noise, the filtered noise for noisy
// data, large when the torque does not come from such a controller (or from other gains).
#pragma once

#include "manipid/core/paper/input_error.h"
#include "manipid/core/paper/simulation.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <vector>

namespace manipid {

struct GainFit {
  PdController gains;  ///< the least-squares Kp (N·m/rad) and Kd (N·m·s/rad), one per joint
  /// Per joint, RMS of τ^f − law(gains) over RMS of τ^f (dimensionless; 0.01 = 1 %).
  Eigen::VectorXd relative_residual;
  /// Per joint, the covariance of (Kp, Kd): σ² (AᵀA)⁻¹ with σ² the law's residual variance, inflated
  /// for the low-passed residual's correlation (estimation/rules.h). Units (N·m/rad)², (N·m·s/rad)².
  std::vector<Eigen::Matrix2d> covariance;
};

/// r^f: each joint's reference low-passed with `filter` (samples × joints, aligned with the
/// outputs of filter_for_input_error on the same data). Throws InputError("ref") without ref.
Eigen::MatrixXd filter_reference(const Trajectory& data, const FilterSettings& filter);

/// The gains that best explain the filtered torque. `filtered` must hold the measured torque
/// (filter_for_input_error with use_reference = false); `reference` is filter_reference's.
GainFit fit_pd_gains(const FilteredData& filtered, const Eigen::MatrixXd& reference);

/// Per joint, RMS of τ^f − Kp (r^f − q^f) + Kd q̇^f over RMS of τ^f, for given gains.
Eigen::VectorXd pd_law_relative_residual(const FilteredData& filtered, const Eigen::MatrixXd& reference,
                                         const PdController& gains);

}  // namespace manipid
