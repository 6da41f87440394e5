// regressor_test.cpp — τ = Y π against the RNEA, the stacked layout, π's order and names, the URDF's own π.
#include "manipid/core/errors.h"
#include "manipid/core/robot/regressor.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/robot/urdf.h"
#include "robot_test_support.h"

#include <gtest/gtest.h>

namespace manipid::robot {
namespace {

using testing::random_vector;

std::vector<ParameterLayout> all_layouts() {
  std::vector<ParameterLayout> layouts;
  for (int bits = 0; bits < 16; ++bits) {
    layouts.push_back(
        {.viscous = bool(bits & 1), .coulomb = bool(bits & 2), .offset = bool(bits & 4), .armature = bool(bits & 8)});
  }
  return layouts;
}

std::vector<Model> test_models() {
  const std::string arm7 = testing::arm7_urdf();
  return {parse_urdf(arm7).model,
          // joint 5 prismatic: the regressor's force rows
          parse_urdf(testing::with_replaced(arm7, R"(name="j5" type="revolute")", R"(name="j5" type="prismatic")")).model,
          parse_urdf(testing::read_file(testing::source_path("examples/robots/ur5_like.urdf"))).model};
}

TEST(Regressor, TimesParametersEqualsRnea) {
  std::mt19937_64 engine(21);
  double worst = 0.0;
  for (const Model& model : test_models()) {
    const int n = model.joint_count();
    Data data(model);
    for (const ParameterLayout& layout : all_layouts()) {
      Eigen::MatrixXd Y(n, layout.size(n));
      Eigen::VectorXd tau(n);
      for (int trial = 0; trial < 25; ++trial) {
        const Eigen::VectorXd pi = testing::random_parameters(engine, n, layout);
        const Eigen::VectorXd q = random_vector(engine, n, M_PI), qd = random_vector(engine, n, 3.0),
                              qdd = random_vector(engine, n, 10.0);
        inverse_dynamics(model, data, layout, pi, q, qd, qdd, tau);
        regressor(model, data, layout, q, qd, qdd, Y);
        const double error = testing::relative_error(Y * pi, tau);
        EXPECT_LE(error, 1e-12) << model.name << " trial " << trial;
        worst = std::max(worst, error);
      }
    }
  }
  std::printf("worst relative |Y pi - rnea| over 1,200 states: %.2e\n", worst);
}

TEST(Regressor, BlocksFollowTheDocumentedStructure) {
  const Model model = parse_urdf(testing::arm7_urdf()).model;
  const ParameterLayout all{.viscous = true, .coulomb = true, .offset = true, .armature = true};
  std::mt19937_64 engine(22);
  const Eigen::VectorXd q = random_vector(engine, 7, M_PI), qd = random_vector(engine, 7, 3.0),
                        qdd = random_vector(engine, 7, 10.0);
  const Eigen::MatrixXd Y = regressor(model, all, q, qd, qdd);
  ASSERT_EQ(Y.cols(), 7 * 14);
  // A body never loads the joints beyond it.
  for (int j = 0; j < 7; ++j) {
    for (int k = 0; k < j; ++k) EXPECT_EQ(Y.block(j, 10 * k, 1, 10).norm(), 0.0) << j << " " << k;
    EXPECT_GT(Y.block(j, 10 * j, 1, 10).norm(), 0.0);
  }
  // Friction blocks: diag q̇, diag sign q̇, identity, diag q̈.
  EXPECT_EQ(Eigen::MatrixXd(Y.block(0, 70, 7, 7)), Eigen::MatrixXd(qd.asDiagonal()));
  EXPECT_EQ(Eigen::MatrixXd(Y.block(0, 77, 7, 7)), Eigen::MatrixXd(qd.array().sign().matrix().asDiagonal()));
  EXPECT_EQ(Eigen::MatrixXd(Y.block(0, 84, 7, 7)), Eigen::MatrixXd::Identity(7, 7));
  EXPECT_EQ(Eigen::MatrixXd(Y.block(0, 91, 7, 7)), Eigen::MatrixXd(qdd.asDiagonal()));
  // sign(0) = 0 in the Coulomb column.
  Eigen::VectorXd at_rest = qd;
  at_rest[2] = 0.0;
  EXPECT_EQ(regressor(model, all, q, at_rest, qdd)(2, 77 + 2), 0.0);
}

TEST(Regressor, StackedIsSampleMajor) {
  const Model model = parse_urdf(testing::arm7_urdf()).model;
  const ParameterLayout layout{.offset = true};
  std::mt19937_64 engine(23);
  const int samples = 6;
  Eigen::MatrixXd q(7, samples), qd(7, samples), qdd(7, samples);
  for (int s = 0; s < samples; ++s) {
    q.col(s) = random_vector(engine, 7, M_PI);
    qd.col(s) = random_vector(engine, 7, 3.0);
    qdd.col(s) = random_vector(engine, 7, 10.0);
  }
  const Eigen::MatrixXd Y = stacked_regressor(model, layout, q, qd, qdd);
  ASSERT_EQ(Y.rows(), samples * 7);
  ASSERT_EQ(Y.cols(), layout.size(7));
  for (int s = 0; s < samples; ++s) {
    EXPECT_EQ(Eigen::MatrixXd(Y.middleRows(7 * s, 7)), regressor(model, layout, q.col(s), qd.col(s), qdd.col(s))) << s;
  }
  // Into a block of a larger matrix, leaving the rest alone.
  Data data(model);
  Eigen::MatrixXd big = Eigen::MatrixXd::Constant(samples * 7 + 3, layout.size(7) + 2, 42.0);
  stacked_regressor(model, data, layout, q, qd, qdd, big.block(2, 1, samples * 7, layout.size(7)));
  EXPECT_EQ(Eigen::MatrixXd(big.block(2, 1, samples * 7, layout.size(7))), Y);
  EXPECT_EQ(big.row(0).norm(), 42.0 * std::sqrt(double(big.cols())));
  EXPECT_EQ(big(2, 0), 42.0);
  EXPECT_THROW(stacked_regressor(model, data, layout, q, qd.leftCols(5), qdd, big.block(2, 1, samples * 7, layout.size(7))),
               InputError);
}

TEST(Parameters, OrderAndNames) {
  const ParameterLayout all{.viscous = true, .coulomb = true, .offset = true, .armature = true};
  const std::vector<std::string> names = standard_parameter_names(2, all);
  const std::vector<std::string> expected = {
      "m1", "mx1", "my1", "mz1", "Ixx1", "Ixy1", "Ixz1", "Iyy1", "Iyz1", "Izz1",  //
      "m2", "mx2", "my2", "mz2", "Ixx2", "Ixy2", "Ixz2", "Iyy2", "Iyz2", "Izz2",  //
      "fv1", "fv2", "fc1", "fc2", "fo1", "fo2", "Ia1", "Ia2"};
  EXPECT_EQ(names, expected);
  EXPECT_EQ(all.size(2), 28);
  EXPECT_EQ(all.viscous_begin(2), 20);
  EXPECT_EQ(all.coulomb_begin(2), 22);
  EXPECT_EQ(all.offset_begin(2), 24);
  EXPECT_EQ(all.armature_begin(2), 26);
  const ParameterLayout coulomb_and_armature{.viscous = false, .coulomb = true, .offset = false, .armature = true};
  EXPECT_EQ(standard_parameter_names(1, coulomb_and_armature).back(), "Ia1");
  EXPECT_EQ(coulomb_and_armature.viscous_begin(1), -1);
  EXPECT_EQ(coulomb_and_armature.coulomb_begin(1), 10);
  EXPECT_EQ(coulomb_and_armature.armature_begin(1), 11);
  EXPECT_EQ(ParameterLayout{}.size(7), 84);  // default: viscous and Coulomb
}

TEST(Parameters, TheUrdfsOwnVector) {
  const Model model = parse_urdf(testing::arm7_urdf()).model;
  const ParameterLayout all{.viscous = true, .coulomb = true, .offset = true, .armature = true};
  const Eigen::VectorXd pi = standard_parameters(model, all);
  ASSERT_EQ(pi.size(), 98);
  for (int k = 0; k < 7; ++k) {
    EXPECT_EQ(Eigen::VectorXd(pi.segment(10 * k, 10)), Eigen::VectorXd(model.bodies[k].inertia.vector()));
    EXPECT_EQ(pi[70 + k], model.joints[k].damping);
    EXPECT_EQ(pi[77 + k], model.joints[k].friction);
    EXPECT_EQ(pi[84 + k], 0.0);
    EXPECT_EQ(pi[91 + k], 0.0);
  }
  EXPECT_EQ(pi[70], 0.9);  // j1: <dynamics damping="0.9" friction="1.2"/>
  EXPECT_EQ(pi[77], 1.2);
  // Link 2 alone in body 2: m = 2.7 kg, first moment m·c with c its inertial origin.
  EXPECT_EQ(pi[10], 2.7);
  EXPECT_LE((pi.segment<3>(11) - 2.7 * Eigen::Vector3d(-0.015, 0.06, 0.018)).norm(), 1e-15);
}

}  // namespace
}  // namespace manipid::robot
