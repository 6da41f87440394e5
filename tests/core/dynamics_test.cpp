// dynamics_test.cpp — equations of motion against closed forms, Lagrange's equations by
// finite differences, and invariants (symmetry, positive definiteness, energy).
#include "manipid/core/paper/dynamics.h"
#include "manipid/core/paper/presets.h"
#include "test_models.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <boost/numeric/odeint.hpp>

#include <cmath>
#include <vector>

namespace manipid {
namespace {

using testing::irregular_model;
using testing::irregular_parameters;
using testing::random_vector;

struct Case {
  const char* name;
  RobotModel model;
  Parameters parameters;
};

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (KineticEnergy energy : {KineticEnergy::complete, KineticEnergy::paper}) {
    const Preset preset = cedro2009(energy);
    cases.push_back({energy == KineticEnergy::complete ? "cedro2009/complete" : "cedro2009/paper", preset.model,
                     preset.true_parameters});
    cases.push_back({energy == KineticEnergy::complete ? "irregular/complete" : "irregular/paper",
                     irregular_model(energy), irregular_parameters()});
  }
  return cases;
}

double relative_error(const Eigen::VectorXd& actual, const Eigen::VectorXd& expected) {
  return (actual - expected).norm() / std::max(1.0, expected.norm());
}

TEST(Dynamics, MassMatrixIsSymmetricPositiveDefinite) {
  std::mt19937_64 engine(7);
  for (const Case& c : all_cases()) {
    for (int trial = 0; trial < 50; ++trial) {
      const Eigen::VectorXd q = random_vector(engine, c.model.joint_count(), M_PI);
      const Eigen::MatrixXd M = mass_matrix(c.model, c.parameters, q);
      EXPECT_LE((M - M.transpose()).norm(), 1e-14 * M.norm()) << c.name;
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(M);
      EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0) << c.name;
    }
  }
}

TEST(Dynamics, PaperKineticEnergyHasDiagonalMassMatrix) {
  const Preset paper = cedro2009(KineticEnergy::paper);
  const Preset complete = cedro2009(KineticEnergy::complete);
  const Eigen::VectorXd q = (Eigen::VectorXd(4) << 0.2, 0.4, -0.3, 0.5).finished();
  const Eigen::MatrixXd M_paper = mass_matrix(paper.model, paper.true_parameters, q);
  const Eigen::MatrixXd M_complete = mass_matrix(complete.model, complete.true_parameters, q);
  EXPECT_EQ((M_paper - Eigen::MatrixXd(M_paper.diagonal().asDiagonal())).norm(), 0.0);
  // Same diagonal: the paper keeps exactly the j = k terms of the double sum.
  EXPECT_LE((M_paper.diagonal() - M_complete.diagonal()).norm(), 1e-12);
  EXPECT_GT(std::abs(M_complete(1, 2)), 1.0);  // the complete model couples joints 2 and 3
}

TEST(Dynamics, InverseOfForwardIsIdentity) {
  std::mt19937_64 engine(11);
  for (const Case& c : all_cases()) {
    const int n = c.model.joint_count();
    for (int trial = 0; trial < 50; ++trial) {
      const Eigen::VectorXd q = random_vector(engine, n, M_PI);
      const Eigen::VectorXd qd = random_vector(engine, n, 3.0);
      const Eigen::VectorXd tau = random_vector(engine, n, 100.0);
      const Eigen::VectorXd qdd = forward_dynamics(c.model, c.parameters, q, qd, tau);
      const Eigen::VectorXd back = inverse_dynamics(c.model, c.parameters, q, qd, qdd);
      EXPECT_LE((back - tau).norm(), 1e-9 * tau.norm()) << c.name;
    }
  }
}

