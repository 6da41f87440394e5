// output_error_fit.h — internal: fitting θ to the output error (the two-stage method's
// second stage, and the output-error method's standard errors).
#pragma once

#include "manipid/core/paper/identification.h"
#include "manipid/core/paper/output_error.h"
#include "estimation/optimizer.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace manipid::detail {

/// Which parameters move and within which bounds (θ order, all parameters).
struct FitBounds {
  int n = 0;  ///< joints
  std::vector<bool> free;
  Eigen::VectorXd lower, upper;
};

/// Forward-difference Jacobian of the output-error residual at θ along the identifiable
/// directions `basis` (relative coordinates over the free parameters), in θ units: zero along
/// the directions the data cannot see. 1e-4 relative steps: well above the adaptive
/// integrator's tolerance-level noise, well below the curvature scale.
Eigen::MatrixXd output_error_jacobian(const OutputErrorCost& cost, const Eigen::VectorXd& theta,
                                      const Eigen::VectorXd& residual, const std::vector<bool>& free,
                                      const Eigen::MatrixXd& basis);

struct GaussNewtonOutcome {
  Eigen::VectorXd theta, start, residual;
  Eigen::MatrixXd jacobian;  ///< ∂residual/∂θ at `theta`, θ units (zero along unseen directions)
  /// The last measured Jacobian the fit stepped with: residual × (identifiable directions in relative
  /// coordinates, then the start angles), and the |θ| that made the directions relative (free parameters).
  Eigen::MatrixXd reduced;
  Eigen::VectorXd scale;
  double cost = 0.0;
  int iterations = 0;
  std::string stop_reason;
  bool cancelled = false;
};

/// Levenberg–Marquardt on the output error from a good start. It moves θ only along the
/// identifiable directions (`basis`, from the exact input-error structure) so the flat m1/l1
/// valley of the paper's robot cannot swallow a step, and it estimates the initial angles
/// alongside: starting from one noisy first sample would bias θ through the start transient.
/// Every evaluation is recorded in `log`.
GaussNewtonOutcome gauss_newton_output_error(const OutputErrorCost& cost, const Eigen::VectorXd& theta_start,
                                             const Eigen::MatrixXd& basis, const FitBounds& bounds,
                                             const IdentificationOptions& options, EvaluationLog& log);

/// ∂θ̂/∂g: how an output-error estimate moves per unit change of each PD gain the simulation used, to first
/// order (θ × 2n, columns Kp1..Kpn then Kd1..Kdn, θ units per N·m/rad and per N·m·s/rad): the fit's unknowns
/// u respond as least squares would, δu = −Ĵ⁺ J_g δg, and θ moves by `to_theta` δu. Ĵ = ∂residual/∂u at the
/// estimate (`unknowns_jacobian`), J_g the residual's forward-difference response to each gain at θ̂ and
/// the start angles `start` (nullptr: the measured ones), 2n simulations with 1e-4 relative steps. Zero
/// along the directions the data cannot see (Ĵ⁺ is a pseudo-inverse).
Eigen::MatrixXd gain_sensitivity(const RobotModel& model, const Trajectory& data, const PdController& gains,
                                 double relative_tolerance, const Eigen::VectorXd& theta, const Eigen::VectorXd* start,
                                 const Eigen::VectorXd& residual, const Eigen::MatrixXd& unknowns_jacobian,
                                 const Eigen::MatrixXd& to_theta);

/// The same for the two-stage fit: its unknowns are the identifiable directions and the start angles.
Eigen::MatrixXd gain_sensitivity(const RobotModel& model, const Trajectory& data, const PdController& gains,
                                 double relative_tolerance, const GaussNewtonOutcome& outcome, const Eigen::MatrixXd& basis,
                                 const FitBounds& bounds);

}  // namespace manipid::detail
