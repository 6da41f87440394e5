// gauss_newton.cpp — the bounded Gauss–Newton / Levenberg–Marquardt minimiser (gauss_newton.h).
#include "estimation/gauss_newton.h"

#include "numbers.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace manipid::detail {

const char* to_string(GaussNewtonStop stop) {
  switch (stop) {
    case GaussNewtonStop::converged_exact: return "converged_exact";
    case GaussNewtonStop::converged_gradient: return "converged_gradient";
    case GaussNewtonStop::converged_noise: return "converged_noise";
    case GaussNewtonStop::converged_cost: return "converged_cost";
    case GaussNewtonStop::converged_step: return "converged_step";
    case GaussNewtonStop::rounding_limited: return "rounding_limited";
    case GaussNewtonStop::max_iterations: return "max_iterations";
    case GaussNewtonStop::cancelled: return "cancelled";
    case GaussNewtonStop::stopped: return "stopped";
  }
  return "unknown";
}

bool converged(GaussNewtonStop stop) {
  return stop != GaussNewtonStop::max_iterations && stop != GaussNewtonStop::cancelled &&
         stop != GaussNewtonStop::stopped;
}

GaussNewtonSummary GaussNewtonMinimizer::minimize(GaussNewtonProblem& problem) {
  problem_ = &problem;
  summary_.initial_cost = summary_.final_cost = problem.cost();
  for (;;) {
    if (options_.cancel && options_.cancel->load()) {
      stop(GaussNewtonStop::cancelled);
      break;
    }
    if (!linearised_ && linearise_and_test()) break;
    if (summary_.iterations >= options_.max_iterations || summary_.accepted_steps >= options_.max_accepted_steps) {
      stop(GaussNewtonStop::max_iterations);
      break;
    }
    if (iterate()) break;
  }
  summary_.final_cost = problem.cost();
  summary_.damping = damping_ < 0.0 ? options_.initial_damping : damping_;  // never linearised: as given
  return summary_;
}

// The model at a new point, and the tests that need it (asked again of a refreshed model). True: stop.
bool GaussNewtonMinimizer::linearise_and_test() {
  linearised_ = true;
  if (!problem_->linearise(model_)) return stop(GaussNewtonStop::rounding_limited);  // never NaN into a solver
  if (damping_ < 0.0) damping_ = options_.initial_damping * problem_->damping_scale();
  const std::optional<GaussNewtonStop> stop_test = test_at_new_point();
  if (!stop_test) return false;
  if (problem_->refresh_model()) return linearise_and_test();
  return stop(*stop_test);
}

std::optional<GaussNewtonStop> GaussNewtonMinimizer::test_at_new_point() {
  const double root = std::sqrt(problem_->cost());
  // An exact fit: the residual is rounding (a few ε of the data's norm) and cannot shrink further.
  if (root <= 32.0 * std::numeric_limits<double>::epsilon() * options_.exact_fit_scale) {
    return GaussNewtonStop::converged_exact;
  }
  // cos = max_i |g_i| / (√H_ii √F): the gradient's largest angle-like share along a free variable.
  double cosine = 0.0;
  for (int i : model_.free) {
    const double h = model_.curvature_diagonal[i];
    if (h > 0.0) cosine = std::max(cosine, std::abs(model_.gradient[i]) / (std::sqrt(h) * root));
  }
  if (model_.free.empty() || cosine <= options_.gradient_tolerance) return GaussNewtonStop::converged_gradient;
  // gᵀH⁻¹g < tol · F / (m − p): the Gauss–Newton step is within the estimate's noise.
  if (model_.decrement < options_.noise_tolerance * problem_->cost() / model_.degrees_of_freedom) {
    return GaussNewtonStop::converged_noise;
  }
  return std::nullopt;
}

// One iteration: the damped step, its candidate, and the verdict. True: stop.
bool GaussNewtonMinimizer::iterate() {
  ++summary_.iterations;
  double ratio = 0.0, candidate_cost = 0.0;
  if (compute_step()) {
    if (try_step(ratio, candidate_cost) && ratio > options_.min_relative_decrease) {
      return accept_step(ratio, candidate_cost);
    }
    if (summary_.stop == GaussNewtonStop::stopped) return true;
  }
  return refuse_step();
}

