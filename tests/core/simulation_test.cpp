// simulation_test.cpp — the paper's pre-filtered step reference, its interpolation, the
// closed-loop simulation (against a closed form and against the model's static balance),
// measurement noise, and the validation of trajectories and settings.
#include "manipid/core/signal/resample.h"
#include "manipid/core/paper/simulation.h"

#include "manipid/core/paper/dynamics.h"
#include "manipid/core/paper/presets.h"
#include "manipid/core/signal/trajectory.h"
#include "input_error_expectations.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace manipid {
namespace {

using test_support::expect_input_error;

Eigen::Index sample_at(double t, double dt) { return static_cast<Eigen::Index>(std::lround(t / dt)); }

// The controller's own output recorded in τ gives back the rate: τ = Kp(r − q) − Kd q̇.
Eigen::VectorXd rate_at(const Trajectory& trajectory, const PdController& controller, Eigen::Index i) {
  const Eigen::VectorXd error = trajectory.ref.row(i).transpose() - trajectory.q.row(i).transpose();
  return (controller.kp.cwiseProduct(error) - trajectory.tau.row(i).transpose()).cwiseQuotient(controller.kd);
}

Eigen::VectorXd gravity_torque(const Preset& preset, const Eigen::VectorXd& q) {
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(q.size());
  return inverse_dynamics(preset.model, preset.true_parameters, q, zero, zero);
}

// ---------------------------------------------------------------- step reference

TEST(StepReference, PaperReferenceHasTheFilteredStepsMovedEarlierByMSamples) {
  const StepReferenceSpec spec = cedro2009().reference;
  const SampledReference reference = make_step_reference(spec);
  ASSERT_EQ(reference.values.rows(), 9800);  // 10,001 raw samples − 2M − 1
  ASSERT_EQ(reference.joint_count(), 4);
  EXPECT_EQ(reference.t0, 0.0);
  EXPECT_EQ(reference.dt, 0.001);

  const int m = spec.half_length;
  for (int j = 0; j < 4; ++j) {
    const Eigen::VectorXd y = reference.values.col(j);
    const double amplitude = spec.amplitudes[j];
    // Output s is centred on raw sample s + M, the first with the step on (UnitStep(0) = 1).
    const Eigen::Index s = sample_at(spec.step_times[j], spec.dt) - m;
    // The 2M+1 taps see no step before s − M and all of it from s + M on.
    for (Eigen::Index i = 0; i < s - m; ++i) ASSERT_NEAR(y[i], 0.0, 1e-12) << "joint " << j + 1 << " i " << i;
    for (Eigen::Index i = s + m; i < y.size(); ++i) ASSERT_NEAR(y[i], amplitude, 1e-12) << "joint " << j + 1;
    // Every tap is positive (sinc's first zero π/Ωg ≈ 126 > M, Harris window ≥ 0): monotone.
    for (Eigen::Index i = 1; i < y.size(); ++i) ASSERT_GE(y[i], y[i - 1] - 1e-15) << "joint " << j + 1;
    // Half amplitude is crossed between samples s − 1 and s, i.e. at step_time − M·dt − dt/2 ...
    EXPECT_LT(y[s - 1], amplitude / 2);
    EXPECT_GT(y[s], amplitude / 2);
    // ... about which the symmetric filter makes the step odd-symmetric.
    for (int k = 0; k < m + 5; ++k) ASSERT_NEAR(y[s + k] + y[s - 1 - k], amplitude, 1e-12) << "k " << k;
  }
}

TEST(StepReference, RejectsBadSpecifications) {
  const StepReferenceSpec good = cedro2009().reference;
  auto with = [&](const std::function<void(StepReferenceSpec&)>& change) {
    StepReferenceSpec spec = good;
    change(spec);
    return [spec] { make_step_reference(spec); };
  };
  expect_input_error(with([](auto& s) {
                       s.step_times.clear();
                       s.amplitudes.clear();
                     }), "step_times");
  expect_input_error(with([](auto& s) { s.amplitudes.pop_back(); }), "amplitudes");
  expect_input_error(with([](auto& s) { s.step_times[2] = std::nan(""); }), "step_times");
  expect_input_error(with([](auto& s) { s.amplitudes[0] = INFINITY; }), "amplitudes");
  expect_input_error(with([](auto& s) { s.dt = 0.0; }), "dt");
  expect_input_error(with([](auto& s) { s.duration = -1.0; }), "duration");
  expect_input_error(with([](auto& s) { s.duration = 0.15; }), "duration");  // shorter than the filter
  expect_input_error(with([](auto& s) { s.half_length = 1; }), "half_length");
  expect_input_error(with([](auto& s) { s.band = 0.0; }), "band");
}

// ---------------------------------------------------------------- interpolation

SampledReference ramp_of(const std::function<double(double)>& f, double t0, double dt, int samples) {
  SampledReference reference;
  reference.t0 = t0;
  reference.dt = dt;
  reference.values.resize(samples, 1);
  for (int i = 0; i < samples; ++i) reference.values(i, 0) = f(t0 + i * dt);
  return reference;
}

TEST(SampledReference, ExactAtSamplesAndHeldOutside) {
  const SampledReference reference = ramp_of([](double t) { return std::sin(7 * t) + t * t; }, 0.25, 0.01, 50);
  for (int i = 0; i < 50; ++i) {
    EXPECT_NEAR(reference.evaluate(0.25 + i * 0.01)[0], reference.values(i, 0), 1e-14) << i;
  }
  EXPECT_EQ(reference.evaluate(-3.0)[0], reference.values(0, 0));
  EXPECT_EQ(reference.evaluate(0.25)[0], reference.values(0, 0));
  EXPECT_EQ(reference.evaluate(100.0)[0], reference.values(49, 0));
  // A single sample is a constant.
  SampledReference single = reference;
  single.values.conservativeResize(1, 1);
  EXPECT_EQ(single.evaluate(0.7)[0], reference.values(0, 0));
}

TEST(SampledReference, ReproducesQuadraticsInsideAndLinesEverywhere) {
  // Central differences give exact slopes for a quadratic, and a cubic Hermite with exact
  // slopes is exact for it; the one-sided end slopes are exact only for lines.
  auto quadratic = [](double t) { return 0.3 - 1.7 * t + 4.2 * t * t; };
  auto line = [](double t) { return -0.8 + 2.5 * t; };
  const double t0 = -0.1, dt = 0.02;
  const int samples = 40;
  const SampledReference q = ramp_of(quadratic, t0, dt, samples);
  const SampledReference l = ramp_of(line, t0, dt, samples);
  for (int k = 0; k <= 20 * (samples - 1); ++k) {
    const double t = t0 + k * dt / 20;
    EXPECT_NEAR(l.evaluate(t)[0], line(t), 1e-13) << t;
    const bool interior = t >= t0 + dt && t <= t0 + (samples - 2) * dt;
    if (interior) {
      EXPECT_NEAR(q.evaluate(t)[0], quadratic(t), 1e-13) << t;
    }
  }
  // Near the ends the quadratic is still close (error O(dt²·f'') from the one-sided slope).
  EXPECT_NEAR(q.evaluate(t0 + dt / 2)[0], quadratic(t0 + dt / 2), 4.2 * dt * dt);
}

TEST(SampledReference, IsContinuousWithCentralDifferenceSlopes) {
  const double dt = 0.01;
  const SampledReference reference = ramp_of([](double t) { return std::cos(9 * t) * std::exp(t); }, 0.0, dt, 60);
  const Eigen::VectorXd y = reference.values.col(0);
  const double epsilon = 1e-7 * dt;
  for (int k = 1; k < 59; ++k) {
    const double t = k * dt;
    const double value = reference.evaluate(t)[0];
    const double left = (value - reference.evaluate(t - epsilon)[0]) / epsilon;
    const double right = (reference.evaluate(t + epsilon)[0] - value) / epsilon;
    const double slope = (y[k + 1] - y[k - 1]) / (2 * dt);
    // Difference quotients over ε: truncation ε·|p''| ≈ 1e-7 and rounding 1e-16/ε ≈ 1e-7.
    EXPECT_NEAR(left, slope, 1e-5) << k;
    EXPECT_NEAR(right, slope, 1e-5) << k;
  }
}

TEST(SampledReference, ThrowsOnOutputOfTheWrongSize) {
  const SampledReference reference = ramp_of([](double t) { return t; }, 0.0, 0.1, 5);
  Eigen::VectorXd r(2);
  expect_input_error([&] { reference.evaluate(0.2, r); }, "reference");
}

// ---------------------------------------------------------------- closed loop: closed form

// One joint turning about the base z axis with gravity along z: no gravity torque, inertia
// I = m l² (1 + 1/12), so the PD loop to a constant reference is a damped oscillator.
struct Oscillator {
  RobotModel model;
  Parameters parameters{Eigen::VectorXd::Constant(1, 2.0), Eigen::VectorXd::Constant(1, 0.5)};
  PdController controller{Eigen::VectorXd::Constant(1, 100.0), Eigen::VectorXd::Constant(1, 3.0)};
  SampledReference reference;
  double target = 1.0;

