// frame_update.h — internal: one step of the DH chain, shared by dynamics.cpp and regressor.cpp.
#pragma once

#include <Eigen/Core>

#include <cmath>

namespace manipid::detail {

/// rotation = previous · Rz(q) · Rx(alpha), given c = cos q, s = sin q and cos/sin of the
/// (constant) twist alpha;
/// the new x axis (along which offset a runs) is unchanged by the twist.
inline void update_rotation(const Eigen::Matrix3d& previous, double c, double s, double cos_alpha, double sin_alpha,
                            Eigen::Matrix3d& rotation) {
  const Eigen::Vector3d x = c * previous.col(0) + s * previous.col(1);
  const Eigen::Vector3d y = c * previous.col(1) - s * previous.col(0);
  const Eigen::Vector3d z = previous.col(2);
  rotation.col(0) = x;
  rotation.col(1) = cos_alpha * y + sin_alpha * z;
  rotation.col(2) = cos_alpha * z - sin_alpha * y;
}

}  // namespace manipid::detail