// τ from Lagrange's equations with K = ½ q̇ᵀM(q)q̇ and V(q), differentiated numerically:
// τ = M q̈ + Ṁ q̇ − ½ ∂(q̇ᵀ M q̇)/∂q + ∂V/∂q. An independent check of both variants.
Eigen::VectorXd lagrange_torque(const RobotModel& model, const Parameters& parameters, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  const int n = model.joint_count();
  const double h = 1e-6;
  Eigen::MatrixXd M_rate = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd kinetic_gradient(n), potential_gradient(n);
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd plus = q, minus = q;
    plus[i] += h;
    minus[i] -= h;
    const Eigen::MatrixXd dM = (mass_matrix(model, parameters, plus) - mass_matrix(model, parameters, minus)) / (2 * h);
    M_rate += dM * qd[i];
    kinetic_gradient[i] = 0.5 * qd.dot(dM * qd);
    potential_gradient[i] = (potential_energy(model, parameters, plus) - potential_energy(model, parameters, minus)) / (2 * h);
  }
  return mass_matrix(model, parameters, q) * qdd + M_rate * qd - kinetic_gradient + potential_gradient;
}

TEST(Dynamics, InverseDynamicsSatisfiesLagrangeEquations) {
  std::mt19937_64 engine(13);
  for (const Case& c : all_cases()) {
    const int n = c.model.joint_count();
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::VectorXd q = random_vector(engine, n, M_PI);
      const Eigen::VectorXd qd = random_vector(engine, n, 2.0);
      const Eigen::VectorXd qdd = random_vector(engine, n, 5.0);
      const Eigen::VectorXd tau = inverse_dynamics(c.model, c.parameters, q, qd, qdd);
      EXPECT_LE(relative_error(tau, lagrange_torque(c.model, c.parameters, q, qd, qdd)), 1e-7) << c.name;
    }
  }
}

// A single link turning about a horizontal axis: point mass m at distance l plus the rod's
// J = m l²/12. With gravity −g along base y, V = m g l sin q, so
// τ = (m l² + m l²/12) q̈ + m g l cos q.
TEST(Dynamics, PendulumMatchesClosedForm) {
  RobotModel model;
  model.joints = {{.alpha = 0, .a = 0, .d = 0, .length_role = LengthRole::a}};
  model.gravity = Eigen::Vector3d(0, -9.81, 0);
  const double m = 2.5, l = 0.7, g = 9.81;
  const Parameters parameters(Eigen::VectorXd::Constant(1, m), Eigen::VectorXd::Constant(1, l));
  for (KineticEnergy energy : {KineticEnergy::complete, KineticEnergy::paper}) {
    model.kinetic_energy = energy;
    for (double q : {-2.0, -0.3, 0.0, 0.9, 2.5}) {
      for (double qdd : {-4.0, 0.0, 3.0}) {
        const double expected = (m * l * l + m * l * l / 12.0) * qdd + m * g * l * std::cos(q);
        const Eigen::VectorXd tau = inverse_dynamics(model, parameters, Eigen::VectorXd::Constant(1, q),
                                                     Eigen::VectorXd::Constant(1, 1.7), Eigen::VectorXd::Constant(1, qdd));
        EXPECT_NEAR(tau[0], expected, 1e-12 * std::max(1.0, std::abs(expected)));
      }
    }
  }
}