  Oscillator() {
    model.joints = {JointDescription{.alpha = 0, .a = 0, .d = 0, .length_role = LengthRole::a}};
    model.gravity = Eigen::Vector3d(0, 0, -9.81);
    reference.values = Eigen::MatrixXd::Constant(2, 1, target);
  }
  double inertia() const { return 2.0 * 0.25 * (1.0 + 1.0 / 12.0); }
};

TEST(ClosedLoop, OneJointMatchesTheDampedOscillator) {
  const Oscillator oscillator;
  ASSERT_NEAR(mass_matrix(oscillator.model, oscillator.parameters, Eigen::VectorXd::Zero(1))(0, 0),
              oscillator.inertia(), 1e-14);
  for (const auto& [x0, v0] : {std::pair{0.0, 0.0}, std::pair{0.3, -1.0}}) {
    SimulationOptions options;
    options.duration = 3.0;
    if (x0 != 0.0 || v0 != 0.0) {
      options.q0 = Eigen::VectorXd::Constant(1, x0);
      options.qd0 = Eigen::VectorXd::Constant(1, v0);
    }
    SimulationSummary summary;
    const Trajectory trajectory = simulate_closed_loop(oscillator.model, oscillator.parameters, oscillator.controller,
                                                       oscillator.reference, options, &summary);
    ASSERT_EQ(trajectory.samples(), 3001);
    EXPECT_GT(summary.steps, 0);
    EXPECT_GT(summary.rhs_evaluations, 6 * summary.steps);
    const double kp = 100.0, kd = 3.0, inertia = oscillator.inertia();
    const double sigma = kd / (2 * inertia), omega0_squared = kp / inertia;
    const double omega = std::sqrt(omega0_squared - sigma * sigma);
    const double e0 = x0 - oscillator.target;  // error coordinate x = q − r
    double worst_q = 0.0, worst_tau = 0.0;
    for (Eigen::Index i = 0; i < trajectory.samples(); ++i) {
      const double t = trajectory.t[i];
      const double decay = std::exp(-sigma * t), c = std::cos(omega * t), s = std::sin(omega * t);
      const double e = decay * (e0 * c + (v0 + sigma * e0) / omega * s);
      const double v = decay * (v0 * c - (omega0_squared * e0 + sigma * v0) / omega * s);
      worst_q = std::max(worst_q, std::abs(trajectory.q(i, 0) - (oscillator.target + e)));
      worst_tau = std::max(worst_tau, std::abs(trajectory.tau(i, 0) - (-kp * e - kd * v)));
      ASSERT_EQ(trajectory.ref(i, 0), oscillator.target);
    }
    // rtol 1e-8 on a unit-size state; measured 4e-9 rad and 4e-7 N·m (the dense output's
    // 4th-order interpolant included), asserted with a 20× margin.
    EXPECT_LT(worst_q, 1e-7);
    EXPECT_LT(worst_tau, 1e-5);
  }
}

TEST(ClosedLoop, OutputTimesIncludeBothEnds) {
  const Oscillator oscillator;
  SimulationOptions options;
  options.duration = 0.05;
  options.dt = 0.01;
  const Trajectory trajectory =
      simulate_closed_loop(oscillator.model, oscillator.parameters, oscillator.controller, oscillator.reference, options);
  ASSERT_EQ(trajectory.samples(), 6);
  EXPECT_EQ(trajectory.t[0], 0.0);
  EXPECT_NEAR(trajectory.t[5], 0.05, 1e-15);
  EXPECT_EQ(trajectory.q(0, 0), 0.0);  // the initial state exactly
  EXPECT_NO_THROW(trajectory.validate());
}

TEST(ClosedLoop, DoesNotStepOverAShortReferencePulse) {
  // At rest with a zero reference the right-hand side is 0 and the adaptive steps grow
  // without bound; uncapped, they skipped this 20 ms pulse entirely (9 steps, q ≡ 0).
  // The cap of 10 reference samples per step makes the loop see it: the kick
  // Kp·1 rad·0.02 s on I = 0.54 kg·m² swings the joint by ≈ 0.2 rad.
  const Oscillator oscillator;
  SampledReference pulse;
  pulse.values = Eigen::MatrixXd::Zero(5001, 1);
  pulse.values.middleRows(3000, 20).setOnes();
  SimulationOptions options;
  options.duration = 5.0;
  const Trajectory trajectory =
      simulate_closed_loop(oscillator.model, oscillator.parameters, oscillator.controller, pulse, options);
  // The interpolant leaves 0 one sample before the pulse (the slope at sample 2999 is a
  // central difference), so the arm is at rest (to the dense output's interpolation error
  // near the pulse, far below the integrator's 1e-8 tolerance) only until t = 2.998 s.
  EXPECT_LT(trajectory.q.topRows(2999).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_GT(trajectory.q.cwiseAbs().maxCoeff(), 0.15);
}

TEST(ClosedLoop, ABlowUpIsARuntimeErrorNotAnInputError) {
  // A negative mass (a candidate an identification may try) makes the loop unstable
  // (growth ≈ e^{136 t}); the settings were valid, so this is not an InputError. It must
  // also fail fast (here within ≈ 0.1 s of simulated time), not grind the steps down.
  Oscillator oscillator;
  oscillator.parameters.mass[0] = -2.0;
  oscillator.controller.kp[0] = 1e4;
  SimulationOptions options;
  options.duration = 10.0;
  options.relative_tolerance = 1e-3;
  try {
    simulate_closed_loop(oscillator.model, oscillator.parameters, oscillator.controller, oscillator.reference, options);
    ADD_FAILURE() << "expected a failure";
  } catch (const InputError& error) {
    ADD_FAILURE() << "unexpected InputError: " << error.what();
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("diverged"), std::string::npos) << error.what();
  }
}

// ---------------------------------------------------------------- closed loop: the paper

class PaperScenario : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    preset_ = new Preset(cedro2009());
    reference_ = new SampledReference(make_step_reference(preset_->reference));
    trajectory_ = new Trajectory(simulate_closed_loop(preset_->model, preset_->true_parameters, preset_->controller,
                                                      *reference_, preset_->simulation, &summary_));
  }
  static void TearDownTestSuite() {
    delete trajectory_;
    delete reference_;
    delete preset_;
  }
  static Preset* preset_;
  static SampledReference* reference_;
  static Trajectory* trajectory_;
  static SimulationSummary summary_;
};
Preset* PaperScenario::preset_ = nullptr;
SampledReference* PaperScenario::reference_ = nullptr;
Trajectory* PaperScenario::trajectory_ = nullptr;
SimulationSummary PaperScenario::summary_;

