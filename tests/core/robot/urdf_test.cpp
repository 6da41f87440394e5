// urdf_test.cpp — URDF → robot::Model: conventions, merging, chain selection, every refusal and warning.
#include "manipid/core/errors.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/robot/urdf.h"
#include "robot_test_support.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <thread>

namespace manipid::robot {
namespace {

using testing::arm7_urdf;
using testing::random_vector;
using testing::with_appended;
using testing::with_replaced;

Eigen::Matrix3d Rx(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }
Eigen::Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }
Eigen::Matrix3d Rz(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

bool any_contains(const std::vector<std::string>& lines, const std::string& part) {
  return std::any_of(lines.begin(), lines.end(), [&](const std::string& line) { return contains(line, part); });
}

/// A one-joint robot: link "base", joint "j" (type, origin, axis), link "body" with `inertial` (XML, may
/// be empty).
std::string one_joint(const std::string& type, const std::string& xyz, const std::string& rpy, const std::string& axis,
                      const std::string& inertial) {
  return R"(<robot name="one"><link name="base"/>
  <joint name="j" type=")" + type + R"("><parent link="base"/><child link="body"/>
    <origin xyz=")" + xyz + R"(" rpy=")" + rpy + R"("/><axis xyz=")" + axis + R"("/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <link name="body">)" + inertial + R"(</link></robot>)";
}

std::string inertial_xml(double mass, const std::string& xyz, const std::string& rpy, const std::string& inertia) {
  return "<inertial><origin xyz=\"" + xyz + "\" rpy=\"" + rpy + "\"/><mass value=\"" + std::to_string(mass) +
         "\"/><inertia " + inertia + "/></inertial>";
}

/// Parses, expecting an InputError whose field is `field` and whose one-line message holds each of `parts`;
/// nothing may reach stderr (urdfdom's console output is captured).
void expect_refused(const std::string& xml, const UrdfOptions& options, const std::string& field,
                    std::initializer_list<std::string> parts) {
  ::testing::internal::CaptureStderr();
  try {
    parse_urdf(xml, options);
    const std::string stderr_text = ::testing::internal::GetCapturedStderr();
    ADD_FAILURE() << "accepted; expected an InputError on " << field;
  } catch (const InputError& error) {
    const std::string stderr_text = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(error.field(), field) << error.what();
    for (const std::string& part : parts) EXPECT_TRUE(contains(error.what(), part)) << error.what() << "\nlacks: " << part;
    EXPECT_FALSE(contains(error.what(), "\n")) << error.what();
    EXPECT_EQ(stderr_text, "") << "urdfdom printed instead of the message being captured";
  }
}
void expect_refused(const std::string& xml, const std::string& field, std::initializer_list<std::string> parts) {
  expect_refused(xml, UrdfOptions{}, field, parts);
}

// ---- the test arm --------------------------------------------------------------------------------------

TEST(Urdf, Arm7ChainJointsLimitsAndFriction) {
  const ParsedUrdf parsed = parse_urdf(arm7_urdf());
  const Model& model = parsed.model;
  EXPECT_TRUE(parsed.warnings.empty()) << parsed.warnings.front();
  EXPECT_EQ(model.name, "arm7");
  EXPECT_EQ(model.base_link, "world");
  EXPECT_EQ(model.tip_link, "flange");  // the only leaf
  ASSERT_EQ(model.joint_count(), 7);
  ASSERT_EQ(model.bodies.size(), 7u);
  for (int k = 1; k <= 7; ++k) {
    EXPECT_EQ(model.joints[k - 1].name, "j" + std::to_string(k));
    EXPECT_EQ(model.joints[k - 1].link, "link" + std::to_string(k));
    EXPECT_EQ(model.bodies[k - 1].links.front(), "link" + std::to_string(k));
  }
  EXPECT_EQ(model.bodies[6].links, (std::vector<std::string>{"link7", "flange"}));
  EXPECT_EQ(model.joints[0].type, JointType::revolute);
  EXPECT_EQ(model.joints[2].type, JointType::continuous);
  EXPECT_EQ(model.gravity, Eigen::Vector3d(0, 0, -9.81));

  // Limits kept as given; a continuous joint has no position limits but keeps effort and velocity.
  const JointLimits& l1 = model.joints[0].limits;
  EXPECT_EQ(l1.lower, -2.9);
  EXPECT_EQ(l1.upper, 2.9);
  EXPECT_EQ(l1.effort, 87.0);
  EXPECT_EQ(l1.velocity, 2.2);
  EXPECT_EQ(model.joints[3].limits.upper, -0.07);
  const JointLimits& l3 = model.joints[2].limits;
  EXPECT_EQ(l3.lower, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(l3.upper, std::numeric_limits<double>::infinity());
  EXPECT_EQ(l3.effort, 87.0);
  EXPECT_EQ(model.joints[0].damping, 0.9);
  EXPECT_EQ(model.joints[0].friction, 1.2);
  EXPECT_EQ(model.joints[6].damping, 0.1);

  // The mount (fixed, before joint 1) composes into joint 1's placement: Trans(0.1 0.2 0.05)·Rz(0.3)
  // then Trans(0 0 0.3)·Rz(0.2). The world's and link0's inertia never enter the model.
  EXPECT_LE((model.joints[0].placement.translation - Eigen::Vector3d(0.1, 0.2, 0.35)).norm(), 1e-15);
  EXPECT_LE((model.joints[0].placement.rotation - Rz(0.5)).norm(), 1e-15);
  double total_mass = 0.0;
  for (const Body& body : model.bodies) total_mass += body.inertia.mass;
  EXPECT_NEAR(total_mass, 3.2 + 2.7 + 2.4 + 2.1 + 1.6 + 1.2 + 0.55 + 0.35, 1e-12);

  // Tilted axes are unit already; signs kept.
  EXPECT_EQ(model.joints[2].axis, Eigen::Vector3d(0, 0, -1));
  EXPECT_LE((model.joints[5].axis - Eigen::Vector3d(0.36, 0.48, 0.8)).norm(), 1e-15);
  EXPECT_EQ(model.joints[6].axis, Eigen::Vector3d(-1, 0, 0));
}

TEST(Urdf, ParsingASoundUrdfPrintsNothing) {
  ::testing::internal::CaptureStderr();
  ::testing::internal::CaptureStdout();
  const ParsedUrdf parsed = parse_urdf(arm7_urdf());
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  EXPECT_EQ(parsed.model.joint_count(), 7);
}

TEST(Urdf, ConcurrentParsesKeepTheirOwnMessages) {
  // urdfdom's console handler is process-global: each parse must still get exactly its own errors.
  const std::string good = arm7_urdf();
  const std::string bad = with_replaced(good, R"(<mass value="2.4"/>)", R"(<mass value="heavy"/>)");
  std::vector<std::thread> threads;
  std::vector<int> failures(4, 0);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 25; ++i) {
        try {
          const ParsedUrdf parsed = parse_urdf(t % 2 ? bad : good);
          if (t % 2 || !parsed.warnings.empty() || parsed.model.joint_count() != 7) ++failures[t];
        } catch (const InputError& error) {
          if (!(t % 2) || error.field() != "link link3" || contains(error.what(), "effort")) ++failures[t];
        }
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(failures, std::vector<int>(4, 0));
}

// ---- conventions ---------------------------------------------------------------------------------------

TEST(Urdf, RpyIsFixedAxisRollPitchYaw) {
  const double roll = 0.3, pitch = -0.5, yaw = 1.1;
  const Model model = parse_urdf(one_joint("revolute", "0.1 -0.2 0.3", "0.3 -0.5 1.1", "0 0 1", "")).model;
  const Eigen::Matrix3d expected = Rz(yaw) * Ry(pitch) * Rx(roll);
  EXPECT_LE((model.joints[0].placement.rotation - expected).norm(), 1e-15);
  EXPECT_GT((model.joints[0].placement.rotation - Rx(roll) * Ry(pitch) * Rz(yaw)).norm(), 0.1);  // not the reverse
  EXPECT_EQ(model.joints[0].placement.translation, Eigen::Vector3d(0.1, -0.2, 0.3));
  EXPECT_LE((rotation_from_rpy(roll, pitch, yaw) - expected).norm(), 1e-15);
}

TEST(Urdf, AxisSignIsKeptAndNonUnitAxisIsNormalisedWithAWarning) {
  EXPECT_EQ(parse_urdf(one_joint("revolute", "0 0 0", "0 0 0", "0 0 -1", "")).model.joints[0].axis,
            Eigen::Vector3d(0, 0, -1));
  const ParsedUrdf scaled = parse_urdf(one_joint("revolute", "0 0 0", "0 0 0", "0 -3 4", ""));
  EXPECT_LE((scaled.model.joints[0].axis - Eigen::Vector3d(0, -0.6, 0.8)).norm(), 1e-16);
  EXPECT_TRUE(any_contains(scaled.warnings, "joint j: axis (0 -3 4) has norm 5; normalised"));
  // Rounded to 7 digits: normalised silently.
  const ParsedUrdf rounded = parse_urdf(one_joint("revolute", "0 0 0", "0 0 0", "0 0.7071068 0.7071068", ""));
  EXPECT_NEAR(rounded.model.joints[0].axis.norm(), 1.0, 1e-15);
  EXPECT_FALSE(any_contains(rounded.warnings, "normalised"));
}

TEST(Urdf, InertialRpyRotatesTheInertiaIntoLinkAxes) {
  const std::string diagonal = R"(ixx="1" ixy="0" ixz="0" iyy="2" iyz="0" izz="3")";
  // yaw 90°: the inertial frame's x is the link's y.
  Model model = parse_urdf(one_joint("revolute", "0 0 0", "0 0 0", "0 0 1",
                                     inertial_xml(2.0, "0 0 0", "0 0 1.5707963267948966", diagonal))).model;
  EXPECT_LE((model.bodies[0].inertia.inertia - Eigen::Vector3d(2, 1, 3).asDiagonal().toDenseMatrix()).norm(), 1e-15);
  // roll 90°: y and z swap.
  model = parse_urdf(one_joint("revolute", "0 0 0", "0 0 0", "0 0 1",
                               inertial_xml(2.0, "0 0 0", "1.5707963267948966 0 0", diagonal))).model;
  EXPECT_LE((model.bodies[0].inertia.inertia - Eigen::Vector3d(1, 3, 2).asDiagonal().toDenseMatrix()).norm(), 1e-15);
  // A general rpy: R I Rᵀ.
  model = parse_urdf(one_joint("revolute", "0 0 0", "0 0 0", "0 0 1",
                               inertial_xml(2.0, "0 0 0", "0.4 -0.3 0.2", diagonal))).model;
  const Eigen::Matrix3d R = Rz(0.2) * Ry(-0.3) * Rx(0.4);
  EXPECT_LE((model.bodies[0].inertia.inertia - R * Eigen::Vector3d(1, 2, 3).asDiagonal() * R.transpose()).norm(), 1e-15);
}

TEST(Urdf, ProductsOfInertiaAreTensorEntriesAndShiftToTheLinkOrigin) {
  const Model model =
      parse_urdf(one_joint("revolute", "0 0 0", "0 0 0", "0 0 1",
                           inertial_xml(2.0, "0.1 0.2 0.3", "0 0 0",
                                        R"(ixx="0.5" ixy="0.01" ixz="-0.02" iyy="0.4" iyz="0.03" izz="0.3")")))
          .model;
  const InertialParameters& p = model.bodies[0].inertia;
  EXPECT_EQ(p.mass, 2.0);
  EXPECT_LE((p.first_moment - Eigen::Vector3d(0.2, 0.4, 0.6)).norm(), 1e-16);
  // I_O = I_c + m (‖c‖² E − c cᵀ), written out entry by entry; ixy etc. are the tensor's own entries.
  const double m = 2.0, x = 0.1, y = 0.2, z = 0.3;
  EXPECT_NEAR(p.inertia(0, 0), 0.5 + m * (y * y + z * z), 1e-15);
  EXPECT_NEAR(p.inertia(1, 1), 0.4 + m * (x * x + z * z), 1e-15);
  EXPECT_NEAR(p.inertia(2, 2), 0.3 + m * (x * x + y * y), 1e-15);
  EXPECT_NEAR(p.inertia(0, 1), 0.01 - m * x * y, 1e-15);
  EXPECT_NEAR(p.inertia(0, 2), -0.02 - m * x * z, 1e-15);
  EXPECT_NEAR(p.inertia(1, 2), 0.03 - m * y * z, 1e-15);
  EXPECT_EQ(p.inertia, p.inertia.transpose());
  // And back.
  EXPECT_LE((p.centre_of_mass() - Eigen::Vector3d(x, y, z)).norm(), 1e-16);
  Eigen::Matrix3d about_com;
  about_com << 0.5, 0.01, -0.02, 0.01, 0.4, 0.03, -0.02, 0.03, 0.3;
  EXPECT_LE((p.inertia_about_centre_of_mass() - about_com).norm(), 1e-15);
}

/// Link 2 of a two-joint arm either carries a flange through a fixed joint (rotated origin, its own
/// inertial rpy), or carries the same mass merged by hand: the classic route, the combined centre of mass and
/// each part's inertia shifted to it. Both must give the same model and torques.
TEST(Urdf, FixedFlangeMergesLikeAHandMergedInertial) {
  const double m1 = 1.7, m2 = 0.6;
  const Eigen::Vector3d c1(0.05, -0.02, 0.12), c2(0.01, 0.03, 0.02);  // in link2 / in the flange
  const Eigen::Vector3d rpy1(0.2, -0.1, 0.3), rpy2(0.4, 0.5, -0.6);    // inertial frames
  const Eigen::Vector3d flange_xyz(0.02, -0.01, 0.15), flange_rpy(0.3, -0.7, 1.2);
  Eigen::Matrix3d I1, I2;  // about each centre of mass, in its inertial frame
  I1 << 0.02, 0.001, -0.002, 0.001, 0.018, 0.0015, -0.002, 0.0015, 0.009;
  I2 << 0.003, -0.0002, 0.0001, -0.0002, 0.002, 0.0003, 0.0001, 0.0003, 0.0025;
  auto rpy = [](const Eigen::Vector3d& a) -> Eigen::Matrix3d { return Rz(a.z()) * Ry(a.y()) * Rx(a.x()); };
  auto text = [](const Eigen::Vector3d& v) {
    char buffer[128];
    std::snprintf(buffer, sizeof buffer, "%.17g %.17g %.17g", v.x(), v.y(), v.z());
    return std::string(buffer);
  };
  auto inertia_text = [](const Eigen::Matrix3d& I) {
    char buffer[256];
    std::snprintf(buffer, sizeof buffer, R"(ixx="%.17g" ixy="%.17g" ixz="%.17g" iyy="%.17g" iyz="%.17g" izz="%.17g")",
                  I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2));
    return std::string(buffer);
  };
  const std::string arm_head = R"(<robot name="two"><link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/><origin xyz="0 0 0.3" rpy="0.1 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <link name="link1">)" +
                               inertial_xml(2.5, "0.01 0.02 0.1", "0 0 0",
                                            R"(ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.01")") +
                               R"(</link>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/><origin xyz="0.05 0 0.2" rpy="0 0.4 0"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="2"/></joint>)";
  const std::string with_flange = arm_head + R"(<link name="link2">)" + inertial_xml(m1, text(c1), text(rpy1), inertia_text(I1)) +
                                  R"(</link><joint name="flange_joint" type="fixed"><parent link="link2"/><child link="flange"/>
    <origin xyz=")" + text(flange_xyz) + R"(" rpy=")" + text(flange_rpy) + R"("/></joint>
  <link name="flange">)" + inertial_xml(m2, text(c2), text(rpy2), inertia_text(I2)) + "</link></robot>";

  // By hand: both parts in link2's axes, about the combined centre of mass.
  const Eigen::Matrix3d Rf = rpy(flange_rpy);
  const Eigen::Vector3d c2_link = flange_xyz + Rf * c2;
  const Eigen::Vector3d c = (m1 * c1 + m2 * c2_link) / (m1 + m2);
  auto shift = [](double m, const Eigen::Vector3d& d) {
    return Eigen::Matrix3d(m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
  };
  const Eigen::Matrix3d I1_link = rpy(rpy1) * I1 * rpy(rpy1).transpose();
  const Eigen::Matrix3d I2_link = Rf * rpy(rpy2) * I2 * rpy(rpy2).transpose() * Rf.transpose();
  const Eigen::Matrix3d merged = I1_link + shift(m1, c1 - c) + I2_link + shift(m2, c2_link - c);
  const std::string by_hand = arm_head + R"(<link name="link2">)" +
                              inertial_xml(m1 + m2, text(c), "0 0 0", inertia_text(merged)) + "</link></robot>";

  const Model a = parse_urdf(with_flange).model, b = parse_urdf(by_hand).model;
  EXPECT_EQ(a.bodies[1].links, (std::vector<std::string>{"link2", "flange"}));
  EXPECT_LE((a.bodies[1].inertia.vector() - b.bodies[1].inertia.vector()).norm(), 1e-14);
  EXPECT_NEAR(a.bodies[1].inertia.mass, m1 + m2, 1e-15);

  const ParameterLayout rigid{.viscous = false, .coulomb = false};
  std::mt19937_64 engine(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd q = random_vector(engine, 2, M_PI), qd = random_vector(engine, 2, 3.0),
                          qdd = random_vector(engine, 2, 10.0);
    const Eigen::VectorXd tau_a = inverse_dynamics(a, rigid, standard_parameters(a, rigid), q, qd, qdd);
    const Eigen::VectorXd tau_b = inverse_dynamics(b, rigid, standard_parameters(b, rigid), q, qd, qdd);
    EXPECT_LE(testing::relative_error(tau_a, tau_b), 1e-13);
  }
  // The flange's rotation matters: with only its translation the merged inertia differs.
  const Model translation_only = parse_urdf(with_replaced(with_flange, text(flange_rpy), "0 0 0")).model;
  EXPECT_GT((translation_only.bodies[1].inertia.vector() - b.bodies[1].inertia.vector()).norm(), 1e-4);
}

