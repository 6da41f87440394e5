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

}  // namespace manipid::detail