TEST_F(PaperScenario, SimulatesTheFullHorizon) {
  const Trajectory& trajectory = *trajectory_;
  ASSERT_EQ(trajectory.samples(), 9701);
  ASSERT_EQ(trajectory.joint_count(), 4);
  EXPECT_NEAR(trajectory.t[9700], 9.7, 1e-12);
  EXPECT_NO_THROW(trajectory.validate());
  // At the sample times the reference is the filtered samples themselves.
  for (Eigen::Index i = 0; i < trajectory.samples(); i += 97) {
    for (int j = 0; j < 4; ++j) ASSERT_NEAR(trajectory.ref(i, j), reference_->values(i, j), 1e-15);
  }
  EXPECT_GT(summary_.steps, 100);
  EXPECT_GT(summary_.rhs_evaluations, 6 * summary_.steps);
  EXPECT_GT(summary_.wall_seconds, 0.0);
}

TEST_F(PaperScenario, ShouldStopEndsTheRunEarlyAndSaysSo) {
  // Asked once before the first step, then after every accepted step: true at the k-th ask
  // ends the run there, with SimulationStopped (not a normal end, not a numerical failure).
  constexpr long k = 50;
  SimulationOptions options = preset_->simulation;
  long asked = 0;
  options.should_stop = [&asked] { return ++asked >= k; };
  try {
    simulate_closed_loop(preset_->model, preset_->true_parameters, preset_->controller, *reference_, options);
    ADD_FAILURE() << "expected SimulationStopped";
  } catch (const SimulationStopped& stopped) {
    EXPECT_EQ(asked, k);
    EXPECT_EQ(stopped.steps(), k - 1);
    EXPECT_GT(stopped.time(), 0.0);
    EXPECT_LT(stopped.time(), 1.0);  // far from the 9.7 s horizon
    EXPECT_NE(std::string(stopped.what()).find("stopped"), std::string::npos) << stopped.what();
  }
  EXPECT_LT(k - 1, summary_.steps);  // the full run takes many more steps than that
}

