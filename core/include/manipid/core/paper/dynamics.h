// dynamics.h — inverse and forward dynamics, mass matrix, energies and kinematics.
//
// Equations of motion from Lagrange's equations, τ = M(q) q̈ + c(q, q̇) + g(q), for the
// model's kinetic-energy variant (model.h). Every algorithm is a free function over a
// constant model, the parameters, and a per-thread DynamicsWorkspace that holds scratch
// space, so nothing allocates in the inner loops once the workspace exists.
//
// Units: q rad, q̇ rad/s, q̈ rad/s², τ N·m; all vectors have the model's joint count n.
#pragma once

#include "manipid/core/paper/model.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace manipid {

/// Per-call scratch space; create one per thread and reuse it. Sized for one model.
struct DynamicsWorkspace {
  explicit DynamicsWorkspace(const RobotModel& model);

  // cos and sin of each joint's constant twist, computed once.
  Eigen::VectorXd twist_cos, twist_sin;
  // cos and sin of the current joint angles.
  Eigen::VectorXd joint_cos, joint_sin;

  // Kinematics of frames 0..n (index 0 is the base), world coordinates.
  std::vector<Eigen::Matrix3d> rotation;       // R_k
  std::vector<Eigen::Vector3d> origin;         // o_k
  std::vector<Eigen::Vector3d> velocity;       // ȯ_k
  std::vector<Eigen::Vector3d> acceleration;   // ö_k
  std::vector<Eigen::Vector3d> angular_velocity;
  std::vector<Eigen::Vector3d> angular_acceleration;
  Eigen::Matrix3Xd jacobian;                   // scratch: 3 × n·n position Jacobians
  Eigen::MatrixXd mass_matrix;                 // n × n
  Eigen::VectorXd bias;                        // n
  Eigen::LDLT<Eigen::MatrixXd> factorization;  // of the mass matrix

  // The complete model's kernels run with the joint count fixed at compile time for 1..6
  // joints and keep their scratch on the stack; for more joints, or when fixed_size_kernels
  // is false (tests compare the two), they use this scratch (n entries each, see
  // core/src/paper/dynamics_kernels.h for the meaning).
  bool fixed_size_kernels = true;
  struct GeneralSizeScratch {
    Eigen::VectorXd joint_sin, joint_cos, link_a, link_d, bias;
    std::vector<Eigen::Vector3d> joint_axis, link_arm, mass_acceleration, mass_jacobian;
    Eigen::MatrixXd mass_matrix, cholesky_factor;
  } general;
};

/// Forward kinematics: fills workspace.rotation and workspace.origin for frames 0..n.
void forward_kinematics(const RobotModel& model, const Parameters& parameters,
                        DynamicsWorkspace& workspace, const Eigen::Ref<const Eigen::VectorXd>& q);

/// Position of the point mass k (1-based, the origin of frame k) in base coordinates, m.
Eigen::Vector3d mass_position(const RobotModel& model, const Parameters& parameters,
                              const Eigen::Ref<const Eigen::VectorXd>& q, int k);

/// τ(q, q̇, q̈, θ): the joint torques that produce the motion (q, q̇, q̈).
void inverse_dynamics(const RobotModel& model, const Parameters& parameters,
                      DynamicsWorkspace& workspace, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& qd,
                      const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::VectorXd> tau);
Eigen::VectorXd inverse_dynamics(const RobotModel& model, const Parameters& parameters,
                                 const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                 const Eigen::VectorXd& qdd);

/// M(q): the joint-space mass matrix, symmetric positive definite (diagonal point-mass part
/// for KineticEnergy::paper). Written to `mass_matrix` (n × n).
void mass_matrix(const RobotModel& model, const Parameters& parameters, DynamicsWorkspace& workspace,
                 const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Ref<Eigen::MatrixXd> mass_matrix);
Eigen::MatrixXd mass_matrix(const RobotModel& model, const Parameters& parameters,
                            const Eigen::VectorXd& q);

/// q̈(q, q̇, τ, θ) = M(q)⁻¹ (τ − c(q, q̇) − g(q)).
void forward_dynamics(const RobotModel& model, const Parameters& parameters,
                      DynamicsWorkspace& workspace, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& qd,
                      const Eigen::Ref<const Eigen::VectorXd>& tau, Eigen::Ref<Eigen::VectorXd> qdd);
Eigen::VectorXd forward_dynamics(const RobotModel& model, const Parameters& parameters,
                                 const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                 const Eigen::VectorXd& tau);

/// Kinetic energy ½ q̇ᵀ M(q) q̇ (J), for the model's variant.
double kinetic_energy(const RobotModel& model, const Parameters& parameters,
                      const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
/// Potential energy V = −Σ m_k gravity·p_k (J).
double potential_energy(const RobotModel& model, const Parameters& parameters,
                        const Eigen::VectorXd& q);

}  // namespace manipid
