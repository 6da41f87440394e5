// excitation_test.cpp — Fourier excitation trajectories: the series and its derivatives, rest at both ends,
// periodicity, the limits after design, the criterion against an independent computation, improvement over
// the start and over a naive sinusoid, determinism, cancellation and budgets, and the option checks.
#include "manipid/core/errors.h"
#include "manipid/core/robot/base_parameters.h"
#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/regressor.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/robot/urdf.h"
#include "robot_test_support.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>

#include <atomic>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace manipid::robot {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::string ur5_urdf() { return testing::read_file(testing::source_path("examples/robots/ur5_like.urdf")); }
std::string panda_urdf() { return testing::read_file(testing::source_path("examples/robots/panda_like.urdf")); }
const Model& ur5() {
  static const Model model = parse_urdf(ur5_urdf()).model;
  return model;
}
const Model& panda() {
  static const Model model = parse_urdf(panda_urdf()).model;
  return model;
}

/// Options small enough for the sanitizer build (a few seconds per design).
ExcitationOptions quick_options(int evaluations = 300) {
  ExcitationOptions options;
  options.max_evaluations = evaluations;
  options.random_starts = 8;
  options.samples = 120;
  options.max_seconds = 600.0;  // never the binding stop here: results must not depend on the machine
  return options;
}

/// The series of excitation.h written out independently: q, q̇, q̈ of joint k at time t.
struct Direct {
  const FourierTrajectory& f;
  double q(int k, double t) const {
    const double w = kTwoPi / f.period;
    double value = f.q0[k];
    for (int l = 1; l <= f.harmonics(); ++l) {
      value += f.a(k, l - 1) / (w * l) * std::sin(w * l * t) - f.b(k, l - 1) / (w * l) * std::cos(w * l * t);
    }
    return value;
  }
  double qd(int k, double t) const {
    const double w = kTwoPi / f.period;
    double value = 0.0;
    for (int l = 1; l <= f.harmonics(); ++l) value += f.a(k, l - 1) * std::cos(w * l * t) + f.b(k, l - 1) * std::sin(w * l * t);
    return value;
  }
  double qdd(int k, double t) const {
    const double w = kTwoPi / f.period;
    double value = 0.0;
    for (int l = 1; l <= f.harmonics(); ++l) {
      value += w * l * (-f.a(k, l - 1) * std::sin(w * l * t) + f.b(k, l - 1) * std::cos(w * l * t));
    }
    return value;
  }
};

FourierTrajectory random_trajectory(std::uint64_t seed, int joints, int harmonics, double period) {
  std::mt19937_64 engine(seed);
  FourierTrajectory f;
  f.period = period;
  f.q0 = testing::random_vector(engine, joints, 1.0);
  f.a = Eigen::MatrixXd(joints, harmonics);
  f.b = Eigen::MatrixXd(joints, harmonics);
  for (int k = 0; k < joints; ++k) {
    f.a.row(k) = testing::random_vector(engine, harmonics, 0.5).transpose();
    f.b.row(k) = testing::random_vector(engine, harmonics, 0.5).transpose();
  }
  return f;
}

/// cond of the column-scaled base regressor at the N midpoints t_j = T (j + ½) / N (the design's instants),
/// from the series evaluated directly, the one-state regressor() and a JacobiSVD: independent of the
/// design's tables, stacking and Gram shortcut.
double independent_condition_number(const Model& model, const FourierTrajectory& f, const ParameterLayout& layout,
                                    int samples) {
  const BaseParameters base = base_parameters(model, layout);
  const int n = model.joint_count();
  const Direct direct{f};
  Eigen::MatrixXd Yb(samples * n, base.size());
  Eigen::VectorXd q(n), qd(n), qdd(n);
  for (int j = 0; j < samples; ++j) {
    const double t = f.period * (j + 0.5) / samples;
    for (int k = 0; k < n; ++k) {
      q[k] = direct.q(k, t);
      qd[k] = direct.qd(k, t);
      qdd[k] = direct.qdd(k, t);
    }
    const Eigen::MatrixXd Y = regressor(model, layout, q, qd, qdd);
    for (int i = 0; i < base.size(); ++i) Yb.block(j * n, i, n, 1) = Y.col(base.independent[static_cast<std::size_t>(i)]);
  }
  const Eigen::VectorXd norms = Yb.colwise().norm().transpose();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Yb * norms.cwiseInverse().asDiagonal());
  return svd.singularValues()[0] / svd.singularValues()[base.size() - 1];
}

/// Every sample within the model's limits (the margin kept from position limits) and the acceleration limit.
void expect_within_limits(const Model& model, const SampledExcitation& s, double margin, double max_acceleration) {
  int violations = 0;
  for (int k = 0; k < model.joint_count(); ++k) {
    const JointLimits& limits = model.joints[static_cast<std::size_t>(k)].limits;
    const double lowest = s.q.row(k).minCoeff(), highest = s.q.row(k).maxCoeff();
    const double fastest = s.qd.row(k).cwiseAbs().maxCoeff(), hardest = s.qdd.row(k).cwiseAbs().maxCoeff();
    violations += !(lowest >= limits.lower + margin) + !(highest <= limits.upper - margin) +
                  !(fastest <= limits.velocity) + !(hardest <= max_acceleration);
    EXPECT_GE(lowest, limits.lower + margin) << "joint " << k + 1;
    EXPECT_LE(highest, limits.upper - margin) << "joint " << k + 1;
    EXPECT_LE(fastest, limits.velocity) << "joint " << k + 1;
    EXPECT_LE(hardest, max_acceleration) << "joint " << k + 1;
  }
  EXPECT_EQ(violations, 0);
}