TEST_F(PaperScenario, ShouldStopAtOnceTakesNoStepAndFalseChangesNothing) {
  SimulationOptions options = preset_->simulation;
  options.should_stop = [] { return true; };
  try {
    simulate_closed_loop(preset_->model, preset_->true_parameters, preset_->controller, *reference_, options);
    ADD_FAILURE() << "expected SimulationStopped";
  } catch (const SimulationStopped& stopped) {
    EXPECT_EQ(stopped.steps(), 0);
    EXPECT_EQ(stopped.time(), 0.0);
  }
  options.duration = 0.5;
  long asked = 0;
  options.should_stop = [&asked] { return ++asked < 0; };
  SimulationSummary summary;
  const Trajectory run =
      simulate_closed_loop(preset_->model, preset_->true_parameters, preset_->controller, *reference_, options, &summary);
  EXPECT_EQ(run.samples(), 501);
  EXPECT_EQ(asked, summary.steps + 1);
  for (Eigen::Index i = 0; i < run.samples(); i += 50) {
    for (int j = 0; j < 4; ++j) ASSERT_EQ(run.q(i, j), trajectory_->q(i, j));
  }
}

TEST_F(PaperScenario, GravityActsFromTheStartExceptOnTheVerticalAxis) {
  // Until t = 0.8 s every reference is exactly 0. Joint 1 turns about the gravity axis and
  // is decoupled from the others at rest, so it stays at 0; joints 2..4 sag under gravity.
  const Eigen::Index i = sample_at(0.79, 0.001);
  EXPECT_NEAR(trajectory_->q(i, 0), 0.0, 1e-12);
  for (int j = 1; j < 4; ++j) EXPECT_GT(trajectory_->q(i, j), 0.005) << "joint " << j + 1;
}

