// robot_result.cpp — a stored robot identification's result read back (robot_result.h).
#include "manipid/api/robot_result.h"

#include "manipid/api/robot_json.h"
#include "manipid/core/errors.h"

#include <algorithm>

namespace manipid::api {
namespace {

/// result[key] when it is an object, else InputError("result") naming `where`.
const nlohmann::json& stored_object(const nlohmann::json& result, const char* key, const std::string& where) {
  const auto found = result.find(key);
  if (found == result.end() || !found->is_object()) throw InputError("result", "the job's result has no " + where + key);
  return *found;
}

}  // namespace

double stored_result_number(const nlohmann::json& object, const char* key, const std::string& where) {
  const auto found = object.find(key);
  if (found == object.end() || !found->is_number()) {
    throw InputError("result", "the job's result has no number " + where + key);
  }
  return found->get<double>();
}

RobotResult decode_robot_result(const robot::Model& model, const nlohmann::json& result) {
  if (!result.is_object()) throw InputError("result", "the job's result is not an object");
  RobotResult decoded;
  const nlohmann::json& parameters = stored_object(result, "parameters", "");
  const auto friction = parameters.find("friction");
  const auto armature = parameters.find("armature");
  if (friction == parameters.end() || !friction->is_array() || armature == parameters.end() || !armature->is_boolean()) {
    throw InputError("result", "the job's result has no parameters.friction or parameters.armature");
  }
  std::vector<std::string> terms;
  for (const nlohmann::json& term : *friction) {
    if (!term.is_string()) throw InputError("result", "the job's result names a friction term that is not a string");
    terms.push_back(term.get<std::string>());
  }
  if (terms.empty()) terms.emplace_back("none");
  parse_friction(terms, decoded.layout, "result");
  decoded.layout.armature = armature->get<bool>();

  const std::vector<std::string> names = robot::standard_parameter_names(model, decoded.layout);
  const nlohmann::json& point = stored_object(result, "point", "");
  const bool has_prior = result.contains("prior");
  const nlohmann::json& prior = has_prior ? stored_object(result, "prior", "") : point;
  decoded.point.resize(static_cast<Eigen::Index>(names.size()));
  decoded.prior = Eigen::VectorXd::Zero(decoded.point.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    decoded.point[static_cast<Eigen::Index>(i)] = stored_result_number(point, names[i].c_str(), "point.");
    if (has_prior) decoded.prior[static_cast<Eigen::Index>(i)] = stored_result_number(prior, names[i].c_str(), "prior.");
  }

  const nlohmann::json& judge = stored_object(result, "judge", "");
  decoded.judge.cutoff_hz = stored_result_number(judge, "cutoff_hz", "judge.");
  decoded.judge.trim_seconds = stored_result_number(judge, "trim_seconds", "judge.");
  const nlohmann::json& filters = stored_object(result, "filters", "");
  decoded.dt = stored_result_number(stored_object(filters, "differentiation", "filters."), "dt", "filters.differentiation.");

  const auto joints = result.find("torque_joints");
  if (joints == result.end() || !joints->is_array()) throw InputError("result", "the job's result has no torque_joints");
  for (const nlohmann::json& name : *joints) {
    const auto found = std::find_if(model.joints.begin(), model.joints.end(), [&](const robot::Joint& joint) {
      return name.is_string() && joint.name == name.get<std::string>();
    });
    if (found == model.joints.end()) throw InputError("result", "the job's result names a joint the robot does not have");
    decoded.torque_joints.push_back(static_cast<int>(found - model.joints.begin()));
  }
  return decoded;
}

}  // namespace manipid::api
