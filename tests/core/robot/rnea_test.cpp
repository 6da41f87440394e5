// rnea_test.cpp — the robot RNEA against closed forms, friction terms and sign(0) = 0, M's symmetry, sizes.
#include "manipid/core/errors.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/robot/urdf.h"
#include "robot_test_support.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>

namespace manipid::robot {
namespace {

using testing::random_vector;

using testing::kRigid;

/// A pendulum: link "rod" turns about `axis` at the base's origin, centre of mass (l, 0, 0), inertia about it
/// diag(a, b, c).
Model pendulum(const std::string& axis, double mass, double l, const Eigen::Vector3d& gravity) {
  const std::string xml = R"(<robot name="pendulum"><link name="base"/>
  <joint name="j" type="continuous"><parent link="base"/><child link="rod"/><axis xyz=")" + axis + R"("/></joint>
  <link name="rod"><inertial><origin xyz=")" + std::to_string(l) + R"( 0 0"/><mass value=")" + std::to_string(mass) +
                          R"("/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link></robot>)";
  return parse_urdf(xml, UrdfOptions{.gravity = gravity}).model;
}

Eigen::VectorXd rigid_torque(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                             const Eigen::VectorXd& qdd) {
  return inverse_dynamics(model, kRigid, standard_parameters(model, kRigid), q, qd, qdd);
}

TEST(Rnea, PendulumMatchesItsClosedForm) {
  const double m = 1.5, l = 0.4, g = 9.81;
  // About z with gravity along −y: τ = (Izz + m l²) q̈ + m g l cos q; q̇ adds nothing about a fixed axis.
  const Model about_z = pendulum("0 0 1", m, l, Eigen::Vector3d(0, -g, 0));
  // About −y with gravity along −z: the same form with Iyy; about +y the gravity term changes sign.
  const Model about_minus_y = pendulum("0 -1 0", m, l, Eigen::Vector3d(0, 0, -g));
  const Model about_y = pendulum("0 1 0", m, l, Eigen::Vector3d(0, 0, -g));
  std::mt19937_64 engine(3);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::VectorXd q = random_vector(engine, 1, M_PI), qd = random_vector(engine, 1, 5.0),
                          qdd = random_vector(engine, 1, 10.0);
    const double gravity_term = m * g * l * std::cos(q[0]);
    const double expected_z = (0.03 + m * l * l) * qdd[0] + gravity_term;
    EXPECT_NEAR(rigid_torque(about_z, q, qd, qdd)[0], expected_z, 1e-12 * (1 + std::abs(expected_z)));
    const double expected_minus_y = (0.02 + m * l * l) * qdd[0] + gravity_term;
    EXPECT_NEAR(rigid_torque(about_minus_y, q, qd, qdd)[0], expected_minus_y, 1e-12 * (1 + std::abs(expected_minus_y)));
    const double expected_y = (0.02 + m * l * l) * qdd[0] - gravity_term;
    EXPECT_NEAR(rigid_torque(about_y, q, qd, qdd)[0], expected_y, 1e-12 * (1 + std::abs(expected_y)));
  }
}

TEST(Rnea, PrismaticJointLiftsAMassAgainstGravity) {
  const Model lift = parse_urdf(R"(<robot name="lift"><link name="base"/>
  <joint name="z" type="prismatic"><parent link="base"/><child link="carriage"/><origin xyz="0.2 0.1 0" rpy="0 0 0.7"/>
    <axis xyz="0 0 1"/><limit lower="0" upper="1" effort="500" velocity="1"/></joint>
  <link name="carriage"><inertial><origin xyz="0.05 -0.03 0.1"/><mass value="12"/>
    <inertia ixx="0.1" ixy="0.01" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial></link></robot>)")
                         .model;
  EXPECT_EQ(lift.joints[0].type, JointType::prismatic);
  std::mt19937_64 engine(4);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd q = random_vector(engine, 1, 1.0), qd = random_vector(engine, 1, 1.0),
                          qdd = random_vector(engine, 1, 5.0);
    EXPECT_NEAR(rigid_torque(lift, q, qd, qdd)[0], 12.0 * (qdd[0] + 9.81), 1e-12);
  }
}

TEST(Rnea, WhirlingSliderHasCentrifugalAndCoriolisTerms) {
  // Joint 1 turns about z (body 1: Izz = J), joint 2 slides along the turning x axis carrying a point mass m:
  //   τ1 = (J + m r²) q̈1 + 2 m r ṙ q̇1,   τ2 = m (r̈ − r q̇1²);   gravity (−z) is along the axis: no load.
  const double J = 0.25, m = 3.0;
  const Model slider = parse_urdf(R"(<robot name="slider"><link name="base"/>
  <joint name="turn" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/></joint>
  <link name="arm"><inertial><mass value="2"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.15" iyz="0" izz="0.25"/></inertial></link>
  <joint name="slide" type="prismatic"><parent link="arm"/><child link="bead"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="1" effort="100" velocity="1"/></joint>
  <link name="bead"><inertial><mass value="3"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  </robot>)")
                           .model;
  std::mt19937_64 engine(6);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::VectorXd q = random_vector(engine, 2, 1.0), qd = random_vector(engine, 2, 3.0),
                          qdd = random_vector(engine, 2, 10.0);
    const double r = q[1];
    const Eigen::Vector2d expected((J + m * r * r) * qdd[0] + 2 * m * r * qd[1] * qd[0], m * (qdd[1] - r * qd[0] * qd[0]));
    EXPECT_LE((rigid_torque(slider, q, qd, qdd) - expected).norm(), 1e-12 * (1 + expected.norm()));
  }
}

