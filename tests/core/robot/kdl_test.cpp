// kdl_test.cpp — manipid's robot RNEA against Orocos KDL's, KDL's chain built from urdfdom, not from our Model.
#include "kdl_reference.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/robot/urdf.h"
#include "robot_test_support.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

namespace manipid::robot {
namespace {

using testing::random_vector;

using testing::kRigid;
const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);
constexpr double kTolerance = 1e-10;  // relative to the largest torque of the state

/// The largest ‖τ − τ_KDL‖∞ / ‖τ_KDL‖∞ over `states` random states, printed under `what`.
template <class Reference>
double worst_relative_error(const Model& model, const ParameterLayout& layout, const Eigen::VectorXd& pi,
                            Reference& reference, int states, std::uint64_t seed, const char* what) {
  const int n = model.joint_count();
  Data data(model);
  Eigen::VectorXd tau(n);
  std::mt19937_64 engine(seed);
  double worst = 0.0;
  for (int trial = 0; trial < states; ++trial) {
    const Eigen::VectorXd q = random_vector(engine, n, M_PI), qd = random_vector(engine, n, 3.0),
                          qdd = random_vector(engine, n, 10.0);
    inverse_dynamics(model, data, layout, pi, q, qd, qdd, tau);
    const Eigen::VectorXd expected = reference.torque(q, qd, qdd);
    const double error = testing::relative_error(tau, expected);
    EXPECT_LE(error, kTolerance) << what << " state " << trial << "\n manipid " << tau.transpose() << "\n KDL     "
                                 << expected.transpose();
    worst = std::max(worst, error);
  }
  std::printf("%s: worst relative error over %d states %.2e\n", what, states, worst);
  return worst;
}

TEST(Kdl, ChainIdSolverAgreesOnTheTestArm) {
  const std::string xml = testing::arm7_urdf();
  const Model model = parse_urdf(xml).model;
  const auto urdf = testing::kdl::parse(xml);
  testing::kdl::ChainDynamics kdl(testing::kdl::chain(*urdf, "world", "flange"), kGravity);
  ASSERT_EQ(kdl.joint_count(), 7);
  worst_relative_error(model, kRigid, standard_parameters(model, kRigid), kdl, 500, 1, "arm7 vs ChainIdSolver_RNE");
}

TEST(Kdl, ChainIdSolverAgreesWithAPrismaticJoint) {
  const std::string xml =
      testing::with_replaced(testing::arm7_urdf(), R"(name="j5" type="revolute")", R"(name="j5" type="prismatic")");
  const Model model = parse_urdf(xml).model;
  const auto urdf = testing::kdl::parse(xml);
  testing::kdl::ChainDynamics kdl(testing::kdl::chain(*urdf, "world", "flange"), kGravity);
  worst_relative_error(model, kRigid, standard_parameters(model, kRigid), kdl, 200, 2,
                       "arm7 with prismatic j5 vs ChainIdSolver_RNE");
}

TEST(Kdl, TreeIdSolverAgreesWithSideBranches) {
  // A camera on link 4 and a tool beside the flange on link 7, both fixed: KDL keeps them as tree
  // segments, manipid merges them into bodies 4 and 7.
  const std::string xml = testing::with_appended(testing::arm7_urdf(), R"(
  <joint name="camera_joint" type="fixed"><parent link="link4"/><child link="camera"/>
    <origin xyz="0.03 0.05 -0.02" rpy="0.3 0.2 -0.4"/></joint>
  <link name="camera"><inertial><origin xyz="0.01 0.0 0.02" rpy="0 0.2 0"/><mass value="0.4"/>
    <inertia ixx="0.0004" ixy="0.00001" ixz="0" iyy="0.0003" iyz="0" izz="0.0002"/></inertial></link>
  <joint name="tool_joint" type="fixed"><parent link="link7"/><child link="tool"/>
    <origin xyz="-0.05 0.02 0.06" rpy="-0.5 0.1 0.2"/></joint>
  <link name="tool"><inertial><origin xyz="0.0 0.03 0.05" rpy="0.1 0 0.3"/><mass value="0.9"/>
    <inertia ixx="0.002" ixy="0.0001" ixz="-0.0002" iyy="0.0015" iyz="0.0001" izz="0.001"/></inertial></link>
)");
  const ParsedUrdf parsed = parse_urdf(xml, UrdfOptions{.tip = "flange"});
  EXPECT_EQ(parsed.model.bodies[6].links, (std::vector<std::string>{"link7", "flange", "tool"}));
  const auto urdf = testing::kdl::parse(xml);
  testing::kdl::TreeDynamics kdl(testing::kdl::tree(*urdf), kGravity);
  worst_relative_error(parsed.model, kRigid, standard_parameters(parsed.model, kRigid), kdl, 200, 3,
                       "arm7 with side branches vs TreeIdSolver_RNE");
}

TEST(Kdl, ArmatureMatchesKdlsJointInertia) {
  const std::string xml = testing::arm7_urdf();
  const Model model = parse_urdf(xml).model;
  const ParameterLayout layout{.viscous = false, .coulomb = false, .offset = false, .armature = true};
  const std::vector<double> armature = {0.4, 0.35, 0.3, 0.25, 0.1, 0.08, 0.05};
  Eigen::VectorXd pi(layout.size(7));
  pi << standard_parameters(model, kRigid), Eigen::Map<const Eigen::VectorXd>(armature.data(), 7);
  const auto urdf = testing::kdl::parse(xml);
  testing::kdl::ChainDynamics kdl(testing::kdl::chain(*urdf, "world", "flange", armature), kGravity);
  worst_relative_error(model, layout, pi, kdl, 200, 4, "arm7 with armature vs ChainIdSolver_RNE");
}

TEST(Kdl, ChainIdSolverAgreesOnTheExamples) {
  for (const char* file : {"examples/robots/panda_like.urdf", "examples/robots/ur5_like.urdf"}) {
    const std::string xml = testing::read_file(testing::source_path(file));
    const Model model = parse_urdf(xml).model;
    const auto urdf = testing::kdl::parse(xml);
    testing::kdl::ChainDynamics kdl(testing::kdl::chain(*urdf, model.base_link, model.tip_link), kGravity);
    worst_relative_error(model, kRigid, standard_parameters(model, kRigid), kdl, 200, 5, file);
  }
}

TEST(Kdl, ChainIdSolverAgreesOnTheRealRobotsWhenPresent) {
  const std::filesystem::path folder = testing::real_robots_folder();
  if (!std::filesystem::is_directory(folder)) GTEST_SKIP() << folder << " is absent (licensed test data, not in a clone)";
  for (const char* file : {"panda/panda.urdf", "panda/panda_published.urdf", "kuka/kuka_lwr4_orig.urdf"}) {
    if (!std::filesystem::exists(folder / file)) continue;
    const std::string xml = testing::read_file((folder / file).string());
    const Model model = parse_urdf(xml).model;
    const auto urdf = testing::kdl::parse(xml);
    testing::kdl::ChainDynamics kdl(testing::kdl::chain(*urdf, model.base_link, model.tip_link), kGravity);
    worst_relative_error(model, kRigid, standard_parameters(model, kRigid), kdl, 100, 6, file);
  }
}

}  // namespace
}  // namespace manipid::robot