bool GaussNewtonMinimizer::compute_step() { return problem_->solve(damping_, step_); }

// The candidate for the step, evaluated when the model promises more than rounding; its ratio
// ρ = actual / predicted decrease. False: refused (or the problem stopped the run).
bool GaussNewtonMinimizer::try_step(double& ratio, double& candidate_cost) {
  const double cost = problem_->cost();
  const double predicted = problem_->candidate(step_);
  if (!(predicted > options_.rounding_level * cost)) return false;  // NaN too: not a point
  const GaussNewtonProblem::Evaluation evaluation = problem_->evaluate_candidate(candidate_cost);
  if (evaluation == GaussNewtonProblem::Evaluation::stopped) {
    stop(GaussNewtonStop::stopped);
    return false;
  }
  ++summary_.evaluations;
  if (evaluation != GaussNewtonProblem::Evaluation::ok) return false;
  ratio = (cost - candidate_cost) / predicted;
  return true;
}

// The candidate becomes the current point; Nielsen's damping update; the cost and step tests.
bool GaussNewtonMinimizer::accept_step(double ratio, double candidate_cost) {
  const double before = problem_->cost();
  const double decrease = before - candidate_cost;
  const double size = problem_->accept();
  linearised_ = false;
  ++summary_.accepted_steps;
  // λ ← max(λ_min, λ · max(1/3, 1 − (2ρ − 1)³)), ν ← 2
  damping_ = std::max(options_.min_damping, damping_ * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3)));
  growth_ = 2.0;
  problem_->on_step(true, damping_);
  if (decrease <= options_.function_tolerance * before) return stop(GaussNewtonStop::converged_cost);
  if (size <= options_.step_tolerance) return stop(GaussNewtonStop::converged_step);
  return false;
}

// More damping, by a factor that doubles with each refusal in a row (λ ← λν, ν ← 2ν); past
// max_damping nothing more can be gained in double precision.
bool GaussNewtonMinimizer::refuse_step() {
  damping_ *= growth_;
  growth_ *= 2.0;
  problem_->on_step(false, damping_);
  if (problem_->refresh_model()) linearised_ = false;
  if (damping_ > options_.max_damping) return stop(GaussNewtonStop::rounding_limited);
  return false;
}

bool GaussNewtonMinimizer::stop(GaussNewtonStop reason) {
  summary_.stop = reason;
  switch (reason) {
    case GaussNewtonStop::converged_exact:
      summary_.message = "the residual is rounding: the fit is exact";
      break;
    case GaussNewtonStop::converged_gradient:
      summary_.message = "the gradient is orthogonal to every direction the parameters can still move in (cosine ≤ " +
                         short_number(options_.gradient_tolerance) + ")";
      break;
    case GaussNewtonStop::converged_noise:
      summary_.message = "the Gauss–Newton step would move the estimate within its own noise (decrement below " +
                         short_number(options_.noise_tolerance) + " of the residual variance)";
      break;
    case GaussNewtonStop::converged_cost:
      summary_.message = "the last step decreased the cost by less than " +
                         short_number(options_.function_tolerance) + " of its value";
      break;
    case GaussNewtonStop::converged_step:
      summary_.message = "the last step moved no parameter by more than " + short_number(options_.step_tolerance) +
                         " of its scale";
      break;
    case GaussNewtonStop::rounding_limited:
      summary_.message = "no step decreases the cost any more in double precision";
      break;
    case GaussNewtonStop::max_iterations:
      summary_.message = "stopped after " + std::to_string(summary_.iterations) + " iterations (" +
                         std::to_string(summary_.accepted_steps) + " accepted) before converging";
      break;
    case GaussNewtonStop::cancelled:
      summary_.message = "cancelled after " + std::to_string(summary_.iterations) + " iterations";
      break;
    case GaussNewtonStop::stopped:
      summary_.message = "the problem refused an evaluation (a budget)";
      break;
  }
  return true;
}

}  // namespace manipid::detail