template <typename F>
void expect_input_error(const std::string& field, F&& call) {
  try {
    call();
    ADD_FAILURE() << "no InputError; expected one naming '" << field << "'";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), field) << error.what();
  }
}

// ---- The series ----------------------------------------------------------------------------

TEST(ExcitationTrajectory, SamplesEqualTheSeriesAndItsDerivatives) {
  const FourierTrajectory f = random_trajectory(3, 4, 5, 7.0);
  const Direct direct{f};
  const SampledExcitation s = sample_excitation(f, 0.01, 2);
  ASSERT_EQ(s.t.size(), 1401);
  EXPECT_EQ(s.t[0], 0.0);
  EXPECT_EQ(s.t[1400], 14.0);
  // q from the exact phase reduction equals the series evaluated directly.
  double worst_q = 0.0;
  for (Eigen::Index i = 0; i < s.t.size(); i += 7) {
    for (int k = 0; k < 4; ++k) worst_q = std::max(worst_q, std::abs(s.q(k, i) - direct.q(k, s.t[i])));
  }
  EXPECT_LE(worst_q, 1e-12);
  // q̇ and q̈ against central differences (h = 1e-5: truncation ~1e-10 · |q'''|, rounding ~1e-11 / h).
  const double h = 1e-5;
  double worst_qd = 0.0, worst_qdd = 0.0;
  for (Eigen::Index i = 0; i < s.t.size(); i += 7) {
    const double t = s.t[i];
    for (int k = 0; k < 4; ++k) {
      worst_qd = std::max(worst_qd, std::abs(s.qd(k, i) - (direct.q(k, t + h) - direct.q(k, t - h)) / (2 * h)));
      worst_qdd = std::max(worst_qdd, std::abs(s.qdd(k, i) - (direct.qd(k, t + h) - direct.qd(k, t - h)) / (2 * h)));
    }
  }
  EXPECT_LE(worst_qd, 1e-7);
  EXPECT_LE(worst_qdd, 1e-7);
  EXPECT_GT(s.qd.cwiseAbs().maxCoeff(), 0.1);  // not vacuous: the motion is real
  EXPECT_GT(s.qdd.cwiseAbs().maxCoeff(), 0.1);
}

TEST(ExcitationTrajectory, PeriodsAreIdentical) {
  const FourierTrajectory f = random_trajectory(4, 3, 3, 2.5);
  const SampledExcitation s = sample_excitation(f, 0.005, 3);  // 500 per period
  ASSERT_EQ(s.t.size(), 1501);
  for (Eigen::Index i = 0; i + 500 < s.t.size(); ++i) {
    ASSERT_EQ(s.q.col(i), s.q.col(i + 500)) << "sample " << i;
    ASSERT_EQ(s.qd.col(i), s.qd.col(i + 500)) << "sample " << i;
    ASSERT_EQ(s.qdd.col(i), s.qdd.col(i + 500)) << "sample " << i;
  }
  const Direct direct{f};
  EXPECT_NEAR(direct.q(1, 0.3), direct.q(1, 0.3 + f.period), 1e-12);
  EXPECT_TRUE(s.q.col(0).isApprox(f.start(), 1e-14));
}

TEST(ExcitationTrajectory, DesignStartsAndEndsAtRest) {
  const ExcitationDesign design = design_excitation(ur5(), quick_options(60));
  const FourierTrajectory& f = design.trajectory;
  ASSERT_EQ(f.joint_count(), 6);
  ASSERT_EQ(f.harmonics(), 5);
  Eigen::VectorXd ramp(5);
  ramp << 1, 2, 3, 4, 5;
  for (int k = 0; k < 6; ++k) {
    EXPECT_LE(std::abs(f.a.row(k).sum()), 1e-14 * f.a.row(k).cwiseAbs().sum()) << "joint " << k + 1;
    EXPECT_LE(std::abs(f.b.row(k).transpose().dot(ramp)), 1e-14 * 5 * f.b.row(k).cwiseAbs().sum()) << "joint " << k + 1;
  }
  const SampledExcitation s = sample_excitation(f, 0.001);
  const Eigen::Index last = s.t.size() - 1;
  EXPECT_EQ(s.t[last], 10.0);
  // Exactly at rest in the samples (sample_excitation sums in the order the rest conditions were imposed).
  EXPECT_EQ(s.qd.col(0), Eigen::VectorXd::Zero(6));
  EXPECT_EQ(s.qdd.col(0), Eigen::VectorXd::Zero(6));
  EXPECT_EQ(s.qd.col(last), Eigen::VectorXd::Zero(6));
  EXPECT_EQ(s.qdd.col(last), Eigen::VectorXd::Zero(6));
  EXPECT_EQ(s.q.col(last), s.q.col(0));
  EXPECT_LE((s.q.col(0) - f.start()).cwiseAbs().maxCoeff(), 1e-12);
  // And from the series evaluated independently, in its own order: at rest to rounding.
  const Direct direct{f};
  for (const double t : {0.0, f.period}) {
    for (int k = 0; k < 6; ++k) {
      EXPECT_NEAR(direct.qd(k, t), 0.0, 1e-12) << "joint " << k + 1 << ", t = " << t;
      EXPECT_NEAR(direct.qdd(k, t), 0.0, 1e-12) << "joint " << k + 1 << ", t = " << t;
      EXPECT_NEAR(direct.q(k, t), s.q(k, 0), 1e-12) << "joint " << k + 1 << ", t = " << t;
    }
  }
  // And it moves: every joint leaves its start by more than a tenth of a radian.
  for (int k = 0; k < 6; ++k) EXPECT_GT((s.q.row(k).array() - s.q(k, 0)).abs().maxCoeff(), 0.1) << "joint " << k + 1;
}

