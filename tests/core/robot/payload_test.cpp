// payload_test.cpp — a tool's mass, centre of mass and inertia on a simulated 6-joint arm: with the true arm, with the arm as identified, known values, no payload, and refusals.
#include "manipid/core/robot/payload.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/urdf.h"
#include "rigid_bodies.h"
#include "robot_test_support.h"
#include "simulated_runs.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace manipid::robot {
namespace {

using testing::Fourier;
using testing::measure;
using testing::measure_excitation;
using testing::uniform_times;

Model ur5_like() { return parse_urdf(testing::read_file(testing::source_path("examples/robots/ur5_like.urdf"))).model; }

/// A tool of 3 kg whose centre of mass is off the flange's axis, a box turned against the tip's axes.
InertialParameters tool(double mass = 3.0, const Eigen::Vector3d& com = Eigen::Vector3d(0.04, -0.03, 0.09)) {
  const Eigen::Matrix3d R = testing::some_rotation();
  return InertialParameters::from_centre_of_mass(mass, com, R * testing::box_inertia(mass, 0.08, 0.06, 0.15) * R.transpose());
}

/// The measurement noise of the real logs: q σ = 2e-5 rad then an 18-bit encoder, τ σ = 1 % of each joint's spread.
void add_noise(Trajectory& data, std::mt19937_64& engine) {
  const Eigen::VectorXd spread = data.tau.colwise().maxCoeff() - data.tau.colwise().minCoeff();
  std::normal_distribution<double> normal;
  const double resolution = 2.0 * std::numbers::pi / 262144.0;
  for (Eigen::Index s = 0; s < data.q.rows(); ++s) {
    for (Eigen::Index k = 0; k < data.q.cols(); ++k) {
      data.q(s, k) = std::round((data.q(s, k) + 2e-5 * normal(engine)) / resolution) * resolution;
      data.tau(s, k) += 0.01 * spread[k] * normal(engine);
    }
  }
}

/// A run of `seconds` at 1 kHz along a random motion (its own period, so it does not stop in the middle).
Trajectory run(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi, double seconds,
               std::mt19937_64& engine, bool noisy, double amplitude = 0.4) {
  Fourier motion = Fourier::random(model.joint_count(), 5, engine, amplitude);
  motion.period = seconds;
  Trajectory data = measure(model, layout, pi, motion, uniform_times(seconds, 1e-3));
  if (noisy) add_noise(data, engine);
  return data;
}

struct Scene {
  Model model = ur5_like();
  ParameterLayout layout;  // viscous and Coulomb friction
  Eigen::VectorXd arm;     // the true arm
  InertialParameters payload = tool();
  Eigen::VectorXd loaded;  // the true arm with the tool
  explicit Scene(std::mt19937_64& engine) {
    arm = testing::perturbed_truth(model, layout, engine);
    loaded = with_payload(model, {layout, arm}, payload.vector());
  }
};

double com_error(const PayloadResult& result, const InertialParameters& truth) {
  return (result.centre_of_mass - truth.centre_of_mass()).norm();
}

TEST(Payload, ExactWithTheTrueArmOnNoiseFreeData) {
  std::mt19937_64 engine(3);
  const Scene scene(engine);
  const Trajectory data = run(scene.model, scene.layout, scene.loaded, 15.0, engine, false);
  const PayloadResult result = identify_payload(scene.model, {scene.layout, scene.arm}, {data}, {});
  ASSERT_TRUE(result.detected);
  EXPECT_NEAR(result.mass, 3.0, 3e-5);
  EXPECT_LT(com_error(result, scene.payload), 1e-5);
  const Eigen::Matrix3d Ic = scene.payload.inertia_about_centre_of_mass();
  const double expected[6] = {Ic(0, 0), Ic(0, 1), Ic(0, 2), Ic(1, 1), Ic(1, 2), Ic(2, 2)};
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(result.inertia[static_cast<std::size_t>(i)], expected[i], 2e-4) << i;
  EXPECT_TRUE(result.undetermined.empty());
  EXPECT_LT(result.with_payload_error, 0.01 * result.arm_only_error);
}

TEST(Payload, NoisyRunWithTheTrueArmAndWithTheArmAsIdentified) {
  // The case: noise as the real logs', a 15 s run with the tool. With the true arm: mass within
  // 0.1 %, centre of mass within 0.5 mm; with the arm identified from a 20 s run without the tool: 1 %, 2 mm.
  std::mt19937_64 engine(5);
  const Scene scene(engine);
  const Trajectory arm_run = run(scene.model, scene.layout, scene.arm, 20.0, engine, true);
  IdentificationOptions arm_options;
  arm_options.layout = scene.layout;
  const IdentificationResult arm = identify(scene.model, arm_run, arm_options);
  const Trajectory data = run(scene.model, scene.layout, scene.loaded, 15.0, engine, true);

  const PayloadResult exact_arm = identify_payload(scene.model, {scene.layout, scene.arm}, {data}, {});
  EXPECT_NEAR(exact_arm.mass, 3.0, 3e-3);
  EXPECT_LT(com_error(exact_arm, scene.payload), 5e-4);
  // The standard errors are honest: the truth within 4 of them.
  EXPECT_LT(std::abs(exact_arm.mass - 3.0), 4.0 * exact_arm.mass_std_error);
  // On white noise the jackknife over blocks of time agrees with the formula: no inflation to speak of.
  EXPECT_LT(exact_arm.variance_inflation, 2.0);

  const PayloadResult identified_arm = identify_payload(scene.model, {arm.layout, arm.point}, {data}, {});
  EXPECT_NEAR(identified_arm.mass, 3.0, 0.03);
  EXPECT_LT(com_error(identified_arm, scene.payload), 2e-3);
  for (const std::string& warning : identified_arm.warnings) EXPECT_EQ(warning.find("explains little"), std::string::npos) << warning;

  // A held-out run with the tool is predicted as well as with the true tool on the identified arm.
  const Trajectory other = run(scene.model, scene.layout, scene.loaded, 15.0, engine, true);
  PayloadResult true_tool = identified_arm;
  true_tool.estimate = scene.payload.vector();
  const PayloadOptions options;
  const PayloadValidation estimated = validate_payload(scene.model, {arm.layout, arm.point}, identified_arm, {other}, options);
  const PayloadValidation reference = validate_payload(scene.model, {arm.layout, arm.point}, true_tool, {other}, options);
  EXPECT_LT(estimated.with_payload.overall_relative_error, 1.1 * reference.with_payload.overall_relative_error);
  EXPECT_LT(estimated.with_payload.overall_relative_error, 0.5 * estimated.arm_only.overall_relative_error);
}

TEST(Payload, ARunWithoutPayloadAnswersZeroWithinItsUncertainty) {
  std::mt19937_64 engine(7);
  const Scene scene(engine);
  const Trajectory data = run(scene.model, scene.layout, scene.arm, 15.0, engine, true);
  const PayloadResult result = identify_payload(scene.model, {scene.layout, scene.arm}, {data}, {});
  EXPECT_FALSE(result.detected);
  EXPECT_LT(std::abs(result.mass), 3.0 * result.mass_std_error);
  EXPECT_GT(result.mass_std_error, 0.0);
  EXPECT_TRUE(std::isnan(result.centre_of_mass[0]));
  ASSERT_FALSE(result.warnings.empty());
  EXPECT_NE(result.warnings.back().find("no payload"), std::string::npos) << result.warnings.back();
}

TEST(Payload, AKnownMassOrCentreOfMassIsKeptAndTheRestEstimated) {
  std::mt19937_64 engine(11);
  const Scene scene(engine);
  const Trajectory data = run(scene.model, scene.layout, scene.loaded, 15.0, engine, true);
  PayloadOptions options;
  options.known_mass = 3.0;
  const PayloadResult mass_known = identify_payload(scene.model, {scene.layout, scene.arm}, {data}, options);
  EXPECT_EQ(mass_known.mass, 3.0);
  EXPECT_EQ(mass_known.mass_std_error, 0.0);
  EXPECT_LT(com_error(mass_known, scene.payload), 5e-4);
  options.known_mass.reset();
  options.known_centre_of_mass = scene.payload.centre_of_mass();
  const PayloadResult centre_known = identify_payload(scene.model, {scene.layout, scene.arm}, {data}, options);
  EXPECT_NEAR(centre_known.mass, 3.0, 3e-3);
  EXPECT_EQ(centre_known.centre_of_mass, scene.payload.centre_of_mass());
  EXPECT_EQ(centre_known.centre_of_mass_std_errors, Eigen::Vector3d::Zero());
  EXPECT_EQ(centre_known.data_share[1], 1.0);
}

TEST(Payload, MotionAboutOneVerticalAxisLeavesMostUndeterminedAndSaysSo) {
  // Only the first joint (a vertical axis) moves: gravity's torque never changes and the tool turns about
  // one axis only, so most of its parameters are not seen; whatever the run cannot determine is named and
  // stays at 0.
  std::mt19937_64 engine(13);
  const Scene scene(engine);
  Fourier motion = Fourier::random(6, 5, engine, 0.4);
  motion.period = 15.0;
  motion.a.bottomRows(5).setZero();
  motion.b.bottomRows(5).setZero();
  const Trajectory data = measure(scene.model, scene.layout, scene.loaded, motion, uniform_times(15.0, 1e-3));
  const PayloadResult result = identify_payload(scene.model, {scene.layout, scene.arm}, {data}, {});
  ASSERT_FALSE(result.undetermined.empty());
  for (const std::string& name : result.undetermined) {
    int index = 0;
    while (PayloadResult::names()[static_cast<std::size_t>(index)] != name) ++index;
    EXPECT_LT(result.data_share[index], 0.5) << name;
    EXPECT_LT(std::abs(result.estimate[index]), 1e-9) << name;
    bool named = false;
    for (const std::string& warning : result.warnings) named = named || warning.find("excite " + name + " ") != std::string::npos;
    EXPECT_TRUE(named) << name;
  }
}

TEST(Payload, ARunOfAnotherArmIsNamedNotPassedOffAsAPayload) {
  // The run comes from an arm whose upper arm and forearm (links 2 and 3) are half again as heavy: the residual
  // is no payload's. Whatever the fit makes of it, the answer says so — a negative mass, or a payload that
  // explains little. (A heavier wrist would be a payload to the tip link: nothing could tell them apart.)
  std::mt19937_64 engine(19);
  const Scene scene(engine);
  Eigen::VectorXd other = scene.arm;
  other.segment(10, 20) *= 1.5;
  const Trajectory data = run(scene.model, scene.layout, other, 15.0, engine, true);
  const PayloadResult result = identify_payload(scene.model, {scene.layout, scene.arm}, {data}, {});
  bool said = false;
  for (const std::string& warning : result.warnings) {
    said = said || warning.find("not a payload's") != std::string::npos || warning.find("explains little") != std::string::npos;
  }
  EXPECT_TRUE(said) << result.mass << " ± " << result.mass_std_error << " kg; " << result.arm_only_error << " -> "
                    << result.with_payload_error;
}

TEST(Payload, PhysicalLeavesARealBodyAloneAndMakesTheRestOne) {
  // A 3 kg tool on a noisy run: its least-squares values are a real body already, and the physical fit
  // changes nothing. A small heavy sphere (a 2 kg point, 1 cm in radius): the noise puts its least-squares
  // inertia about the centre of mass where no body has one, and the physical fit makes it one at almost no
  // cost to the fit, keeping mass and centre of mass.
  std::mt19937_64 engine(29);
  Scene scene(engine);
  PayloadOptions physical;
  physical.physical = true;
  const Trajectory tool_run = run(scene.model, scene.layout, scene.loaded, 15.0, engine, true);
  const PayloadResult plain = identify_payload(scene.model, {scene.layout, scene.arm}, {tool_run}, {});
  const PayloadResult kept = identify_payload(scene.model, {scene.layout, scene.arm}, {tool_run}, physical);
  ASSERT_TRUE(plain.consistent);
  ASSERT_TRUE(kept.physical.has_value());
  EXPECT_TRUE(kept.physical->least_squares_consistent);
  EXPECT_EQ(kept.estimate, plain.estimate);

  const Eigen::Vector3d centre(0.02, 0.05, 0.07);
  scene.payload = InertialParameters::from_centre_of_mass(2.0, centre, Eigen::Matrix3d::Identity() * 0.4 * 2.0 * 1e-4);
  scene.loaded = with_payload(scene.model, {scene.layout, scene.arm}, scene.payload.vector());
  const Trajectory sphere_run = run(scene.model, scene.layout, scene.loaded, 15.0, engine, true);
  const PayloadResult least_squares = identify_payload(scene.model, {scene.layout, scene.arm}, {sphere_run}, {});
  ASSERT_FALSE(least_squares.consistent) << "the case must exercise the fit";
  bool said = false;
  for (const std::string& warning : least_squares.warnings) said = said || warning.find("not a real rigid body") != std::string::npos;
  EXPECT_TRUE(said);
  const PayloadResult real = identify_payload(scene.model, {scene.layout, scene.arm}, {sphere_run}, physical);
  ASSERT_TRUE(real.physical.has_value());
  EXPECT_FALSE(real.physical->least_squares_consistent);
  EXPECT_FALSE(real.physical->least_squares_findings.empty());
  EXPECT_TRUE(real.consistent);
  EXPECT_TRUE(check_link(real.estimate, "payload").consistent());
  EXPECT_NEAR(real.mass, 2.0, 0.02);
  EXPECT_LT(com_error(real, scene.payload), 2e-3);
  EXPECT_LT(real.physical->relative_cost_increase, 1e-2);
  EXPECT_GE(real.with_payload_error, least_squares.with_payload_error);

  // A known mass and centre of mass hold through the physical fit.
  physical.known_mass = 2.0;
  physical.known_centre_of_mass = centre;
  const PayloadResult held = identify_payload(scene.model, {scene.layout, scene.arm}, {sphere_run}, physical);
  EXPECT_TRUE(held.consistent);
  EXPECT_NEAR(held.estimate[0], 2.0, 2e-5);
  EXPECT_LT((held.estimate.segment<3>(1) / held.estimate[0] - centre).norm(), 1e-5);
}

TEST(Payload, PhysicalOnARunWithoutPayloadKeepsTheAnswerAndSaysWhy) {
  std::mt19937_64 engine(31);
  const Scene scene(engine);
  const Trajectory data = run(scene.model, scene.layout, scene.arm, 15.0, engine, true);
  PayloadOptions options;
  options.physical = true;
  const PayloadResult result = identify_payload(scene.model, {scene.layout, scene.arm}, {data}, options);
  EXPECT_FALSE(result.detected);
  EXPECT_FALSE(result.physical.has_value());
  bool said = false;
  for (const std::string& warning : result.warnings) said = said || warning.find("no physical fit") != std::string::npos;
  EXPECT_TRUE(said);
}

TEST(Payload, AFewSecondsOfDesignedWristMotionDetermineTheTool) {
  // `excitation --payload`: 5 s in which only the wrist (joints 4–6) moves, the rest holding the pose the design
  // chose. Its payload columns are well conditioned (column-scaled condition < 2.5), every joint that holds still
  // has no motion at all, and on the run with the 3 kg tool and the real logs' noise every payload parameter
  // is determined: mass within 1 %, centre of mass within 3 mm (measured: 2.9994 ± 0.012 kg, 1.8 mm; the
  // condition number 1.72 against 6.4 for the random motion). A random wrist motion of the same length and
  // size does worse by the design's own measure.
  std::mt19937_64 engine(37);
  const Scene scene(engine);
  ExcitationOptions options;
  options.target = ExcitationTarget::payload;
  options.moving_joints = {3, 4, 5};
  options.period = 5.0;
  options.harmonics = 3;
  options.max_evaluations = 1500;
  const ExcitationDesign design = design_excitation(scene.model, options);
  EXPECT_EQ(design.summary.target, ExcitationTarget::payload);
  EXPECT_EQ(design.summary.base_parameters, 10);
  EXPECT_LT(design.summary.condition_number, 2.5);
  EXPECT_NE(design.summary.brief_report().find("10 payload parameters"), std::string::npos);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(design.trajectory.a.row(k).cwiseAbs().maxCoeff(), 0.0) << k;
    EXPECT_EQ(design.trajectory.b.row(k).cwiseAbs().maxCoeff(), 0.0) << k;
  }
  FourierTrajectory random = design.trajectory;
  std::normal_distribution<double> normal;
  for (int k = 3; k < 6; ++k) {
    for (int l = 1; l < random.harmonics(); ++l) {
      random.a(k, l) = normal(engine);
      random.b(k, l) = normal(engine);
    }
    random.a(k, 0) = -random.a.row(k).tail(random.harmonics() - 1).sum();
    double weighted = 0.0;
    for (int l = 2; l <= random.harmonics(); ++l) weighted += l * random.b(k, l - 1);
    random.b(k, 0) = -weighted;
    const double size = std::sqrt(design.trajectory.a.row(k).squaredNorm() + design.trajectory.b.row(k).squaredNorm()) /
                        std::sqrt(random.a.row(k).squaredNorm() + random.b.row(k).squaredNorm());
    random.a.row(k) *= size;
    random.b.row(k) *= size;
  }
  EXPECT_LT(design.summary.condition_number, excitation_quality(scene.model, random, options).condition_number);

