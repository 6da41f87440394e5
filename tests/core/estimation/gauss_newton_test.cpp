// gauss_newton_test.cpp — core's one Levenberg–Marquardt minimiser (estimation/gauss_newton.h, internal): exact linear least squares, Rosenbrock with bounds, an active bound, the stop reasons.
#include "estimation/gauss_newton.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>

namespace manipid::detail {
namespace {

/// A dense test problem: r(x) with its Jacobian, box bounds projected, Marquardt's D = diag(JᵀJ).
class DenseProblem final : public GaussNewtonProblem {
 public:
  using Residual = std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd& J)>;
  DenseProblem(Residual residual, Eigen::VectorXd start, Eigen::VectorXd lower, Eigen::VectorXd upper)
      : residual_(std::move(residual)), x_(std::move(start)), lower_(std::move(lower)), upper_(std::move(upper)) {
    residual_(x_, r_, j_);
  }
  const Eigen::VectorXd& x() const { return x_; }
  int evaluations() const { return evaluations_; }

  double cost() const override { return r_.squaredNorm(); }
  bool linearise(GaussNewtonModel& model) override {
    model.gradient = j_.transpose() * r_;
    model.curvature_diagonal = j_.colwise().squaredNorm().transpose();
    model.free.clear();
    for (int i = 0; i < x_.size(); ++i) {
      if (!held_on_bound(x_[i], lower_[i], upper_[i], model.gradient[i])) model.free.push_back(i);
    }
    free_ = model.free;
    return model.gradient.allFinite();
  }
  bool solve(double damping, Eigen::VectorXd& step) override {
    const int f = static_cast<int>(free_.size());
    Eigen::MatrixXd system(f, f);
    Eigen::VectorXd rhs(f);
    const Eigen::MatrixXd h = j_.transpose() * j_;
    const Eigen::VectorXd g = j_.transpose() * r_;
    for (int a = 0; a < f; ++a) {
      for (int b = 0; b < f; ++b) system(a, b) = h(free_[a], free_[b]);
      system(a, a) += damping * std::max(h(free_[a], free_[a]), 1e-12);
      rhs[a] = -g[free_[a]];
    }
    const Eigen::LLT<Eigen::MatrixXd> cholesky(system);
    if (cholesky.info() != Eigen::Success) return false;
    const Eigen::VectorXd solved = cholesky.solve(rhs);
    step = Eigen::VectorXd::Zero(x_.size());
    for (int a = 0; a < f; ++a) step[free_[a]] = solved[a];
    return true;
  }
  double candidate(const Eigen::VectorXd& step) override {
    candidate_ = (x_ + step).cwiseMax(lower_).cwiseMin(upper_);
    const Eigen::VectorXd taken = candidate_ - x_;
    return r_.squaredNorm() - (r_ + j_ * taken).squaredNorm();
  }
  Evaluation evaluate_candidate(double& cost) override {
    if (budget_ >= 0 && evaluations_ >= budget_) return Evaluation::stopped;
    ++evaluations_;
    residual_(candidate_, candidate_r_, candidate_j_);
    cost = candidate_r_.squaredNorm();
    return std::isfinite(cost) ? Evaluation::ok : Evaluation::not_finite;
  }
  double accept() override {
    const double size = (candidate_ - x_).norm() / (x_.norm() + 1e-10);
    x_ = candidate_;
    std::swap(r_, candidate_r_);
    std::swap(j_, candidate_j_);
    return size;
  }
  void set_budget(int evaluations) { budget_ = evaluations; }

 private:
  Residual residual_;
  Eigen::VectorXd x_, lower_, upper_, r_, candidate_, candidate_r_;
  Eigen::MatrixXd j_, candidate_j_;
  std::vector<int> free_;
  int evaluations_ = 0, budget_ = -1;
};

Eigen::VectorXd unbounded(int n, double sign) { return Eigen::VectorXd::Constant(n, sign * std::numeric_limits<double>::infinity()); }

/// Rosenbrock as residuals, r = (10 (x2 − x1²), 1 − x1): the minimum 0 at (1, 1) along a curved valley.
void rosenbrock_residuals(const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd& j) {
  r.resize(2);
  r << 10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0];
  j.resize(2, 2);
  j << -20.0 * x[0], 10.0, -1.0, 0.0;
}

