// output_error_fit.cpp — Levenberg–Marquardt on the output error (output_error_fit.h), a problem for core's one minimiser (estimation/gauss_newton.h).
#include "paper/output_error_fit.h"

#include "estimation/gauss_newton.h"

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

namespace {

// The output-error fit as the shared minimiser's problem (estimation/gauss_newton.h). The
// unknowns u are the identifiable directions (relative coordinates over the free parameters,
// θ = θ₀ + D B u_B, D = diag|θ|) and the start angles; the model is the residual's forward-
// difference Jacobian J over them (r + n simulations), kept current between measurements by
// Broyden's rank-one updates from the simulations the steps make anyway.
class OutputErrorFit final : public GaussNewtonProblem {
 public:
  OutputErrorFit(const OutputErrorCost& cost, const Eigen::MatrixXd& basis, const FitBounds& bounds, EvaluationLog& log,
                 GaussNewtonOutcome& outcome)
      : cost_(cost), basis_(basis), bounds_(bounds), log_(log), outcome_(outcome), n_(bounds.n),
        r_(static_cast<int>(basis.cols())) {
    for (int i = 0; i < outcome.theta.size(); ++i) {
      if (bounds.free[i]) free_index_.push_back(i);
    }
    outcome_.scale.resize(parameter_count());
  }
  int parameter_count() const { return static_cast<int>(free_index_.size()); }
  int free_parameter(int a) const { return free_index_[static_cast<std::size_t>(a)]; }
  bool fresh() const { return jacobian_fresh_; }
  bool finite_model() const { return finite_model_; }

  double evaluate(const Eigen::VectorXd& theta, const Eigen::VectorXd& start, Eigen::VectorXd* residual) const {
    return cost_.evaluate(Parameters::from_vector(theta), residual, &start);
  }

  // J at the current point, measured: residual × (r + n), relative θ directions, then start angles.
  void measure_jacobian() {
    const double theta_step = 1e-4;  // relative; above integrator noise, below curvature
    const double start_step = 1e-5;  // rad
    const int p = parameter_count();
    for (int a = 0; a < p; ++a) outcome_.scale[a] = std::max(std::abs(outcome_.theta[free_index_[a]]), 1e-12);
    outcome_.reduced.resize(outcome_.residual.size(), r_ + n_);
    Eigen::VectorXd moved;
    for (int c = 0; c < r_; ++c) {
      Eigen::VectorXd shifted = outcome_.theta;
      for (int a = 0; a < p; ++a) shifted[free_index_[a]] += theta_step * basis_(a, c) * outcome_.scale[a];
      evaluate(shifted, outcome_.start, &moved);
      outcome_.reduced.col(c) = (moved - outcome_.residual) / theta_step;
    }
    for (int j = 0; j < n_; ++j) {
      Eigen::VectorXd shifted_start = outcome_.start;
      shifted_start[j] += start_step;
      evaluate(outcome_.theta, shifted_start, &moved);
      outcome_.reduced.col(r_ + j) = (moved - outcome_.residual) / start_step;
    }
    jacobian_fresh_ = true;
    updates_since_measured_ = 0;
  }

  double cost() const override { return outcome_.residual.squaredNorm(); }

  // N = JᵀJ, g = Jᵀr; for the statistical test gᵀN⁻¹g (the full Gauss–Newton step's length in
  // N's metric) against the residual variance ‖r‖² / (m − r − n).
  bool linearise(GaussNewtonModel& model) override {
    normal_ = outcome_.reduced.transpose() * outcome_.reduced;
    gradient_ = outcome_.reduced.transpose() * outcome_.residual;
    finite_model_ = normal_.allFinite() && gradient_.allFinite();
    if (!finite_model_) return false;  // a diverged simulation: no step to solve for
    const Eigen::VectorXd full_step = -normal_.ldlt().solve(gradient_);
    model.gradient = gradient_;
    model.curvature_diagonal = normal_.diagonal();
    model.free.resize(static_cast<std::size_t>(r_ + n_));
    for (int i = 0; i < r_ + n_; ++i) model.free[static_cast<std::size_t>(i)] = i;
    model.decrement = full_step.dot(normal_ * full_step);
    model.degrees_of_freedom = std::max(1.0, static_cast<double>(outcome_.residual.size() - r_ - n_));
    return true;
  }

  // (N + λ diag N + 10⁻¹⁴ max(diag N) I) δ = −g (Marquardt's scaling; the floor keeps an unseen
  // direction from an unbounded step).
  bool solve(double damping, Eigen::VectorXd& step) override {
    const double largest = normal_.diagonal().maxCoeff();
    Eigen::MatrixXd damped = normal_;
    damped.diagonal() += damping * normal_.diagonal() + Eigen::VectorXd::Constant(r_ + n_, 1e-14 * largest);
    step = -damped.ldlt().solve(gradient_);
    return true;
  }

  // Trust region: no parameter moves by more than 10 % in one step; θ projected on the bounds.
  // The linear model's decrease ‖r‖² − ‖r + Jδ‖².
  double candidate(const Eigen::VectorXd& proposed) override {
    step_ = proposed;
    const double biggest = (basis_ * step_.head(r_)).cwiseAbs().maxCoeff();
    if (biggest > 0.1) step_ *= 0.1 / biggest;
    candidate_theta_ = outcome_.theta;
    for (int a = 0; a < parameter_count(); ++a) {
      candidate_theta_[free_index_[a]] += outcome_.scale[a] * (basis_.row(a) * step_.head(r_))(0);
    }
    candidate_theta_ = candidate_theta_.cwiseMax(bounds_.lower).cwiseMin(bounds_.upper);
    candidate_start_ = outcome_.start + step_.tail(n_);
    predicted_ = outcome_.residual.squaredNorm() - (outcome_.residual + outcome_.reduced * step_).squaredNorm();
    return predicted_;
  }

