// output_error_fit.cpp — Levenberg–Marquardt on the output error (output_error_fit.h).
#include "paper/output_error_fit.h"

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>

namespace manipid::detail {

Eigen::MatrixXd output_error_jacobian(const OutputErrorCost& cost, const Eigen::VectorXd& theta,
                                      const Eigen::VectorXd& residual, const std::vector<bool>& free,
                                      const Eigen::MatrixXd& basis) {
  std::vector<int> free_index;
  for (int i = 0; i < theta.size(); ++i) {
    if (free[i]) free_index.push_back(i);
  }
  const int p = static_cast<int>(free_index.size());
  Eigen::VectorXd scale(p);
  for (int a = 0; a < p; ++a) scale[a] = theta[free_index[a]] != 0.0 ? std::abs(theta[free_index[a]]) : 1.0;
  const double step = 1e-4;
  Eigen::MatrixXd reduced(residual.size(), basis.cols());
  for (int c = 0; c < basis.cols(); ++c) {
    Eigen::VectorXd shifted = theta;
    for (int a = 0; a < p; ++a) shifted[free_index[a]] += step * basis(a, c) * scale[a];
    Eigen::VectorXd moved;
    cost.evaluate(Parameters::from_vector(shifted), &moved);
    reduced.col(c) = (moved - residual) / step;
  }
  // J_θ = J_B Bᵀ D⁻¹ (B has orthonormal columns).
  const Eigen::MatrixXd relative = reduced * basis.transpose();
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(residual.size(), theta.size());
  for (int a = 0; a < p; ++a) jacobian.col(free_index[a]) = relative.col(a) / scale[a];
  return jacobian;
}

GaussNewtonOutcome gauss_newton_output_error(const OutputErrorCost& cost, const Eigen::VectorXd& theta_start,
                                             const Eigen::MatrixXd& basis, const FitBounds& bounds,
                                             const IdentificationOptions& options, EvaluationLog& log) {
  const int n = bounds.n;
  std::vector<int> free_index;
  for (int i = 0; i < theta_start.size(); ++i) {
    if (bounds.free[i]) free_index.push_back(i);
  }
  const int p = static_cast<int>(free_index.size());
  const int r = static_cast<int>(basis.cols());
  GaussNewtonOutcome outcome;
  outcome.theta = theta_start;
  outcome.start = cost.measured_start();
  auto record = [&](double value, const Eigen::VectorXd& theta) { log.record(value, theta); };
  auto evaluate = [&](const Eigen::VectorXd& theta, const Eigen::VectorXd& start, Eigen::VectorXd* residual) {
    return cost.evaluate(Parameters::from_vector(theta), residual, &start);
  };
  outcome.cost = evaluate(outcome.theta, outcome.start, &outcome.residual);
  record(outcome.cost, outcome.theta);
  outcome.stop_reason = "max_iterations";
  const double theta_step = 1e-4;  // relative; above integrator noise, below curvature
  const double start_step = 1e-5;  // rad
  Eigen::MatrixXd reduced;         // residual × (r + n): relative θ directions, then start angles
  Eigen::VectorXd scale(p);
  auto jacobian_at_current = [&]() {
    for (int a = 0; a < p; ++a) scale[a] = std::max(std::abs(outcome.theta[free_index[a]]), 1e-12);
    reduced.resize(outcome.residual.size(), r + n);
    Eigen::VectorXd moved;
    for (int c = 0; c < r; ++c) {
      Eigen::VectorXd shifted = outcome.theta;
      for (int a = 0; a < p; ++a) shifted[free_index[a]] += theta_step * basis(a, c) * scale[a];
      evaluate(shifted, outcome.start, &moved);
      reduced.col(c) = (moved - outcome.residual) / theta_step;
    }
    for (int j = 0; j < n; ++j) {
      Eigen::VectorXd shifted_start = outcome.start;
      shifted_start[j] += start_step;
      evaluate(outcome.theta, shifted_start, &moved);
      reduced.col(r + j) = (moved - outcome.residual) / start_step;
    }
  };
  // The finite-difference Jacobian costs r + n simulations; between recomputations Broyden's
  // rank-one updates keep it current from the simulations the steps make anyway.
  jacobian_at_current();
  bool jacobian_fresh = true;
  int updates_since_measured = 0;
  int failures = 0;
  double damping = 0.0;
  for (int pass = 0; outcome.iterations < options.output_error_iterations && pass < 3 * options.output_error_iterations;
       ++pass) {
    if (options.cancel && options.cancel->load()) {
      outcome.cancelled = true;
      outcome.stop_reason = "cancelled";
      break;
    }
    const Eigen::MatrixXd normal = reduced.transpose() * reduced;
    const Eigen::VectorXd gradient = reduced.transpose() * outcome.residual;
    if (!normal.allFinite() || !gradient.allFinite()) {  // a diverged simulation: no step to solve for
      outcome.stop_reason = "non_finite_jacobian";
      break;
    }
    const double largest = normal.diagonal().maxCoeff();
    // Statistically converged: the full Gauss–Newton step is under a tenth of a standard
    // error (its Mahalanobis length under the residual variance), so further steps would
    // only move the estimate within its own noise.
    const Eigen::VectorXd full_step = -normal.ldlt().solve(gradient);
    const double variance =
        outcome.residual.squaredNorm() / std::max(1.0, static_cast<double>(outcome.residual.size() - r - n));
    if (full_step.dot(normal * full_step) < 1e-2 * variance) {
      if (jacobian_fresh) {
        outcome.stop_reason = "converged";
        break;
      }
      jacobian_at_current();  // confirm with a measured Jacobian before stopping
      jacobian_fresh = true;
      continue;
    }
    Eigen::MatrixXd damped = normal;
    damped.diagonal() += damping * normal.diagonal() + Eigen::VectorXd::Constant(r + n, 1e-14 * largest);
    Eigen::VectorXd step = -damped.ldlt().solve(gradient);
    // Trust region: no parameter moves by more than 10 % in one step.
    const double biggest = (basis * step.head(r)).cwiseAbs().maxCoeff();
    if (biggest > 0.1) step *= 0.1 / biggest;
    Eigen::VectorXd candidate = outcome.theta;
    for (int a = 0; a < p; ++a) candidate[free_index[a]] += scale[a] * (basis.row(a) * step.head(r))(0);
    candidate = candidate.cwiseMax(bounds.lower).cwiseMin(bounds.upper);
    const Eigen::VectorXd candidate_start = outcome.start + step.tail(n);
    Eigen::VectorXd residual;
    const double value = evaluate(candidate, candidate_start, &residual);
    record(value, candidate);
    if (value < outcome.cost) {
      // How much of the reduction the linear model promised did the step deliver?
      const double promised = outcome.residual.squaredNorm() - (outcome.residual + reduced * step).squaredNorm();
      const double delivered = outcome.residual.squaredNorm() - residual.squaredNorm();
      const bool model_was_good = promised > 0 && delivered >= 0.25 * promised;
      // Broyden: make the model reproduce the residual change this step actually produced.
      // (Scale drift from the new θ is negligible within one step.)
      if (residual.allFinite() && step.squaredNorm() > 0) {
        reduced += ((residual - outcome.residual) - reduced * step) * step.transpose() / step.squaredNorm();
      }
      outcome.theta = candidate;
      outcome.start = candidate_start;
      outcome.residual = residual;
      outcome.cost = value;
      damping *= 0.1;
      jacobian_fresh = false;
      failures = 0;
      ++outcome.iterations;
      // An updated model that mispredicts, or that has drifted through several updates,
      // only crawls along the narrow valleys of this problem: measure it again.
      if (!model_was_good || ++updates_since_measured >= 3) {
        jacobian_at_current();
        jacobian_fresh = true;
        updates_since_measured = 0;
      }
    } else if (!jacobian_fresh) {
      jacobian_at_current();  // the updated model misled the step: measure it again
      jacobian_fresh = true;
      damping = 0.0;
    } else {
      damping = damping == 0.0 ? 1e-3 : damping * 10.0;
      if (++failures >= 8) {
        outcome.stop_reason = "converged";  // no step along the identifiable directions lowers the cost
        break;
      }
    }
  }
  // Standard errors need a measured Jacobian at the estimate, not an updated one.
  if (!jacobian_fresh && !outcome.cancelled) jacobian_at_current();
  // ∂residual/∂θ = J_B Bᵀ D⁻¹ (B orthonormal); the start angles stay nuisance parameters.
  const Eigen::MatrixXd relative = reduced.leftCols(r) * basis.transpose();
  outcome.jacobian = Eigen::MatrixXd::Zero(outcome.residual.size(), outcome.theta.size());
  for (int a = 0; a < p; ++a) outcome.jacobian.col(free_index[a]) = relative.col(a) / scale[a];
  outcome.reduced = reduced;
  outcome.scale = scale;
  return outcome;
}

Eigen::MatrixXd gain_sensitivity(const RobotModel& model, const Trajectory& data, const PdController& gains,
                                 double relative_tolerance, const Eigen::VectorXd& theta, const Eigen::VectorXd* start,
                                 const Eigen::VectorXd& residual, const Eigen::MatrixXd& unknowns_jacobian,
                                 const Eigen::MatrixXd& to_theta) {
  const int n = static_cast<int>(gains.kp.size());
  Eigen::MatrixXd response(residual.size(), 2 * n);  // J_g
  for (int g = 0; g < 2 * n; ++g) {
    PdController moved = gains;
    double& gain = g < n ? moved.kp[g] : moved.kd[g - n];
    const double step = 1e-4 * std::max(std::abs(gain), 1e-6);
    gain += step;
    Eigen::VectorXd shifted;
    OutputErrorCost(model, data, moved, relative_tolerance).evaluate(Parameters::from_vector(theta), &shifted, start);
    response.col(g) = (shifted - residual) / step;
  }
  // Least squares' response of the unknowns (a pseudo-inverse: Ĵ may be rank-deficient along directions the
  // run barely sees, and is zero along those it cannot).
  return to_theta * (-unknowns_jacobian.completeOrthogonalDecomposition().solve(response));
}

Eigen::MatrixXd gain_sensitivity(const RobotModel& model, const Trajectory& data, const PdController& gains,
                                 double relative_tolerance, const GaussNewtonOutcome& outcome, const Eigen::MatrixXd& basis,
                                 const FitBounds& bounds) {
  const int n = bounds.n;
  const int r = static_cast<int>(basis.cols());
  // θ moves by D B along the directions (D = |θ| of the free parameters); the start angles move θ not at all.
  Eigen::MatrixXd to_theta = Eigen::MatrixXd::Zero(outcome.theta.size(), r + n);
  Eigen::Index a = 0;
  for (int i = 0; i < static_cast<int>(bounds.free.size()); ++i) {
    if (!bounds.free[static_cast<std::size_t>(i)]) continue;
    to_theta.row(i).head(r) = basis.row(a) * outcome.scale[a];
    ++a;
  }
  return gain_sensitivity(model, data, gains, relative_tolerance, outcome.theta, &outcome.start, outcome.residual,
                          outcome.reduced, to_theta);
}

}  // namespace manipid::detail
