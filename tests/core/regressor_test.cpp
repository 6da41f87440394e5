// regressor_test.cpp — the linear-in-products form τ = Y β(θ) against inverse dynamics,
// the products' structure for the paper's robot, and ∂β/∂θ against finite differences.
#include "manipid/core/paper/regressor.h"
#include "test_models.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace manipid {
namespace {

using testing::random_vector;

TEST(Regressor, EqualsInverseDynamicsAtRandomStatesAndParameters) {
  std::mt19937_64 engine(23);
  for (KineticEnergy energy : {KineticEnergy::complete, KineticEnergy::paper}) {
    for (const RobotModel& model : {cedro2009(energy).model, testing::irregular_model(energy)}) {
      const ParameterProducts products = parameter_products(model);
      const int n = model.joint_count();
      for (int trial = 0; trial < 50; ++trial) {
        const Parameters parameters(Eigen::VectorXd(random_vector(engine, n, 1.0).array() + 2.0),
                                    Eigen::VectorXd(random_vector(engine, n, 0.2).array() + 0.5));
        const Eigen::VectorXd q = random_vector(engine, n, M_PI), qd = random_vector(engine, n, 3.0),
                              qdd = random_vector(engine, n, 10.0);
        const Eigen::VectorXd tau = inverse_dynamics(model, parameters, q, qd, qdd);
        const Eigen::VectorXd from_regressor = regressor(model, products, q, qd, qdd) * products.evaluate(parameters);
        EXPECT_LE((from_regressor - tau).norm(), 1e-9 * std::max(1.0, tau.norm()))
            << to_string(energy) << " trial " << trial;
      }
    }
  }
}

// regressor_rows computes four samples at once (vector lanes, AVX2 where the machine has it):
// each sample's rows must be regressor()'s at that sample, to the last bit, whatever the count
// (whole groups of four and a remainder), including samples at rest (the paper's kinetic
// energy skips a joint whose q̇ is zero, which a group can hold in some lanes only).
TEST(Regressor, RowsOfManySamplesAreEachSamplesRegressorExactly) {
  std::mt19937_64 engine(31);
  for (KineticEnergy energy : {KineticEnergy::complete, KineticEnergy::paper}) {
    for (const RobotModel& model : {cedro2009(energy).model, testing::irregular_model(energy)}) {
      const ParameterProducts products = parameter_products(model);
      const int n = model.joint_count();
      for (const int samples : {1, 4, 11}) {
        Eigen::MatrixXd q(samples, n), qd(samples, n), qdd(samples, n);
        for (int t = 0; t < samples; ++t) {
          q.row(t) = random_vector(engine, n, M_PI).transpose();
          qd.row(t) = random_vector(engine, n, 3.0).transpose();
          qdd.row(t) = random_vector(engine, n, 10.0).transpose();
        }
        if (samples > 4) qd(5, 0) = 0.0;  // at rest in one lane of the second group
        DynamicsWorkspace workspace(model);
        Eigen::MatrixXd rows(static_cast<Eigen::Index>(samples) * n, products.size());
        regressor_rows(model, products, workspace, q, qd, qdd, rows);
        for (int t = 0; t < samples; ++t) {
          const Eigen::MatrixXd single = regressor(model, products, q.row(t).transpose(), qd.row(t).transpose(),
                                                   qdd.row(t).transpose());
          for (int j = 0; j < n; ++j) {
            for (int c = 0; c < products.size(); ++c) {
              EXPECT_EQ(rows(static_cast<Eigen::Index>(t) * n + j, c), single(j, c))
                  << to_string(energy) << ", " << samples << " samples: sample " << t << ", joint " << j + 1 << ", "
                  << products.name(c);
            }
          }
        }
      }
      DynamicsWorkspace workspace(model);
      Eigen::MatrixXd wrong(3, products.size());
      EXPECT_THROW(regressor_rows(model, products, workspace, Eigen::MatrixXd::Zero(2, n), Eigen::MatrixXd::Zero(2, n),
                                  Eigen::MatrixXd::Zero(2, n), wrong),
                   InputError);
    }
  }
}

// Joint j carries links j, j+1, …: its torque involves no mass before j, so its row of Y is zero
// in every column of such a mass (the input-error QR skips those rows, input_error.cpp).
TEST(Regressor, AJointsRowIsZeroInTheColumnsOfTheMassesBeforeIt) {
  std::mt19937_64 engine(29);
  for (KineticEnergy energy : {KineticEnergy::complete, KineticEnergy::paper}) {
    for (const RobotModel& model : {cedro2009(energy).model, testing::irregular_model(energy)}) {
      const ParameterProducts products = parameter_products(model);
      const int n = model.joint_count();
      int nonzero_elsewhere = 0;
      for (int trial = 0; trial < 20; ++trial) {
        const Eigen::VectorXd q = random_vector(engine, n, M_PI), qd = random_vector(engine, n, 3.0),
                              qdd = random_vector(engine, n, 10.0);
        const Eigen::MatrixXd Y = regressor(model, products, q, qd, qdd);
        for (int j = 0; j < n; ++j) {
          for (int column = 0; column < products.size(); ++column) {
            if (products.terms[static_cast<std::size_t>(column)].mass < j) {
              EXPECT_EQ(Y(j, column), 0.0) << to_string(energy) << ": joint " << j + 1 << ", " << products.name(column);
            } else if (Y(j, column) != 0.0) {
              ++nonzero_elsewhere;
            }
          }
        }
      }
      EXPECT_GT(nonzero_elsewhere, 0);  // the rule is not met by an all-zero Y
    }
  }
}

TEST(Regressor, PaperRobotProducts) {
  const ParameterProducts products = parameter_products(cedro2009().model);
  std::vector<std::string> names;
  for (int i = 0; i < products.size(); ++i) names.push_back(products.name(i));
  // m1 and l1 enter only as m1·l1²: the first link has no offset, so only its rod inertia counts.
  for (const std::string& name : names) {
    if (name.find("m1") != std::string::npos || name.find("l1") != std::string::npos) {
      EXPECT_EQ(name, "m1*l1^2");
    }
  }
  EXPECT_NE(std::find(names.begin(), names.end(), "m1*l1^2"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "m4*l2*l3"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "m3*l2"), names.end());  // gravity
  EXPECT_EQ(products.size(), 17);
  EXPECT_EQ(products.column(3, 2, 1), products.column(3, 1, 2));
  EXPECT_EQ(products.column(0, 1, 1), -1);  // m1 is not moved by l2
}

TEST(Regressor, ProductJacobianMatchesFiniteDifferences) {
  const Preset preset = cedro2009();
  const ParameterProducts products = parameter_products(testing::irregular_model(KineticEnergy::complete));
  const Parameters parameters = testing::irregular_parameters();
  const Eigen::MatrixXd analytic = products.jacobian(parameters);
  const Eigen::VectorXd theta = parameters.vector();
  for (int i = 0; i < theta.size(); ++i) {
    const double h = 1e-6;
    Eigen::VectorXd plus = theta, minus = theta;
    plus[i] += h;
    minus[i] -= h;
    const Eigen::VectorXd numeric =
        (products.evaluate(Parameters::from_vector(plus)) - products.evaluate(Parameters::from_vector(minus))) / (2 * h);
    EXPECT_LE((analytic.col(i) - numeric).norm(), 1e-8) << "column " << i;
  }
}

}  // namespace
}  // namespace manipid