TEST_F(PaperScenario, JointOneSettlesOnItsReference) {
  // The gravity-free joint 1 (slowest mode ≈ e^{-2.4 t}) settles exactly on its reference.
  // Measured: |r − q| = 2.6e-6 rad, |q̇| = 1.2e-4 rad/s at 6.8 s; 1.1e-8 rad, 3.2e-8 rad/s
  // at 9.7 s. Asserted with a ≈ 4× margin.
  const Trajectory& trajectory = *trajectory_;
  struct Check {
    double t, angle, rate;
  };
  for (const Check& check : {Check{6.8, 1e-5, 5e-4}, Check{9.7, 5e-8, 1.5e-7}}) {
    const Eigen::Index i = sample_at(check.t, 0.001);
    EXPECT_NEAR(trajectory.q(i, 0), trajectory.ref(i, 0), check.angle) << "t " << check.t;
    EXPECT_NEAR(rate_at(trajectory, preset_->controller, i)[0], 0.0, check.rate) << "t " << check.t;
  }
}

TEST_F(PaperScenario, JointsTwoToFourOscillateAboutTheStaticBalance) {
  // With the paper's gains the slowest closed-loop mode (mostly joint 2) is barely damped,
  // ≈ e^{-0.87 t} at 3.5 Hz, so the arm still rings when the next step comes: at 4.8 s
  // joint 2 moves at ≈ 1 rad/s. Averaged over the last second (3.4 periods) the PD torque
  // balances gravity, Kp∘(r − q) ≈ g(q): measured mean residuals −0.91, −0.16, −0.012 N·m
  // against g = −371, −63, −0.53 N·m (0.25%, 0.25%, 2%); asserted as 1% of g + 0.05 N·m.
  const Trajectory& trajectory = *trajectory_;
  EXPECT_GT(std::abs(rate_at(trajectory, preset_->controller, sample_at(4.8, 0.001))[1]), 0.5);
  const Eigen::Index first = sample_at(8.7, 0.001), last = sample_at(9.7, 0.001);
  Eigen::VectorXd residual = Eigen::VectorXd::Zero(4), gravity = Eigen::VectorXd::Zero(4);
  for (Eigen::Index i = first; i <= last; ++i) {
    const Eigen::VectorXd q = trajectory.q.row(i).transpose();
    const Eigen::VectorXd g = gravity_torque(*preset_, q);
    residual += preset_->controller.kp.cwiseProduct(trajectory.ref.row(i).transpose() - q) - g;
    gravity += g;
  }
  residual /= double(last - first + 1);
  gravity /= double(last - first + 1);
  for (int j = 1; j < 4; ++j) {
    EXPECT_LT(std::abs(residual[j]), 0.01 * std::abs(gravity[j]) + 0.05) << "joint " << j + 1;
  }
}