// The planar 2-link arm with point masses at the link ends (the textbook case), plus joint
// inertias J_k = m_k l_k²/12 that see their own joint rate only. Gravity −g along base y.
TEST(Dynamics, PlanarTwoLinkMatchesClosedForm) {
  RobotModel model;
  model.joints = {{.alpha = 0, .a = 0, .d = 0, .length_role = LengthRole::a},
                  {.alpha = 0, .a = 0, .d = 0, .length_role = LengthRole::a}};
  model.gravity = Eigen::Vector3d(0, -9.81, 0);
  const double m1 = 3.0, m2 = 1.8, l1 = 0.9, l2 = 0.6, g = 9.81;
  const Parameters parameters(Eigen::Vector2d(m1, m2), Eigen::Vector2d(l1, l2));
  const double J1 = m1 * l1 * l1 / 12, J2 = m2 * l2 * l2 / 12;
  std::mt19937_64 engine(17);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd q = random_vector(engine, 2, M_PI), qd = random_vector(engine, 2, 3.0),
                          qdd = random_vector(engine, 2, 5.0);
    const double c2 = std::cos(q[1]), s2 = std::sin(q[1]);
    const double c1 = std::cos(q[0]), c12 = std::cos(q[0] + q[1]);
    const double M11 = m1 * l1 * l1 + m2 * (l1 * l1 + l2 * l2 + 2 * l1 * l2 * c2) + J1;
    const double M12 = m2 * (l2 * l2 + l1 * l2 * c2);
    const double M22 = m2 * l2 * l2 + J2;
    const double h = m2 * l1 * l2 * s2;
    const double g1 = (m1 + m2) * g * l1 * c1 + m2 * g * l2 * c12;
    const double g2 = m2 * g * l2 * c12;
    const double tau1 = M11 * qdd[0] + M12 * qdd[1] - h * (2 * qd[0] * qd[1] + qd[1] * qd[1]) + g1;
    const double tau2 = M12 * qdd[0] + M22 * qdd[1] + h * qd[0] * qd[0] + g2;
    model.kinetic_energy = KineticEnergy::complete;
    const Eigen::VectorXd tau = inverse_dynamics(model, parameters, q, qd, qdd);
    EXPECT_NEAR(tau[0], tau1, 1e-11 * std::max(1.0, std::abs(tau1)));
    EXPECT_NEAR(tau[1], tau2, 1e-11 * std::max(1.0, std::abs(tau2)));
    const Eigen::MatrixXd M = mass_matrix(model, parameters, q);
    EXPECT_NEAR(M(0, 0), M11, 1e-12);
    EXPECT_NEAR(M(0, 1), M12, 1e-12);
    EXPECT_NEAR(M(1, 1), M22, 1e-12);
  }
}

// Free motion (τ = 0, no damping) conserves K + V. Integrated with a tight adaptive
// Runge–Kutta so that the check measures the model, not the integrator.
TEST(Dynamics, EnergyIsConservedInFreeMotion) {
  namespace odeint = boost::numeric::odeint;
  using State = std::vector<double>;
  for (const Case& c : all_cases()) {
    const int n = c.model.joint_count();
    DynamicsWorkspace workspace(c.model);
    Eigen::VectorXd zero = Eigen::VectorXd::Zero(n), qdd(n);
    auto rhs = [&](const State& x, State& dxdt, double) {
      const Eigen::Map<const Eigen::VectorXd> q(x.data(), n), qd(x.data() + n, n);
      forward_dynamics(c.model, c.parameters, workspace, q, qd, zero, qdd);
      for (int i = 0; i < n; ++i) {
        dxdt[i] = x[n + i];
        dxdt[n + i] = qdd[i];
      }
    };
    State x(2 * n);
    for (int i = 0; i < n; ++i) {
      x[i] = 0.3 * (i + 1) - 0.5;
      x[n + i] = 0.8 - 0.35 * i;
    }
    auto energy = [&](const State& s) {
      const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(s.data(), n);
      const Eigen::VectorXd qd = Eigen::Map<const Eigen::VectorXd>(s.data() + n, n);
      return kinetic_energy(c.model, c.parameters, q, qd) + potential_energy(c.model, c.parameters, q);
    };
    const double start = energy(x);
    const double scale = std::abs(start) + kinetic_energy(c.model, c.parameters,
                                                          Eigen::Map<const Eigen::VectorXd>(x.data(), n),
                                                          Eigen::Map<const Eigen::VectorXd>(x.data() + n, n));
    odeint::integrate_adaptive(odeint::make_controlled(1e-12, 1e-12, odeint::runge_kutta_dopri5<State>()), rhs, x,
                               0.0, 2.0, 1e-4);
    EXPECT_LE(std::abs(energy(x) - start), 1e-6 * scale) << c.name;
    // The motion must be real for the check to mean anything.
    EXPECT_GT(std::abs(x[0] - (0.3 - 0.5)), 0.05) << c.name;
  }
}

