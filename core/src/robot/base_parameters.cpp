// base_parameters.cpp — structural base parameters from random states (robot/base_parameters.h).
#include "manipid/core/robot/base_parameters.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/regressor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

namespace manipid::robot {
namespace {

/// Y at random states: q uniform within the limits (a 2π window for unlimited rotations, ±1 m for
/// unlimited slides), q̇ and q̈ standard normal. Stacked sample-major.
Eigen::MatrixXd random_regressor(const Model& model, const ParameterLayout& layout, int states, std::uint64_t seed) {
  const int n = model.joint_count();
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd q(n, states), qd(n, states), qdd(n, states);
  for (int k = 0; k < n; ++k) {
    const JointLimits& limits = model.joints[k].limits;
    const double fallback = model.joints[k].is_prismatic() ? 1.0 : M_PI;
    const double lower = std::isfinite(limits.lower) ? limits.lower : -fallback;
    const double upper = std::isfinite(limits.upper) ? limits.upper : fallback;
    std::uniform_real_distribution<double> uniform(lower, std::max(upper, lower));
    for (int s = 0; s < states; ++s) {
      q(k, s) = uniform(engine);
      qd(k, s) = normal(engine);
      qdd(k, s) = normal(engine);
    }
  }
  return stacked_regressor(model, layout, q, qd, qdd);
}

std::string coefficient_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

}  // namespace

BaseParameters base_parameters(const Model& model, const ParameterLayout& layout, const BaseParameterOptions& options) {
  const int n = model.joint_count();
  const int p = layout.size(n);
  if (options.random_states < 0) throw InputError("random_states", "random_states must be 0 (automatic) or positive");
  if (!(options.tolerance > 0.0 && options.tolerance < 1.0)) {
    throw InputError("tolerance", "the rank tolerance must lie in (0, 1)");
  }
  const int states = options.random_states > 0 ? options.random_states : std::max(100, (2 * p + n - 1) / std::max(n, 1));
  const Eigen::MatrixXd Y = random_regressor(model, layout, states, options.seed);
  const std::vector<std::string> names = standard_parameter_names(n, layout);

  BaseParameters base;
  base.standard_count = p;
  const double zero_norm = 1e-10 * std::sqrt(static_cast<double>(Y.rows()));
  // Y's kept columns = basis · R: the orthonormal basis and, recorded as the columns are orthogonalised,
  // the upper-triangular R (column c = its norm × (its projections on the basis + what stays outside)).
  Eigen::MatrixXd basis(Y.rows(), p);
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd projection(p);
  int kept = 0;
  for (int c = 0; c < p; ++c) {
    checkpoint(options.cancel, "the base parameters' computation");  // ~2 ms a column for 50 joints
    const double norm = Y.col(c).norm();
    if (norm <= zero_norm) {
      base.absent.push_back(c);
      continue;
    }
    Eigen::VectorXd v = Y.col(c) / norm;
    projection.head(kept).setZero();
    for (int pass = 0; pass < 2; ++pass) {  // modified Gram–Schmidt, repeated once for orthogonality
      for (int b = 0; b < kept; ++b) {
        const double along = basis.col(b).dot(v);
        v -= along * basis.col(b);
        projection[b] += along;
      }
    }
    const double rest = v.norm();
    if (rest > options.tolerance) {
      R.col(kept).head(kept) = norm * projection.head(kept);
      R(kept, kept) = norm * rest;
      basis.col(kept++) = v / rest;
      base.independent.push_back(c);
    } else {
      base.dependent.push_back(c);
    }
  }

  // Regrouping: each dependent column as a combination of the independent ones (unscaled, so the
  // coefficients carry the robot's lengths and units): the least-squares K of Y_indep K = Y_dep, which with
  // Y_indep = basis R is R⁻¹ basisᵀ Y_dep (exact to round-off: the dependent columns lie in the span).
  const int b = base.size();
  base.combination = Eigen::MatrixXd::Zero(b, p);
  for (int i = 0; i < b; ++i) base.combination(i, base.independent[static_cast<std::size_t>(i)]) = 1.0;
  if (!base.dependent.empty() && b > 0) {
    const auto dependents = static_cast<Eigen::Index>(base.dependent.size());
    Eigen::MatrixXd K(b, dependents);
    for (Eigen::Index d = 0; d < dependents; ++d) {
      checkpoint(options.cancel, "the base parameters' computation");
      K.col(d).noalias() = basis.leftCols(b).transpose() * Y.col(base.dependent[static_cast<std::size_t>(d)]);
    }
    R.topLeftCorner(b, b).triangularView<Eigen::Upper>().solveInPlace(K);
    const double largest = K.cwiseAbs().maxCoeff();
    for (Eigen::Index d = 0; d < dependents; ++d) {
      for (int i = 0; i < b; ++i) {
        const double value = K(i, d);
        if (std::abs(value) > 1e-9 * largest) base.combination(i, base.dependent[static_cast<std::size_t>(d)]) = value;
      }
    }
  }
  for (int i = 0; i < b; ++i) {
    std::string text = names[static_cast<std::size_t>(base.independent[static_cast<std::size_t>(i)])];
    for (int d : base.dependent) {
      const double value = base.combination(i, d);
      if (value == 0.0) continue;
      const std::string magnitude = coefficient_text(std::abs(value));
      text += (value < 0 ? " - " : " + ") + (magnitude == "1" ? "" : magnitude + "*") + names[static_cast<std::size_t>(d)];
    }
    base.names.push_back(text);
  }
  return base;
}

}  // namespace manipid::robot
