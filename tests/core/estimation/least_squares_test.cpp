// least_squares_test.cpp — Levenberg–Marquardt, the "LM" minimiser (estimation/least_squares.h, internal to
// core): Rosenbrock's valley, bounds that hold, fixed parameters that stay, budgets and cancel as stops.
#include "estimation/least_squares.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

namespace manipid::detail {
namespace {

/// Rosenbrock as residuals, r = (10 (θ2 − θ1²), 1 − θ1): the minimum 0 at (1, 1) along a curved valley.
LeastSquaresFunction rosenbrock() {
  LeastSquaresFunction function;
  function.residual = [](const Eigen::VectorXd& theta, Eigen::VectorXd& residual, Eigen::MatrixXd* jacobian) {
    residual.resize(2);
    residual << 10.0 * (theta[1] - theta[0] * theta[0]), 1.0 - theta[0];
    if (jacobian) {
      jacobian->resize(2, 2);
      *jacobian << -20.0 * theta[0], 10.0, -1.0, 0.0;
    }
  };
  return function;
}

MinimizeSettings settings_for(int parameters) {
  MinimizeSettings settings;
  settings.algorithm = kLeastSquaresAlgorithm;
  settings.free.assign(static_cast<std::size_t>(parameters), true);
  settings.lower = Eigen::VectorXd::Constant(parameters, -10.0);
  settings.upper = Eigen::VectorXd::Constant(parameters, 10.0);
  return settings;
}

TEST(LevenbergMarquardt, FollowsRosenbrocksValleyToItsMinimum) {
  Eigen::VectorXd start(2);
  start << -1.2, 1.0;
  const MinimizeOutcome outcome = minimize_least_squares(rosenbrock(), start, settings_for(2));
  EXPECT_NEAR(outcome.theta[0], 1.0, 1e-8);
  EXPECT_NEAR(outcome.theta[1], 1.0, 1e-8);
  EXPECT_LT(outcome.cost, 1e-16);
  EXPECT_NEAR(outcome.initial_cost, 24.2, 1e-12);  // (10·(1 − 1.44))² + 2.2²
  EXPECT_EQ(outcome.stop_reason.rfind("converged", 0), 0u) << outcome.stop_reason;
  EXPECT_LT(outcome.evaluations, 200);
}

TEST(LevenbergMarquardt, ABoundHoldsAndTheMinimumOnItIsFound) {
  // θ1 ≤ 0.5: the minimum along the bound is at θ1 = 0.5, θ2 = 0.25.
  MinimizeSettings settings = settings_for(2);
  settings.upper[0] = 0.5;
  Eigen::VectorXd start(2);
  start << -1.2, 1.0;
  const MinimizeOutcome outcome = minimize_least_squares(rosenbrock(), start, settings);
  EXPECT_LE(outcome.theta[0], 0.5);
  EXPECT_NEAR(outcome.theta[0], 0.5, 1e-8);
  EXPECT_NEAR(outcome.theta[1], 0.25, 1e-8);
}

TEST(LevenbergMarquardt, AFixedParameterStaysAtItsStart) {
  MinimizeSettings settings = settings_for(2);
  settings.free[1] = false;
  Eigen::VectorXd start(2);
  start << 3.0, 4.0;
  const MinimizeOutcome outcome = minimize_least_squares(rosenbrock(), start, settings);
  EXPECT_EQ(outcome.theta[1], 4.0);
  // With θ2 = 4: minimise 100 (4 − θ1²)² + (1 − θ1)², near θ1 = 2.
  EXPECT_NEAR(outcome.theta[0], 2.0, 1e-2);
}

TEST(LevenbergMarquardt, BudgetsAndCancelStopIt) {
  Eigen::VectorXd start(2);
  start << -1.2, 1.0;
  MinimizeSettings settings = settings_for(2);
  settings.max_evaluations = 3;
  const MinimizeOutcome budget = minimize_least_squares(rosenbrock(), start, settings);
  EXPECT_EQ(budget.stop_reason, "maxeval_reached");
  EXPECT_LE(budget.evaluations, 3);
  EXPECT_LE(budget.cost, budget.initial_cost);  // the best point so far
  std::atomic<bool> cancel{true};
  settings = settings_for(2);
  settings.cancel = &cancel;
  const MinimizeOutcome cancelled = minimize_least_squares(rosenbrock(), start, settings);
  EXPECT_TRUE(cancelled.cancelled);
  EXPECT_EQ(cancelled.stop_reason, "cancelled");
}

}  // namespace
}  // namespace manipid::detail
