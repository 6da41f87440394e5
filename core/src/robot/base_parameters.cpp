// base_parameters.cpp — structural base parameters from random states (robot/base_parameters.h).
#include "manipid/core/robot/base_parameters.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/regressor.h"

#include <Eigen/QR>

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
  Eigen::MatrixXd basis(Y.rows(), 0);  // orthonormal, spans the kept columns
  basis.resize(Y.rows(), p);
  int kept = 0;
  for (int c = 0; c < p; ++c) {
    const double norm = Y.col(c).norm();
    if (norm <= zero_norm) {
      base.absent.push_back(c);
      continue;
    }
    Eigen::VectorXd v = Y.col(c) / norm;
    for (int pass = 0; pass < 2; ++pass) {  // modified Gram–Schmidt, repeated once for orthogonality
      for (int b = 0; b < kept; ++b) v -= basis.col(b).dot(v) * basis.col(b);
    }
    const double rest = v.norm();
    if (rest > options.tolerance) {
      basis.col(kept++) = v / rest;
      base.independent.push_back(c);
    } else {
      base.dependent.push_back(c);
    }
  }

  // Regrouping: each dependent column as a combination of the independent ones (unscaled, so the
  // coefficients carry the robot's lengths and units).
  const int b = base.size();
  base.combination = Eigen::MatrixXd::Zero(b, p);
  for (int i = 0; i < b; ++i) base.combination(i, base.independent[static_cast<std::size_t>(i)]) = 1.0;
  if (!base.dependent.empty() && b > 0) {
    Eigen::MatrixXd independent(Y.rows(), b), dependent(Y.rows(), static_cast<Eigen::Index>(base.dependent.size()));
    for (int i = 0; i < b; ++i) independent.col(i) = Y.col(base.independent[static_cast<std::size_t>(i)]);
    for (std::size_t d = 0; d < base.dependent.size(); ++d) dependent.col(static_cast<Eigen::Index>(d)) = Y.col(base.dependent[d]);
    const Eigen::MatrixXd K = independent.colPivHouseholderQr().solve(dependent);  // b × dependent
    const double largest = K.cwiseAbs().maxCoeff();
    for (std::size_t d = 0; d < base.dependent.size(); ++d) {
      for (int i = 0; i < b; ++i) {
        const double value = K(i, static_cast<Eigen::Index>(d));
        if (std::abs(value) > 1e-9 * largest) base.combination(i, base.dependent[d]) = value;
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