  Trajectory data = measure_excitation(scene.model, scene.layout, scene.loaded, design.trajectory, 1e-3, 1);
  add_noise(data, engine);
  const PayloadResult result = identify_payload(scene.model, {scene.layout, scene.arm}, {data}, {});
  EXPECT_TRUE(result.undetermined.empty());
  EXPECT_NEAR(result.mass, 3.0, 0.03) << result.mass_std_error;
  EXPECT_LT(com_error(result, scene.payload), 3e-3);
}

TEST(Payload, ExcitationRefusesMovingJointsOutsideTheArm) {
  std::mt19937_64 engine(41);
  const Scene scene(engine);
  ExcitationOptions options;
  options.target = ExcitationTarget::payload;
  options.moving_joints = {3, 6};
  try {
    (void)design_excitation(scene.model, options);
    ADD_FAILURE() << "joint 7 of a 6-joint arm was accepted";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "moving_joints");
    EXPECT_NE(std::string(error.what()).find("joint 7 is not one of the robot's 6"), std::string::npos) << error.what();
  }
  options.moving_joints = {4, 4};
  try {
    (void)design_excitation(scene.model, options);
    ADD_FAILURE() << "a joint named twice was accepted";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "moving_joints");
  }
}

TEST(Payload, RefusalsNameTheirField) {
  std::mt19937_64 engine(17);
  const Scene scene(engine);
  const Trajectory data = run(scene.model, scene.layout, scene.loaded, 5.0, engine, false);
  const auto field_of = [&](const ArmParameters& arm, const std::vector<Trajectory>& runs, const PayloadOptions& options) {
    try {
      identify_payload(scene.model, arm, runs, options);
    } catch (const InputError& error) {
      return std::string(error.field());
    }
    return std::string("none");
  };
  EXPECT_EQ(field_of({scene.layout, scene.arm.head(10)}, {data}, {}), "arm");
  EXPECT_EQ(field_of({scene.layout, scene.arm}, {}, {}), "dataset_ids");
  PayloadOptions negative;
  negative.known_mass = -1.0;
  EXPECT_EQ(field_of({scene.layout, scene.arm}, {data}, negative), "known_mass");
  Trajectory no_torque = data;
  no_torque.tau.resize(0, 0);
  EXPECT_EQ(field_of({scene.layout, scene.arm}, {no_torque}, {}), "tau");
}

}  // namespace
}  // namespace manipid::robot
