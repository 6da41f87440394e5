// resample_test.cpp — logged data made uniform: stale repeats, jittery steps, gaps and trimming
// (resample.h), against signals whose values at any time are known.
#include "manipid/core/signal/resample.h"

#include "manipid/core/errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace manipid {
namespace {

/// Two joints sampled at the given times: a quadratic and a sine; tau and qd alike.
Trajectory sampled(const Eigen::VectorXd& t) {
  Trajectory data;
  data.t = t;
  data.q.resize(t.size(), 2);
  data.tau.resize(t.size(), 2);
  data.qd.resize(t.size(), 2);
  for (Eigen::Index i = 0; i < t.size(); ++i) {
    const double x = t[i];
    data.q.row(i) << 0.3 + 0.5 * x - 0.2 * x * x, std::sin(2.0 * x);
    data.qd.row(i) << 0.5 - 0.4 * x, 2.0 * std::cos(2.0 * x);
    data.tau.row(i) << 1.0 + 2.0 * x * x, -3.0 * std::sin(2.0 * x);
  }
  return data;
}

/// Times around a 1 ms median with steps from 0.7 to ~2 ms, like the Panda's logger.
Eigen::VectorXd jittery_times(int count, std::mt19937_64& engine) {
  std::uniform_real_distribution<double> step(0.7e-3, 1.3e-3);
  Eigen::VectorXd t(count);
  t[0] = 0.0;
  for (int i = 1; i < count; ++i) t[i] = t[i - 1] + (i % 97 == 0 ? 2.0e-3 : step(engine));
  return t;
}

TEST(MakeUniform, UniformDataPassesThroughUnchanged) {
  const Trajectory data = sampled(Eigen::VectorXd::LinSpaced(501, 0.0, 0.5));
  TimingReport report;
  const Trajectory same = make_uniform(data, {}, &report);
  EXPECT_FALSE(report.resampled);
  EXPECT_EQ(report.warning(), "");
  EXPECT_EQ(same.t, data.t);
  EXPECT_EQ(same.q, data.q);
  EXPECT_NEAR(report.dt, 1e-3, 1e-15);
}

TEST(MakeUniform, UniformDataOntoAnotherPeriodSaysSoWithoutCallingItJittery) {
  const Trajectory data = sampled(Eigen::VectorXd::LinSpaced(501, 0.0, 0.5));
  TimingReport report;
  UniformOptions options;
  options.dt = 1.25e-3;
  const Trajectory coarser = make_uniform(data, options, &report);
  ASSERT_TRUE(report.resampled);
  EXPECT_EQ(coarser.samples(), 401);
  EXPECT_EQ(report.warning(),
            "resampled from its uniform 1 ms steps onto a 1.25 ms grid by cubic interpolation, 401 samples");
}

TEST(MakeUniform, JitteryQuadraticsAreInterpolatedExactly) {
  // Cubic Hermite with three-point slopes reproduces a quadratic on any spacing.
  std::mt19937_64 engine(7);
  const Trajectory data = sampled(jittery_times(2000, engine));
  TimingReport report;
  const Trajectory uniform = make_uniform(data, {}, &report);
  ASSERT_TRUE(report.resampled);
  EXPECT_NEAR(report.dt, data.median_step(), 1e-15);
  EXPECT_EQ(report.repeats_dropped, 0);
  EXPECT_EQ(report.samples_out, uniform.samples());
  const Trajectory truth = sampled(uniform.t);
  EXPECT_LT((uniform.q.col(0) - truth.q.col(0)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((uniform.tau.col(0) - truth.tau.col(0)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((uniform.qd.col(0) - truth.qd.col(0)).cwiseAbs().maxCoeff(), 1e-12);
  // A sine: third-order accurate, (ω h)³ / 24 ≈ 3e-10 for ω = 2 rad/s, h ≤ 2 ms.
  EXPECT_LT((uniform.q.col(1) - truth.q.col(1)).cwiseAbs().maxCoeff(), 1e-9);
  // The grid: uniform, from the first time stamp, never beyond the last.
  EXPECT_EQ(uniform.t[0], data.t[0]);
  EXPECT_LE(uniform.t[uniform.t.size() - 1], data.t[data.t.size() - 1]);
  EXPECT_TRUE(uniform.is_uniform());
}

TEST(MakeUniform, StaleRepeatsAreDroppedAndTheirTimesIgnored) {
  // Every 10th row repeats the previous row's values under a new time stamp: kept, it would
  // put those values 1 ms late.
  std::mt19937_64 engine(3);
  const Eigen::VectorXd times = jittery_times(1000, engine);
  Trajectory logged = sampled(times);
  int repeats = 0;
  for (Eigen::Index i = 10; i < logged.t.size(); i += 10, ++repeats) {
    logged.q.row(i) = logged.q.row(i - 1);
    logged.tau.row(i) = logged.tau.row(i - 1);
    logged.qd.row(i) = logged.qd.row(i - 1);
  }
  TimingReport report;
  const Trajectory uniform = make_uniform(logged, {}, &report);
  EXPECT_EQ(report.repeats_dropped, repeats);
  const Trajectory truth = sampled(uniform.t);
  EXPECT_LT((uniform.q.col(0) - truth.q.col(0)).cwiseAbs().maxCoeff(), 1e-12);
  const std::string warning = report.warning();
  EXPECT_NE(warning.find("time steps are not uniform (0.7"), std::string::npos) << warning;
  EXPECT_NE(warning.find(std::to_string(repeats) + " repeated rows dropped"), std::string::npos) << warning;
  EXPECT_NE(warning.find("resampled onto a uniform 1"), std::string::npos) << warning;
}

TEST(MakeUniform, AGapTooLongToBridgeIsAnErrorSayingWhere) {
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(400, 0.0, 0.399);
  t.tail(200).array() += 0.3;  // 300 ms missing after sample 200
  t[3] += 1e-4;                // and not uniform
  try {
    make_uniform(sampled(t));
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "t");
    const std::string message = error.what();
    EXPECT_NE(message.find("a gap of 0.301 s"), std::string::npos) << message;
    EXPECT_NE(message.find("(sample 200) and t = 0.5 s (sample 201)"), std::string::npos) << message;
  }
  UniformOptions wide;
  wide.max_gap_steps = 400;
  EXPECT_NO_THROW(make_uniform(sampled(t), wide));
}

TEST(MakeUniform, AGivenPeriodIsUsedAndCheckedAndBadOptionsAreRefused) {
  std::mt19937_64 engine(5);
  const Trajectory data = sampled(jittery_times(1000, engine));
  UniformOptions options;
  options.dt = 2e-3;
  TimingReport report;
  const Trajectory coarse = make_uniform(data, options, &report);
  EXPECT_EQ(report.dt, 2e-3);
  EXPECT_NEAR(coarse.t[1] - coarse.t[0], 2e-3, 1e-15);
  options.dt = 1e-9;
  EXPECT_THROW(make_uniform(data, options), InputError);
  options.dt = -1;
  EXPECT_THROW(make_uniform(data, options), InputError);
}

TEST(Trim, DropsTheStartAndTheEnd) {
  const Trajectory data = sampled(Eigen::VectorXd::LinSpaced(1001, 0.0, 1.0));
  const Trajectory trimmed = trim(data, 0.2, 0.3);
  EXPECT_NEAR(trimmed.t[0], 0.2, 1e-12);
  EXPECT_NEAR(trimmed.t[trimmed.t.size() - 1], 0.7, 1e-12);
  EXPECT_EQ(trimmed.samples(), 501);
  EXPECT_EQ(trimmed.qd.rows(), 501);
  EXPECT_EQ(trimmed.q.row(0), data.q.row(200));
  EXPECT_THROW(trim(data, 0.6, 0.6), InputError);
  EXPECT_THROW(trim(data, -1.0, 0.0), InputError);
  EXPECT_THROW(trim(data, NAN, 0.0), InputError);
}

TEST(PrepareData, TrimsThenResamplesAndSaysSo) {
  std::mt19937_64 engine(11);
  const Trajectory data = sampled(jittery_times(3000, engine));
  DataPreparation options;
  options.trim_start = 0.5;
  options.trim_end = 0.5;
  std::vector<std::string> warnings;
  const Trajectory prepared = prepare_data(data, options, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_GE(prepared.t[0], 0.5);
  EXPECT_LE(prepared.t[prepared.t.size() - 1], data.t[data.t.size() - 1] - 0.5);
  EXPECT_TRUE(prepared.is_uniform());
}

}  // namespace
}  // namespace manipid
