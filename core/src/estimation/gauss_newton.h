// gauss_newton.h — internal: core's one bounded Gauss–Newton / Levenberg–Marquardt minimiser, the one home of its damping rule and stop tests.
//
// Every least-squares loop of core runs here: the "LM" algorithm (least_squares.cpp), the
// output-error fit (paper/output_error_fit.cpp), the Gauss–Newton polish of an input-error minimum
// (paper/identification.cpp) and the physically consistent fit (robot/consistent_fit.cpp). What
// differs between them is the problem's and is handed in as a GaussNewtonProblem: how the model is
// formed (a Jacobian, a Gram matrix, a Broyden update), how the damped step is solved (an SVD, an
// eigen-decomposition that drops the directions the data cannot see, a Cholesky factor), and how a
// step becomes a point (projection on bounds, a retraction, a barrier's fraction to the boundary).
// What is the same is here, built as Ceres's TrustRegionMinimizer is, one method per step:
//
//   linearise_and_test()  the model at a new point; the exact-fit and gradient tests
//   iterate()             compute_step() (the problem's solve), try_step() (the problem's candidate,
//                         evaluated when the model promises a decrease), then
//   accept_step()         (Nielsen's damping update; the cost and step tests) or
//   refuse_step()         (more damping; the rounding test)
//
// The cost is F = ‖r‖² (+ a constant); the problem's model is g = ½∇F and H ≈ ½∇²F (JᵀJ for
// Gauss–Newton), so a step δ is predicted to lower F by −(2gᵀδ + δᵀHδ) (or, exactly for the linear
// model, ‖r‖² − ‖r + Jδ‖²), and the ratio ρ = (F(x) − F(x + δ)) / predicted judges it.
//
// The damping rule (Nielsen's, Madsen, Nielsen & Tingleff, "Methods for non-linear least squares
// problems", 2004, §3.2), the only one in core:
//   accepted (ρ > min_relative_decrease):  λ ← max(min_damping, λ · max(1/3, 1 − (2ρ − 1)³)),  ν ← 2
//   refused:                               λ ← λ · ν,  ν ← 2ν
// The stop tests, the only ones in core (Summary: the stop and a sentence saying why):
//   converged_exact     √F ≤ 32 ε · exact_fit_scale (the residual is rounding; off unless a scale is given)
//   converged_gradient  no free variable, or max over the free i of |g_i| / (√H_ii · √F) ≤ gradient_tolerance
//   converged_noise     the undamped Gauss–Newton step would lower F by gᵀH⁻¹g < noise_tolerance · F / (m − p)
//                       (its length in the model's metric under √noise_tolerance standard errors: further
//                       steps move the estimate within its own noise; only a problem that forms gᵀH⁻¹g)
//   converged_cost      an accepted step lowered F by ≤ function_tolerance · F
//   converged_step      an accepted step's size (the problem's measure) ≤ step_tolerance
//   rounding_limited    λ > max_damping after a refusal, or the model cannot be formed (not finite)
//   max_iterations      max_iterations steps tried, or max_accepted_steps taken
//   cancelled, stopped  the cancel flag; the problem refused an evaluation (its budgets)
// A model that is an approximation (a Broyden update) is formed anew (refresh_model()) before a
// test at a new point may stop the run, and after a refused step.
// A step whose predicted decrease is ≤ rounding_level · F is refused without being evaluated: the
// model promises nothing the cost's rounding would not hide.
#pragma once

#include <Eigen/Core>

#include <atomic>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace manipid::detail {

/// What the minimiser does; the defaults are the consistent fit's (and Ceres's where it has one).
struct GaussNewtonOptions {
  /// λ at the start, times the problem's damping_scale().
  double initial_damping = 1e-4;
  /// λ never falls below this on an accepted step (Ceres: trust-region radius 1e16 ↔ λ = 1e-16).
  double min_damping = 1e-15;
  /// Past this after a refusal, every step is a rounding-sized gradient step that still fails to
  /// lower F: nothing more can be gained in double precision (rounding_limited).
  double max_damping = 1e32;
  /// A step is accepted when it achieves more than this share of its predicted decrease (Ceres's
  /// min_relative_decrease).
  double min_relative_decrease = 1e-3;
  /// A step predicted to lower F by no more than this share of F is refused unevaluated.
  double rounding_level = 0.0;
  /// The stop tests (the header's comment); 0 turns the gradient and step tests into "exactly zero".
  double gradient_tolerance = 1e-10;
  double function_tolerance = 1e-12;
  double step_tolerance = 1e-10;
  /// The statistical test's share (converged_noise); 0: no such test.
  double noise_tolerance = 0.0;
  /// The exact-fit test's scale (‖z‖ of a fit to z); NaN: no such test.
  double exact_fit_scale = std::numeric_limits<double>::quiet_NaN();
  /// Iterations (steps tried, accepted or not) this run may make.
  int max_iterations = std::numeric_limits<int>::max();
  /// Accepted steps this run may take.
  int max_accepted_steps = std::numeric_limits<int>::max();
  /// Checked before every iteration.
  const std::atomic<bool>* cancel = nullptr;
};