TEST(Rnea, FrictionAndArmatureAddTheirDefinitions) {
  const Model arm = parse_urdf(testing::arm7_urdf()).model;
  const ParameterLayout all{.viscous = true, .coulomb = true, .offset = true, .armature = true};
  std::mt19937_64 engine(8);
  const Eigen::VectorXd pi = testing::random_parameters(engine, 7, all);
  const Eigen::VectorXd fv = pi.segment(all.viscous_begin(7), 7), fc = pi.segment(all.coulomb_begin(7), 7),
                        fo = pi.segment(all.offset_begin(7), 7), Ia = pi.segment(all.armature_begin(7), 7);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd q = random_vector(engine, 7, M_PI), qd = random_vector(engine, 7, 3.0),
                          qdd = random_vector(engine, 7, 10.0);
    const Eigen::VectorXd rigid = inverse_dynamics(arm, kRigid, pi.head(70), q, qd, qdd);
    Eigen::VectorXd expected = rigid;
    for (int k = 0; k < 7; ++k) expected[k] += fv[k] * qd[k] + fc[k] * (qd[k] > 0 ? 1.0 : -1.0) + fo[k] + Ia[k] * qdd[k];
    EXPECT_LE(testing::relative_error(inverse_dynamics(arm, all, pi, q, qd, qdd), expected), 1e-14);
  }
}

TEST(Rnea, CoulombFrictionIsZeroAtRest) {
  EXPECT_EQ(friction_sign(0.0), 0.0);
  EXPECT_EQ(friction_sign(-0.0), 0.0);
  EXPECT_EQ(friction_sign(std::nan("")), 0.0);
  EXPECT_EQ(friction_sign(1e-300), 1.0);
  EXPECT_EQ(friction_sign(-1e-300), -1.0);
  EXPECT_EQ(friction_sign(-7.0), -1.0);

  const Model arm = parse_urdf(testing::arm7_urdf()).model;
  const ParameterLayout coulomb_only{.viscous = false, .coulomb = true};
  const ParameterLayout rigid = kRigid;
  Eigen::VectorXd pi = Eigen::VectorXd::Zero(coulomb_only.size(7));
  pi.head(70) = standard_parameters(arm, rigid);
  pi.tail(7).setConstant(5.0);
  const Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(7, -1.0, 1.0), qdd = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd qd(7);
  qd << 0.0, -0.0, 1e-300, -1e-300, 0.0, 0.0, 0.0;
  const Eigen::VectorXd difference =
      inverse_dynamics(arm, coulomb_only, pi, q, qd, qdd) - inverse_dynamics(arm, rigid, pi.head(70), q, qd, qdd);
  Eigen::VectorXd expected(7);
  expected << 0.0, 0.0, 5.0, -5.0, 0.0, 0.0, 0.0;
  EXPECT_LE((difference - expected).norm(), 1e-12);
}

TEST(Rnea, MassMatrixFromRneaIsSymmetricPositiveDefinite) {
  const Model arm = parse_urdf(testing::arm7_urdf()).model;
  const Eigen::VectorXd pi = standard_parameters(arm, kRigid);
  Data data(arm);
  std::mt19937_64 engine(10);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd q = random_vector(engine, 7, M_PI), zero = Eigen::VectorXd::Zero(7);
    Eigen::VectorXd bias(7), column(7);
    inverse_dynamics(arm, data, kRigid, pi, q, zero, zero, bias);
    Eigen::MatrixXd M(7, 7);
    for (int i = 0; i < 7; ++i) {
      inverse_dynamics(arm, data, kRigid, pi, q, zero, Eigen::VectorXd::Unit(7, i), column);
      M.col(i) = column - bias;
    }
    EXPECT_LE((M - M.transpose()).norm(), 1e-13 * M.norm());
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues().minCoeff(), 0.0);
  }
}

TEST(Rnea, SizesAreChecked) {
  const Model arm = parse_urdf(testing::arm7_urdf()).model;
  const ParameterLayout layout;
  Data data(arm);
  const Eigen::VectorXd pi = standard_parameters(arm, layout), v7 = Eigen::VectorXd::Zero(7), v6 = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd tau(7);
  try {
    inverse_dynamics(arm, data, layout, pi, v6, v7, v7, tau);
    ADD_FAILURE() << "accepted a 6-entry q";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "q");
    EXPECT_STREQ(error.what(), "q has 6 entries, expected 7");
  }
  EXPECT_THROW(inverse_dynamics(arm, data, layout, pi.head(70), v7, v7, v7, tau), InputError);
  const Model one = parse_urdf(R"(<robot name="r"><link name="a"/><link name="b"/>
    <joint name="j" type="continuous"><parent link="a"/><child link="b"/></joint></robot>)").model;
  Data small(one);
  try {
    inverse_dynamics(arm, small, layout, pi, v7, v7, v7, tau);
    ADD_FAILURE() << "accepted a workspace of another model";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "data");
  }
}

}  // namespace
}  // namespace manipid::robot