TEST(GaussNewtonMinimizer, SolvesLinearLeastSquaresExactly) {
  // r = A x − b, overdetermined, full rank: the minimum is the normal equations' solution.
  Eigen::MatrixXd a(4, 3);
  a << 1, 2, 0, 0, 1, 1, 3, 0, 1, 1, 1, 1;
  Eigen::VectorXd b(4);
  b << 1, 2, 3, 5;
  const Eigen::VectorXd exact = (a.transpose() * a).ldlt().solve(a.transpose() * b);
  DenseProblem problem(
      [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd& j) {
        r = a * x - b;
        j = a;
      },
      Eigen::VectorXd::Zero(3), unbounded(3, -1), unbounded(3, 1));
  GaussNewtonOptions options;
  const GaussNewtonSummary summary = GaussNewtonMinimizer(options).minimize(problem);
  EXPECT_TRUE(converged(summary.stop)) << to_string(summary.stop);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(problem.x()[i], exact[i], 1e-9);
  EXPECT_NEAR(summary.final_cost, (a * exact - b).squaredNorm(), 1e-12);
  EXPECT_EQ(summary.initial_cost, b.squaredNorm());
  // A linear model is exact: the first (barely damped) step lands on the minimum.
  EXPECT_LE(summary.accepted_steps, 3);
}

TEST(GaussNewtonMinimizer, FollowsRosenbrocksValleyToItsMinimum) {
  DenseProblem problem(rosenbrock_residuals, Eigen::Vector2d(-1.2, 1.0), Eigen::Vector2d(-5, -5), Eigen::Vector2d(5, 5));
  GaussNewtonOptions options;
  options.gradient_tolerance = 0.0;
  options.function_tolerance = 0.0;
  options.step_tolerance = 0.0;
  options.exact_fit_scale = 1.0;  // r = 0 exactly at the minimum: stop once √F is rounding
  const GaussNewtonSummary summary = GaussNewtonMinimizer(options).minimize(problem);
  EXPECT_NEAR(problem.x()[0], 1.0, 1e-10);
  EXPECT_NEAR(problem.x()[1], 1.0, 1e-10);
  EXPECT_LT(summary.final_cost, 1e-20);
  EXPECT_NEAR(summary.initial_cost, 24.2, 1e-12);  // (10·(1 − 1.44))² + 2.2²
  EXPECT_TRUE(converged(summary.stop)) << to_string(summary.stop);
  EXPECT_LT(summary.iterations, 100);
  EXPECT_EQ(summary.evaluations, problem.evaluations());
}

TEST(GaussNewtonMinimizer, StopsOnTheBoundThatBecomesActive) {
  // Rosenbrock with x1 ≤ 0.5: the minimum on the bound is x1 = 0.5, x2 = x1² = 0.25.
  DenseProblem problem(rosenbrock_residuals, Eigen::Vector2d(-1.2, 1.0), Eigen::Vector2d(-5, -5), Eigen::Vector2d(0.5, 5));
  GaussNewtonOptions options;
  options.gradient_tolerance = 1e-8;  // cos = 2|r1| along x2: |x2 − x1²| ≤ 5e-10
  options.function_tolerance = 0.0;
  options.step_tolerance = 0.0;
  const GaussNewtonSummary summary = GaussNewtonMinimizer(options).minimize(problem);
  EXPECT_LE(problem.x()[0], 0.5);
  EXPECT_NEAR(problem.x()[0], 0.5, 1e-10);
  EXPECT_NEAR(problem.x()[1], 0.25, 1e-9);
  EXPECT_NEAR(summary.final_cost, 0.25, 1e-12);  // (1 − 0.5)²
  // At the end x1 is held on its bound (the gradient pushes it out: were it free, its cosine would be
  // about 0.1) and x2 has no gradient left.
  EXPECT_EQ(summary.stop, GaussNewtonStop::converged_gradient) << summary.message;
}

