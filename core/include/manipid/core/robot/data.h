// data.h — the per-call workspace of the robot algorithms (RNEA, regressor), one per thread.
//
// Pinocchio's Model/Data split: a Model (robot/model.h) is constant and shared; a Data holds what an
// algorithm computes along the way. It is sized once for one Model, so the algorithms allocate nothing.
// After a call, its fields hold that call's kinematics and wrenches (documented per field).
#pragma once

#include "manipid/core/robot/model.h"

#include <Eigen/Core>

#include <vector>

namespace manipid::robot {

/// Workspace for one Model; index k−1 of every vector is body k (k = 1..n), expressed in body k's frame.
struct Data {
  explicit Data(const Model& model);

  int joint_count() const { return static_cast<int>(rotation.size()); }

  std::vector<Eigen::Matrix3d> rotation;     ///< R_{k−1,k}(q): body k's axes in body k−1's frame
  std::vector<Eigen::Vector3d> translation;  ///< p_{k−1,k}(q): body k's origin in body k−1's frame, m
  std::vector<Eigen::Vector3d> angular_velocity;      ///< ω_k, rad/s
  std::vector<Eigen::Vector3d> angular_acceleration;  ///< ω̇_k, rad/s²
  /// Acceleration of body k's origin minus gravity (what an accelerometer there reads), m/s².
  std::vector<Eigen::Vector3d> proper_acceleration;
  std::vector<Eigen::Vector3d> force;   ///< f_k: force joint k exerts on body k (and all beyond), N
  std::vector<Eigen::Vector3d> moment;  ///< n_k: its moment about body k's origin, N·m
};

}  // namespace manipid::robot