// ---- chain selection -----------------------------------------------------------------------------------

const char* kCamera = R"(<joint name="camera_joint" type="fixed"><parent link="link4"/><child link="camera"/>
    <origin xyz="0.03 0.05 -0.02" rpy="0.3 0.2 -0.4"/></joint>
  <link name="camera"><inertial><origin xyz="0.01 0.0 0.02" rpy="0 0.2 0"/><mass value="0.4"/>
    <inertia ixx="0.0004" ixy="0.00001" ixz="0" iyy="0.0003" iyz="0" izz="0.0002"/></inertial></link>
)";

TEST(Urdf, SideBranchFixedLinksAreMergedIntoTheirBody) {
  const ParsedUrdf parsed = parse_urdf(with_appended(arm7_urdf(), kCamera), UrdfOptions{.tip = "flange"});
  EXPECT_TRUE(parsed.warnings.empty());
  const Model plain = parse_urdf(arm7_urdf()).model;
  EXPECT_EQ(parsed.model.bodies[3].links, (std::vector<std::string>{"link4", "camera"}));
  EXPECT_NEAR(parsed.model.bodies[3].inertia.mass, plain.bodies[3].inertia.mass + 0.4, 1e-15);
  for (int k : {0, 1, 2, 4, 5, 6}) EXPECT_EQ(parsed.model.bodies[k].inertia.vector(), plain.bodies[k].inertia.vector());
}