enum class GaussNewtonStop {
  converged_exact,
  converged_gradient,
  converged_noise,
  converged_cost,
  converged_step,
  rounding_limited,
  max_iterations,
  cancelled,
  stopped,  // the problem refused an evaluation (a budget of its own, its cancel flag)
};

const char* to_string(GaussNewtonStop stop);
/// True for the converged_* stops and rounding_limited (a minimum within the precision at hand).
bool converged(GaussNewtonStop stop);

/// What a run did and why it stopped.
struct GaussNewtonSummary {
  GaussNewtonStop stop = GaussNewtonStop::max_iterations;
  std::string message;  ///< why it stopped, in words, with the tolerance that decided
  int iterations = 0;   ///< steps tried (accepted or refused)
  int accepted_steps = 0;
  int evaluations = 0;  ///< candidates evaluated (refused unevaluated steps are not)
  double initial_cost = 0.0, final_cost = 0.0;
  double damping = 0.0;  ///< λ at the end (a continuation starts its next run from it)
};

/// The model at the current point, filled by GaussNewtonProblem::linearise().
struct GaussNewtonModel {
  Eigen::VectorXd gradient;            ///< g = ½∇F, every variable
  Eigen::VectorXd curvature_diagonal;  ///< diag(H), every variable (the gradient test's scale)
  std::vector<int> free;               ///< the variables the step may move (see held_on_bound())
  /// For the statistical test (converged_noise): gᵀH⁻¹g, and the residual's degrees of freedom m − p;
  /// NaN when the problem does not form it.
  double decrement = std::numeric_limits<double>::quiet_NaN();
  double degrees_of_freedom = 1.0;
};

/// The problem's part of the minimisation: its point, its model, its step and its candidate.
class GaussNewtonProblem {
 public:
  virtual ~GaussNewtonProblem() = default;
  /// F at the current point.
  virtual double cost() const = 0;
  /// The model at the current point. False when it cannot be formed (not finite).
  virtual bool linearise(GaussNewtonModel& model) = 0;
  /// The units λ is in, asked once after the first linearise() (Marquardt's scaling makes it 1).
  virtual double damping_scale() const { return 1.0; }
  /// The damped step for λ (0 outside the free variables). False: no step (a failed factorisation).
  virtual bool solve(double damping, Eigen::VectorXd& step) = 0;
  /// Forms the candidate point for `step` (projection, retraction, fraction to the boundary) and
  /// returns the model's decrease of F for the step as taken; NaN when the candidate is not a point
  /// (outside the feasible set). Evaluates nothing.
  virtual double candidate(const Eigen::VectorXd& step) = 0;
  enum class Evaluation { ok, not_finite, stopped };
  /// Evaluates F at the candidate (cost set when ok). `stopped`: the run ends (a budget, cancel).
  virtual Evaluation evaluate_candidate(double& cost) = 0;
  /// The candidate becomes the current point; returns the step's size for the step test.
  virtual double accept() = 0;
  /// Told after every accepted or refused step, with λ after its update.
  virtual void on_step(bool /*accepted*/, double /*damping*/) {}
  /// Forms the model anew from the cost when it is an approximation; true when it did (the
  /// minimiser then linearises again). Asked before a test at a new point stops the run, and
  /// after a refused step.
  virtual bool refresh_model() { return false; }
};

/// A variable held for a step: on its bound with the gradient pushing it outward (the KKT
/// conditions hold for it). g = ½∇F.
inline bool held_on_bound(double x, double lower, double upper, double gradient) {
  return (x <= lower && gradient > 0.0) || (x >= upper && gradient < 0.0);
}

/// The minimiser. One object per run; minimize() runs once.
class GaussNewtonMinimizer {
 public:
  explicit GaussNewtonMinimizer(const GaussNewtonOptions& options) : options_(options) {}
  GaussNewtonSummary minimize(GaussNewtonProblem& problem);

 private:
  bool linearise_and_test();
  std::optional<GaussNewtonStop> test_at_new_point();
  bool iterate();
  bool compute_step();
  bool try_step(double& ratio, double& candidate_cost);
  bool accept_step(double ratio, double candidate_cost);
  bool refuse_step();
  bool stop(GaussNewtonStop reason);

  const GaussNewtonOptions& options_;
  GaussNewtonProblem* problem_ = nullptr;
  GaussNewtonSummary summary_;
  GaussNewtonModel model_;
  Eigen::VectorXd step_;
  bool linearised_ = false;
  double damping_ = -1.0;  // λ (negative: not set yet)
  double growth_ = 2.0;    // ν
};

}  // namespace manipid::detail
