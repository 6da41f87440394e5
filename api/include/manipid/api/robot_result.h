// robot_result.h — a stored robot identification's result (the object of robot_json.h, as a
// robot_identification job stored it) read back into a struct: what the views of a finished job
// (plots.h: its fit and validation) are drawn from, decoded in one place.
#pragma once

#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/signal/judge.h"

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

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

}  // namespace manipid::api
