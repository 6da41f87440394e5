// uncertainty.h — internal: standard errors, correlations and identifiability of the paper's (m, l)
// parameters from the Gauss–Newton information matrix J_rᵀJ_r of any of its identification methods, with the
// identifiable products named (m1*l1^2). The rank rule is estimation/rules.h's, shared with robot/.
#pragma once

#include "manipid/core/estimation/rules.h"
#include "manipid/core/paper/identification.h"
#include "manipid/core/paper/regressor.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace manipid::detail {

struct UncertaintyInput {
  std::vector<std::string> names;  // all parameters
  Eigen::VectorXd theta;           // estimate, all parameters
  std::vector<bool> free;
  Eigen::MatrixXd information;     // J_rᵀ J_r, all parameters (θ units)
  // Exact-structure information (the input-error Gram form) that decides which directions
  // are unidentifiable; empty = use `information`. Finite-difference Jacobians (output-error)
  // never have an exact null space, so they should not decide it.
  Eigen::MatrixXd structure;
  double residual_variance = 0.0;  // σ² of one residual (with any correlation correction)
  // Covariance of θ (all parameters, θ units) from what the residual cannot show — the PD gains two-stage
  // estimated and simulated with — added to σ² H⁺ on the identifiable parameters; empty = none.
  Eigen::MatrixXd added_covariance;
  const ParameterProducts* products = nullptr;  // to name identifiable combinations
};

struct Uncertainty {
  Eigen::VectorXd std_errors;   // all parameters; NaN when fixed or unidentifiable
  Eigen::MatrixXd correlation;  // free × free; NaN rows for unidentifiable ones
  IdentifiabilityReport report;
  // Why nothing could be assessed (a non-finite estimate or information matrix), else empty.
  std::string unavailable;
};

/// Directions whose scaled singular value is below estimation::kUnidentifiableRatio of the largest are
/// reported as not identifiable; below estimation::kWeakRatio as poorly determined (estimation/rules.h).
using estimation::kUnidentifiableRatio;
using estimation::kWeakRatio;

Uncertainty assess_uncertainty(const UncertaintyInput& input);

/// Orthonormal basis (columns, in relative coordinates δθ_i/θ_i over the free parameters) of
/// the directions `information` can see, and of those it cannot (`null_basis`). A matrix or
/// θ with a non-finite entry sees nothing: every direction goes to the null basis (no
/// eigensolver is ever handed NaN or an empty matrix).
Eigen::MatrixXd identifiable_basis(const Eigen::MatrixXd& information, const Eigen::VectorXd& theta,
                                   const std::vector<bool>& free, Eigen::MatrixXd* null_basis = nullptr);

}  // namespace manipid::detail