  Evaluation evaluate_candidate(double& cost) override {
    candidate_value_ = evaluate(candidate_theta_, candidate_start_, &candidate_residual_);
    log_.record(candidate_value_, candidate_theta_);
    cost = candidate_residual_.squaredNorm();
    return std::isfinite(candidate_value_) && std::isfinite(cost) ? Evaluation::ok : Evaluation::not_finite;
  }

  // Broyden: J ← J + ((Δr − J δ) δᵀ) / δᵀδ, the model made to reproduce the residual change this step
  // produced (the scale's drift from the new θ is negligible within one step). A model that
  // mispredicted (under a quarter of its promise), or that has drifted through three updates, only
  // crawls along the narrow valleys of this problem: it is measured again.
  double accept() override {
    const double delivered = outcome_.residual.squaredNorm() - candidate_residual_.squaredNorm();
    const bool model_was_good = predicted_ > 0 && delivered >= 0.25 * predicted_;
    if (candidate_residual_.allFinite() && step_.squaredNorm() > 0) {
      outcome_.reduced += ((candidate_residual_ - outcome_.residual) - outcome_.reduced * step_) * step_.transpose() /
                          step_.squaredNorm();
    }
    const double size = (candidate_theta_ - outcome_.theta).cwiseAbs().maxCoeff();
    outcome_.theta = candidate_theta_;
    outcome_.start = candidate_start_;
    outcome_.residual = candidate_residual_;
    outcome_.cost = candidate_value_;
    ++outcome_.iterations;
    jacobian_fresh_ = false;
    if (!model_was_good || ++updates_since_measured_ >= 3) measure_jacobian();
    return size;
  }

  // An updated model is measured before it may stop the fit, and after it misled a step.
  bool refresh_model() override {
    if (jacobian_fresh_) return false;
    measure_jacobian();
    return true;
  }

 private:
  const OutputErrorCost& cost_;
  const Eigen::MatrixXd& basis_;
  const FitBounds& bounds_;
  EvaluationLog& log_;
  GaussNewtonOutcome& outcome_;  // the current point, its Jacobian and the scale
  const int n_, r_;
  std::vector<int> free_index_;
  Eigen::MatrixXd normal_;
  Eigen::VectorXd gradient_, step_, candidate_theta_, candidate_start_, candidate_residual_;
  double predicted_ = 0.0, candidate_value_ = 0.0;
  bool jacobian_fresh_ = false, finite_model_ = true;
  int updates_since_measured_ = 0;
};

}  // namespace

GaussNewtonOutcome gauss_newton_output_error(const OutputErrorCost& cost, const Eigen::VectorXd& theta_start,
                                             const Eigen::MatrixXd& basis, const FitBounds& bounds,
                                             const IdentificationOptions& options, EvaluationLog& log) {
  GaussNewtonOutcome outcome;
  outcome.theta = theta_start;
  outcome.start = cost.measured_start();
  OutputErrorFit fit(cost, basis, bounds, log, outcome);
  outcome.cost = fit.evaluate(outcome.theta, outcome.start, &outcome.residual);
  log.record(outcome.cost, outcome.theta);
  fit.measure_jacobian();
  // Measured against the fit's own loop before it ran on the shared minimiser (Marquardt's ×10 / ×0.1
  // from λ = 0, eight refusals a stop; manipid simulate --noise-q 1e-4 --quantize-q 16
  // --noise-tau-relative 0.01 --seed S; manipid identify --method two-stage --json), seeds 1–7:
  // estimates within 7.5e-5 relative (0.38 standard errors at most, < 0.1 on six seeds), the final
  // cost lower on five, higher by ≤ 2.1e-6 relative on two, simulations 620 → 579 in all; clean data:
  // estimates within 2.5e-7, cost 9.14e-17 → 9.03e-17, simulations 59 → 75.
  GaussNewtonOptions settings;
  settings.noise_tolerance = 1e-2;                  // the step under a tenth of a standard error
  settings.gradient_tolerance = 0.0;
  settings.function_tolerance = 0.0;
  settings.step_tolerance = 0.0;
  settings.max_accepted_steps = options.output_error_iterations;
  settings.max_iterations = 3 * options.output_error_iterations;
  settings.cancel = options.cancel;
  const GaussNewtonSummary summary = GaussNewtonMinimizer(settings).minimize(fit);
  if (summary.stop == GaussNewtonStop::cancelled) {
    outcome.cancelled = true;
    outcome.stop_reason = "cancelled";
  } else if (!fit.finite_model()) {
    outcome.stop_reason = "non_finite_jacobian";
  } else {
    outcome.stop_reason = converged(summary.stop) ? "converged" : "max_iterations";
  }
  // Standard errors need a measured Jacobian at the estimate, not an updated one.
  if (!fit.fresh() && !outcome.cancelled) fit.measure_jacobian();
  // ∂residual/∂θ = J_B Bᵀ D⁻¹ (B orthonormal); the start angles stay nuisance parameters.
  const Eigen::MatrixXd relative = outcome.reduced.leftCols(basis.cols()) * basis.transpose();
  outcome.jacobian = Eigen::MatrixXd::Zero(outcome.residual.size(), outcome.theta.size());
  for (int a = 0; a < fit.parameter_count(); ++a) {
    outcome.jacobian.col(fit.free_parameter(a)) = relative.col(a) / outcome.scale[a];
  }
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
