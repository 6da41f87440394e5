// robot_result.cpp — stored robot and payload identifications' results read back, and a payload's arm (robot_result.h).
#include "manipid/api/robot_result.h"

#include "manipid/api/job_kinds.h"
#include "manipid/api/problem.h"
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

  decoded.torque_joints = stored_torque_joints(model, result);
  return decoded;
}

std::vector<int> stored_torque_joints(const robot::Model& model, const nlohmann::json& result) {
  const auto joints = result.find("torque_joints");
  if (joints == result.end() || !joints->is_array()) throw InputError("result", "the job's result has no torque_joints");
  std::vector<int> indices;
  for (const nlohmann::json& name : *joints) {
    const auto found = std::find_if(model.joints.begin(), model.joints.end(), [&](const robot::Joint& joint) {
      return name.is_string() && joint.name == name.get<std::string>();
    });
    if (found == model.joints.end()) throw InputError("result", "the job's result names a joint the robot does not have");
    indices.push_back(static_cast<int>(found - model.joints.begin()));
  }
  return indices;
}

robot::ArmParameters urdf_arm(const robot::Model& model) {
  robot::ArmParameters arm;
  arm.pi = robot::standard_parameters(model, arm.layout);
  return arm;
}

robot::ArmParameters arm_of_job(const robot::Model& model, const std::optional<JobInfo>& job,
                                const std::string& arm_job_id, const std::string& robot_id) {
  const auto refuse = [&](const std::string& why) {
    throw ApiError(ProblemKind::invalid_field, "arm_job_id: " + why, "arm_job_id");
  };
  const std::string leave_out = "; or leave arm_job_id out to take the URDF's own values as the arm";
  if (!job) refuse("no job " + arm_job_id + leave_out);
  if (job->kind != JobKind::robot_identification) {
    refuse("job " + arm_job_id + " is " + kind_with_article(job->kind) +
           ", not a robot_identification: name the job that identified the arm (POST /v1/identifications with "
           "robot_id " + robot_id + " and runs without the payload)" + leave_out);
  }
  if (job->robot_id != robot_id) {
    refuse("job " + arm_job_id + " identified robot " + job->robot_id + ", not " + robot_id +
           ": the arm must be identified on the robot the payload is mounted on");
  }
  if (job->state == JobState::queued || job->state == JobState::running) {
    refuse("job " + arm_job_id + " is " + to_string(job->state) +
           ": submit the payload identification once it has succeeded (GET /v1/jobs/" + arm_job_id + "?wait=30)");
  }
  if (job->state != JobState::succeeded) {
    refuse("job " + arm_job_id + " " + (job->state == JobState::failed ? "failed" : "was cancelled") +
           ": it has no arm to use; identify the arm again" + leave_out);
  }
  try {
    const RobotResult result = decode_robot_result(model, nlohmann::json::parse(job->result));
    return {result.layout, result.point};
  } catch (const InputError& error) {
    refuse("job " + arm_job_id + " has no usable result (" + error.what() + "); identify the arm again" + leave_out);
  } catch (const nlohmann::json::exception&) {
    refuse("job " + arm_job_id + " has no usable result; identify the arm again" + leave_out);
  }
  return {};  // unreachable: refuse throws
}

nlohmann::ordered_json arm_point_json(const robot::Model& model, const robot::ArmParameters& arm) {
  const std::vector<std::string> names = robot::standard_parameter_names(model, arm.layout);
  nlohmann::ordered_json point = nlohmann::ordered_json::object();
  for (std::size_t i = 0; i < names.size(); ++i) point[names[i]] = arm.pi[static_cast<Eigen::Index>(i)];
  return point;
}

StoredPayload decode_payload_result(const robot::Model& model, const nlohmann::json& result) {
  if (!result.is_object()) throw InputError("result", "the job's result is not an object");
  StoredPayload decoded;
  // The point's names say its layout exactly (robot_json.h: parameters_from_json on an identify result).
  const ParameterValues arm = parameters_from_json(model, {{"point", stored_object(result, "arm_point", "")}}, "result");
  decoded.arm = {arm.layout, arm.values};
  const auto parameters = result.find("parameters");
  if (parameters == result.end() || !parameters->is_array() || parameters->size() != 10) {
    throw InputError("result", "the job's result has no parameters of the payload");
  }
  for (std::size_t i = 0; i < 10; ++i) {
    const nlohmann::json& parameter = (*parameters)[i];
    if (!parameter.is_object() || parameter.value("name", std::string()) != robot::PayloadResult::names()[i]) {
      throw InputError("result", std::string("the job's result has no payload parameter ") + robot::PayloadResult::names()[i]);
    }
    decoded.estimate[static_cast<Eigen::Index>(i)] = stored_result_number(parameter, "estimate", "parameters[].");
  }
  decoded.torque_joints = stored_torque_joints(model, result);
  const auto detected = result.find("detected");
  if (detected == result.end() || !detected->is_boolean()) throw InputError("result", "the job's result has no detected");
  decoded.detected = detected->get<bool>();
  decoded.mass = stored_result_number(result, "mass", "");
  return decoded;
}

}  // namespace manipid::api
