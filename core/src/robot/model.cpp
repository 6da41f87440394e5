// model.cpp — rigid transforms, standard inertial parameters and the Data workspace (robot/model.h, data.h).
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/model.h"

#include "robot/skew.h"

#include <cmath>

namespace manipid::robot {

Placement Placement::operator*(const Placement& child) const {
  Placement result;
  result.rotation.noalias() = rotation * child.rotation;
  result.translation = translation + rotation * child.translation;
  return result;
}

Placement Placement::inverse() const {
  Placement result;
  result.rotation = rotation.transpose();
  result.translation = -(result.rotation * translation);
  return result;
}

Eigen::Matrix3d rotation_from_rpy(double roll, double pitch, double yaw) {
  const double cr = std::cos(roll), sr = std::sin(roll);
  const double cp = std::cos(pitch), sp = std::sin(pitch);
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  Eigen::Matrix3d Rx, Ry, Rz;
  Rx << 1, 0, 0, 0, cr, -sr, 0, sr, cr;
  Ry << cp, 0, sp, 0, 1, 0, -sp, 0, cp;
  Rz << cy, -sy, 0, sy, cy, 0, 0, 0, 1;
  return Rz * Ry * Rx;
}

InertialParameters InertialParameters::from_centre_of_mass(double mass, const Eigen::Vector3d& com,
                                                           const Eigen::Matrix3d& inertia_about_com) {
  InertialParameters result;
  result.mass = mass;
  result.first_moment = mass * com;
  // I_O = I_c + m (‖c‖² E − c cᵀ) = I_c − m [c]×²
  const Eigen::Matrix3d C = skew(com);
  result.inertia = inertia_about_com - mass * (C * C);
  return result;
}

Eigen::Matrix<double, 10, 1> InertialParameters::vector() const {
  Eigen::Matrix<double, 10, 1> v;
  v << mass, first_moment, inertia(0, 0), inertia(0, 1), inertia(0, 2), inertia(1, 1), inertia(1, 2), inertia(2, 2);
  return v;
}

InertialParameters InertialParameters::from_vector(const Eigen::Ref<const Eigen::Matrix<double, 10, 1>>& v) {
  InertialParameters result;
  result.mass = v[0];
  result.first_moment = v.segment<3>(1);
  result.inertia << v[4], v[5], v[6],  //
      v[5], v[7], v[8],                 //
      v[6], v[8], v[9];
  return result;
}

Eigen::Vector3d InertialParameters::centre_of_mass() const {
  return mass > 0.0 ? Eigen::Vector3d(first_moment / mass) : Eigen::Vector3d::Zero();
}

Eigen::Matrix3d InertialParameters::inertia_about_centre_of_mass() const {
  if (!(mass > 0.0)) return inertia;
  // I_c = I_O + m [c]×² = I_O + [h]×² / m
  const Eigen::Matrix3d H = skew(first_moment);
  return inertia + (H * H) / mass;
}

InertialParameters InertialParameters::expressed_in(const Placement& pose) const {
  const Eigen::Matrix3d& R = pose.rotation;
  const Eigen::Vector3d& t = pose.translation;
  InertialParameters result;
  result.mass = mass;
  const Eigen::Vector3d Rh = R * first_moment;
  result.first_moment = Rh + mass * t;
  // Σ −m_i [R r_i + t]×² expanded: R I Rᵀ − [Rh]×[t]× − [t]×[Rh]× − m [t]×².
  const Eigen::Matrix3d T = skew(t), H = skew(Rh);
  const Eigen::Matrix3d I = R * inertia * R.transpose() - H * T - T * H - mass * (T * T);
  result.inertia = 0.5 * (I + I.transpose());  // exactly symmetric, whatever R's rounding
  return result;
}

InertialParameters& InertialParameters::operator+=(const InertialParameters& other) {
  mass += other.mass;
  first_moment += other.first_moment;
  inertia += other.inertia;
  return *this;
}

const char* to_string(JointType type) {
  switch (type) {
    case JointType::revolute: return "revolute";
    case JointType::continuous: return "continuous";
    case JointType::prismatic: return "prismatic";
  }
  return "unknown";
}

Data::Data(const Model& model)
    : rotation(model.joints.size(), Eigen::Matrix3d::Identity()),
      translation(model.joints.size(), Eigen::Vector3d::Zero()),
      angular_velocity(model.joints.size(), Eigen::Vector3d::Zero()),
      angular_acceleration(model.joints.size(), Eigen::Vector3d::Zero()),
      proper_acceleration(model.joints.size(), Eigen::Vector3d::Zero()),
      force(model.joints.size(), Eigen::Vector3d::Zero()),
      moment(model.joints.size(), Eigen::Vector3d::Zero()) {}

}  // namespace manipid::robot