// ---- Limits ----------------------------------------------------------------------------------

TEST(ExcitationDesign, EveryLimitHoldsOnAFineGrid) {
  for (const Model* model : {&ur5(), &panda()}) {
    ExcitationOptions options = quick_options(150);
    options.position_margin = 0.1;
    options.max_acceleration = Eigen::VectorXd::Constant(1, 6.0);
    const ExcitationDesign design = design_excitation(*model, options);
    // 0.2 ms: 50,000 samples, 160 per period of the highest harmonic — finer than the design's grid.
    const SampledExcitation s = sample_excitation(design.trajectory, 0.0002);
    expect_within_limits(*model, s, options.position_margin, 6.0);
    EXPECT_FALSE(first_limit_violation(excitation_limits(*model, options), s).has_value()) << model->name;
    // Each joint is scaled to its own largest amplitude, so each one reaches (within 1 %) some limit.
    std::vector<bool> reached(static_cast<std::size_t>(model->joint_count()), false);
    for (const ActiveLimit& active : design.summary.active_limits) {
      reached[static_cast<std::size_t>(active.joint - 1)] = true;
      EXPECT_EQ(active.joint_name, model->joints[static_cast<std::size_t>(active.joint - 1)].name);
      EXPECT_GE(design.summary.usage(active.joint - 1, static_cast<int>(active.kind)), 0.99);
      if (active.kind == LimitKind::velocity || active.kind == LimitKind::acceleration) {
        EXPECT_GE(active.peak, 0.99 * active.limit);
        EXPECT_LE(active.peak, active.limit);
      }
    }
    for (int k = 0; k < model->joint_count(); ++k) EXPECT_TRUE(reached[static_cast<std::size_t>(k)]) << model->name << " joint " << k + 1;
    // The bound between grid points is rigorous but tight: the binding limit is used to within 1 %.
    EXPECT_LE(design.summary.usage.maxCoeff(), 1.0);
    EXPECT_GE(design.summary.usage.maxCoeff(), 0.99);
  }
}

TEST(ExcitationDesign, PerJointAccelerationAndUnlimitedJoints) {
  // wrist_3 made continuous without <limit>: no position limits, no velocity limit; the acceleration
  // limit alone bounds it.
  std::string xml = ur5_urdf();
  xml = testing::with_replaced(xml, R"(<joint name="wrist_3_joint" type="revolute">)", R"(<joint name="wrist_3_joint" type="continuous">)");
  const std::string wrist_limit =
      R"(<limit lower="-6.283185307179586" upper="6.283185307179586" effort="28" velocity="3.141592653589793"/>)";
  const std::size_t wrist = xml.find(R"(<joint name="wrist_3_joint")");
  xml.replace(xml.find(wrist_limit, wrist), wrist_limit.size(), "");
  const Model model = parse_urdf(xml).model;
  ASSERT_EQ(model.joints[5].type, JointType::continuous);
  ASSERT_FALSE(std::isfinite(model.joints[5].limits.velocity));

  ExcitationOptions options = quick_options(80);
  options.max_acceleration.resize(6);
  options.max_acceleration << 3, 4, 5, 6, 7, 2;
  const ExcitationLimits limits = excitation_limits(model, options);
  EXPECT_FALSE(std::isfinite(limits.lower[5]));
  EXPECT_FALSE(std::isfinite(limits.upper[5]));
  EXPECT_FALSE(std::isfinite(limits.velocity[5]));
  EXPECT_EQ(limits.acceleration[5], 2.0);
  const ExcitationDesign design = design_excitation(model, options);
  const SampledExcitation s = sample_excitation(design.trajectory, 0.0005);
  EXPECT_FALSE(first_limit_violation(limits, s).has_value());
  for (int k = 0; k < 6; ++k) EXPECT_LE(s.qdd.row(k).cwiseAbs().maxCoeff(), options.max_acceleration[k]);
  EXPECT_GE(s.qdd.row(5).cwiseAbs().maxCoeff(), 0.99 * 2.0);  // the only limit it has, so it binds
  EXPECT_TRUE(std::isnan(design.summary.usage(5, 0)));
  EXPECT_TRUE(std::isnan(design.summary.usage(5, 2)));
}

TEST(ExcitationDesign, FirstLimitViolationFindsTheSample) {
  const FourierTrajectory f = random_trajectory(5, 2, 2, 4.0);
  SampledExcitation s = sample_excitation(f, 0.01);
  ExcitationLimits limits;
  limits.lower = Eigen::VectorXd::Constant(2, -100.0);
  limits.upper = Eigen::VectorXd::Constant(2, 100.0);
  limits.velocity = Eigen::VectorXd::Constant(2, 100.0);
  limits.acceleration = Eigen::VectorXd::Constant(2, 100.0);
  EXPECT_FALSE(first_limit_violation(limits, s).has_value());
  s.qd(1, 57) = -150.0;
  const std::optional<LimitViolation> violation = first_limit_violation(limits, s);
  ASSERT_TRUE(violation.has_value());
  EXPECT_EQ(violation->joint, 2);
  EXPECT_EQ(violation->kind, LimitKind::velocity);
  EXPECT_EQ(violation->t, s.t[57]);
  EXPECT_EQ(violation->value, -150.0);
}

