// job_kinds.cpp — the api side of each job kind (job_kinds.h): one entry per JobKind, in its order.
#include "manipid/api/job_kinds.h"

#include "manipid/api/plots.h"
#include "manipid/api/problem.h"
#include "manipid/api/requests.h"
#include "manipid/api/robot_json.h"
#include "manipid/api/robot_result.h"
#include "manipid/core/robot/urdf_writer.h"

#include "job_shapes.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <utility>

namespace manipid::api {
namespace {

JobSubmission simulation_submission(const nlohmann::json& body, const SubmissionLookups&) {
  (void)simulation_from_json(body);  // validates; the worker parses the stored text again
  return {JobKind::simulation, body.dump(), "", "", ""};
}

JobSubmission identification_submission(const nlohmann::json& body, const SubmissionLookups& lookups) {
  const IdentificationSpec spec = identification_from_json(body);
  std::string dataset_id;
  if (spec.simulation) {
    const SimulationOptions& run = spec.simulation->preset.simulation;
    const int samples = static_cast<int>(std::floor(run.duration / run.dt + 1e-9)) + 1;
    check_against_data(spec, spec.simulation->preset.model.joint_count(), samples, true, true);
  } else {
    dataset_id = spec.dataset_id;
    const auto dataset = lookups.dataset(dataset_id);
    if (!dataset) throw ApiError(ProblemKind::invalid_field, "no dataset " + dataset_id, "dataset_id");
    check_against_data(spec, dataset->joints, dataset->samples, dataset->has_torque, dataset->has_reference);
  }
  return {JobKind::identification, body.dump(), dataset_id, "", ""};
}

/// The runs a job on a stored robot reads, checked against it: each exists for the caller, has the robot's
/// joints and torque; and the joints whose torque is fitted are the robot's.
void check_robot_runs(const RobotRuns& runs, const std::vector<int>& torque_joints, const robot::Model& model,
                      const SubmissionLookups& lookups) {
  const int joints = model.joint_count();
  for (const auto& [ids, field] : {std::pair{runs.dataset_ids, std::string("dataset_id")},
                                   std::pair{runs.validation_dataset_ids, std::string("validation_dataset_id")}}) {
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const std::string where = ids.size() > 1 ? field + "s[" + std::to_string(i) + "]" : field;
      const auto dataset = lookups.dataset(ids[i]);
      if (!dataset) throw ApiError(ProblemKind::invalid_field, "no dataset " + ids[i], where);
      check_robot_data(joints, model.name, dataset->joints, dataset->has_torque, where);
    }
  }
  for (int k : torque_joints) {
    if (k >= joints) {
      throw ApiError(ProblemKind::invalid_field,
                     "torque_joints names joint " + std::to_string(k + 1) + "; the robot " + model.name + " has " +
                         std::to_string(joints),
                     "torque_joints");
    }
  }
}

JobSubmission robot_identification_submission(const nlohmann::json& body, const SubmissionLookups& lookups) {
  const RobotIdentificationSpec spec = robot_identification_from_json(body);
  const std::shared_ptr<const ParsedRobot> stored = lookups.robot(spec.robot_id, "robot_id");
  check_robot_runs(spec, spec.options.torque_joints, stored->model, lookups);
  return {JobKind::robot_identification, body.dump(), spec.dataset_id, spec.robot_id, spec.validation_dataset_id};
}

JobSubmission payload_identification_submission(const nlohmann::json& body, const SubmissionLookups& lookups) {
  const PayloadIdentificationSpec spec = payload_identification_from_json(body);
  const std::shared_ptr<const ParsedRobot> stored = lookups.robot(spec.robot_id, "robot_id");
  check_robot_runs(spec, spec.options.torque_joints, stored->model, lookups);
  // The arm must be there and usable now; the job reads it again when it runs.
  if (!spec.arm_job_id.empty()) (void)arm_of_job(stored->model, lookups.job(spec.arm_job_id), spec.arm_job_id, spec.robot_id);
  return {JobKind::payload_identification, body.dump(), spec.dataset_id, spec.robot_id, spec.validation_dataset_id};
}

JobSubmission excitation_submission(const nlohmann::json& body, const SubmissionLookups& lookups) {
  const ExcitationSpec spec = excitation_from_json(body);
  check_excitation(spec, lookups.robot(spec.robot_id, "robot_id")->model);
  return {JobKind::excitation, body.dump(), "", spec.robot_id, ""};
}

nlohmann::ordered_json preset_fit(const FitInputs& inputs) {
  return torque_fit_to_json(inputs.job.request, inputs.job.result, inputs.data, inputs.max_points);
}

nlohmann::ordered_json robot_fit(const FitInputs& inputs) {
  return robot_fit_to_json(*inputs.robot, inputs.job.request, inputs.job.result, inputs.data, inputs.max_points,
                           inputs.validation);
}

nlohmann::ordered_json payload_fit(const FitInputs& inputs) {
  return payload_fit_to_json(*inputs.robot, inputs.job.request, inputs.job.result, inputs.data, inputs.max_points);
}

/// A robot identification's URDF: each link's <inertial> and each joint's <dynamics> from the result's point.
UrdfDocument identified_urdf(const UrdfInputs& inputs) {
  // The result's point names its layout (fv…, fc…, fo…, Ia…).
  const nlohmann::json result = nlohmann::json::parse(inputs.job.result);
  const ParameterValues point = parameters_from_json(inputs.robot, result, "result");
  // Where it came from: the job and its (first) dataset; the result says how many runs.
  const std::string note = identified_urdf_note(result, "job " + inputs.job.id + ", dataset " + inputs.job.dataset_id);
  try {
    return {robot::write_identified_urdf(inputs.urdf, inputs.robot, point.layout, point.values, note), "identified"};
  } catch (const InputError& error) {  // an estimate a URDF cannot hold
    throw ApiError(ProblemKind::conflict,
                   std::string(error.what()) + "; for a URDF, identify again with \"physical\": true (every link a real "
                   "rigid body)",
                   "physical");
  }
}

/// A payload identification's URDF: the robot's document with the payload mounted on the tip link as a fixed link.
UrdfDocument payload_mounted_urdf(const UrdfInputs& inputs) {
  const StoredPayload stored = decode_payload_result(inputs.robot, nlohmann::json::parse(inputs.job.result));
  if (!stored.detected) {
    throw ApiError(ProblemKind::conflict,
                   "job " + inputs.job.id + " found no payload (its mass is not distinguishable from 0): nothing to mount "
                   "on " + inputs.robot.tip_link,
                   "id");
  }
  char mass[32];
  std::snprintf(mass, sizeof mass, "%.6g", stored.mass);
  const std::string note = "payload identified by manipid (job " + inputs.job.id + ", dataset " + inputs.job.dataset_id +
                           "): mass " + mass + " kg on " + inputs.robot.tip_link;
  try {
    return {robot::write_payload_urdf(inputs.urdf, inputs.robot, robot::InertialParameters::from_vector(stored.estimate), note),
            "payload"};
  } catch (const InputError& error) {  // a payload a URDF cannot hold (an inertia that is not a real body's)
    throw ApiError(ProblemKind::conflict,
                   std::string(error.what()) + "; for a URDF, identify the payload again with \"physical\": true (a real "
                   "rigid body)",
                   "physical");
  }
}

// Indexed by JobKind; the static_asserts below keep each entry at its kind's place.
constexpr std::array<JobKindHandler, std::size(kJobKinds)> kHandlers = {{
    {JobKind::simulation, "simulating", false, false, false, false, false, simulation_submission,
     shapes::simulation, nullptr, nullptr},
    {JobKind::identification, "identifying", false, true, true, false, false, identification_submission,
     shapes::preset_identification, preset_fit, nullptr},
    {JobKind::excitation, "designing the excitation", true, false, false, false, false, excitation_submission,
     shapes::excitation, nullptr, nullptr},
    {JobKind::robot_identification, "identifying the robot", true, false, true, true, true,
     robot_identification_submission, shapes::robot_identification, robot_fit, identified_urdf},
    {JobKind::payload_identification, "identifying the payload", true, false, true, true, true,
     payload_identification_submission, shapes::payload_identification, payload_fit, payload_mounted_urdf},
}};

constexpr bool in_kind_order() {
  for (std::size_t i = 0; i < kHandlers.size(); ++i) {
    if (kHandlers[i].kind != kJobKinds[i] || static_cast<std::size_t>(kJobKinds[i]) != i) return false;
  }
  return true;
}
static_assert(in_kind_order(), "kHandlers has one entry per JobKind, in its order");

}  // namespace

const JobKindHandler& job_kind_handler(JobKind kind) { return kHandlers.at(static_cast<std::size_t>(kind)); }

JobKind identification_kind(const nlohmann::json& body) {
  if (asks_for_payload(body)) return JobKind::payload_identification;
  return names_a_robot(body) ? JobKind::robot_identification : JobKind::identification;
}

std::string kind_with_article(JobKind kind) {
  const std::string name = to_string(kind);
  const bool vowel = name.front() == 'a' || name.front() == 'e' || name.front() == 'i' || name.front() == 'o';
  return (vowel ? "an " : "a ") + name;
}

}  // namespace manipid::api