TEST(ClosedLoop, WellDampedPaperRobotSettlesOnTheGravityOffset) {
  // The paper's robot and reference with each joint damped near critically
  // (Kd = 2·sqrt(Kp·M_jj) at the final pose): before each next step the arm is at rest
  // and PD without integral action holds it where Kp∘(r − q) = g(q), off the reference.
  Preset preset = cedro2009();
  const Eigen::MatrixXd mass = mass_matrix(preset.model, preset.true_parameters, Eigen::VectorXd::Constant(4, 0.5));
  preset.controller.kd = 2.0 * (preset.controller.kp.cwiseProduct(mass.diagonal())).cwiseSqrt();
  const SampledReference reference = make_step_reference(preset.reference);
  const Trajectory trajectory =
      simulate_closed_loop(preset.model, preset.true_parameters, preset.controller, reference, preset.simulation);
  // Measured: at 2.8 s joint 1 (stepped at 0.9 s, less damped with the arm stretched out)
  // is within 2.4e-2 N·m (5e-5 of the 480 N·m load) and 2.3e-5 rad/s; from 4.8 s on every
  // joint is within 2e-8 N·m and 5e-9 rad/s. Asserted with margins for rounding changes.
  struct Check {
    double t, torque, rate;
  };
  for (const Check& check : {Check{2.8, 0.05, 1e-4}, Check{4.8, 1e-5, 1e-6}, Check{6.8, 1e-5, 1e-6},
                             Check{9.7, 1e-5, 1e-6}}) {
    const Eigen::Index i = sample_at(check.t, 0.001);
    const Eigen::VectorXd q = trajectory.q.row(i).transpose();
    const Eigen::VectorXd r = trajectory.ref.row(i).transpose();
    const Eigen::VectorXd balance = preset.controller.kp.cwiseProduct(r - q) - gravity_torque(preset, q);
    const Eigen::VectorXd rate = rate_at(trajectory, preset.controller, i);
    for (int j = 0; j < 4; ++j) {
      EXPECT_NEAR(rate[j], 0.0, check.rate) << "t " << check.t << " joint " << j + 1;
      EXPECT_NEAR(balance[j], 0.0, check.torque) << "t " << check.t << " joint " << j + 1;
    }
    const double t = check.t;
    // The offset is real: joint 2 carries the arm, 480 N·m at 40000 N·m/rad ≈ 0.01 rad.
    EXPECT_GT(std::abs(r[1] - q[1]), 5e-3) << "t " << t;
  }
}

TEST(ClosedLoop, PaperKineticEnergyVariantRuns) {
  const Preset preset = cedro2009(KineticEnergy::paper);
  const SampledReference reference = make_step_reference(preset.reference);
  const Trajectory trajectory =
      simulate_closed_loop(preset.model, preset.true_parameters, preset.controller, reference, preset.simulation);
  ASSERT_EQ(trajectory.samples(), 9701);
  EXPECT_NO_THROW(trajectory.validate());
  EXPECT_NEAR(trajectory.q(9700, 0), 0.5, 1e-6);
}

// ---------------------------------------------------------------- closed loop: validation

TEST(ClosedLoop, RejectsInconsistentInputs) {
  const Preset preset = cedro2009();
  const SampledReference reference = make_step_reference(preset.reference);
  auto run = [&](const std::function<void(PdController&, SampledReference&, SimulationOptions&)>& change) {
    return [&, change] {
      PdController controller = preset.controller;
      SampledReference changed_reference = reference;
      SimulationOptions options = preset.simulation;
      options.duration = 0.01;
      change(controller, changed_reference, options);
      simulate_closed_loop(preset.model, preset.true_parameters, controller, changed_reference, options);
    };
  };
  expect_input_error(run([](auto& c, auto&, auto&) { c.kp = Eigen::VectorXd::Ones(3); }), "kp");
  expect_input_error(run([](auto& c, auto&, auto&) { c.kd[2] = -1.0; }), "kd");
  expect_input_error(run([](auto&, auto& r, auto&) { r.values.conservativeResize(Eigen::NoChange, 3); }), "reference");
  expect_input_error(run([](auto&, auto& r, auto&) { r.values.resize(0, 4); }), "reference");
  expect_input_error(run([](auto&, auto& r, auto&) { r.dt = 0.0; }), "reference");
  expect_input_error(run([](auto&, auto& r, auto&) { r.values(5, 1) = std::nan(""); }), "reference");
  expect_input_error(run([](auto&, auto&, auto& o) { o.q0 = Eigen::VectorXd::Zero(3); }), "q0");
  expect_input_error(run([](auto&, auto&, auto& o) { o.qd0 = Eigen::VectorXd::Constant(4, NAN); }), "qd0");
  expect_input_error(run([](auto&, auto&, auto& o) { o.dt = 0.0; }), "dt");
  expect_input_error(run([](auto&, auto&, auto& o) { o.duration = -1.0; }), "duration");
  expect_input_error(run([](auto&, auto&, auto& o) { o.duration = 0.0004; }), "duration");  // < dt
  expect_input_error(run([](auto&, auto&, auto& o) { o.relative_tolerance = 0.0; }), "relative_tolerance");
  expect_input_error(run([](auto&, auto&, auto& o) { o.absolute_tolerance = -1e-9; }), "absolute_tolerance");
  EXPECT_THROW(simulate_closed_loop(preset.model, Parameters(Eigen::VectorXd::Ones(3), Eigen::VectorXd::Ones(3)),
                                    preset.controller, reference, preset.simulation),
               InputError);
}

