// dynamics.cpp — kinematics, inverse/forward dynamics and energies (dynamics.h).
//
// Everything is computed in base coordinates. For point masses the complete model's inverse
// dynamics is Newton's law projected on the joint axes, τ_j = z_{j-1}·Σ_{k≥j} (o_k − o_{j-1})
// × m_k (ö_k − gravity) + J_j q̈_j, evaluated by one forward (accelerations) and one backward
// (forces, moments) pass. The paper's simplified kinetic energy has a diagonal, configuration-
// dependent mass matrix; its Lagrange equations are written out from the position Jacobians.
#include "manipid/core/dynamics.h"

#include "frame_update.h"

#include <cmath>
#include <string>

namespace manipid {
namespace {

void check_state_size(const RobotModel& model, Eigen::Index size, const char* field) {
  if (size != model.joint_count()) {
    throw InputError(field, std::string(field) + " has " + std::to_string(size) + " entries, the model has " +
                                std::to_string(model.joint_count()) + " joints");
  }
}

double joint_inertia(const RobotModel& model, const Parameters& parameters, int k) {
  return model.joint_inertia_factor * parameters.mass[k] * parameters.length[k] * parameters.length[k];
}

// Translation offsets of joint k's DH row, with the length parameter substituted.
void offsets(const RobotModel& model, const Parameters& parameters, int k, double& a, double& d) {
  const JointDescription& joint = model.joints[k];
  a = joint.length_role == LengthRole::a ? parameters.length[k] : joint.a;
  d = joint.length_role == LengthRole::d ? parameters.length[k] : joint.d;
}

// Velocities of the frames (ω_k, ȯ_k), needed by the paper variant; the complete variant
// gets them inside its acceleration pass.
void frame_velocities(const RobotModel& model, DynamicsWorkspace& w, const Eigen::Ref<const Eigen::VectorXd>& qd) {
  const int n = model.joint_count();
  for (int k = 1; k <= n; ++k) {
    const Eigen::Vector3d axis = w.rotation[k - 1].col(2);
    w.angular_velocity[k] = w.angular_velocity[k - 1] + qd[k - 1] * axis;
    w.velocity[k] = w.velocity[k - 1] + w.angular_velocity[k].cross(w.origin[k] - w.origin[k - 1]);
  }
}

// Position Jacobians J_kj = z_{j-1} × (o_k − o_{j-1}) for j ≤ k, stored at column k·n + j
// (0-based k, j); zero for j > k.
void position_jacobians(const RobotModel& model, DynamicsWorkspace& w) {
  const int n = model.joint_count();
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      if (j > k) {
        w.jacobian.col(k * n + j).setZero();
      } else {
        w.jacobian.col(k * n + j) = w.rotation[j].col(2).cross(w.origin[k + 1] - w.origin[j]);
      }
    }
  }
}

void inverse_dynamics_complete(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                               const Eigen::Ref<const Eigen::VectorXd>& qd,
                               const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::VectorXd> tau) {
  const int n = model.joint_count();
  // Running values stay in registers; only what the backward pass needs is stored.
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_rate = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();
  for (int k = 1; k <= n; ++k) {
    const Eigen::Vector3d axis = w.rotation[k - 1].col(2);
    const Eigen::Vector3d arm = w.origin[k] - w.origin[k - 1];
    omega_rate += qdd[k - 1] * axis + qd[k - 1] * omega.cross(axis);
    omega += qd[k - 1] * axis;
    acceleration += omega_rate.cross(arm) + omega.cross(omega.cross(arm));
    w.acceleration[k] = acceleration;
  }
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   // Σ_{k≥j} m_k (ö_k − g)
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  // about o_{j-1}
  for (int j = n; j >= 1; --j) {
    force += parameters.mass[j - 1] * (w.acceleration[j] - model.gravity);
    moment += (w.origin[j] - w.origin[j - 1]).cross(force);
    tau[j - 1] = w.rotation[j - 1].col(2).dot(moment) + joint_inertia(model, parameters, j - 1) * qdd[j - 1];
  }
}