TEST(Urdf, SeveralLeavesAreListed) {
  expect_refused(with_appended(arm7_urdf(), kCamera), "tip", {"2 leaves below base link world", "camera", "flange"});
}

TEST(Urdf, BodiesBeyondAMovingJointOffTheChainAreLeftOutWithAWarning) {
  const std::string finger = R"(<joint name="finger_joint" type="prismatic"><parent link="flange"/><child link="finger"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.04" effort="20" velocity="0.2"/></joint>
  <link name="finger"><inertial><mass value="0.1"/>
    <inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial></link>
  <joint name="finger_tip_joint" type="fixed"><parent link="finger"/><child link="finger_tip"/></joint>
  <link name="finger_tip"/>
)";
  const ParsedUrdf parsed = parse_urdf(with_appended(arm7_urdf(), finger), UrdfOptions{.tip = "flange"});
  ASSERT_EQ(parsed.warnings.size(), 1u);
  EXPECT_EQ(parsed.warnings[0],
            "joint finger_joint (prismatic) is not on the chain from world to flange: links finger, finger_tip are left "
            "out of the dynamics");
  EXPECT_EQ(parsed.model.joint_count(), 7);
  EXPECT_EQ(parsed.model.bodies[6].inertia.vector(), parse_urdf(arm7_urdf()).model.bodies[6].inertia.vector());
  // Without a tip, the only leaf is the finger's tip: the chain then ends there, through the prismatic joint.
  const Model longer = parse_urdf(with_appended(arm7_urdf(), finger)).model;
  EXPECT_EQ(longer.joint_count(), 8);
  EXPECT_EQ(longer.joints[7].type, JointType::prismatic);
  EXPECT_EQ(longer.tip_link, "finger_tip");
}

