// butterworth_test.cpp — the Butterworth design and zero-phase filtering against scipy.signal's butter() and
// filtfilt() (reference values printed by scipy 1.10), and their invariants.
#include "manipid/core/signal/butterworth.h"

#include "../input_error_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace manipid {
namespace {

void expect_relatively_near(const std::vector<double>& actual, const std::vector<double>& expected, double tolerance) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i) {
    EXPECT_NEAR(actual[i], expected[i], tolerance * std::abs(expected[i])) << "coefficient " << i;
  }
}

TEST(Butterworth, CoefficientsAreScipys) {
  // butter(4, 20, fs=1000) and butter(2, 100, fs=1000).
  const IirFilter fourth = butterworth_lowpass(4, 20.0, 1e-3);
  expect_relatively_near(fourth.b, {1.32937288987529e-05, 5.31749155950116e-05, 7.97623733925174e-05, 5.31749155950116e-05,
                                    1.32937288987529e-05},
                         1e-12);
  expect_relatively_near(fourth.a, {1.0, -3.671729089161935, 5.067998386734189, -3.1159669252017452, 0.7199103272918712}, 1e-12);
  const IirFilter second = butterworth_lowpass(2, 100.0, 1e-3);
  expect_relatively_near(second.b, {0.06745527388907192, 0.13491054777814385, 0.06745527388907192}, 1e-12);
  expect_relatively_near(second.a, {1.0, -1.1429805025399011, 0.41280159809618877}, 1e-12);
}

TEST(Butterworth, FiltfiltIsScipys) {
  // filtfilt(b, a, x) with scipy's defaults (odd padding of 15 samples, steady-state start). The transfer
  // function form (b, a) carries ~1e-11 of rounding at these cut-offs, as scipy's does.
  Eigen::VectorXd x(300);
  for (int i = 0; i < 300; ++i) x[i] = std::sin(0.05 * i) + 0.3 * std::cos(0.31 * i) + 0.01 * i;
  Eigen::VectorXd y(300);
  filtfilt(butterworth_lowpass(4, 20.0, 1e-3), x, y);
  EXPECT_NEAR(y[0], 0.2866893067135826, 1e-10);
  EXPECT_NEAR(y[1], 0.3152385670296421, 1e-10);
  EXPECT_NEAR(y[50], 1.111486176767106, 1e-10);
  EXPECT_NEAR(y[150], 2.437387044213277, 1e-10);
  EXPECT_NEAR(y[298], 3.818117289349116, 1e-10);
  EXPECT_NEAR(y[299], 3.8173292984095153, 1e-10);
}

TEST(Butterworth, ColumnsAtOnceAreTheSameAsOneByOne) {
  const IirFilter filter = butterworth_lowpass(4, 7.0, 2e-3);
  Eigen::MatrixXd x(500, 3);
  for (int i = 0; i < 500; ++i) x.row(i) << std::sin(0.02 * i), std::cos(0.3 * i) * i, i % 7 == 0 ? 1.0 : 0.0;
  const Eigen::MatrixXd together = filtfilt_columns(filter, x);
  for (int c = 0; c < 3; ++c) {
    Eigen::VectorXd alone(500);
    filtfilt(filter, x.col(c), alone);
    EXPECT_EQ(together.col(c), alone) << "column " << c;  // bit for bit: the same operations
  }
}

TEST(Butterworth, ZeroPhaseUnitDcAndHalfPowerAtTheCutOff) {
  const double dt = 1e-3, cutoff = 10.0;
  const IirFilter filter = butterworth_lowpass(4, cutoff, dt);
  const int N = 20000;
  Eigen::VectorXd constant = Eigen::VectorXd::Constant(N, 3.5), out(N);
  filtfilt(filter, constant, out);
  EXPECT_LT((out.array() - 3.5).abs().maxCoeff(), 1e-9);  // the (b, a) form's rounding at f_c = f_s / 100
  // A sinusoid in the passband comes out without delay; one at the cut-off with |H|² = 1/2 (the two passes).
  for (const auto& [frequency, gain] : {std::pair{1.0, 1.0 / (1.0 + std::pow(0.1, 8))}, {cutoff, 0.5}}) {
    Eigen::VectorXd x(N), expected(N);
    for (int i = 0; i < N; ++i) {
      x[i] = std::sin(2.0 * std::numbers::pi * frequency * i * dt);
      expected[i] = gain * x[i];
    }
    filtfilt(filter, x, out);
    EXPECT_LT((out - expected).segment(N / 4, N / 2).cwiseAbs().maxCoeff(), 1e-6) << frequency << " Hz";
  }
}

TEST(Butterworth, RefusesWhatItCannotDesign) {
  const auto field_of = [](auto&& call) { return testing::input_error_field(call); };
  EXPECT_EQ(field_of([] { butterworth_lowpass(4, 500.0, 1e-3); }), "cutoff_hz");  // at Nyquist
  EXPECT_EQ(field_of([] { butterworth_lowpass(4, 0.0, 1e-3); }), "cutoff_hz");
  EXPECT_EQ(field_of([] { butterworth_lowpass(4, 5.0, 0.0); }), "dt");
  EXPECT_EQ(field_of([] { butterworth_lowpass(9, 5.0, 1e-3); }), "order");
  Eigen::VectorXd short_signal = Eigen::VectorXd::Ones(15), out(15);
  EXPECT_EQ(field_of([&] { filtfilt(butterworth_lowpass(4, 5.0, 1e-3), short_signal, out); }), "samples");
}

}  // namespace
}  // namespace manipid