// ---------------------------------------------------------------- measurement noise

class Noise : public PaperScenario {};

TEST_F(Noise, SameSeedSameDataOtherSeedOtherData) {
  MeasurementNoise noise{.q_sigma = 1e-4, .tau_sigma = 0.1, .quantize_bits = 16, .seed = 42};
  Trajectory a = *trajectory_, b = *trajectory_, c = *trajectory_;
  apply_measurement_noise(a, noise);
  apply_measurement_noise(b, noise);
  noise.seed = 43;
  apply_measurement_noise(c, noise);
  EXPECT_TRUE((a.q.array() == b.q.array()).all());
  EXPECT_TRUE((a.tau.array() == b.tau.array()).all());
  EXPECT_FALSE((a.q.array() == c.q.array()).all());
  EXPECT_FALSE((a.tau.array() == c.tau.array()).all());
  EXPECT_TRUE((a.ref.array() == trajectory_->ref.array()).all());  // the reference is not measured
}

TEST_F(Noise, QuantisedAnglesAreMultiplesOfTheResolution) {
  for (const int bits : {8, 12, 20}) {
    Trajectory noisy = *trajectory_;
    apply_measurement_noise(noisy, MeasurementNoise{.q_sigma = 1e-3, .quantize_bits = bits});
    const double resolution = 2 * std::numbers::pi / std::ldexp(1.0, bits);
    const Eigen::ArrayXXd steps = noisy.q.array() / resolution;
    EXPECT_LT((steps - steps.round()).abs().maxCoeff(), 1e-6) << bits;
    // Without noise, quantisation alone is rounding to the nearest multiple.
    Trajectory clean = *trajectory_;
    apply_measurement_noise(clean, MeasurementNoise{.quantize_bits = bits});
    EXPECT_LE((clean.q - trajectory_->q).cwiseAbs().maxCoeff(), resolution / 2 * (1 + 1e-9)) << bits;
  }
}

TEST_F(Noise, GaussianStatisticsAreRight) {
  const double q_sigma = 2e-3, tau_sigma = 0.5;
  Trajectory noisy = *trajectory_;
  apply_measurement_noise(noisy, MeasurementNoise{.q_sigma = q_sigma, .tau_sigma = tau_sigma, .seed = 7});
  const Eigen::ArrayXXd dq = noisy.q - trajectory_->q, dtau = noisy.tau - trajectory_->tau;
  const double count = static_cast<double>(dq.size());  // 9,701 × 4 = 38,804
  auto standard_deviation = [count](const Eigen::ArrayXXd& x) {
    return std::sqrt((x - x.mean()).square().sum() / (count - 1));
  };
  // The sample std's relative error is ≈ 1/sqrt(2N) = 0.36%; 3% is > 8 of those.
  EXPECT_NEAR(standard_deviation(dq) / q_sigma, 1.0, 0.03);
  EXPECT_NEAR(standard_deviation(dtau) / tau_sigma, 1.0, 0.03);
  // The mean's error is σ/sqrt(N) ≈ 0.5% of σ; allow 5 of those.
  EXPECT_LT(std::abs(dq.mean()), 5 * q_sigma / std::sqrt(count));
  EXPECT_LT(std::abs(dtau.mean()), 5 * tau_sigma / std::sqrt(count));
}

TEST(MeasurementNoise, ValidatesSettingsAndToleratesMissingTorque) {
  Trajectory trajectory;
  trajectory.t = Eigen::VectorXd::LinSpaced(3, 0.0, 0.002);
  trajectory.q = Eigen::MatrixXd::Zero(3, 2);
  expect_input_error([&] { apply_measurement_noise(trajectory, {.q_sigma = -1.0}); }, "q_sigma");
  expect_input_error([&] { apply_measurement_noise(trajectory, {.tau_sigma = NAN}); }, "tau_sigma");
  expect_input_error([&] { apply_measurement_noise(trajectory, {.quantize_bits = 63}); }, "quantize_bits");
  expect_input_error([&] { apply_measurement_noise(trajectory, {.quantize_bits = -1}); }, "quantize_bits");
  EXPECT_NO_THROW(apply_measurement_noise(trajectory, {.q_sigma = 0.1, .tau_sigma = 0.1}));
  EXPECT_EQ(trajectory.tau.size(), 0);
  EXPECT_FALSE(MeasurementNoise{}.any());
}

