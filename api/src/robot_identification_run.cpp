// robot_identification_run.cpp — identify, validate and the result JSON of a URDF robot
// (robot_identification_run.h).
#include "manipid/api/robot_identification_run.h"

#include "manipid/api/robot_json.h"

namespace manipid::api {

RobotIdentificationRun run_robot_identification(
    const robot::Model& model, const std::vector<Trajectory>& runs, const robot::IdentificationOptions& options,
    const std::function<std::vector<Trajectory>()>& held_out,
    const std::function<void(RobotRunStep step, const InputError& error)>& on_error) {
  RobotIdentificationRun run;
  try {
    run.result = robot::identify(model, runs, options);
  } catch (const InputError& error) {
    if (on_error) on_error(RobotRunStep::identify, error);
    throw;
  }
  if (run.result.cancelled) return run;
  const std::vector<Trajectory> validation_runs = held_out ? held_out() : std::vector<Trajectory>();
  if (!validation_runs.empty()) {
    try {
      run.validation = robot::validate(model, run.result, validation_runs, options.preparation);
    } catch (const InputError& error) {
      if (on_error) on_error(RobotRunStep::validate, error);
      throw;
    }
  }
  run.json = robot_result_to_json(model, run.result, run.validation);
  return run;
}

}  // namespace manipid::api