TEST(ExcitationTrajectory, JerkIsTheDerivativeOfTheAcceleration) {
  // The sampled jerk against a central difference of the sampled q̈ (error O(dt²)).
  const FourierTrajectory f = random_trajectory(11, 3, 4, 5.0);
  const double dt = 1e-4;
  const SampledExcitation s = sample_excitation(f, dt);
  ASSERT_EQ(s.jerk.cols(), s.t.size());
  double worst = 0.0, scale = 0.0;
  for (Eigen::Index i = 1; i + 1 < s.t.size(); i += 97) {
    for (int k = 0; k < 3; ++k) {
      worst = std::max(worst, std::abs((s.qdd(k, i + 1) - s.qdd(k, i - 1)) / (2 * dt) - s.jerk(k, i)));
      scale = std::max(scale, std::abs(s.jerk(k, i)));
    }
  }
  EXPECT_GT(scale, 1.0);
  EXPECT_LT(worst, 1e-5 * scale);
}

// ---- Jerk, torque, velocity limits and the start pose -----------------------------------------

/// The torque the URDF's parameters predict at every sample: the largest |τ_k| per joint.
Eigen::VectorXd peak_torque(const Model& model, const SampledExcitation& s) {
  const ParameterLayout layout;
  const Eigen::VectorXd pi = standard_parameters(model, layout);
  Eigen::VectorXd peak = Eigen::VectorXd::Zero(model.joint_count());
  for (Eigen::Index i = 0; i < s.t.size(); ++i) {
    peak = peak.cwiseMax(inverse_dynamics(model, layout, pi, s.q.col(i), s.qd.col(i), s.qdd.col(i)).cwiseAbs());
  }
  return peak;
}

TEST(ExcitationLimits, VelocityJerkAndTorqueResolvePerJoint) {
  ExcitationOptions options = quick_options();
  options.max_velocity = Eigen::VectorXd::Constant(1, 1.0);  // below the Panda-like arm's 2.175..2.61
  options.max_jerk = Eigen::VectorXd::Constant(1, 50.0);
  options.max_torque = Eigen::VectorXd::Constant(1, 40.0);  // below 87 on joints 1–4, above 12 on 5–7
  const ExcitationLimits limits = excitation_limits(panda(), options);
  for (int k = 0; k < 7; ++k) {
    const JointLimits& urdf = panda().joints[static_cast<std::size_t>(k)].limits;
    EXPECT_EQ(limits.velocity[k], std::min(1.0, urdf.velocity));
    EXPECT_EQ(limits.jerk[k], 50.0);
    EXPECT_EQ(limits.torque[k], std::min(40.0, urdf.effort)) << k;
  }
  EXPECT_EQ(limits.torque[6], 12.0);  // never above the URDF's effort
  // Defaults: the URDF's velocity and effort, no jerk limit, the URDF's parameters as the torque model.
  const ExcitationLimits defaults = excitation_limits(panda(), quick_options());
  EXPECT_EQ(defaults.velocity[0], panda().joints[0].limits.velocity);
  EXPECT_EQ(defaults.torque[0], panda().joints[0].limits.effort);
  EXPECT_FALSE(std::isfinite(defaults.jerk[0]));
  EXPECT_TRUE(defaults.torque_parameters.isApprox(standard_parameters(panda(), ParameterLayout{})));
}

TEST(ExcitationDesign, JerkAndVelocityLimitsHold) {
  ExcitationOptions options = quick_options(150);
  options.max_velocity = Eigen::VectorXd::Constant(1, 0.8);
  options.max_jerk = Eigen::VectorXd::Constant(1, 4.0);  // binding: the default design reaches ~16 rad/s³
  const ExcitationDesign design = design_excitation(ur5(), options);
  const SampledExcitation s = sample_excitation(design, 0.0005);
  const ExcitationLimits limits = excitation_limits(ur5(), options);
  EXPECT_FALSE(first_limit_violation(limits, s, &ur5()).has_value());
  double jerk = 0.0;
  for (int k = 0; k < 6; ++k) {
    EXPECT_LE(s.qd.row(k).cwiseAbs().maxCoeff(), 0.8);
    EXPECT_LE(s.jerk.row(k).cwiseAbs().maxCoeff(), 4.0);
    jerk = std::max(jerk, s.jerk.row(k).cwiseAbs().maxCoeff());
  }
  EXPECT_GE(jerk, 0.99 * 4.0);  // some joint uses it: the limit shaped the design
  bool jerk_active = false;
  for (const ActiveLimit& active : design.summary.active_limits) jerk_active |= active.kind == LimitKind::jerk;
  EXPECT_TRUE(jerk_active);
}

TEST(ExcitationDesign, TorqueLimitsHoldAndCutTheMotion) {
  // Unlimited, the design's shoulder torque reaches some peak; held below 60 % of it, every sample keeps
  // the limit, the motion shrinks (torque_scale < 1) and the limit is used (it binds).
  ExcitationOptions options = quick_options(100);
  const ExcitationDesign free = design_excitation(panda(), options);
  const Eigen::VectorXd free_peak = peak_torque(panda(), sample_excitation(free, 0.001));
  EXPECT_NEAR(free.summary.peaks(1, 5), free_peak[1], 0.02 * free_peak[1]);  // the report agrees
  options.max_torque = Eigen::VectorXd::Constant(7, 1e3);
  options.max_torque[1] = 0.6 * free_peak[1];
  const ExcitationDesign held = design_excitation(panda(), options);
  const SampledExcitation s = sample_excitation(held, 0.0005);
  const Eigen::VectorXd peak = peak_torque(panda(), s);
  EXPECT_LE(peak[1], options.max_torque[1]);
  EXPECT_GE(peak[1], 0.9 * options.max_torque[1]);
  EXPECT_LT(held.summary.torque_scale, 1.0);
  EXPECT_FALSE(first_limit_violation(excitation_limits(panda(), options), s, &panda()).has_value());
  EXPECT_LE(held.summary.usage(1, 5), 1.0);
}

