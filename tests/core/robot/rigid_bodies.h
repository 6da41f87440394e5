// rigid_bodies.h — test support: textbook solids as standard parameters, random θ, parameter structures.
#pragma once

#include "manipid/core/robot/consistency.h"

#include <Eigen/Geometry>

#include <random>
#include <string>

namespace manipid::robot::testing {

/// Standard parameters (about the link origin, in link axes) of a body with mass m (kg),
/// inertia I_c about its centre of mass in its own axes (kg·m²), turned by `rotation` and with
/// its centre of mass at c (m): I_O = R I_c Rᵀ + m(‖c‖²E − c cᵀ), h = m c.
inline Vector10d place(double mass, const Eigen::Matrix3d& inertia_about_com, const Eigen::Vector3d& com,
                       const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity()) {
  const Eigen::Matrix3d turned = rotation * inertia_about_com * rotation.transpose();
  const Eigen::Matrix3d origin =
      turned + mass * (com.squaredNorm() * Eigen::Matrix3d::Identity() - com * com.transpose());
  Vector10d link;
  link << mass, mass * com, origin(0, 0), origin(0, 1), origin(0, 2), origin(1, 1), origin(1, 2), origin(2, 2);
  return link;
}

/// Solid box with edges a, b, c (m) along x, y, z: I_c = m/12 diag(b²+c², a²+c², a²+b²).
inline Eigen::Matrix3d box_inertia(double mass, double a, double b, double c) {
  return Eigen::Vector3d(b * b + c * c, a * a + c * c, a * a + b * b).asDiagonal() * (mass / 12.0);
}

/// Solid cylinder of radius r and height h (m) along z: I_c = diag(m(3r²+h²)/12, same, m r²/2).
inline Eigen::Matrix3d cylinder_inertia(double mass, double radius, double height) {
  const double side = mass * (3.0 * radius * radius + height * height) / 12.0;
  return Eigen::Vector3d(side, side, 0.5 * mass * radius * radius).asDiagonal();
}

/// Solid sphere of radius r (m): I_c = (2/5) m r² E.
inline Eigen::Matrix3d sphere_inertia(double mass, double radius) {
  return Eigen::Matrix3d::Identity() * (0.4 * mass * radius * radius);
}

inline Eigen::Matrix3d some_rotation() {
  return (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, -0.5).normalized()) *
          Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

/// θ drawn so that the body is like a robot link: m = e^{2α} ∈ [0.05, 55] kg, conditional radii
/// of gyration e^{d} ∈ [0.03, 0.37] m, couplings s within ±0.12 m (a 0.4 m × 0.1 m box turned
/// any way has |s| ≤ 0.4/√12 = 0.115 m and e^{d} ≥ 0.1/√12 = 0.029 m), centre of mass t within ±0.3 m.
inline Vector10d random_log_cholesky(std::mt19937_64& engine) {
  std::uniform_real_distribution<double> alpha(-1.5, 2.0), d(-3.5, -1.0), s(-0.12, 0.12), t(-0.3, 0.3);
  Vector10d theta;
  theta << alpha(engine), d(engine), d(engine), d(engine), s(engine), s(engine), s(engine), t(engine), t(engine),
      t(engine);
  return theta;
}

/// A serial arm's parameter structure: `links` links (10 entries each, first), then per joint
/// fv (≥ 0), fc (≥ 0), fo (free). Names: "link1".."linkN" and "m1", "mx1", ..., "fv1", "fc1", "fo1".
inline ParameterStructure arm_structure(int links) {
  ParameterStructure structure;
  structure.parameter_count = 13 * links;
  const char* inertial[10] = {"m", "mx", "my", "mz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"};
  for (int k = 0; k < links; ++k) {
    structure.link_offsets.push_back(10 * k);
    structure.link_names.push_back("link" + std::to_string(k + 1));
    for (const char* name : inertial) structure.parameter_names.push_back(name + std::to_string(k + 1));
  }
  for (int k = 0; k < links; ++k) {
    const int base = 10 * links + 3 * k;
    structure.non_negative.push_back(base);      // fv
    structure.non_negative.push_back(base + 1);  // fc
    for (const char* name : {"fv", "fc", "fo"}) structure.parameter_names.push_back(name + std::to_string(k + 1));
  }
  return structure;
}

}  // namespace manipid::robot::testing
