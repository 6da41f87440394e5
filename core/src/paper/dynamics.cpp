// dynamics.cpp — kinematics, inverse/forward dynamics and energies (dynamics.h).
//
// Everything is computed in base coordinates. For point masses the complete model's inverse
// dynamics is Newton's law projected on the joint axes, τ_j = z_{j-1}·Σ_{k≥j} (o_k − o_{j-1})
// × m_k (ö_k − gravity) + J_j q̈_j, evaluated by one forward (accelerations) and one backward
// (forces, moments) pass. The paper's simplified kinetic energy has a diagonal, configuration-
// dependent mass matrix; its Lagrange equations are written out from the position Jacobians.
// The complete model's inverse and forward dynamics run in dynamics_kernels.h, specialised
// on the joint count; the paper variant and the kinematics queries use the code here.
#include "manipid/core/paper/dynamics.h"

#include "paper/dynamics_kernels.h"
#include "paper/frame_update.h"
#include "vector_clones.h"

#include <cmath>
#include <string>

// The complete model's two kernels are compiled for baseline x86-64 and for AVX2
// (vector_clones.h): ~25 % faster on this host, and the same numbers bit for bit (compared on
// every output of bench/dynamics_count's calls).

namespace manipid {
namespace {

[[noreturn, gnu::noinline, gnu::cold]] void throw_state_size_error(const RobotModel& model, Eigen::Index size,
                                                                 const char* field) {
  throw InputError(field, std::string(field) + " has " + std::to_string(size) + " entries, the model has " +
                              std::to_string(model.joint_count()) + " joints");
}

// Inline, with the message built out of line: the check runs four times per dynamics call.
inline void check_state_size(const RobotModel& model, Eigen::Index size, const char* field) {
  if (size != model.joint_count()) [[unlikely]] throw_state_size_error(model, size, field);
}

using detail::joint_inertia;

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

// The complete model through the kernel for N joints (Eigen::Dynamic: any number, with the
// workspace's scratch). Always inlined, so that each copy below is compiled for its target.
template <int N>
[[gnu::always_inline]] inline void inverse_dynamics_sized(const RobotModel& model, const Parameters& parameters,
                                                          DynamicsWorkspace& w, const double* q, const double* qd,
                                                          const double* qdd, Eigen::Ref<Eigen::VectorXd>& tau) {
  if constexpr (N == Eigen::Dynamic) {
    detail::complete_inverse_dynamics<N>(model, parameters, w, q, qd, qdd, w.general, tau);
  } else {
    detail::FixedStorage<N> storage;
    detail::complete_inverse_dynamics<N>(model, parameters, w, q, qd, qdd, storage, tau);
  }
}

// Returns false when M is not positive definite, leaving M (lower triangle) in
// w.mass_matrix and the bias in w.bias for the caller's fallback.
template <int N>
[[gnu::always_inline]] inline bool forward_dynamics_sized(const RobotModel& model, const Parameters& parameters,
                                                          DynamicsWorkspace& w, const double* q, const double* qd,
                                                          const double* tau, Eigen::Ref<Eigen::VectorXd>& qdd) {
  if constexpr (N == Eigen::Dynamic) {
    if (detail::complete_forward_dynamics<N>(model, parameters, w, q, qd, tau, w.general, qdd)) return true;
    w.mass_matrix = w.general.mass_matrix;
    w.bias = w.general.bias;
  } else {
    detail::FixedStorage<N> storage;
    if (detail::complete_forward_dynamics<N>(model, parameters, w, q, qd, tau, storage, qdd)) return true;
    w.mass_matrix = storage.mass_matrix;
    w.bias = storage.bias;
  }
  return false;
}

// The kernels specialised for 1..6 joints, the general-size code otherwise or when the
// workspace asks for it. Nothing here throws (the callers check sizes), as target_clones'
// dispatcher requires.
MANIPID_VECTOR_CLONES
void complete_inverse_dynamics(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                               const double* q, const double* qd, const double* qdd,
                               Eigen::Ref<Eigen::VectorXd>& tau) noexcept {
  switch (w.fixed_size_kernels ? model.joint_count() : 0) {
    case 1: return inverse_dynamics_sized<1>(model, parameters, w, q, qd, qdd, tau);
    case 2: return inverse_dynamics_sized<2>(model, parameters, w, q, qd, qdd, tau);
    case 3: return inverse_dynamics_sized<3>(model, parameters, w, q, qd, qdd, tau);
    case 4: return inverse_dynamics_sized<4>(model, parameters, w, q, qd, qdd, tau);
    case 5: return inverse_dynamics_sized<5>(model, parameters, w, q, qd, qdd, tau);
    case 6: return inverse_dynamics_sized<6>(model, parameters, w, q, qd, qdd, tau);
    default: return inverse_dynamics_sized<Eigen::Dynamic>(model, parameters, w, q, qd, qdd, tau);
  }
}

MANIPID_VECTOR_CLONES
bool complete_forward_dynamics(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                               const double* q, const double* qd, const double* tau,
                               Eigen::Ref<Eigen::VectorXd>& qdd) noexcept {
  switch (w.fixed_size_kernels ? model.joint_count() : 0) {
    case 1: return forward_dynamics_sized<1>(model, parameters, w, q, qd, tau, qdd);
    case 2: return forward_dynamics_sized<2>(model, parameters, w, q, qd, tau, qdd);
    case 3: return forward_dynamics_sized<3>(model, parameters, w, q, qd, tau, qdd);
    case 4: return forward_dynamics_sized<4>(model, parameters, w, q, qd, tau, qdd);
    case 5: return forward_dynamics_sized<5>(model, parameters, w, q, qd, tau, qdd);
    case 6: return forward_dynamics_sized<6>(model, parameters, w, q, qd, tau, qdd);
    default: return forward_dynamics_sized<Eigen::Dynamic>(model, parameters, w, q, qd, tau, qdd);
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
  for (Eigen::VectorXd* scalars : {&general.joint_sin, &general.joint_cos, &general.link_a, &general.link_d,
                                   &general.bias}) {
    scalars->setZero(n);
  }
  for (std::vector<Eigen::Vector3d>* vectors :
       {&general.joint_axis, &general.link_arm, &general.mass_acceleration, &general.mass_jacobian}) {
    vectors->assign(n, Eigen::Vector3d::Zero());
  }
  general.mass_matrix.setZero(n, n);
  general.cholesky_factor.setZero(n, n);
}

void forward_kinematics(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& w,
                        const Eigen::Ref<const Eigen::VectorXd>& q) {
  const int n = model.joint_count();
  check_state_size(model, q.size(), "q");
  for (int k = 0; k < n; ++k) detail::sine_cosine(q[k], w.joint_sin[k], w.joint_cos[k]);
  Eigen::Matrix3d rotation = w.rotation[0];
  Eigen::Vector3d origin = w.origin[0];
  for (int k = 1; k <= n; ++k) {
    const Eigen::Vector3d z = rotation.col(2);
    detail::update_rotation(rotation, w.joint_cos[k - 1], w.joint_sin[k - 1], w.twist_cos[k - 1], w.twist_sin[k - 1], rotation);
    double a = 0.0;
    double d = 0.0;
    detail::link_offsets(model, parameters, k - 1, a, d);
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
  if (model.kinetic_energy == KineticEnergy::paper) {
    forward_kinematics(model, parameters, workspace, q);
    inverse_dynamics_paper(model, parameters, workspace, qd, qdd, tau);
    return;
  }
  check_state_size(model, q.size(), "q");
  complete_inverse_dynamics(model, parameters, workspace, q.data(), qd.data(), qdd.data(), tau);
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
  if (model.kinetic_energy == KineticEnergy::paper) {
    forward_kinematics(model, parameters, w, q);
    // Bias c(q, q̇) + g(q) is the inverse dynamics at zero acceleration.
    qdd.setZero();
    inverse_dynamics_paper(model, parameters, w, qd, qdd, w.bias);
    mass_matrix_at_kinematics(model, parameters, w, w.mass_matrix);
    w.factorization.compute(w.mass_matrix);
    qdd = tau - w.bias;
    w.factorization.solveInPlace(qdd);
    return;
  }
  check_state_size(model, q.size(), "q");
  if (!complete_forward_dynamics(model, parameters, w, q.data(), qd.data(), tau.data(), qdd)) {
    // M is not positive definite (e.g. a negative mass from a user's parameters): a pivoting
    // LDLT still solves what can be solved, as it always has.
    w.mass_matrix.triangularView<Eigen::StrictlyUpper>() = w.mass_matrix.transpose();
    w.factorization.compute(w.mass_matrix);
    qdd = tau - w.bias;
    w.factorization.solveInPlace(qdd);
  }
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
