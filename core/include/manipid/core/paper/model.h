// model.h — the constant description of a serial manipulator and its parameters.
//
// A chain of revolute joints. Joint k moves frame k relative to frame k-1 by the standard
// Denavit–Hartenberg row
//
//     T_k = Rz(q_k) · Tz(d_k) · Tx(a_k) · Rx(alpha_k),
//
// so joint k turns about the z axis of frame k-1. Each link carries a point mass m_k at the
// origin of frame k (its distal end) and a joint inertia J_k = m_k l_k^2 / 12 that sees only
// its own joint rate q̇_k (the paper's Ko[k]). The link length l_k is a *parameter*: it sets
// a_k or d_k (see LengthRole) and it sets J_k, so identification can estimate it.
//
// Following Pinocchio, the model never changes during an algorithm; per-call scratch space
// lives in a separate workspace (dynamics.h), so threads can share one model.
#pragma once

#include "manipid/core/errors.h"

#include <Eigen/Core>

#include <stdexcept>
#include <string>
#include <vector>

namespace manipid {

/// Which DH offset of a joint's row the link-length parameter l_k sets.
enum class LengthRole {
  none,  ///< l_k enters only through the joint inertia J_k (the paper's link 1)
  a,     ///< a_k = l_k: translation along the new x axis (the paper's links 2..4)
  d,     ///< d_k = l_k: translation along the previous z axis
};

/// How kinetic energy is formed.
enum class KineticEnergy {
  /// K = ½ Σ_k m_k |ṗ_k|² + ½ Σ_k J_k q̇_k²: the physics. Default.
  complete,
  /// The paper's printed K: for each mass only the j = k terms of the double sum,
  /// K = ½ Σ_k m_k Σ_j |∂p_k/∂q_j|² q̇_j² + ½ Σ_k J_k q̇_k², which drops the cross terms
  /// between joints and makes the point-mass part of the mass matrix diagonal. A
  /// simplification, offered only to reproduce the paper's published numbers.
  paper,
};

const char* to_string(KineticEnergy kinetic_energy);
/// Parses "complete" or "paper"; throws InputError(field) otherwise.
KineticEnergy parse_kinetic_energy(const std::string& text,
                                   const std::string& field = "kinetic_energy");

/// One revolute joint's DH row. Offsets not set by the length parameter are fixed here.
struct JointDescription {
  double alpha = 0.0;  ///< twist about the new x axis, rad
  double a = 0.0;      ///< fixed offset along the new x axis, m (ignored when length_role == a)
  double d = 0.0;      ///< fixed offset along the previous z axis, m (ignored when length_role == d)
  LengthRole length_role = LengthRole::a;
};

/// The constant description of a manipulator.
struct RobotModel {
  std::vector<JointDescription> joints;
  /// Acceleration of gravity in base coordinates, m/s². The potential energy of mass k is
  /// V_k = -m_k gravity·p_k. The paper prints V_k = -m_k (0,0,g)·p_k, i.e. gravity = (0,0,+g).
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  KineticEnergy kinetic_energy = KineticEnergy::complete;
  /// J_k = joint_inertia_factor · m_k · l_k². The paper uses 1/12 (a slender rod about its centre).
  double joint_inertia_factor = 1.0 / 12.0;

  int joint_count() const { return static_cast<int>(joints.size()); }
  /// Number of parameters: n masses then n lengths.
  int parameter_count() const { return 2 * joint_count(); }
};

/// The identifiable parameters θ = (m_1..m_n, l_1..l_n): masses in kg, lengths in m.
struct Parameters {
  Eigen::VectorXd mass;
  Eigen::VectorXd length;

  Parameters() = default;
  Parameters(Eigen::VectorXd mass_kg, Eigen::VectorXd length_m)
      : mass(std::move(mass_kg)), length(std::move(length_m)) {}

  int joint_count() const { return static_cast<int>(mass.size()); }
  /// θ as one vector: (m_1..m_n, l_1..l_n).
  Eigen::VectorXd vector() const;
  static Parameters from_vector(const Eigen::VectorXd& theta);

  /// Value by name ("m1".."mn", "l1".."ln"); throws InputError on an unknown name.
  double get(const std::string& name) const;
  void set(const std::string& name, double value);
};

/// Names of the parameters in θ order: m1..mn, l1..ln.
std::vector<std::string> parameter_names(int joint_count);
/// Index of a parameter name in θ, or -1 when the name is not one of them.
int parameter_index(const std::string& name, int joint_count);

/// Throws InputError unless the parameters fit the model (sizes) and are finite.
void check_parameters(const RobotModel& model, const Parameters& parameters);

/// The values a link's mass and length can sensibly take, for values a user gives: starting
/// values of an identification and the robot a simulation runs. A gram to a hundred tonnes,
/// a millimetre to a hundred metres — wide for any manipulator, narrow enough that products
/// such as m·l² (down to 1e-9, up to 1e9) and the filtered torques stay far from underflow
/// and overflow. Where the optimiser may go afterwards is set by the bounds, not by these.
struct ValueRange {
  double lowest = 0.0;
  double highest = 0.0;
};
inline constexpr ValueRange kMassRange{1e-3, 1e5};    ///< kg
inline constexpr ValueRange kLengthRange{1e-3, 1e2};  ///< m

/// Throws InputError unless every mass lies in kMassRange and every length in kLengthRange.
/// The field is `prefix` + "." + the parameter name ("initial.m2"), or the bare name when
/// `prefix` is empty; the message says the value, the unit and the range.
void check_parameter_ranges(const Parameters& parameters, const std::string& prefix);

}  // namespace manipid
