// parameters.cpp — the standard vector's layout, names and the model's own values (robot/parameters.h).
#include "manipid/core/robot/parameters.h"

namespace manipid::robot {

int ParameterLayout::size(int joint_count) const {
  return joint_count * (kInertialParametersPerBody + int(viscous) + int(coulomb) + int(offset) + int(armature));
}

// The blocks follow each other in the order viscous, coulomb, offset, armature after the inertial ones.
int ParameterLayout::viscous_begin(int joint_count) const {
  return viscous ? kInertialParametersPerBody * joint_count : -1;
}
int ParameterLayout::coulomb_begin(int joint_count) const {
  return coulomb ? joint_count * (kInertialParametersPerBody + int(viscous)) : -1;
}
int ParameterLayout::offset_begin(int joint_count) const {
  return offset ? joint_count * (kInertialParametersPerBody + int(viscous) + int(coulomb)) : -1;
}
int ParameterLayout::armature_begin(int joint_count) const {
  return armature ? joint_count * (kInertialParametersPerBody + int(viscous) + int(coulomb) + int(offset)) : -1;
}

std::vector<std::string> standard_parameter_names(int joint_count, const ParameterLayout& layout) {
  std::vector<std::string> names;
  names.reserve(layout.size(joint_count));
  // (append rather than "m" + to_string: g++ 12 warns falsely on the latter at -O3, bug 105329)
  for (int k = 1; k <= joint_count; ++k) {
    for (const char* prefix : {"m", "mx", "my", "mz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"}) {
      names.push_back(std::string(prefix).append(std::to_string(k)));
    }
  }
  const std::pair<bool, const char*> blocks[] = {
      {layout.viscous, "fv"}, {layout.coulomb, "fc"}, {layout.offset, "fo"}, {layout.armature, "Ia"}};
  for (const auto& [present, prefix] : blocks) {
    if (!present) continue;
    for (int k = 1; k <= joint_count; ++k) names.push_back(std::string(prefix).append(std::to_string(k)));
  }
  return names;
}

std::vector<std::string> standard_parameter_names(const Model& model, const ParameterLayout& layout) {
  return standard_parameter_names(model.joint_count(), layout);
}

Eigen::VectorXd standard_parameters(const Model& model, const ParameterLayout& layout) {
  const int n = model.joint_count();
  Eigen::VectorXd pi = Eigen::VectorXd::Zero(layout.size(n));  // offset and armature stay 0
  for (int k = 0; k < n; ++k) {
    pi.segment<kInertialParametersPerBody>(kInertialParametersPerBody * k) = model.bodies[k].inertia.vector();
    if (layout.viscous) pi[layout.viscous_begin(n) + k] = model.joints[k].damping;
    if (layout.coulomb) pi[layout.coulomb_begin(n) + k] = model.joints[k].friction;
  }
  return pi;
}

}  // namespace manipid::robot
