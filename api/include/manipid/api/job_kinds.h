// job_kinds.h — the api side of every job kind in one table keyed by JobKind: how its submission is checked
// and queued, the memory its work holds, the links and views its resource has, and its fit. The routes, job
// memory and the resources' JSON look a kind up here instead of testing fields of the job; the run of each
// kind is the same kind's entry in server/jobs/job_runner.cpp (the server's side: api/ does not see it).
#pragma once

#include "manipid/api/job_memory.h"
#include "manipid/api/records.h"
#include "manipid/api/robot_requests.h"
#include "manipid/api/service.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/signal/trajectory.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace manipid::api {

/// What checking a submission needs to look up, within the caller's scope.
struct SubmissionLookups {
  /// A dataset's description by id, or nullopt when the caller has none by that id.
  std::function<std::optional<DatasetInfo>(const std::string& id)> dataset;
  /// A stored robot, parsed (robot_requests.h: parsed_robot); throws ApiError(invalid_field, `field`) when the
  /// caller has none by that id.
  std::function<std::shared_ptr<const ParsedRobot>(const std::string& id, const std::string& field)> robot;
  /// A job by id (a payload identification's arm_job_id), or nullopt when the caller has none by that id.
  std::function<std::optional<JobInfo>(const std::string& id)> job;
};

/// What a fit (GET /v1/jobs/{id}/fit or /validation) is drawn from.
struct FitInputs {
  const JobInfo& job;
  const Trajectory& data;           ///< the job's dataset (fit) or its validation dataset
  long max_points = 2000;
  bool validation = false;          ///< the validation view: also the URDF's own values' errors
  const robot::Model* robot = nullptr;  ///< the job's robot, for a kind that works on one (on_robot)
};

/// What a URDF view (GET /v1/jobs/{id}/urdf) is written from.
struct UrdfInputs {
  const JobInfo& job;          ///< succeeded
  const std::string& urdf;     ///< the robot's document as uploaded
  const robot::Model& robot;   ///< parsed as the job parsed it
};

/// A URDF view's document and what its file name ends with ("<robot>-<suffix>.urdf").
struct UrdfDocument {
  std::string text;
  std::string suffix;
};

struct JobKindHandler {
  JobKind kind;
  /// What a running job of this kind is doing, for messages ("... while identifying the robot").
  const char* doing;
  bool on_robot;        ///< works on a stored robot, named by the job's robot_id
  bool has_history;     ///< evaluates a cost step by step: GET /v1/jobs/{id}/history has entries
  bool has_fit;         ///< its estimate's torque beside the measured: GET /v1/jobs/{id}/fit
  bool has_validation;  ///< judges a validation dataset when it names one: GET /v1/jobs/{id}/validation
  bool writes_urdf;     ///< its robot with the estimate (or payload): GET /v1/jobs/{id}/urdf
  /// Checks a submission's body in full against what it names and says what to queue; throws ApiError or
  /// InputError naming the field at fault.
  JobSubmission (*submission)(const nlohmann::json& body, const SubmissionLookups& lookups);
  /// The job's shape (job_memory.h) from its request, as submitted or as stored.
  JobShape (*shape)(const nlohmann::json& request, const DatasetLookup& datasets, const RobotJointsLookup& robots);
  /// The fit of a finished job (null when !has_fit); throws InputError or a JSON error when the stored request,
  /// result and data do not fit together.
  nlohmann::ordered_json (*fit)(const FitInputs& inputs);
  /// The robot's document with a finished job's result written in (null when !writes_urdf); throws ApiError
  /// (conflict) saying why when the result cannot be written, InputError or a JSON error when the stored result
  /// does not fit the robot.
  UrdfDocument (*urdf)(const UrdfInputs& inputs);
};

/// The entry of `kind`.
const JobKindHandler& job_kind_handler(JobKind kind);

/// The kind a body POSTed to /v1/identifications asks for: payload_identification when it has "payload",
/// robot_identification when it names a robot_id, identification (the paper's preset) otherwise.
JobKind identification_kind(const nlohmann::json& body);

/// "a simulation", "an excitation", "a robot_identification": the kind's name with its article, for messages.
std::string kind_with_article(JobKind kind);

}  // namespace manipid::api