TEST(ExcitationDesign, AnIdentifiedTorqueModelIsTheOneLimited) {
  // A torque model twice as heavy as the URDF: the same limit binds sooner.
  ExcitationOptions options = quick_options(60);
  options.max_torque = Eigen::VectorXd::Constant(7, 1e3);
  options.max_torque[1] = 30.0;
  options.torque_parameters = 2.0 * standard_parameters(panda(), options.torque_layout);
  const ExcitationDesign design = design_excitation(panda(), options);
  const ExcitationLimits limits = excitation_limits(panda(), options);
  const SampledExcitation s = sample_excitation(design, 0.001);
  EXPECT_FALSE(first_limit_violation(limits, s, &panda()).has_value());
  EXPECT_LE(peak_torque(panda(), s)[1], 0.5 * 30.0 * 1.0001);  // the URDF's own torque is half the model's
}

TEST(ExcitationDesign, TorqueThatCannotHoldTheArmIsNamed) {
  ExcitationOptions options = quick_options(40);
  options.max_torque = Eigen::VectorXd::Constant(1, 0.01);  // gravity alone needs more on the shoulder
  expect_input_error("max_torque", [&] { (void)design_excitation(panda(), options); });
}

TEST(ExcitationDesign, MeanPoseStaysInTheMiddleHalf) {
  const ExcitationDesign design = design_excitation(panda(), quick_options(200));
  const ExcitationLimits limits = excitation_limits(panda(), quick_options());
  for (int k = 0; k < 7; ++k) {
    const double share = (design.trajectory.q0[k] - limits.lower[k]) / (limits.upper[k] - limits.lower[k]);
    EXPECT_GE(share, 0.25 - 1e-12) << k;
    EXPECT_LE(share, 0.75 + 1e-12) << k;
  }
}

TEST(ExcitationRamp, ShortestQuinticWithinTheLimits) {
  // One joint moves 1 rad; velocity 0.5 rad/s binds: D = 1.875 · 1 / 0.5 = 3.75 s (acceleration needs
  // √(5.7735 / 7.5) = 0.88 s).
  ExcitationOptions options = quick_options();
  options.max_velocity = Eigen::VectorXd::Constant(1, 0.5);
  options.max_torque = Eigen::VectorXd::Constant(1, 1e4);
  const ExcitationLimits limits = excitation_limits(ur5(), options);
  Eigen::VectorXd pose = Eigen::VectorXd::Zero(6), target = pose;
  target[2] = 1.0;
  const StartRamp ramp = plan_ramp(ur5(), limits, pose, target);
  EXPECT_NEAR(ramp.duration, 3.75, 1e-12);
  EXPECT_NEAR(ramp.peaks(2, 0), 0.5, 1e-12);
  EXPECT_NEAR(ramp.peaks(2, 1), 10.0 / std::sqrt(3.0) / (3.75 * 3.75), 1e-12);
  EXPECT_EQ(ramp.peaks(0, 0), 0.0);
  // A jerk limit of 1 rad/s³ binds instead: D = ∛60 ≈ 3.915 s.
  options.max_jerk = Eigen::VectorXd::Constant(1, 1.0);
  EXPECT_NEAR(plan_ramp(ur5(), excitation_limits(ur5(), options), pose, target).duration, std::cbrt(60.0), 1e-12);
}

TEST(ExcitationRamp, SampledRunStartsAndEndsAtThePoseSmoothly) {
  ExcitationOptions options = quick_options(60);
  options.start_pose = Eigen::VectorXd::Zero(7);
  options.start_pose[3] = -1.5;  // the Panda-like elbow's range is −3.07..−0.07
  options.start_pose[5] = 1.5;
  const ExcitationDesign design = design_excitation(panda(), options);
  ASSERT_TRUE(design.ramp.has_value());
  EXPECT_GT(design.ramp->duration, 0.0);
  const double dt = 0.001;
  const SampledExcitation s = sample_excitation(design, dt);
  const SampledExcitation series = sample_excitation(design.trajectory, dt);
  const long steps = std::lround(s.ramp_duration / dt);
  EXPECT_GE(s.ramp_duration, design.ramp->duration);
  EXPECT_LT(s.ramp_duration, design.ramp->duration + dt + 1e-12);
  ASSERT_EQ(s.t.size(), series.t.size() + 2 * steps);
  // At rest at the pose at both ends, the series unchanged in the middle.
  EXPECT_TRUE(s.q.col(0).isApprox(options.start_pose));
  EXPECT_TRUE(s.q.col(s.t.size() - 1).isApprox(options.start_pose));
  EXPECT_EQ(s.qd.col(0).norm(), 0.0);
  EXPECT_EQ(s.qd.col(s.t.size() - 1).norm(), 0.0);
  EXPECT_EQ(s.q.middleCols(steps, series.t.size()), series.q);
  EXPECT_NEAR(s.t[steps], s.ramp_duration, 1e-12);
  // Smooth at the junctions: q, q̇, q̈ change by no more than one step's worth.
  for (const Eigen::Index i : {steps - 1, steps + series.t.size() - 1}) {
    EXPECT_LT((s.q.col(i + 1) - s.q.col(i)).cwiseAbs().maxCoeff(), 3.0 * dt);
    EXPECT_LT((s.qd.col(i + 1) - s.qd.col(i)).cwiseAbs().maxCoeff(), 8.0 * dt);
    EXPECT_LT((s.qdd.col(i + 1) - s.qdd.col(i)).cwiseAbs().maxCoeff(), 200.0 * dt);
  }
  // Every limit holds over the whole output, ramps and torque included.
  EXPECT_FALSE(first_limit_violation(excitation_limits(panda(), options), s, &panda()).has_value());
}

