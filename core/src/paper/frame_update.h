// frame_update.h — internal: one step of the DH chain, shared by dynamics.cpp and regressor.cpp.
#pragma once

#include <Eigen/Core>

#include <cmath>

namespace manipid::detail {

/// The axes of frame k from those of frame k − 1 (x, y, z): R_k = R_{k−1} · Rz(q) · Rx(α), given
/// c = cos q, s = sin q and cos/sin of the (constant) twist α; the new x axis (along which offset
/// a runs) is unchanged by the twist. For any vector type with +, − and a scalar's ×: Eigen's,
/// and the regressor's four-sample lanes (regressor.cpp), so both compute it alike.
template <typename Vector, typename Scalar>
inline void next_axes(const Vector& x, const Vector& y, const Vector& z, const Scalar& c, const Scalar& s,
                      double cos_alpha, double sin_alpha, Vector& new_x, Vector& new_y, Vector& new_z) {
  const Vector turned_y = c * y - s * x;
  new_x = c * x + s * y;
  new_y = cos_alpha * turned_y + sin_alpha * z;
  new_z = cos_alpha * z - sin_alpha * turned_y;
}

/// rotation = previous · Rz(q) · Rx(alpha) (next_axes on its columns); `rotation` may be `previous`.
inline void update_rotation(const Eigen::Matrix3d& previous, double c, double s, double cos_alpha, double sin_alpha,
                            Eigen::Matrix3d& rotation) {
  Eigen::Vector3d x, y, z;
  next_axes<Eigen::Vector3d, double>(previous.col(0), previous.col(1), previous.col(2), c, s, cos_alpha, sin_alpha, x, y, z);
  rotation.col(0) = x;
  rotation.col(1) = y;
  rotation.col(2) = z;
}

}  // namespace manipid::detail