TEST(Urdf, LinkWithoutInertialIsMasslessWithAWarning) {
  const ParsedUrdf parsed = parse_urdf(one_joint("continuous", "0 0 0", "0 0 0", "0 0 1", ""));
  EXPECT_EQ(parsed.warnings, (std::vector<std::string>{"link body has no <inertial>: counted as massless"}));
  EXPECT_EQ(parsed.model.bodies[0].inertia.vector(), (Eigen::Matrix<double, 10, 1>::Zero()));
  EXPECT_EQ(parsed.model.joints[0].limits.velocity, 2.0);
  EXPECT_EQ(parsed.model.joints[0].limits.lower, -std::numeric_limits<double>::infinity());
}

TEST(Urdf, BaseAndTipSelectASubChain) {
  const ParsedUrdf full_parse = parse_urdf(arm7_urdf());
  const Model& full = full_parse.model;
  // Base link3: gravity must then be given in link3's frame (it moves relative to the root). At q1..3 = 0,
  // link3's axes in the world's are the product of the first three placements.
  Eigen::Matrix3d world_to_link3 = Eigen::Matrix3d::Identity();
  for (int k = 0; k < 3; ++k) world_to_link3 = world_to_link3 * full.joints[k].placement.rotation;
  const Eigen::Vector3d gravity3 = world_to_link3.transpose() * full.gravity;
  const Model sub = parse_urdf(arm7_urdf(), UrdfOptions{.base = "link3", .tip = "link7",
                                                        .gravity = gravity3, .gravity_frame = GravityFrame::base})
                        .model;
  ASSERT_EQ(sub.joint_count(), 4);
  EXPECT_EQ(sub.joints[0].name, "j4");
  EXPECT_EQ(sub.joints[3].name, "j7");
  EXPECT_EQ(sub.base_link, "link3");
  EXPECT_EQ(sub.tip_link, "link7");
  // The flange below the tip is still rigidly attached to body 4: merged.
  EXPECT_EQ(sub.bodies[3].links, (std::vector<std::string>{"link7", "flange"}));

  const ParameterLayout rigid{.viscous = false, .coulomb = false};
  std::mt19937_64 engine(17);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(7), qd = Eigen::VectorXd::Zero(7), qdd = Eigen::VectorXd::Zero(7);
    q.tail(4) = random_vector(engine, 4, M_PI);
    qd.tail(4) = random_vector(engine, 4, 3.0);
    qdd.tail(4) = random_vector(engine, 4, 10.0);
    const Eigen::VectorXd tau_full = inverse_dynamics(full, rigid, standard_parameters(full, rigid), q, qd, qdd);
    const Eigen::VectorXd tau_sub =
        inverse_dynamics(sub, rigid, standard_parameters(sub, rigid), q.tail(4), qd.tail(4), qdd.tail(4));
    EXPECT_LE(testing::relative_error(tau_sub, tau_full.tail(4)), 1e-13);
  }

  // Gravity in the root frame is refused when the base moves relative to the root ...
  expect_refused(arm7_urdf(), UrdfOptions{.base = "link3"}, "base",
                 {"base link link3 moves relative to the root link world (joint j1 is revolute)"});
  // ... and rotated through fixed joints when it does not: the mount turns by 0.3 rad about z.
  const Eigen::Vector3d tilted(1.0, 0.0, -9.81);
  const Model on_link0 = parse_urdf(arm7_urdf(), UrdfOptions{.base = "link0", .gravity = tilted}).model;
  EXPECT_LE((on_link0.gravity - Rz(0.3).transpose() * tilted).norm(), 1e-15);
  const Model on_world = parse_urdf(arm7_urdf(), UrdfOptions{.gravity = tilted}).model;
  const Eigen::VectorXd q = random_vector(engine, 7, M_PI), qd = random_vector(engine, 7, 3.0),
                        qdd = random_vector(engine, 7, 10.0);
  EXPECT_LE(testing::relative_error(
                inverse_dynamics(on_link0, rigid, standard_parameters(on_link0, rigid), q, qd, qdd),
                inverse_dynamics(on_world, rigid, standard_parameters(on_world, rigid), q, qd, qdd)),
            1e-13);
  // A tip above the base, the base itself, a chain without a moving joint.
  expect_refused(arm7_urdf(), UrdfOptions{.base = "link5", .tip = "link2"}, "tip", {"link2 is not below base link link5"});
  expect_refused(arm7_urdf(), UrdfOptions{.base = "link5", .tip = "link5"}, "tip", {"is the base link"});
  expect_refused(arm7_urdf(), UrdfOptions{.base = "flange"}, "base", {"no joint hangs below base link flange"});
  expect_refused(arm7_urdf(), UrdfOptions{.tip = "link0"}, "tip",
                 {"no moving joint between base link world and tip link link0"});
}