TEST(ExcitationRamp, BadStartPosesAreNamed) {
  ExcitationOptions options = quick_options(20);
  options.start_pose = Eigen::VectorXd::Zero(7);  // joint 4's range is −3.07..−0.07: 0 is outside
  expect_input_error("start_pose", [&] { (void)excitation_limits(panda(), options); });
  options.start_pose = Eigen::VectorXd::Zero(3);
  expect_input_error("start_pose", [&] { (void)excitation_limits(panda(), options); });
  // A pose the torque limits cannot hold (arm stretched out, shoulder limited to 5 N m).
  options.start_pose = Eigen::VectorXd::Zero(7);
  options.start_pose[1] = 1.5;
  options.start_pose[3] = -0.1;
  const ExcitationLimits generous = excitation_limits(panda(), options);
  ExcitationLimits weak = generous;
  weak.torque[1] = 5.0;
  EXPECT_NO_THROW((void)plan_ramp(panda(), generous, options.start_pose, options.start_pose));
  expect_input_error("start_pose", [&] { (void)plan_ramp(panda(), weak, options.start_pose, options.start_pose); });
}

// ---- The criterion ---------------------------------------------------------------------------

TEST(ExcitationDesign, ReportedConditionNumberMatchesAnIndependentComputation) {
  const ExcitationOptions options = quick_options(60);
  const ExcitationDesign design = design_excitation(ur5(), options);
  const double independent = independent_condition_number(ur5(), design.trajectory, options.layout, options.samples);
  EXPECT_NEAR(design.summary.condition_number, independent, 1e-8 * independent);
  const ExcitationQuality quality = excitation_quality(ur5(), design.trajectory, options);
  EXPECT_NEAR(quality.condition_number, independent, 1e-8 * independent);
  EXPECT_NEAR(quality.log_det, design.summary.log_det, 1e-9 * std::abs(quality.log_det));
  EXPECT_EQ(quality.base_parameters, design.summary.base_parameters);
  EXPECT_EQ(design.summary.base_parameters, 48);  // the UR5-like arm with viscous and Coulomb friction
  // What the optimiser saw (the Gram form) agrees with the SVD figure.
  EXPECT_NEAR(design.summary.final_value, design.summary.condition_number, 1e-6 * design.summary.condition_number);
}

TEST(ExcitationDesign, OptimisedBeatsTheStartAndANaiveSinusoid) {
  const ExcitationOptions options = quick_options(500);
  const ExcitationDesign design = design_excitation(ur5(), options);
  const ExcitationSummary& summary = design.summary;
  EXPECT_LT(summary.final_value, summary.initial_value);
  EXPECT_LT(summary.condition_number, summary.initial_condition_number);

  // Naive: every joint the same two-harmonic wave at rest at both ends, q̇ = A (cos ωt − cos 2ωt) about
  // the middle of its range (UR5-like: ±2π, π rad/s; A = 0.5 rad/s keeps |q̇| ≤ 1, |q̈| ≤ 0.95).
  FourierTrajectory naive;
  naive.period = 10.0;
  naive.q0 = Eigen::VectorXd::Zero(6);
  naive.a = Eigen::MatrixXd::Zero(6, 5);
  naive.b = Eigen::MatrixXd::Zero(6, 5);
  naive.a.col(0).setConstant(0.5);
  naive.a.col(1).setConstant(-0.5);
  EXPECT_FALSE(first_limit_violation(excitation_limits(ur5(), options), sample_excitation(naive, 0.001)).has_value());
  const double naive_condition = excitation_quality(ur5(), naive, options).condition_number;
  std::printf("UR5-like condition number: naive sinusoid %.4g, best random start %.4g, designed %.4g\n",
              naive_condition, summary.initial_condition_number, summary.condition_number);
  EXPECT_LT(summary.condition_number, naive_condition);
  EXPECT_LT(5 * summary.condition_number, naive_condition);
}

TEST(ExcitationDesign, LogDetCriterionIncreasesLogDet) {
  ExcitationOptions options = quick_options(300);
  options.criterion = ExcitationCriterion::logdet;
  const ExcitationDesign design = design_excitation(ur5(), options);
  EXPECT_EQ(design.summary.criterion, ExcitationCriterion::logdet);
  EXPECT_GT(design.summary.final_value, design.summary.initial_value);
  EXPECT_NEAR(design.summary.final_value, design.summary.log_det, 1e-6 * std::abs(design.summary.log_det));
  EXPECT_NEAR(excitation_quality(ur5(), design.trajectory, options).log_det, design.summary.log_det,
              1e-9 * std::abs(design.summary.log_det));
}

// ---- The run: determinism, budgets, cancellation, progress ----------------------------------

