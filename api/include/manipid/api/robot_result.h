// robot_result.h — a stored robot identification's result (the object of robot_json.h, as a
// robot_identification job stored it) and a stored payload identification's (payload_json.h's object with the
// arm it used) read back into structs: what the views of a finished job (plots.h: its fit and validation; its
// URDF) and a payload identification's arm (arm_job_id) are drawn from, decoded in one place.
#pragma once

#include "manipid/api/records.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/robot/payload.h"
#include "manipid/core/signal/judge.h"

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace manipid::api {

struct RobotResult {
  robot::ParameterLayout layout;   ///< "parameters": {"friction": [...], "armature"}
  Eigen::VectorXd point;           ///< "point": every standard parameter, in robot::standard_parameter_names order
  Eigen::VectorXd prior;           ///< "prior": the URDF's own values, same order (zeros when the result has none)
  JudgeOptions judge;              ///< "judge": {"cutoff_hz", "trim_seconds"}
  std::vector<int> torque_joints;  ///< "torque_joints" (names) as the model's joint indices
  double dt = 0.0;                 ///< "filters.differentiation.dt": the grid the identification worked on, s
};

/// The result `result` of an identification of `model`. Throws InputError("result") saying what it lacks (a
/// member, a number, a joint the robot does not have): a result that is not a robot identification's.
RobotResult decode_robot_result(const robot::Model& model, const nlohmann::json& result);

/// The number `object[key]` of a stored result; InputError("result") naming `where` + key when it is not one.
double stored_result_number(const nlohmann::json& object, const char* key, const std::string& where);

/// A stored result's "torque_joints" (joint names) as `model`'s joint indices; InputError("result") for a name
/// the robot does not have.
std::vector<int> stored_torque_joints(const robot::Model& model, const nlohmann::json& result);

// ---- Payloads ---------------------------------------------------------------------------------

/// The arm when a payload identification names none: the URDF's own values, with its viscous and Coulomb
/// friction (the default layout), as `manipid payload` without --arm.
robot::ArmParameters urdf_arm(const robot::Model& model);

/// The arm `arm_job_id` names for a payload identification on robot `robot_id`: `job` (the caller's job by that
/// id, nullopt when it has none) must be a succeeded robot_identification of that robot; its result's point and
/// layout are the arm. Throws ApiError(invalid_field, …, "arm_job_id") saying what is wrong and what to do.
robot::ArmParameters arm_of_job(const robot::Model& model, const std::optional<JobInfo>& job,
                                const std::string& arm_job_id, const std::string& robot_id);

/// The arm as a payload job's result keeps it ({"name": value}: the standard vector, its names giving the
/// layout), so that its views need not the arm's job, which may be deleted since.
nlohmann::ordered_json arm_point_json(const robot::Model& model, const robot::ArmParameters& arm);

struct StoredPayload {
  robot::ArmParameters arm;                               ///< "arm_point"
  Eigen::Matrix<double, 10, 1> estimate;                  ///< "parameters": each name's estimate (PayloadResult::names)
  std::vector<int> torque_joints;                         ///< "torque_joints" as joint indices
  bool detected = false;                                  ///< "detected"
  double mass = 0.0;                                      ///< "mass", kg
};

/// The result `result` of a payload identification of `model`; throws InputError("result") saying what it lacks.
StoredPayload decode_payload_result(const robot::Model& model, const nlohmann::json& result);

}  // namespace manipid::api
