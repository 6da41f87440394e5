// forward_pass.h — the outward kinematic sweep shared by the RNEA and the regressor (not installed).
#pragma once

#include "manipid/core/errors.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/model.h"

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross

#include <cmath>
#include <string>

namespace manipid::robot::detail {

/// Rot(a, q) for a unit axis a, from c = cos q and s = sin q (Rodrigues): c E + s [a]× + (1 − c) a aᵀ.
inline Eigen::Matrix3d axis_rotation(const Eigen::Vector3d& a, double c, double s) {
  const double v = 1.0 - c;
  const double xv = a.x() * v, yv = a.y() * v, zv = a.z() * v;
  const double xs = a.x() * s, ys = a.y() * s, zs = a.z() * s;
  Eigen::Matrix3d R;
  R << a.x() * xv + c, a.x() * yv - zs, a.x() * zv + ys,  //
      a.y() * xv + zs, a.y() * yv + c, a.y() * zv - xs,    //
      a.z() * xv - ys, a.z() * yv + xs, a.z() * zv + c;
  return R;
}

/// Throws InputError unless `data` was made for a model with this many joints.
inline void check_data(const Model& model, const Data& data) {
  if (data.joint_count() != model.joint_count()) {
    throw InputError("data", "the workspace was made for a " + std::to_string(data.joint_count()) +
                                 "-joint model, not this " + std::to_string(model.joint_count()) + "-joint one");
  }
}

/// Throws InputError(field) unless v has `expected` entries.
inline void check_size(const char* field, Eigen::Index size, Eigen::Index expected) {
  if (size != expected) {
    throw InputError(field, std::string(field) + " has " + std::to_string(size) + " entries, expected " +
                                std::to_string(expected));
  }
}

/// Outward sweep: for bodies 1..n, R_{k−1,k}, p_{k−1,k}, ω_k, ω̇_k and the proper acceleration of the
/// origin (a_k − g), each in body k's frame; the base's "acceleration" −g carries gravity to every body.
inline void forward_pass(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                         const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd) {
  const int n = model.joint_count();
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();  // of body k−1, in its frame
  Eigen::Vector3d alpha = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration = -model.gravity;
  for (int k = 0; k < n; ++k) {
    const Joint& joint = model.joints[k];
    const Eigen::Vector3d& axis = joint.axis;
    Eigen::Matrix3d& R = data.rotation[k];
    Eigen::Vector3d& p = data.translation[k];
    const bool prismatic = joint.is_prismatic();
    if (prismatic) {
      R = joint.placement.rotation;
      p = joint.placement.translation + R * (axis * q[k]);
    } else {
      R.noalias() = joint.placement.rotation * axis_rotation(axis, std::cos(q[k]), std::sin(q[k]));
      p = joint.placement.translation;
    }
    // Body k's origin as a point of body k−1, then into body k's frame.
    const Eigen::Vector3d point_acceleration = acceleration + alpha.cross(p) + omega.cross(omega.cross(p));
    const Eigen::Vector3d omega_parent = R.transpose() * omega;
    acceleration.noalias() = R.transpose() * point_acceleration;
    alpha = R.transpose() * alpha;
    const Eigen::Vector3d rate = axis * qd[k];  // joint rate: angular (revolute) or linear (prismatic)
    if (prismatic) {
      acceleration += 2.0 * omega_parent.cross(rate) + axis * qdd[k];
      omega = omega_parent;
    } else {
      alpha += omega_parent.cross(rate) + axis * qdd[k];
      omega = omega_parent + rate;
    }
    data.angular_velocity[k] = omega;
    data.angular_acceleration[k] = alpha;
    data.proper_acceleration[k] = acceleration;
  }
}

}  // namespace manipid::robot::detail