// The paper's K: M = diag(M_jj(q)), M_jj = Σ_k m_k |J_kj|² + J_j. Lagrange's equations give
// τ_j = M_jj q̈_j + Ṁ_jj q̇_j − ½ Σ_i ∂M_ii/∂q_j q̇_i² + g_j, with
// ∂M_ii/∂q_j = Σ_k 2 m_k J_ki·(z_{i-1} × J_kj) for i ≤ j ≤ k (a joint before i turns the
// whole sub-chain rigidly and leaves the distance to axis i unchanged).
void inverse_dynamics_paper(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                            const Eigen::Ref<const Eigen::VectorXd>& qd,
                            const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::VectorXd> tau) {
  const int n = model.joint_count();
  frame_velocities(model, w, qd);
  position_jacobians(model, w);
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector3d axis = w.rotation[j].col(2);
    const Eigen::Vector3d axis_rate = w.angular_velocity[j].cross(axis);
    double inertia = joint_inertia(model, parameters, j);
    double inertia_rate = 0.0;
    double gravity_torque = 0.0;
    double centrifugal = 0.0;
    for (int k = j; k < n; ++k) {
      const double m = parameters.mass[k];
      const Eigen::Vector3d jacobian = w.jacobian.col(k * n + j);
      const Eigen::Vector3d jacobian_rate = axis_rate.cross(w.origin[k + 1] - w.origin[j]) +
                                            axis.cross(w.velocity[k + 1] - w.velocity[j]);
      inertia += m * jacobian.squaredNorm();
      inertia_rate += 2.0 * m * jacobian.dot(jacobian_rate);
      gravity_torque -= m * jacobian.dot(model.gravity);
      for (int i = 0; i <= j; ++i) {
        const Eigen::Vector3d jacobian_i = w.jacobian.col(k * n + i);
        const double dM_ii_dq_j = 2.0 * m * jacobian_i.dot(w.rotation[i].col(2).cross(jacobian));
        centrifugal += 0.5 * dM_ii_dq_j * qd[i] * qd[i];
      }
    }
    tau[j] = inertia * qdd[j] + inertia_rate * qd[j] - centrifugal + gravity_torque;
  }
}

void inverse_dynamics_at_kinematics(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                                    const Eigen::Ref<const Eigen::VectorXd>& qd,
                                    const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::VectorXd> tau) {
  if (model.kinetic_energy == KineticEnergy::complete) {
    inverse_dynamics_complete(model, parameters, w, qd, qdd, tau);
  } else {
    inverse_dynamics_paper(model, parameters, w, qd, qdd, tau);
  }
}

}  // namespace

DynamicsWorkspace::DynamicsWorkspace(const RobotModel& model) {
  const int n = model.joint_count();
  rotation.assign(n + 1, Eigen::Matrix3d::Identity());
  origin.assign(n + 1, Eigen::Vector3d::Zero());
  velocity.assign(n + 1, Eigen::Vector3d::Zero());
  acceleration.assign(n + 1, Eigen::Vector3d::Zero());
  angular_velocity.assign(n + 1, Eigen::Vector3d::Zero());
  angular_acceleration.assign(n + 1, Eigen::Vector3d::Zero());
  jacobian.setZero(3, n * n);
  twist_cos.resize(n);
  joint_cos.setZero(n);
  joint_sin.setZero(n);
  twist_sin.resize(n);
  for (int k = 0; k < n; ++k) {
    twist_cos[k] = std::cos(model.joints[k].alpha);
    twist_sin[k] = std::sin(model.joints[k].alpha);
  }
  mass_matrix.setZero(n, n);
  bias.setZero(n);
  factorization.compute(Eigen::MatrixXd::Identity(n, n));
}

void forward_kinematics(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                        const Eigen::Ref<const Eigen::VectorXd>& q) {
  const int n = model.joint_count();
  check_state_size(model, q.size(), "q");
  // One loop of sin and cos of the same angle: the compiler fuses each pair into sincos.
  for (int k = 0; k < n; ++k) {
    w.joint_cos[k] = std::cos(q[k]);
    w.joint_sin[k] = std::sin(q[k]);
  }
  Eigen::Matrix3d rotation = w.rotation[0];
  Eigen::Vector3d origin = w.origin[0];
  for (int k = 1; k <= n; ++k) {
    const Eigen::Vector3d z = rotation.col(2);
    detail::update_rotation(rotation, w.joint_cos[k - 1], w.joint_sin[k - 1], w.twist_cos[k - 1], w.twist_sin[k - 1], rotation);
    double a = 0.0;
    double d = 0.0;
    offsets(model, parameters, k - 1, a, d);
    origin += d * z + a * rotation.col(0);
    w.rotation[k] = rotation;
    w.origin[k] = origin;
  }
}

Eigen::Vector3d mass_position(const RobotModel& model, const Parameters& parameters,
                              const Eigen::Ref<const Eigen::VectorXd>& q, int k) {
  if (k < 1 || k > model.joint_count()) throw InputError("k", "mass index out of range");
  DynamicsWorkspace workspace(model);
  forward_kinematics(model, parameters, workspace, q);
  return workspace.origin[k];
}