// ---- refusals ------------------------------------------------------------------------------------------

TEST(UrdfRefuses, MalformedXml) {
  expect_refused("<robot name='x'><link name='a'>", "urdf", {"invalid URDF"});
  expect_refused("", "urdf", {"invalid URDF"});
  expect_refused("<robot name='x'><link name='a'/><link name='a'/></robot>", "link a", {"not unique"});
}

/// arm7 with `extra` inside <robot>, before its first link.
std::string arm7_with(const std::string& extra) {
  std::string xml = arm7_urdf();
  const std::size_t link = xml.find("<link ");
  return xml.insert(link, extra);
}

/// `depth` elements <x> nested in each other.
std::string nested(int depth) {
  std::string open, close;
  for (int i = 0; i < depth; ++i) {
    open += "<x>";
    close += "</x>";
  }
  return open + close;
}

TEST(UrdfRefuses, NestingTheXmlParserWouldRecurseThroughBeforeItSeesIt) {
  // 40,000 levels overflowed the stack inside the XML parser (SIGSEGV); refused in one pass instead.
  expect_refused(arm7_with(nested(40000)), "urdf", {"<x>", "nested 101 deep", "more than the 100", "line "});
  // The bound itself (the robot element is level 1): 99 more levels are still a URDF (urdfdom ignores <x>).
  EXPECT_NO_THROW((void)parse_urdf(arm7_with(nested(99))));
  expect_refused(arm7_with(nested(100)), "urdf", {"nested 101 deep"});
}

