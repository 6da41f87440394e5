// model.h — a rigid-body serial robot as a constant model: joints, bodies, standard inertial parameters.
//
// The `robot` family sits beside the paper's point-mass chain (manipid/core/paper/model.h): any serial arm
// described by a URDF (robot/urdf.h), with recursive Newton–Euler inverse dynamics (robot/rnea.h) and a
// regressor linear in the standard parameters (robot/regressor.h).
//
// Frames. Body 0 is the base link and everything rigidly attached to it (the world). Body k (k = 1..n) is
// the link that moving joint k moves — the URDF joint's child link — together with every link rigidly
// attached to it through fixed joints; its frame is that child link's frame, which URDF makes equal to
// joint k's frame. Joint k moves body k relative to body k−1:
//
//     T_{k−1,k}(q_k) = placement_k · Rot(axis_k, q_k)      (revolute, continuous)
//     T_{k−1,k}(q_k) = placement_k · Trans(axis_k · q_k)   (prismatic)
//
// with placement_k the URDF joint origin (composed through any fixed joints between body k−1's frame and
// joint k) and axis_k a unit vector in joint k's frame.
//
// Following Pinocchio, a Model never changes during an algorithm; the per-call workspace is a separate
// Data (robot/data.h), so threads share one Model and each owns its Data.
//
// Units are SI throughout: m, rad, kg, kg·m, kg·m², s, N, N·m.
#pragma once

#include <Eigen/Core>

#include <limits>
#include <string>
#include <vector>

namespace manipid::robot {

/// A rigid transform: the pose of a child frame C in a parent frame P, x_P = rotation · x_C + translation.
struct Placement {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< C's axes in P's coordinates (orthonormal)
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   ///< C's origin in P's coordinates, m

  /// this · child: the pose, in this placement's parent frame, of a frame whose pose in C is `child`.
  Placement operator*(const Placement& child) const;
  /// The pose of P in C.
  Placement inverse() const;
};

/// URDF's fixed-axis roll, pitch, yaw: R = Rz(yaw) · Ry(pitch) · Rx(roll), angles in rad.
Eigen::Matrix3d rotation_from_rpy(double roll, double pitch, double yaw);

/// The 10 standard inertial parameters of a rigid body, in a body-fixed frame F and about F's origin:
/// mass m, first moment h = m·c (c the centre of mass in F) and the inertia tensor I_O about F's origin.
/// Newton–Euler is linear in them (robot/regressor.h), which is why identification uses this form
/// rather than (m, c, I_c).
struct InertialParameters {
  double mass = 0.0;                                       ///< m, kg
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();  ///< h = m·c, kg·m
  /// I_O about F's origin, kg·m²: the tensor's entries (Ixy is the (0,1) element, not a negated product of
  /// inertia), symmetric.
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();

  /// From the centre of mass `com` (m, in F) and the inertia about it in F's axes (kg·m²), with the
  /// parallel-axis term: I_O = I_c + m (‖c‖² E − c cᵀ).
  static InertialParameters from_centre_of_mass(double mass, const Eigen::Vector3d& com,
                                                const Eigen::Matrix3d& inertia_about_com);
  /// (m, mx, my, mz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz): one body's block of the standard vector (robot/parameters.h).
  Eigen::Matrix<double, 10, 1> vector() const;
  /// The inverse of vector().
  static InertialParameters from_vector(const Eigen::Ref<const Eigen::Matrix<double, 10, 1>>& values);

  /// c = h / m, m; zero for a massless body.
  Eigen::Vector3d centre_of_mass() const;
  /// I_c = I_O − m (‖c‖² E − c cᵀ), kg·m², in F's axes; I_O itself for a massless body.
  Eigen::Matrix3d inertia_about_centre_of_mass() const;

  /// The same body's parameters in a frame P, given the pose of F in P (`pose`): m' = m, h' = R h + m t,
  /// I'_O = R I_O Rᵀ − [R h]×[t]× − [t]×[R h]× − m [t]×².
  InertialParameters expressed_in(const Placement& pose) const;
  /// Two bodies described in the same frame, rigidly joined: every parameter adds.
  InertialParameters& operator+=(const InertialParameters& other);
};

enum class JointType {
  revolute,    ///< rotation about the axis, position limits
  continuous,  ///< rotation about the axis, no position limits
  prismatic,   ///< translation along the axis
};
/// "revolute", "continuous" or "prismatic" (the URDF's words).
const char* to_string(JointType type);

/// A joint's limits as the URDF gives them (<limit lower upper velocity effort>), for excitation design.
struct JointLimits {
  double lower = -std::numeric_limits<double>::infinity();  ///< rad (m prismatic); −∞ for continuous joints
  double upper = std::numeric_limits<double>::infinity();   ///< rad (m prismatic); +∞ for continuous joints
  double velocity = std::numeric_limits<double>::infinity();  ///< rad/s (m/s); +∞ when the URDF has no <limit>
  double effort = std::numeric_limits<double>::infinity();    ///< N·m (N); +∞ when the URDF has no <limit>
};

/// Moving joint k (1..n from the base): what it is, where it sits, how it is limited.
struct Joint {
  std::string name;  ///< the URDF joint's name
  std::string link;  ///< the URDF link it moves (its child link): body k, whose frame is this link's frame
  JointType type = JointType::revolute;
  /// Unit vector in joint k's frame (= body k's frame): rotation axis (right-handed) or direction of travel.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  /// Pose of joint k's frame at q_k = 0 in body k−1's frame (body 0: the base link's frame), composed
  /// through any fixed joints between.
  Placement placement;
  JointLimits limits;
  /// URDF <dynamics damping>: viscous friction coefficient, N·m·s/rad (N·s/m prismatic); 0 when absent.
  double damping = 0.0;
  /// URDF <dynamics friction>: Coulomb friction, N·m (N prismatic); 0 when absent.
  double friction = 0.0;

  bool is_prismatic() const { return type == JointType::prismatic; }
};

/// Body k: the links moving with joint k, merged into one rigid body.
struct Body {
  /// The URDF links merged into this body: joint k's child link first, then the links rigidly attached to
  /// it (a flange, a sensor, a side branch), in the order they were found.
  std::vector<std::string> links;
  /// The merged inertial parameters, in body k's frame about its origin.
  InertialParameters inertia;
};

/// The constant description of a serial robot: n moving joints, n bodies, gravity. Index k−1 of `joints`
/// and `bodies` is joint k and body k.
struct Model {
  std::string name;       ///< the URDF robot's name
  std::string base_link;  ///< the URDF link fixed to the world (body 0's frame)
  std::string tip_link;   ///< the URDF link that ends the chain (rigidly attached to body n)
  std::vector<Joint> joints;
  std::vector<Body> bodies;
  /// Acceleration of gravity in the base link's frame, m/s².
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  /// Pose of the tip link's frame in body n's frame (identity when the tip is joint n's child link).
  Placement tip_placement;

  int joint_count() const { return static_cast<int>(joints.size()); }
};

}  // namespace manipid::robot
