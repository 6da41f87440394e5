// urdf_writer_test.cpp — identified parameters written into a URDF read back to the same dynamics, with
// everything else in the document kept, and what a URDF cannot hold refused.
#include "manipid/core/robot/urdf_writer.h"

#include "manipid/core/errors.h"
#include "manipid/core/robot/rnea.h"
#include "robot_test_support.h"

#include <gtest/gtest.h>

#include <random>

namespace manipid::robot {
namespace {

using testing::read_file;
using testing::source_path;

std::size_t count(const std::string& text, const std::string& word) {
  std::size_t found = 0;
  for (auto at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) ++found;
  return found;
}

TEST(IdentifiedUrdf, ReadsBackToTheSameParametersAndTorques) {
  // The test arm has a fixed mount, a flange merged into body 7 and side links: every merging case.
  for (const std::string& file : {std::string("tests/data/robots/arm7.urdf"), std::string("examples/robots/panda_like.urdf")}) {
    SCOPED_TRACE(file);
    const std::string xml = read_file(source_path(file));
    const Model model = parse_urdf(xml).model;
    const ParameterLayout layout;  // viscous and Coulomb: what <dynamics> holds
    std::mt19937_64 engine(21);
    const Eigen::VectorXd pi = testing::random_parameters(engine, model.joint_count(), layout);
    const std::string written = write_identified_urdf(xml, model, layout, pi);
    const Model again = parse_urdf(written).model;
    ASSERT_EQ(again.joint_count(), model.joint_count());
    EXPECT_LT(testing::relative_error(standard_parameters(again, layout), pi), 1e-12);
    for (int trial = 0; trial < 20; ++trial) {
      const int n = model.joint_count();
      const Eigen::VectorXd q = testing::random_vector(engine, n, 3.0), qd = testing::random_vector(engine, n, 2.0),
                            qdd = testing::random_vector(engine, n, 5.0);
      EXPECT_LT(testing::relative_error(inverse_dynamics(again, layout, standard_parameters(again, layout), q, qd, qdd),
                                        inverse_dynamics(model, layout, pi, q, qd, qdd)),
                1e-12);
    }
    // Only <inertial> and <dynamics> changed: limits, visuals, joints and links are all still there.
    EXPECT_EQ(count(written, "<limit"), count(xml, "<limit"));
    EXPECT_EQ(count(written, "<visual"), count(xml, "<visual"));
    EXPECT_EQ(count(written, "<joint "), count(xml, "<joint "));
    EXPECT_EQ(count(written, "<link "), count(xml, "<link "));
  }
}

TEST(IdentifiedUrdf, OffsetsAndArmatureBecomeACommentAndUnphysicalBodiesAreRefused) {
  const std::string xml = read_file(source_path("examples/robots/ur5_like.urdf"));
  const Model model = parse_urdf(xml).model;
  ParameterLayout layout;
  layout.offset = layout.armature = true;
  std::mt19937_64 engine(5);
  Eigen::VectorXd pi = testing::random_parameters(engine, model.joint_count(), layout);
  const std::string written = write_identified_urdf(xml, model, layout, pi);
  EXPECT_EQ(count(written, "identified by manipid, no URDF element for them: torque offset fo = "), 6u);
  EXPECT_EQ(count(written, "rotor inertia Ia = "), 6u);

  pi[20] = -1.0;  // body 3's mass
  try {
    write_identified_urdf(xml, model, layout, pi);
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "parameters");
    EXPECT_NE(std::string(error.what()).find("link " + model.joints[2].link + " has mass -1 kg"), std::string::npos)
        << error.what();
  }
  EXPECT_THROW(write_identified_urdf("<robot", model, layout, testing::random_parameters(engine, 6, layout)), InputError);
  EXPECT_THROW(write_identified_urdf(xml, model, layout, Eigen::VectorXd::Ones(3)), InputError);
}

TEST(PayloadUrdf, TheTipBodyReadsBackWithThePayloadAddedAndBadInputIsRefused) {
  // The UR5-like arm's tip tool0 sits 0.0823 m along z of its last body: the payload written as a fixed link
  // on it, parsed again, adds exactly its parameters moved into the last body's frame.
  const std::string xml = read_file(source_path("examples/robots/ur5_like.urdf"));
  const Model model = parse_urdf(xml).model;
  const InertialParameters tool =
      InertialParameters::from_centre_of_mass(1.5, Eigen::Vector3d(0.01, 0.02, 0.05), Eigen::Vector3d(0.004, 0.005, 0.003).asDiagonal());
  const std::string written = write_payload_urdf(xml, model, tool, "a test -- note");
  const Model loaded = parse_urdf(written).model;
  ASSERT_EQ(loaded.joint_count(), model.joint_count());
  EXPECT_EQ(loaded.tip_link, kPayloadLink);
  const Eigen::Matrix<double, 10, 1> expected =
      model.bodies.back().inertia.vector() + tool.expressed_in(model.tip_placement).vector();
  EXPECT_LT((loaded.bodies.back().inertia.vector() - expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NE(written.find("a test - - note"), std::string::npos);
  EXPECT_THROW(write_payload_urdf(written, model, tool), InputError);  // it has a payload link already
  EXPECT_THROW(write_payload_urdf(xml, model, InertialParameters::from_centre_of_mass(-1.0, Eigen::Vector3d::Zero(),
                                                                                      Eigen::Matrix3d::Identity())),
               InputError);
}

}  // namespace
}  // namespace manipid::robot
