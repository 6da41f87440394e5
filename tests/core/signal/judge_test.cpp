// judge_test.cpp — the neutral judge: figures of known errors, the trimmed span, the states it predicts from.
#include "manipid/core/signal/judge.h"

#include "manipid/core/errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace manipid {
namespace {

Eigen::VectorXd times(int samples, double dt) { return Eigen::VectorXd::LinSpaced(samples, 0.0, (samples - 1) * dt); }

TEST(Judge, AScaledPredictionIsOffByItsScale) {
  const Eigen::VectorXd t = times(5000, 1e-3);
  Eigen::MatrixXd measured(5000, 2);
  for (int i = 0; i < 5000; ++i) measured.row(i) << std::sin(2.0 * t[i]), 3.0 * std::cos(t[i]);
  const JudgeOptions options;
  const TorqueScore same = judge_torque(t, measured, measured, {}, options);
  EXPECT_EQ(same.overall_relative_error, 0.0);
  // The low-pass is linear: 1.1 × the measurement is off by 10 % on every joint and overall.
  Eigen::MatrixXd scaled = measured;
  scaled.col(0) *= 1.1;
  scaled.col(1) *= 1.1;
  const TorqueScore off = judge_torque(t, measured, scaled, {}, options);
  // (To the low-pass's rounding, ~1e-11.)
  EXPECT_NEAR(off.overall_relative_error, 0.1, 1e-9);
  EXPECT_NEAR(off.relative_error[0], 0.1, 1e-9);
  EXPECT_NEAR(off.rms_error[1], 0.1 * std::sqrt(off.measured.col(1).squaredNorm() / off.measured.rows()), 1e-9);
  // Judged over joint 2 only.
  scaled.col(1) = measured.col(1);
  const TorqueScore second = judge_torque(t, measured, scaled, {1}, options);
  EXPECT_EQ(second.overall_relative_error, 0.0);
  EXPECT_EQ(second.measured.cols(), 1);
}

TEST(Judge, TrimsItsSecondsAtEachEnd) {
  const Eigen::VectorXd t = times(1001, 1e-3);  // 0 .. 1 s
  JudgeOptions options;
  options.trim_seconds = 0.25;
  const JudgedSpan span = judged_span(t, options);
  EXPECT_EQ(span.first, 250);
  EXPECT_EQ(span.last, 750);
  const TorqueScore score = judge_torque(t, Eigen::MatrixXd::Ones(1001, 1), Eigen::MatrixXd::Ones(1001, 1), {}, options);
  EXPECT_EQ(score.t.size(), 501);
  EXPECT_DOUBLE_EQ(score.t[0], 0.25);
}

TEST(Judge, StatesOfAQuadraticHaveItsSecondDerivative) {
  // A zero-phase low-pass with unit DC gain keeps a line and moves a parabola by a constant: q̈ stays 2a, q̇
  // is 2a t + b, away from the ends (to the low-pass's rounding, 1e-11 of q, divided by Δ² = 1e-6 in q̈).
  Trajectory data;
  // (The odd extension at each end bends a parabola: its transient lasts about 2 s at 5 Hz.)
  data.t = times(8001, 1e-3);
  data.q.resize(8001, 1);
  for (int i = 0; i < 8001; ++i) data.q(i, 0) = 0.7 * data.t[i] * data.t[i] - 0.2 * data.t[i];
  const JudgedStates states = judge_states(data, JudgeOptions{});
  for (int i = 3000; i <= 5000; i += 250) {
    EXPECT_NEAR(states.qdd(i, 0), 1.4, 1e-4) << i;
    EXPECT_NEAR(states.qd(i, 0), 1.4 * data.t[i] - 0.2, 1e-6) << i;
  }
}

TEST(Judge, RefusesACutOffAboveNyquistAndATrimLongerThanTheRun) {
  const auto field_of = [](const JudgeOptions& options, double dt, double duration) -> std::string {
    try {
      options.validate(dt, duration);
    } catch (const InputError& error) {
      return error.field();
    }
    return "no error";
  };
  JudgeOptions options;
  EXPECT_EQ(field_of(options, 1e-3, 10.0), "no error");
  EXPECT_EQ(field_of(options, 0.1, 10.0), "judge_cutoff");  // Nyquist 5 Hz
  options.trim_seconds = 6.0;
  EXPECT_EQ(field_of(options, 1e-3, 10.0), "judge_trim");
}

}  // namespace
}  // namespace manipid