TEST(GaussNewtonMinimizer, SaysWhyItStopped) {
  const Eigen::Vector2d start(-1.2, 1.0);
  const Eigen::Vector2d lower(-5, -5), upper(5, 5);
  {  // the iteration limit
    DenseProblem problem(rosenbrock_residuals, start, lower, upper);
    GaussNewtonOptions options;
    options.max_iterations = 2;
    const GaussNewtonSummary summary = GaussNewtonMinimizer(options).minimize(problem);
    EXPECT_EQ(summary.stop, GaussNewtonStop::max_iterations);
    EXPECT_EQ(summary.iterations, 2);
    EXPECT_NE(summary.message.find("2 iterations"), std::string::npos) << summary.message;
    EXPECT_FALSE(converged(summary.stop));
  }
  {  // the cancel flag, before the first step
    DenseProblem problem(rosenbrock_residuals, start, lower, upper);
    const std::atomic<bool> cancel{true};
    GaussNewtonOptions options;
    options.cancel = &cancel;
    const GaussNewtonSummary summary = GaussNewtonMinimizer(options).minimize(problem);
    EXPECT_EQ(summary.stop, GaussNewtonStop::cancelled);
    EXPECT_EQ(summary.iterations, 0);
    EXPECT_EQ(summary.final_cost, summary.initial_cost);
  }
  {  // the problem's own budget
    DenseProblem problem(rosenbrock_residuals, start, lower, upper);
    problem.set_budget(3);
    const GaussNewtonSummary summary = GaussNewtonMinimizer(GaussNewtonOptions{}).minimize(problem);
    EXPECT_EQ(summary.stop, GaussNewtonStop::stopped);
    EXPECT_EQ(problem.evaluations(), 3);
    EXPECT_LE(summary.final_cost, summary.initial_cost);
  }
  {  // a loose cost tolerance
    DenseProblem problem(rosenbrock_residuals, start, lower, upper);
    GaussNewtonOptions options;
    options.function_tolerance = 0.5;
    const GaussNewtonSummary summary = GaussNewtonMinimizer(options).minimize(problem);
    EXPECT_EQ(summary.stop, GaussNewtonStop::converged_cost);
    EXPECT_NE(summary.message.find("0.5"), std::string::npos) << summary.message;
  }
  {  // a minimum that is not exact and no tolerance: only rounding ends it
    DenseProblem problem(
        [](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd& j) {
          r.resize(2);
          r << x[0] * x[0] - 1.0, x[0] * x[0] + 1.0;  // F = 2x⁴ + 2: minimum 2 at x = 0
          j.resize(2, 1);
          j << 2.0 * x[0], 2.0 * x[0];
        },
        Eigen::VectorXd::Constant(1, 1.0), unbounded(1, -1), unbounded(1, 1));
    GaussNewtonOptions options;
    options.gradient_tolerance = 0.0;
    options.function_tolerance = 0.0;
    options.step_tolerance = 0.0;
    const GaussNewtonSummary summary = GaussNewtonMinimizer(options).minimize(problem);
    EXPECT_TRUE(converged(summary.stop)) << to_string(summary.stop);
    EXPECT_NEAR(summary.final_cost, 2.0, 1e-12);
  }
}

TEST(GaussNewtonMinimizer, DampingFollowsNielsensRule) {
  // Records λ after every step: a refusal multiplies it by ν = 2, 4, 8, …; an acceptance divides it
  // by at most 3 and resets ν.
  class Recording final : public GaussNewtonProblem {
   public:
    std::vector<std::pair<bool, double>> steps;
    double value = 4.0;
    int refusals_left = 3;
    double cost() const override { return value; }
    bool linearise(GaussNewtonModel& model) override {
      model.gradient = Eigen::VectorXd::Constant(1, -2.0);
      model.curvature_diagonal = Eigen::VectorXd::Constant(1, 1.0);
      model.free = {0};
      return true;
    }
    bool solve(double, Eigen::VectorXd& step) override {
      step = Eigen::VectorXd::Constant(1, 1.0);
      return true;
    }
    double candidate(const Eigen::VectorXd&) override { return 1.0; }
    Evaluation evaluate_candidate(double& cost) override {
      cost = refusals_left-- > 0 ? value : value - 1.0;  // three refusals, then exactly as predicted (ρ = 1)
      return Evaluation::ok;
    }
    double accept() override {
      value -= 1.0;
      return 1.0;
    }
    void on_step(bool accepted, double damping) override { steps.emplace_back(accepted, damping); }
  } problem;
  GaussNewtonOptions options;
  options.initial_damping = 1.0;
  options.max_iterations = 5;
  GaussNewtonMinimizer(options).minimize(problem);
  ASSERT_EQ(problem.steps.size(), 5u);
  EXPECT_EQ(problem.steps[0].second, 2.0);
  EXPECT_EQ(problem.steps[1].second, 8.0);
  EXPECT_EQ(problem.steps[2].second, 64.0);
  EXPECT_TRUE(problem.steps[3].first);
  EXPECT_DOUBLE_EQ(problem.steps[3].second, 64.0 / 3.0);  // ρ = 1: max(1/3, 1 − 1) = 1/3
  EXPECT_DOUBLE_EQ(problem.steps[4].second, 64.0 / 9.0);
}

TEST(GaussNewtonMinimizer, HeldOnBoundIsTheKktTest) {
  EXPECT_TRUE(held_on_bound(0.0, 0.0, 1.0, 1.0));    // on the lower bound, pushed down
  EXPECT_FALSE(held_on_bound(0.0, 0.0, 1.0, -1.0));  // on the lower bound, pulled inside
  EXPECT_TRUE(held_on_bound(1.0, 0.0, 1.0, -1.0));   // on the upper bound, pushed up
  EXPECT_FALSE(held_on_bound(0.5, 0.0, 1.0, 1.0));   // inside
}

}  // namespace
}  // namespace manipid::detail
