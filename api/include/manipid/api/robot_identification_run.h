// robot_identification_run.h — a URDF robot's identification from its runs to its result JSON, done one way
// for `manipid identify --robot` (server/cli/identify_robot.cpp) and for a robot_identification job
// (server/jobs/job_runner.cpp): identify (the fit on the training runs included), validate on held-out runs
// when there are any, and the result object of robot_json.h.
#pragma once

#include "manipid/core/errors.h"
#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/signal/trajectory.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <optional>
#include <vector>

namespace manipid::api {

struct RobotIdentificationRun {
  robot::IdentificationResult result;
  std::optional<robot::ValidationReport> validation;  ///< when held-out runs were given
  nlohmann::ordered_json json;                         ///< robot_result_to_json; null when cancelled
};

/// The step an InputError came from.
enum class RobotRunStep { identify, validate };

/// Identifies `model` on `runs` with `options` (its cancel flag stops it: the run comes back with
/// result.cancelled and nothing else), then judges the estimate on the runs `held_out` gives (asked for only
/// once the identification has succeeded; none: no validation), and writes the result JSON. An InputError of
/// a step is handed to `on_error` first, which may throw its own (naming the step's source its way); if it
/// returns, or there is none, the error goes on as it was.
RobotIdentificationRun run_robot_identification(
    const robot::Model& model, const std::vector<Trajectory>& runs, const robot::IdentificationOptions& options,
    const std::function<std::vector<Trajectory>()>& held_out,
    const std::function<void(RobotRunStep step, const InputError& error)>& on_error = {});

}  // namespace manipid::api