TEST(ExcitationDesign, SameSeedSameCoefficients) {
  ExcitationOptions options = quick_options(120);
  options.seed = 11;
  const ExcitationDesign first = design_excitation(ur5(), options);
  const ExcitationDesign second = design_excitation(ur5(), options);
  EXPECT_EQ(first.trajectory.q0, second.trajectory.q0);
  EXPECT_EQ(first.trajectory.a, second.trajectory.a);
  EXPECT_EQ(first.trajectory.b, second.trajectory.b);
  EXPECT_EQ(first.summary.final_value, second.summary.final_value);
  EXPECT_EQ(first.summary.evaluations, 120);
  EXPECT_EQ(first.summary.termination, ExcitationTermination::max_evaluations);
  options.seed = 12;
  const ExcitationDesign other = design_excitation(ur5(), options);
  EXPECT_NE(first.trajectory.a, other.trajectory.a);
}

TEST(ExcitationDesign, CancellationStopsItWithAFeasibleTrajectory) {
  std::atomic<bool> cancel{false};
  ExcitationOptions options = quick_options(100000);
  options.cancel = &cancel;
  long calls = 0;
  options.progress = [&](const ExcitationProgress& progress) {
    calls = progress.evaluation;
    if (progress.evaluation == 40) cancel = true;
  };
  const ExcitationDesign design = design_excitation(ur5(), options);
  EXPECT_EQ(design.summary.termination, ExcitationTermination::cancelled);
  EXPECT_EQ(design.summary.evaluations, 40);
  EXPECT_EQ(calls, 40);
  EXPECT_TRUE(std::isfinite(design.summary.condition_number));
  EXPECT_FALSE(first_limit_violation(excitation_limits(ur5(), options), sample_excitation(design.trajectory, 0.001)).has_value());

  // Set before the start: the base parameters' first checkpoint stops it, with no trajectory and no figures.
  options.progress = nullptr;
  const ExcitationDesign early = design_excitation(ur5(), options);
  EXPECT_EQ(early.summary.termination, ExcitationTermination::cancelled);
  EXPECT_EQ(early.summary.evaluations, 0);
  EXPECT_EQ(early.trajectory.q0.size(), 0);
  EXPECT_NE(early.summary.message.find("base parameters"), std::string::npos) << early.summary.message;
}

/// A serial chain of `joints` revolute joints about alternating y and z axes, 0.1 m apart.
std::string chain_urdf(int joints) {
  std::string text = "<robot name='chain'><link name='l0'/>";
  for (int k = 1; k <= joints; ++k) {
    const std::string axis = k % 2 ? "0 1 0" : "0 0 1";
    text += "<joint name='j" + std::to_string(k) + "' type='revolute'><parent link='l" + std::to_string(k - 1) +
            "'/><child link='l" + std::to_string(k) + "'/><origin xyz='0 0 0.1'/><axis xyz='" + axis +
            "'/><limit lower='-2' upper='2' effort='5000' velocity='2'/></joint><link name='l" + std::to_string(k) +
            "'><inertial><mass value='1'/><origin xyz='0.01 0.02 0.05'/><inertia ixx='0.01' ixy='0' ixz='0' "
            "iyy='0.02' iyz='0' izz='0.03'/></inertial></link>";
  }
  return text + "</robot>";
}

TEST(ExcitationQuality, RowBlocksOfALargeProblemGiveTheFiguresOfOneSvd) {
  // 10 joints at 3000 instants: Y_b is 30,000 rows × ~80 columns, over the work the criterion does whole,
  // so the condition number comes from the R of a QR taken in row blocks (with checkpoints between them).
  const Model model = parse_urdf(chain_urdf(10)).model;
  const FourierTrajectory f = random_trajectory(3, 10, 5, 10.0);
  ExcitationOptions options;
  options.samples = 3000;
  const ExcitationQuality quality = excitation_quality(model, f, options);
  const double independent = independent_condition_number(model, f, options.layout, options.samples);
  ASSERT_GT(static_cast<double>(options.samples) * 10 * quality.base_parameters * quality.base_parameters, 1e8);
  EXPECT_NEAR(quality.condition_number, independent, 1e-8 * independent);
}

TEST(BaseParametersOptions, ACancelStopsTheComputation) {
  std::atomic<bool> cancel{true};
  BaseParameterOptions options;
  options.cancel = &cancel;
  EXPECT_THROW(base_parameters(ur5(), ParameterLayout{}, options), Interrupted);
  cancel = false;
  EXPECT_EQ(base_parameters(ur5(), ParameterLayout{}, options).size(), 48);
}

TEST(ExcitationDesign, TimeBudgetStopsIt) {
  ExcitationOptions options = quick_options(100000);
  options.max_seconds = 1e-9;  // spent by the first evaluation, whatever the machine
  const ExcitationDesign design = design_excitation(ur5(), options);
  EXPECT_EQ(design.summary.termination, ExcitationTermination::max_seconds);
  EXPECT_EQ(design.summary.evaluations, 1);
}

TEST(ExcitationDesign, ProgressReportsEveryEvaluationAndTheBest) {
  ExcitationOptions options = quick_options(80);
  long count = 0;
  double best = std::numeric_limits<double>::infinity();
  bool monotone = true;
  options.progress = [&](const ExcitationProgress& progress) {
    ++count;
    EXPECT_EQ(progress.evaluation, count);
    // The best by the cost, which adds the centring tie-break (≤ 0.025 % of the criterion) to log cond.
    EXPECT_LE(progress.best_value, progress.value * 1.0003);
    monotone = monotone && progress.best_value <= best * 1.0003;
    best = progress.best_value;
  };
  const ExcitationDesign design = design_excitation(ur5(), options);
  EXPECT_EQ(count, 80);
  EXPECT_TRUE(monotone);
  EXPECT_EQ(best, design.summary.final_value);
}