// ---------------------------------------------------------------- Trajectory::validate

Trajectory small_trajectory() {
  Trajectory trajectory;
  trajectory.t = Eigen::VectorXd::LinSpaced(200, 0.0, 0.199);
  trajectory.q = Eigen::MatrixXd::Random(200, 3);
  trajectory.tau = Eigen::MatrixXd::Random(200, 3);
  return trajectory;
}

TEST(Trajectory, ValidateAcceptsConsistentData) {
  Trajectory trajectory = small_trajectory();
  EXPECT_NO_THROW(trajectory.validate());
  trajectory.tau.resize(0, 0);  // torque and reference are optional
  EXPECT_NO_THROW(trajectory.validate());
}

TEST(Trajectory, ValidateNamesTheOffendingColumnAndSample) {
  Trajectory trajectory = small_trajectory();
  trajectory.tau(119, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(expect_input_error([&] { trajectory.validate(); }, "tau"), "tau3 is NaN at sample 120 (t = 0.119 s)");
  trajectory = small_trajectory();
  trajectory.q(0, 0) = -INFINITY;
  EXPECT_EQ(expect_input_error([&] { trajectory.validate(); }, "q"), "q1 is infinite at sample 1 (t = 0 s)");
  trajectory = small_trajectory();
  trajectory.ref = Eigen::MatrixXd::Zero(200, 3);
  trajectory.ref(10, 1) = NAN;
  expect_input_error([&] { trajectory.validate(); }, "ref");
}

TEST(Trajectory, ValidateChecksSizes) {
  Trajectory trajectory = small_trajectory();
  trajectory.q.resize(200, 0);
  expect_input_error([&] { trajectory.validate(); }, "q");
  trajectory = small_trajectory();
  trajectory.q.conservativeResize(199, Eigen::NoChange);
  expect_input_error([&] { trajectory.validate(); }, "q");
  trajectory = small_trajectory();
  trajectory.tau.conservativeResize(Eigen::NoChange, 2);
  expect_input_error([&] { trajectory.validate(); }, "tau");
  trajectory = small_trajectory();
  trajectory.ref = Eigen::MatrixXd::Zero(100, 3);
  expect_input_error([&] { trajectory.validate(); }, "ref");
  trajectory = small_trajectory();
  trajectory.t.conservativeResize(1);
  trajectory.q.conservativeResize(1, Eigen::NoChange);
  trajectory.tau.conservativeResize(1, Eigen::NoChange);
  expect_input_error([&] { trajectory.validate(); }, "t");
}

TEST(Trajectory, ValidateChecksTheClock) {
  Trajectory trajectory = small_trajectory();
  trajectory.t[50] = trajectory.t[49];
  EXPECT_NE(expect_input_error([&] { trajectory.validate(); }, "t").find("increasing at sample 51"), std::string::npos);
  trajectory = small_trajectory();
  trajectory.t[150] += 1e-5;  // 1% of dt: jitter, as real loggers have; resampled at identification
  EXPECT_NO_THROW(trajectory.validate());
  EXPECT_FALSE(trajectory.is_uniform());
  trajectory = small_trajectory();
  trajectory.t[150] += 1e-11;  // 1e-8 of dt: printing noise, uniform
  EXPECT_NO_THROW(trajectory.validate());
  EXPECT_TRUE(trajectory.is_uniform());
  trajectory.t[3] = NAN;
  expect_input_error([&] { trajectory.validate(); }, "t");
}

TEST(Trajectory, ValidateChecksTheSamplePeriodIsInAWorkableRange) {
  // A period of 1e-320 s was accepted at upload; the filters' 1/Δ² then overflow.
  for (const double period : {1e-320, 1e-7, 11.0}) {  // the median step decides
    SCOPED_TRACE(period);
    Trajectory trajectory = small_trajectory();
    for (Eigen::Index i = 0; i < trajectory.t.size(); ++i) trajectory.t[i] = static_cast<double>(i) * period;
    EXPECT_NE(expect_input_error([&] { trajectory.validate(); }, "t").find("sample period"), std::string::npos);
  }
  for (const double period : {kShortestSamplePeriod, kLongestSamplePeriod}) {
    Trajectory trajectory = small_trajectory();
    for (Eigen::Index i = 0; i < trajectory.t.size(); ++i) trajectory.t[i] = static_cast<double>(i) * period;
    EXPECT_NO_THROW(trajectory.validate());
  }
}

}  // namespace
}  // namespace manipid