TEST(UrdfRefuses, MoreAttributesOnOneElementThanAnyUrdfNeeds) {
  std::string many = "<x";
  for (int i = 0; i < 100'000; ++i) many += " a" + std::to_string(i) + "=\"1\"";
  expect_refused(arm7_with(many + "/>"), "urdf", {"<x>", "more than 100 attributes"});
  std::string hundred = "<x";
  for (int i = 0; i < 100; ++i) hundred += " a" + std::to_string(i) + "=\"1\"";
  EXPECT_NO_THROW((void)parse_urdf(arm7_with(hundred + "/>")));
}

TEST(UrdfRefuses, NothingButElementsCountsTowardTheBounds) {
  // Comments, CDATA, processing instructions, a DOCTYPE with an internal subset, self-closing tags and
  // '>', '/' and '=' inside quoted values open no level and add no attribute.
  std::string noise = "<!DOCTYPE robot [ <!ENTITY e \"<x><x>\"> ]>";
  std::string body;
  for (int i = 0; i < 300; ++i) {
    body += "<!-- <x><x a=1 b=2> --><![CDATA[<x><x>]]><?pi <x> ?><y a=\"/>=>\" b='=='/>";
  }
  const std::string xml = arm7_urdf();
  const std::size_t robot = xml.find("<robot");
  std::string document = xml.substr(0, robot) + noise + xml.substr(robot);
  document.insert(document.find("<link "), body);
  EXPECT_NO_THROW(check_urdf_shape(document));
  // What the XML parser itself takes of it (not the internal subset): still the same arm.
  std::string plain = xml;
  plain.insert(plain.find("<link "), body);
  EXPECT_EQ(parse_urdf(plain).model.joint_count(), parse_urdf(xml).model.joint_count());
}

TEST(UrdfRefuses, WhatUrdfdomRejectsNamingTheElement) {
  expect_refused(with_replaced(arm7_urdf(), R"(effort="12" velocity="2.6")", R"(effort="12x" velocity="2.6")"), "joint j5",
                 {"invalid URDF", "12x", "joint [j5]"});
  expect_refused(with_replaced(arm7_urdf(), R"(type="revolute">)", R"(type="spherical">)"), "joint j1", {"spherical"});
  expect_refused(with_replaced(arm7_urdf(), R"(<child link="link3"/>)", R"(<child link="link33"/>)"), "joint j3",
                 {"link33"});
}

TEST(UrdfRefuses, AMalformedInertialThatUrdfdomWouldParsePast) {
  // urdfdom logs an error for the inertial, then returns a model with a massless link3.
  expect_refused(with_replaced(arm7_urdf(), R"(<mass value="2.4"/>)", R"(<mass value="heavy"/>)"), "link link3",
                 {"inertial", "Link [link3]"});
}

TEST(UrdfRefuses, KinematicLoops) {
  // link b is the child of two joints (urdfdom accepts this and keeps one).
  expect_refused(R"(<robot name="loop"><link name="a"/><link name="b"/><link name="c"/>
    <joint name="ab" type="continuous"><parent link="a"/><child link="b"/></joint>
    <joint name="bc" type="continuous"><parent link="b"/><child link="c"/></joint>
    <joint name="cb" type="continuous"><parent link="c"/><child link="b"/></joint></robot>)",
                 "link b", {"child of joints ab and cb", "loop"});
  // A cycle that never reaches the root.
  expect_refused(R"(<robot name="cycle"><link name="a"/><link name="b"/><link name="c"/><link name="d"/>
    <joint name="ab" type="continuous"><parent link="a"/><child link="b"/></joint>
    <joint name="cd" type="continuous"><parent link="c"/><child link="d"/></joint>
    <joint name="dc" type="continuous"><parent link="d"/><child link="c"/></joint></robot>)",
                 "link c", {"links c, d are not reachable from the root link a", "joints dc, cd", "loop"});
}