TEST(ExcitationDesign, AnExceptionInTheProgressCallbackComesThrough) {
  ExcitationOptions options = quick_options(80);
  options.progress = [](const ExcitationProgress& progress) {
    if (progress.evaluation == 20) throw std::domain_error("progress sink closed");
  };
  try {
    design_excitation(ur5(), options);
    ADD_FAILURE() << "no exception";
  } catch (const std::domain_error& error) {
    EXPECT_STREQ(error.what(), "progress sink closed");
  }
}

TEST(ExcitationDesign, SummaryReadsWell) {
  const ExcitationDesign design = design_excitation(ur5(), quick_options(30));
  const std::string report = design.summary.brief_report();
  EXPECT_NE(report.find("condition "), std::string::npos) << report;
  EXPECT_NE(report.find("30 evaluations"), std::string::npos) << report;
  EXPECT_NE(report.find("stopped: max_evaluations"), std::string::npos) << report;
  EXPECT_EQ(design.summary.free_coefficients, 6 * 9);
  EXPECT_EQ(design.summary.samples, 120);
}

// ---- Input checks --------------------------------------------------------------------------

TEST(ExcitationOptions, BadOptionsNameTheirField) {
  const Model& model = panda();
  const auto with = [](auto change) {
    ExcitationOptions options;
    change(options);
    return options;
  };
  const auto check = [&](const std::string& field, const ExcitationOptions& options) {
    expect_input_error(field, [&] { options.validate(model); });
    expect_input_error(field, [&] { design_excitation(model, options); });
  };
  check("period", with([](ExcitationOptions& o) { o.period = 0.0; }));
  check("period", with([](ExcitationOptions& o) { o.period = -1.0; }));
  check("period", with([](ExcitationOptions& o) { o.period = std::nan(""); }));
  check("harmonics", with([](ExcitationOptions& o) { o.harmonics = 0; }));
  check("harmonics", with([](ExcitationOptions& o) { o.harmonics = 1; }));
  check("harmonics", with([](ExcitationOptions& o) { o.harmonics = 21; }));
  check("max_acceleration", with([](ExcitationOptions& o) { o.max_acceleration = Eigen::VectorXd::Constant(1, 0.0); }));
  check("max_acceleration", with([](ExcitationOptions& o) {
          o.max_acceleration = Eigen::VectorXd::Constant(1, std::numeric_limits<double>::infinity());
        }));
  check("max_acceleration", with([](ExcitationOptions& o) { o.max_acceleration = Eigen::VectorXd::Constant(3, 5.0); }));
  check("position_margin", with([](ExcitationOptions& o) { o.position_margin = -0.1; }));
  // Panda joint 4 spans 3.002 rad: a 1.6 rad margin on each side leaves nothing.
  check("joint panda_joint4", with([](ExcitationOptions& o) { o.position_margin = 1.6; }));
  check("samples", with([](ExcitationOptions& o) { o.samples = 39; }));
  check("samples", with([](ExcitationOptions& o) { o.samples = -1; }));
  check("random_starts", with([](ExcitationOptions& o) { o.random_starts = 0; }));
  check("local_starts", with([](ExcitationOptions& o) { o.local_starts = 0; }));
  check("max_seconds", with([](ExcitationOptions& o) { o.max_seconds = 0.0; }));
  check("max_evaluations", with([](ExcitationOptions& o) { o.max_evaluations = 0; }));
  EXPECT_NO_THROW(ExcitationOptions{}.validate(model));

  expect_input_error("criterion", [] { parse_excitation_criterion("d-optimal"); });
  EXPECT_EQ(parse_excitation_criterion("logdet"), ExcitationCriterion::logdet);
  EXPECT_EQ(parse_excitation_criterion("condition"), ExcitationCriterion::condition);
}

TEST(ExcitationOptions, AJointThatCannotMoveIsNamed) {
  const std::string xml = testing::with_replaced(panda_urdf(), R"(effort="12" velocity="2.61")", R"(effort="12" velocity="0")");
  const Model model = parse_urdf(xml).model;
  expect_input_error("joint panda_joint5", [&] { design_excitation(model); });
}

TEST(ExcitationOptions, BadSamplingNamesItsField) {
  const FourierTrajectory f = random_trajectory(6, 2, 5, 10.0);
  expect_input_error("dt", [&] { sample_excitation(f, 0.0); });
  expect_input_error("dt", [&] { sample_excitation(f, -0.001); });
  expect_input_error("dt", [&] { sample_excitation(f, std::nan("")); });
  expect_input_error("dt", [&] { sample_excitation(f, 0.003); });  // 3333.3 steps per period
  expect_input_error("dt", [&] { sample_excitation(f, 1.0); });    // 10 per period < 4 × 5
  expect_input_error("dt", [&] { sample_excitation(f, 1e-6, 101); });  // 1e9 samples
  expect_input_error("periods", [&] { sample_excitation(f, 0.001, 0); });
  EXPECT_EQ(sample_excitation(f, 0.5).t.size(), 21);  // 20 per period = 4 × 5: the coarsest allowed

  FourierTrajectory bad = f;
  bad.period = 0.0;
  expect_input_error("period", [&] { sample_excitation(bad, 0.001); });
  bad = f;
  bad.b.resize(2, 4);
  expect_input_error("a", [&] { sample_excitation(bad, 0.001); });
  bad = f;
  bad.q0[1] = std::numeric_limits<double>::infinity();
  expect_input_error("q0", [&] { sample_excitation(bad, 0.001); });
  expect_input_error("q0", [&] { excitation_quality(ur5(), f); });  // 2 joints, the UR5-like arm has 6
}

}  // namespace
}  // namespace manipid::robot
