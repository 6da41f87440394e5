// json_numbers.h — how numbers go into answers: a finite double as a number, NaN or ±∞ as null (internal to api).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>
#include <vector>

namespace manipid::api::json_numbers {

/// One value: JSON has no NaN or infinity, so a value that is not finite is written as null.
inline nlohmann::ordered_json number(double value) {
  return std::isfinite(value) ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
}

/// A vector as an array of number()s.
inline nlohmann::ordered_json numbers(const Eigen::VectorXd& values) {
  nlohmann::ordered_json array = nlohmann::ordered_json::array();
  for (Eigen::Index i = 0; i < values.size(); ++i) array.push_back(number(values[i]));
  return array;
}

/// A vector as an object {names[i]: number(values[i])}.
inline nlohmann::ordered_json by_name(const std::vector<std::string>& names, const Eigen::VectorXd& values) {
  nlohmann::ordered_json object = nlohmann::ordered_json::object();
  for (std::size_t i = 0; i < names.size(); ++i) object[names[i]] = number(values[static_cast<Eigen::Index>(i)]);
  return object;
}

}  // namespace manipid::api::json_numbers