TEST(UrdfRefuses, FloatingPlanarAndMimicJointsOnTheChain) {
  expect_refused(with_replaced(arm7_urdf(), R"(name="j4" type="revolute")", R"(name="j4" type="floating")"), "joint j4",
                 {"joint j4 is floating"});
  expect_refused(with_replaced(arm7_urdf(), R"(name="j2" type="revolute")", R"(name="j2" type="planar")"), "joint j2",
                 {"joint j2 is planar"});
  expect_refused(with_replaced(arm7_urdf(), R"(<dynamics damping="0.2")", R"(<mimic joint="j4"/><dynamics damping="0.2")"),
                 "joint j5", {"joint j5 mimics joint j4"});
  // A mimic tag on a fixed joint merged into a body.
  expect_refused(with_appended(arm7_urdf(), with_replaced(kCamera, "</joint>", R"(<mimic joint="j4"/></joint>)")),
                 UrdfOptions{.tip = "flange"}, "joint camera_joint", {"mimics joint j4"});
  // Off the chain, a mimic joint is only left out.
  const std::string finger = R"(<joint name="f1" type="prismatic"><parent link="flange"/><child link="f1"/>
    <limit lower="0" upper="0.04" effort="20" velocity="0.2"/></joint><link name="f1"/>
    <joint name="f2" type="prismatic"><parent link="flange"/><child link="f2"/><mimic joint="f1"/>
    <limit lower="0" upper="0.04" effort="20" velocity="0.2"/></joint><link name="f2"/>)";
  const ParsedUrdf parsed = parse_urdf(with_appended(arm7_urdf(), finger), UrdfOptions{.tip = "flange"});
  EXPECT_EQ(parsed.warnings.size(), 2u);
  EXPECT_TRUE(any_contains(parsed.warnings, "joint f2 (prismatic) is not on the chain"));
}

TEST(UrdfRefuses, UnknownBaseOrTip) {
  expect_refused(arm7_urdf(), UrdfOptions{.tip = "hand"}, "tip", {"tip link 'hand' is not in the URDF", "link7"});
  expect_refused(arm7_urdf(), UrdfOptions{.base = "table"}, "base", {"base link 'table' is not in the URDF", "world"});
}

TEST(UrdfRefuses, ZeroOrNonFiniteAxis) {
  expect_refused(one_joint("revolute", "0 0 0", "0 0 0", "0 0 0", ""), "joint j", {"joint j has a zero axis"});
  // urdfdom itself refuses a NaN component; manipid names the joint.
  expect_refused(one_joint("prismatic", "0 0 0", "0 0 0", "0 nan 1", ""), "joint j", {"Malformed axis element for joint [j]"});
}

TEST(UrdfRefuses, NegativeMass) {
  expect_refused(with_replaced(arm7_urdf(), R"(<mass value="2.1"/>)", R"(<mass value="-2.1"/>)"), "link link4",
                 {"link link4 has a negative mass, -2.1 kg"});
}

TEST(UrdfRefuses, MassesAndInertiasNoLinkHas) {
  // 1e-300 kg "succeeded" as a prior with inertias of 1e146 written back out.
  expect_refused(with_replaced(arm7_urdf(), R"(<mass value="2.1"/>)", R"(<mass value="1e-300"/>)"), "link link4",
                 {"link link4 has a mass of 1e-300 kg", "(0 for a massless link)"});
  expect_refused(with_replaced(arm7_urdf(), R"(<mass value="2.1"/>)", R"(<mass value="1e9"/>)"), "link link4", {"1e+09 kg"});
  EXPECT_NO_THROW((void)parse_urdf(with_replaced(arm7_urdf(), R"(<mass value="2.1"/>)", R"(<mass value="0"/>)")));
  expect_refused(one_joint("revolute", "0 0 0", "0 0 0", "0 0 1",
                           inertial_xml(1.0, "0 0 0", "0 0 0", R"(ixx="1e200" ixy="0" ixz="0" iyy="1e200" iyz="0" izz="1e200")")),
                 "link body", {"inertia entry of 1e+200"});
}

TEST(UrdfRefuses, NegativeFrictionAndVelocityLimits) {
  expect_refused(with_replaced(arm7_urdf(), R"(damping="0.9")", R"(damping="-0.9")"), "joint j1",
                 {"negative <dynamics> damping, -0.9"});
  expect_refused(with_replaced(arm7_urdf(), R"(friction="1.2")", R"(friction="-1.2")"), "joint j1",
                 {"negative <dynamics> friction, -1.2"});
}

