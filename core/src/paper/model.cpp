// model.cpp — parameter naming and validation for the manipulator description (model.h).
#include "manipid/core/paper/model.h"

#include <charconv>
#include <cmath>
#include <sstream>

namespace manipid {

const char* to_string(KineticEnergy kinetic_energy) {
  return kinetic_energy == KineticEnergy::paper ? "paper" : "complete";
}

KineticEnergy parse_kinetic_energy(const std::string& text, const std::string& field) {
  if (text == "complete") return KineticEnergy::complete;
  if (text == "paper") return KineticEnergy::paper;
  throw InputError(field, "unknown kinetic energy '" + text + "' (expected 'complete' or 'paper')");
}

std::vector<std::string> parameter_names(int joint_count) {
  std::vector<std::string> names;
  names.reserve(2 * joint_count);
  // (append rather than "m" + to_string: g++ 12 warns falsely on the latter at -O3, bug 105329)
  for (char prefix : {'m', 'l'}) {
    for (int k = 1; k <= joint_count; ++k) names.push_back(std::string(1, prefix).append(std::to_string(k)));
  }
  return names;
}

int parameter_index(const std::string& name, int joint_count) {
  if (name.size() < 2 || (name[0] != 'm' && name[0] != 'l')) return -1;
  if (name[1] == '0' || name[1] == '+') return -1;  // no leading zeros or signs
  int k = 0;
  const char* first = name.data() + 1;
  const char* last = name.data() + name.size();
  auto [end, error] = std::from_chars(first, last, k);
  if (error != std::errc() || end != last || k < 1 || k > joint_count) return -1;
  return (name[0] == 'm' ? 0 : joint_count) + (k - 1);
}

Eigen::VectorXd Parameters::vector() const {
  Eigen::VectorXd theta(mass.size() + length.size());
  theta << mass, length;
  return theta;
}

Parameters Parameters::from_vector(const Eigen::VectorXd& theta) {
  const Eigen::Index n = theta.size() / 2;
  return Parameters(theta.head(n), theta.tail(n));
}

double Parameters::get(const std::string& name) const {
  const int n = joint_count();
  const int index = parameter_index(name, n);
  if (index < 0) {
    throw InputError(name, "unknown parameter '" + name + "' (this robot has m1..m" +
                               std::to_string(n) + " and l1..l" + std::to_string(n) + ")");
  }
  return index < n ? mass[index] : length[index - n];
}

void Parameters::set(const std::string& name, double value) {
  const int n = joint_count();
  const int index = parameter_index(name, n);
  if (index < 0) {
    throw InputError(name, "unknown parameter '" + name + "' (this robot has m1..m" +
                               std::to_string(n) + " and l1..l" + std::to_string(n) + ")");
  }
  if (!std::isfinite(value)) throw InputError(name, "parameter " + name + " must be a finite number");
  (index < n ? mass[index] : length[index - n]) = value;
}

void check_parameters(const RobotModel& model, const Parameters& parameters) {
  const int n = model.joint_count();
  if (n < 1) throw InputError("model", "the model has no joints");
  if (parameters.mass.size() != n || parameters.length.size() != n) {
    throw InputError("parameters", "expected " + std::to_string(n) + " masses and " +
                                       std::to_string(n) + " lengths, got " +
                                       std::to_string(parameters.mass.size()) + " and " +
                                       std::to_string(parameters.length.size()));
  }
  const auto names = parameter_names(n);
  const Eigen::VectorXd theta = parameters.vector();
  for (int i = 0; i < theta.size(); ++i) {
    if (!std::isfinite(theta[i])) throw InputError(names[i], names[i] + " is not a finite number");
  }
}

void check_parameter_ranges(const Parameters& parameters, const std::string& prefix) {
  const int n = parameters.joint_count();
  const auto names = parameter_names(n);
  const Eigen::VectorXd theta = parameters.vector();
  for (int i = 0; i < theta.size(); ++i) {
    const bool mass = i < n;
    const ValueRange range = mass ? kMassRange : kLengthRange;
    if (theta[i] >= range.lowest && theta[i] <= range.highest) continue;  // false for NaN too
    const std::string field = prefix.empty() ? names[i] : prefix + "." + names[i];
    std::ostringstream text;
    text.precision(6);
    text << field << " = " << theta[i] << (mass ? " kg" : " m") << " is not a sensible link " << (mass ? "mass" : "length")
         << ": give a value from " << range.lowest << " to " << range.highest << (mass ? " kg" : " m");
    throw InputError(field, text.str());
  }
}

}  // namespace manipid