// A chain of n joints cycling through the irregular model's rows (twists, d-type lengths,
// fixed offsets), for the size-specialised kernels.
RobotModel chain_of(int n) {
  const RobotModel pattern = irregular_model(KineticEnergy::complete);
  RobotModel model = pattern;
  model.joints.clear();
  for (int k = 0; k < n; ++k) model.joints.push_back(pattern.joints[k % pattern.joint_count()]);
  return model;
}

// The kernels specialised for 1..6 joints and the general-size code give the same torques
// and accelerations (n = 7 exercises the dispatch to the general code).
TEST(Dynamics, FixedSizeKernelsMatchGeneralSize) {
  std::mt19937_64 engine(11);
  for (int n = 1; n <= 7; ++n) {
    const RobotModel model = chain_of(n);
    const Parameters parameters(random_vector(engine, n, 1.0).array().abs() + 0.5,
                                random_vector(engine, n, 0.3).array().abs() + 0.1);
    DynamicsWorkspace fixed(model);
    DynamicsWorkspace general(model);
    general.fixed_size_kernels = false;
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::VectorXd q = random_vector(engine, n, M_PI);
      const Eigen::VectorXd qd = random_vector(engine, n, 2.0);
      const Eigen::VectorXd qdd = random_vector(engine, n, 5.0);
      Eigen::VectorXd tau_fixed(n), tau_general(n), qdd_fixed(n), qdd_general(n);
      inverse_dynamics(model, parameters, fixed, q, qd, qdd, tau_fixed);
      inverse_dynamics(model, parameters, general, q, qd, qdd, tau_general);
      EXPECT_LE((tau_fixed - tau_general).norm(), 1e-12 * std::max(1.0, tau_general.norm())) << "n = " << n;
      forward_dynamics(model, parameters, fixed, q, qd, tau_fixed, qdd_fixed);
      forward_dynamics(model, parameters, general, q, qd, tau_fixed, qdd_general);
      EXPECT_LE((qdd_fixed - qdd_general).norm(), 1e-12 * std::max(1.0, qdd_general.norm())) << "n = " << n;
      EXPECT_LE((qdd_fixed - qdd).norm(), 1e-9 * std::max(1.0, qdd.norm())) << "n = " << n;
    }
  }
}

// A mass matrix that is not positive definite (a negative mass) falls back to the pivoting
// LDLT in both code paths, and they agree.
TEST(Dynamics, IndefiniteMassMatrixFallsBackToLdlt) {
  const RobotModel model = chain_of(3);
  Parameters parameters(Eigen::Vector3d(2.0, -1.5, 1.0), Eigen::Vector3d(0.4, 0.3, 0.2));
  const Eigen::VectorXd q = Eigen::Vector3d(0.3, -0.8, 1.1);
  const Eigen::VectorXd qd = Eigen::Vector3d(0.5, 0.2, -0.4);
  const Eigen::VectorXd tau = Eigen::Vector3d(1.0, -2.0, 0.5);
  const Eigen::MatrixXd M = mass_matrix(model, parameters, q);
  ASSERT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues().minCoeff(), 0.0);
  for (bool fixed_size : {true, false}) {
    DynamicsWorkspace workspace(model);
    workspace.fixed_size_kernels = fixed_size;
    Eigen::VectorXd qdd(3);
    forward_dynamics(model, parameters, workspace, q, qd, tau, qdd);
    const Eigen::VectorXd back = inverse_dynamics(model, parameters, q, qd, qdd);
    EXPECT_LE((back - tau).norm(), 1e-9 * tau.norm()) << fixed_size;
  }
}

TEST(Dynamics, WrongStateSizeIsAnInputError) {
  const Preset preset = cedro2009();
  try {
    inverse_dynamics(preset.model, preset.true_parameters, Eigen::VectorXd::Zero(3), Eigen::VectorXd::Zero(4),
                     Eigen::VectorXd::Zero(4));
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "q");
  }
}

}  // namespace
}  // namespace manipid