void inverse_dynamics(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& workspace,
                      const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
                      const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::VectorXd> tau) {
  check_state_size(model, qd.size(), "qd");
  check_state_size(model, qdd.size(), "qdd");
  check_state_size(model, tau.size(), "tau");
  forward_kinematics(model, parameters, workspace, q);
  inverse_dynamics_at_kinematics(model, parameters, workspace, qd, qdd, tau);
}

Eigen::VectorXd inverse_dynamics(const RobotModel& model, const Parameters& parameters, const Eigen::VectorXd& q,
                                 const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  check_parameters(model, parameters);
  DynamicsWorkspace workspace(model);
  Eigen::VectorXd tau(model.joint_count());
  inverse_dynamics(model, parameters, workspace, q, qd, qdd, tau);
  return tau;
}

namespace {

// M from the kinematics already in the workspace.
void mass_matrix_at_kinematics(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                               Eigen::Ref<Eigen::MatrixXd> mass_matrix) {
  const int n = model.joint_count();
  position_jacobians(model, w);
  mass_matrix.setZero();
  const bool complete = model.kinetic_energy == KineticEnergy::complete;
  for (int k = 0; k < n; ++k) {
    const double m = parameters.mass[k];
    for (int i = 0; i <= k; ++i) {
      const auto jacobian_i = w.jacobian.col(k * n + i);
      mass_matrix(i, i) += m * jacobian_i.squaredNorm();
      if (!complete) continue;
      for (int j = 0; j < i; ++j) {
        const double entry = m * jacobian_i.dot(w.jacobian.col(k * n + j));
        mass_matrix(i, j) += entry;
        mass_matrix(j, i) += entry;
      }
    }
    mass_matrix(k, k) += joint_inertia(model, parameters, k);
  }
}

}  // namespace

void mass_matrix(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                 const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Ref<Eigen::MatrixXd> mass_matrix) {
  forward_kinematics(model, parameters, w, q);
  mass_matrix_at_kinematics(model, parameters, w, mass_matrix);
}

Eigen::MatrixXd mass_matrix(const RobotModel& model, const Parameters& parameters, const Eigen::VectorXd& q) {
  check_parameters(model, parameters);
  DynamicsWorkspace workspace(model);
  Eigen::MatrixXd result(model.joint_count(), model.joint_count());
  mass_matrix(model, parameters, workspace, q, result);
  return result;
}

void forward_dynamics(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                      const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
                      const Eigen::Ref<const Eigen::VectorXd>& tau, Eigen::Ref<Eigen::VectorXd> qdd) {
  check_state_size(model, qd.size(), "qd");
  check_state_size(model, tau.size(), "tau");
  check_state_size(model, qdd.size(), "qdd");
  forward_kinematics(model, parameters, w, q);
  // Bias c(q, q̇) + g(q) is the inverse dynamics at zero acceleration.
  qdd.setZero();
  inverse_dynamics_at_kinematics(model, parameters, w, qd, qdd, w.bias);
  mass_matrix_at_kinematics(model, parameters, w, w.mass_matrix);
  w.factorization.compute(w.mass_matrix);
  qdd = tau - w.bias;
  w.factorization.solveInPlace(qdd);
}

Eigen::VectorXd forward_dynamics(const RobotModel& model, const Parameters& parameters, const Eigen::VectorXd& q,
                                 const Eigen::VectorXd& qd, const Eigen::VectorXd& tau) {
  check_parameters(model, parameters);
  DynamicsWorkspace workspace(model);
  Eigen::VectorXd qdd(model.joint_count());
  forward_dynamics(model, parameters, workspace, q, qd, tau, qdd);
  return qdd;
}

double kinetic_energy(const RobotModel& model, const Parameters& parameters, const Eigen::VectorXd& q,
                      const Eigen::VectorXd& qd) {
  check_state_size(model, qd.size(), "qd");
  const Eigen::MatrixXd M = mass_matrix(model, parameters, q);
  return 0.5 * qd.dot(M * qd);
}

double potential_energy(const RobotModel& model, const Parameters& parameters, const Eigen::VectorXd& q) {
  check_parameters(model, parameters);
  DynamicsWorkspace workspace(model);
  forward_kinematics(model, parameters, workspace, q);
  double energy = 0.0;
  for (int k = 1; k <= model.joint_count(); ++k) {
    energy -= parameters.mass[k - 1] * model.gravity.dot(workspace.origin[k]);
  }
  return energy;
}

}  // namespace manipid