TEST(Urdf, AHugeAxisIsNormalisedNotZeroed) {
  // (1e200 1e200 0): its norm overflowed to ∞ and the axis became (0 0 0), accepted.
  const ParsedUrdf parsed = parse_urdf(one_joint("revolute", "0 0 0", "0 0 0", "1e200 1e200 0", ""));
  EXPECT_NEAR(parsed.model.joints[0].axis.x(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(parsed.model.joints[0].axis.y(), std::sqrt(0.5), 1e-15);
  ASSERT_FALSE(parsed.warnings.empty());
  EXPECT_NE(parsed.warnings[0].find("normalised"), std::string::npos);
}

TEST(UrdfRefuses, InertiaThatIsNotPositiveSemiDefinite) {
  // Eigenvalues of [[0.01, 0.02], [0.02, 0.01]] are 0.03 and −0.01.
  expect_refused(one_joint("revolute", "0 0 0", "0 0 0", "0 0 1",
                           inertial_xml(1.0, "0 0 0", "0 0 0", R"(ixx="0.01" ixy="0.02" ixz="0" iyy="0.01" iyz="0" izz="0.05")")),
                 "link body", {"link body has an inertia about its centre of mass that is not positive semi-definite",
                               "eigenvalue -0.01 kg·m²"});
  expect_refused(one_joint("revolute", "0 0 0", "0 0 0", "0 0 1",
                           inertial_xml(1.0, "0 0 0", "0 0 0", R"(ixx="-1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6")")),
                 "link body", {"eigenvalue -1e-06"});
}

TEST(UrdfWarns, InertiaBreakingTheTriangleInequality) {
  // Positive semi-definite, yet no rigid body has principal moments 1, 1, 3.
  const ParsedUrdf parsed = parse_urdf(one_joint(
      "revolute", "0 0 0", "0 0 0", "0 0 1",
      inertial_xml(1.0, "0 0 0", "0 0 0", R"(ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="3")")));
  ASSERT_EQ(parsed.warnings.size(), 1u);
  EXPECT_TRUE(contains(parsed.warnings[0],
                       "link body: principal moments of inertia 1, 1, 3 kg·m² break the triangle inequality"));
}

TEST(UrdfRefuses, LimitsOutOfOrderAndNonFiniteGravity) {
  expect_refused(with_replaced(arm7_urdf(), R"(lower="-1.8" upper="1.8")", R"(lower="1.8" upper="-1.8")"), "joint j2",
                 {"joint j2 has its lower limit 1.8 above its upper limit -1.8"});
  expect_refused(arm7_urdf(), UrdfOptions{.gravity = Eigen::Vector3d(0, std::nan(""), -9.81)}, "gravity", {"non-finite"});
}

TEST(UrdfWarns, EqualLowerAndUpperLimits) {
  const ParsedUrdf parsed = parse_urdf(with_replaced(arm7_urdf(), R"(lower="-1.8" upper="1.8")", R"(upper="0")"));
  EXPECT_TRUE(any_contains(parsed.warnings, "joint j2: lower and upper limits are both 0"));
}

// ---- robots from elsewhere -----------------------------------------------------------------------------

TEST(UrdfExamples, PandaLikeAndUr5LikeParse) {
  const ParsedUrdf panda = parse_urdf(testing::read_file(testing::source_path("examples/robots/panda_like.urdf")));
  ASSERT_EQ(panda.model.joint_count(), 7);
  EXPECT_EQ(panda.model.joints[0].name, "panda_joint1");
  EXPECT_EQ(panda.model.tip_link, "panda_link8");
  EXPECT_EQ(panda.model.bodies[6].links, (std::vector<std::string>{"panda_link7", "panda_link8"}));
  EXPECT_EQ(panda.warnings, (std::vector<std::string>{"link panda_link8 has no <inertial>: counted as massless"}));
  // Franka's datasheet: joint 4 in [−3.0718, −0.0698], joint 6 in [−0.0175, 3.7525], 12 N·m wrist torque.
  EXPECT_EQ(panda.model.joints[3].limits.lower, -3.0718);
  EXPECT_EQ(panda.model.joints[3].limits.upper, -0.0698);
  EXPECT_EQ(panda.model.joints[5].limits.upper, 3.7525);
  EXPECT_EQ(panda.model.joints[6].limits.effort, 12.0);
  EXPECT_EQ(panda.model.joints[4].limits.velocity, 2.61);
  // The flange (d = 0.107 along link 7's z) is the tip's placement in body 7.
  EXPECT_LE((panda.model.tip_placement.translation - Eigen::Vector3d(0, 0, 0.107)).norm(), 1e-15);
  for (const Joint& joint : panda.model.joints) {
    EXPECT_GT(joint.damping, 0.0);
    EXPECT_GT(joint.friction, 0.0);
  }

  const ParsedUrdf ur5 = parse_urdf(testing::read_file(testing::source_path("examples/robots/ur5_like.urdf")));
  ASSERT_EQ(ur5.model.joint_count(), 6);
  EXPECT_EQ(ur5.model.joints[1].name, "shoulder_lift_joint");
  EXPECT_EQ(ur5.model.joints[0].limits.effort, 150.0);
  EXPECT_EQ(ur5.model.joints[5].limits.effort, 28.0);
  EXPECT_LE((ur5.model.tip_placement.translation - Eigen::Vector3d(0, 0, 0.0823)).norm(), 1e-15);
  EXPECT_EQ(ur5.warnings, (std::vector<std::string>{"link tool0 has no <inertial>: counted as massless"}));
}

TEST(UrdfExamples, RealRobotsParseWhenPresent) {
  const std::filesystem::path folder = testing::real_robots_folder();
  if (!std::filesystem::is_directory(folder)) GTEST_SKIP() << folder << " is absent (licensed test data, not in a clone)";
  int parsed_count = 0;
  for (const char* robot : {"panda", "kuka"}) {
    if (!std::filesystem::is_directory(folder / robot)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(folder / robot)) {
      if (entry.path().extension() != ".urdf") continue;
      const std::string xml = testing::read_file(entry.path().string());
      if (entry.path().filename() == "kuka_lwr4_gaz.urdf") {
        // Its link 1 carries placeholder products of inertia (0.01 each) that make the tensor indefinite.
        expect_refused(xml, "link lwr_1_link", {"not positive semi-definite", "eigenvalue -0.00584512"});
        continue;
      }
      const ParsedUrdf parsed = parse_urdf(xml);
      EXPECT_EQ(parsed.model.joint_count(), 7) << entry.path();
      for (const std::string& warning : parsed.warnings) {
        std::printf("%s: %s\n", entry.path().filename().c_str(), warning.c_str());
      }
      ++parsed_count;
    }
  }
  EXPECT_GT(parsed_count, 0);
}

}  // namespace
}  // namespace manipid::robot
