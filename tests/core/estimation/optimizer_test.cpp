// optimizer_test.cpp — the NLopt adapter behind minimize() (estimation/optimizer.h, internal to core): analytic minima, bounds, fixed parameters, stop reasons, cancel and stop.
#include "estimation/optimizer.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>

namespace manipid::detail {
namespace {

/// F(θ) = Σ w_i (θ_i − c_i)², c = (1, −2, 3), w = (1, 10, 100): the minimum 0 at c.
double quadratic(const Eigen::VectorXd& theta, Eigen::VectorXd* gradient) {
  const Eigen::Vector3d centre(1.0, -2.0, 3.0), weight(1.0, 10.0, 100.0);
  const Eigen::VectorXd difference = theta - centre;
  if (gradient) *gradient = 2.0 * weight.cwiseProduct(difference);
  return difference.cwiseAbs2().dot(weight);
}

MinimizeSettings nlopt_settings(const std::string& algorithm) {
  MinimizeSettings settings;
  settings.algorithm = algorithm;
  settings.free.assign(3, true);
  settings.lower = Eigen::VectorXd::Constant(3, -10.0);
  settings.upper = Eigen::VectorXd::Constant(3, 10.0);
  settings.relative_x_tolerance = 1e-12;
  settings.relative_f_tolerance = 0.0;
  settings.max_seconds = 30.0;
  return settings;
}

const Eigen::Vector3d kStart(0.5, -1.0, 2.0);

TEST(NloptAdapter, FindsTheQuadraticsMinimumWithAndWithoutGradients) {
  for (const char* algorithm : {"LN_BOBYQA", "LN_SBPLX", "LD_LBFGS", "LD_SLSQP"}) {
    const MinimizeOutcome outcome = minimize(quadratic, kStart, nlopt_settings(algorithm));
    EXPECT_NEAR(outcome.theta[0], 1.0, 1e-5) << algorithm;
    EXPECT_NEAR(outcome.theta[1], -2.0, 1e-5) << algorithm;
    EXPECT_NEAR(outcome.theta[2], 3.0, 1e-5) << algorithm;
    EXPECT_LT(outcome.cost, 1e-8) << algorithm;
    EXPECT_DOUBLE_EQ(outcome.initial_cost, quadratic(kStart, nullptr)) << algorithm;
    EXPECT_GT(outcome.evaluations, 0) << algorithm;
    EXPECT_FALSE(outcome.cancelled) << algorithm;
    EXPECT_FALSE(outcome.failure) << algorithm;
    EXPECT_TRUE(outcome.stop_reason == "xtol_reached" || outcome.stop_reason == "ftol_reached" ||
                outcome.stop_reason == "success" || outcome.stop_reason == "roundoff_limited")
        << algorithm << ": " << outcome.stop_reason;
  }
}

TEST(NloptAdapter, BoundsHoldAtEveryEvaluationAndTheMinimumOnThemIsFound) {
  for (const char* algorithm : {"LN_BOBYQA", "LD_LBFGS"}) {
    MinimizeSettings settings = nlopt_settings(algorithm);
    settings.upper[2] = 2.5;  // the unconstrained minimum θ3 = 3 lies outside
    bool inside = true;
    EvaluationLog log(100, [&](long, double, const Eigen::VectorXd& theta) {
      inside = inside && (theta.array() >= settings.lower.array()).all() && (theta.array() <= settings.upper.array()).all();
    });
    settings.log = &log;
    const MinimizeOutcome outcome = minimize(quadratic, kStart, settings);
    EXPECT_TRUE(inside) << algorithm;
    EXPECT_EQ(log.count(), outcome.evaluations) << algorithm;
    EXPECT_NEAR(outcome.theta[2], 2.5, 1e-6) << algorithm;
    EXPECT_NEAR(outcome.theta[0], 1.0, 1e-5) << algorithm;
    EXPECT_NEAR(outcome.cost, 100.0 * 0.25, 1e-5) << algorithm;
  }
}

TEST(NloptAdapter, AFixedParameterStaysAtItsStart) {
  MinimizeSettings settings = nlopt_settings("LN_BOBYQA");
  settings.free[1] = false;
  const MinimizeOutcome outcome = minimize(quadratic, kStart, settings);
  EXPECT_EQ(outcome.theta[1], kStart[1]);
  EXPECT_NEAR(outcome.theta[0], 1.0, 1e-5);
  EXPECT_NEAR(outcome.theta[2], 3.0, 1e-5);

  settings.free.assign(3, false);
  const MinimizeOutcome none = minimize(quadratic, kStart, settings);
  EXPECT_EQ(none.stop_reason, "no_free_parameters");
  EXPECT_EQ(none.theta, Eigen::VectorXd(kStart));
}

TEST(NloptAdapter, SaysWhyItStopped) {
  MinimizeSettings budget = nlopt_settings("LN_BOBYQA");
  budget.max_evaluations = 5;
  const MinimizeOutcome out_of_budget = minimize(quadratic, kStart, budget);
  EXPECT_EQ(out_of_budget.stop_reason, "maxeval_reached");
  EXPECT_EQ(out_of_budget.evaluations, 5);
  EXPECT_LE(out_of_budget.cost, out_of_budget.initial_cost);  // the best point so far

  const CostFunction overflowing = [](const Eigen::VectorXd&, Eigen::VectorXd*) {
    return std::numeric_limits<double>::infinity();
  };
  EXPECT_EQ(minimize(overflowing, kStart, nlopt_settings("LN_BOBYQA")).stop_reason, "non_finite_start");

  EXPECT_THROW(minimize(quadratic, kStart, nlopt_settings("LN_NO_SUCH_ALGORITHM")), InputError);
  EXPECT_THROW(minimize(quadratic, kStart, nlopt_settings(kLeastSquaresAlgorithm)), InputError);  // no residuals given
  EXPECT_TRUE(algorithm_uses_gradient("LD_LBFGS"));
  EXPECT_FALSE(algorithm_uses_gradient("LN_BOBYQA"));
  EXPECT_TRUE(algorithm_uses_gradient(kLeastSquaresAlgorithm));
}

TEST(NloptAdapter, CancelAndStopEndTheRunWithTheBestPointSoFar) {
  std::atomic<bool> cancel{false};
  long evaluations = 0;
  const CostFunction counting = [&](const Eigen::VectorXd& theta, Eigen::VectorXd* gradient) {
    if (++evaluations == 10) cancel = true;
    return quadratic(theta, gradient);
  };
  MinimizeSettings settings = nlopt_settings("LN_BOBYQA");
  settings.cancel = &cancel;
  const MinimizeOutcome cancelled = minimize(counting, kStart, settings);
  EXPECT_TRUE(cancelled.cancelled);
  EXPECT_EQ(cancelled.stop_reason, "cancelled");
  EXPECT_EQ(cancelled.evaluations, 10);  // the eleventh was refused
  EXPECT_LE(cancelled.cost, cancelled.initial_cost);
  EXPECT_EQ(quadratic(cancelled.theta, nullptr), cancelled.cost);

  int asked = 0;
  MinimizeSettings stopping = nlopt_settings("LD_LBFGS");
  stopping.stop = [&] { return ++asked > 3; };
  const MinimizeOutcome stopped = minimize(quadratic, kStart, stopping);
  EXPECT_TRUE(stopped.stopped);
  EXPECT_FALSE(stopped.cancelled);
  EXPECT_EQ(stopped.stop_reason, "stopped");
  EXPECT_EQ(stopped.evaluations, 3);
}

TEST(NloptAdapter, ScalesByTheStartUnlessTold) {
  // A first step of 1 % of each scaled parameter: with scale_by_start the first move of θ3 is
  // about 1 % of |θ3| = 2; without it about 1 % of 1.
  for (const bool scaled : {true, false}) {
    MinimizeSettings settings = nlopt_settings("LN_BOBYQA");
    settings.scale_by_start = scaled;
    settings.max_evaluations = 7;  // the 2n + 1 points of its first model
    double largest_move = 0.0;
    EvaluationLog log(100, [&](long, double, const Eigen::VectorXd& theta) {
      largest_move = std::max(largest_move, std::abs(theta[2] - kStart[2]));
    });
    settings.log = &log;
    minimize(quadratic, kStart, settings);
    EXPECT_NEAR(largest_move, scaled ? 0.02 : 0.01, 1e-12) << scaled;
  }
}

}  // namespace
}  // namespace manipid::detail
