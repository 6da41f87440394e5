// skew.h — the cross-product matrix [v]×, shared by the robot sources (not installed).
#pragma once

#include <Eigen/Core>

namespace manipid::robot {

/// [v]× with [v]× w = v × w.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v.z(), v.y(),  //
      v.z(), 0.0, -v.x(),    //
      -v.y(), v.x(), 0.0;
  return S;
}

}  // namespace manipid::robot
