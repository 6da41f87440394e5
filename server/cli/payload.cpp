// payload.cpp — `manipid payload RUN.csv --robot ARM.urdf [--arm ARM.json]`: the payload on the tip link, printed as a table or, with --json, as payload_json.h's object.
#include "cli/payload.h"

#include "manipid/api/csv.h"
#include "manipid/api/payload_json.h"
#include "manipid/api/robot_json.h"
#include "manipid/core/robot/payload.h"
#include "manipid/core/robot/urdf_writer.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <optional>

namespace manipid::server::cli {
namespace {

/// A value and its standard error for the table: "3.0012 ± 0.0004", "-" where there is none.
std::string with_error(double value, double error) {
  if (!std::isfinite(value)) return "-";
  return format(value, 6) + (std::isfinite(error) ? " ± " + format(error, 2) : " (not determined)");
}

void print_table(const robot::Model& model, const robot::PayloadResult& result, const std::string& arm_source,
                 const std::optional<robot::PayloadValidation>& validation) {
  std::printf("robot %s, payload on %s; the arm: %s\n", model.name.c_str(), model.tip_link.c_str(), arm_source.c_str());
  std::printf("payload from the arm's residual torque, linear least squares: %d rows, comparison low-pass %s Hz%s%s\n",
              result.rows, format(result.comparison_cutoff_hz, 3).c_str(),
              result.candidates.empty() ? " (given)"
                                        : (" (chosen by held-out error, " + format(100.0 * result.held_out_error, 3) +
                                           " % of the arm's residual, among " + std::to_string(result.candidates.size()) +
                                           ")").c_str(),
              result.variance_inflation > 1.0
                  ? (", standard errors widened x" + format(std::sqrt(result.variance_inflation), 3) +
                     " (the residual is correlated over time)")
                        .c_str()
                  : "");
  std::printf("\n%-40s %s\n", "mass kg", with_error(result.mass, result.mass_std_error).c_str());
  const char* axes[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    std::printf("%-40s %s\n", ("centre of mass " + std::string(axes[i]) + " m (tip-link frame)").c_str(),
                with_error(result.centre_of_mass[i], result.centre_of_mass_std_errors[i]).c_str());
  }
  const char* entries[] = {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"};
  for (std::size_t i = 0; i < 6; ++i) {
    std::printf("%-40s %s\n", ("inertia about the com " + std::string(entries[i]) + " kg m^2").c_str(),
                with_error(result.inertia[i], result.inertia_std_errors[i]).c_str());
  }
  std::printf("\ntorque error on the run (filtered, relative): arm alone %s %%, with the payload %s %%\n",
              format(100.0 * result.arm_only_error, 3).c_str(), format(100.0 * result.with_payload_error, 3).c_str());
  if (validation) {
    std::printf("held-out runs (judged at %s Hz): arm alone %s %%, with the payload %s %%\n",
                format(validation->with_payload.judge.cutoff_hz, 3).c_str(),
                format(100.0 * validation->arm_only.overall_relative_error, 3).c_str(),
                format(100.0 * validation->with_payload.overall_relative_error, 3).c_str());
  }
  if (result.physical) {
    std::printf("physical fit: %s\n", result.physical->least_squares_consistent
                                          ? "the least-squares payload is a real rigid body already; unchanged"
                                          : ("the least-squares payload was not a real rigid body; the fit over real bodies "
                                             "costs " + format(100.0 * result.physical->relative_cost_increase, 3) +
                                             " % more squared residual (" + result.physical->report + ")").c_str());
  }
  for (const std::string& warning : result.warnings) std::printf("\nwarning: %s\n", warning.c_str());
}

}  // namespace

CLI::App* add_payload_command(CLI::App& app, PayloadOptions& options) {
  CLI::App* command = app.add_subcommand(
      "payload",
      "Identify a payload (a tool, a gripper, a part) rigidly fixed to the tip link from runs of the arm carrying it: "
      "its mass, centre of mass and inertia from the torque the arm's model leaves unexplained.");
  command->add_option("data", options.inputs, "Runs with the payload (CSV t,q1..qn,tau1..taun, or a ROS 2 bag)")->required();
  add_log_options(*command, options.log, options.topic);
  add_urdf_options(*command, options.urdf, true);
  command->add_option("--arm", options.arm,
                      "The arm as identified: the JSON of `manipid identify --robot ... --json` (default: the URDF's "
                      "values with its viscous and Coulomb friction)");
  command->add_option("--mass", options.mass, "The payload's mass if known, kg: then only the rest is estimated");
  command->add_option("--com", options.centre_of_mass,
                      "The payload's centre of mass if known, X,Y,Z m in the tip link's frame: then only the rest is estimated");
  command->add_option("--validate", options.validate, "Runs with the payload to predict without and with it (repeatable)");
  command->add_option("--trim", options.trim, "Seconds dropped at the start and the end, START,END");
  command->add_option("--dt", options.dt, "Resample onto this period, s (default: the median time step)")->check(positive_number());
  command->add_option("--comparison-cutoff", options.comparison_cutoff,
                      "The comparison low-pass's cut-off, Hz (default: chosen by held-out error, as identify chooses it)")
      ->check(positive_number());
  command->add_option("--torque-joints", options.torque_joints, "Joints whose torque is fitted, e.g. 1-6 (default: all)");
  command->add_option("--judge-cutoff", options.judge_cutoff, "The cut-off (Hz) of the fixed low-pass torque figures are judged under")
      ->check(positive_number())
      ->capture_default_str();
  command->add_option("--judge-trim", options.judge_trim, "Seconds the judge drops at each end of a run")
      ->check(non_negative_number())
      ->capture_default_str();
  command->add_option("--weights", options.weights,
                      "unit, or per-joint: each joint's rows divided by its residual RMS from a first fit (as identify --robot)")
      ->check(CLI::IsMember({"unit", "per-joint"}))
      ->capture_default_str();
  command->add_flag("--physical", options.physical,
                    "Make the payload a real rigid body (mass > 0, inertia about the centre of mass positive definite, "
                    "triangle inequalities): the least squares over such bodies only");
  command->add_flag("--json", options.json, "Print the result as JSON");
  command->add_option("--write-urdf", options.write_urdf,
                      "Write the URDF (--robot's document) with the payload mounted as a fixed link on the tip link");
  return command;
}

int run_payload(const PayloadOptions& options) {
  const robot::ParsedUrdf parsed_urdf = load_urdf_robot(options.urdf);
  const robot::Model& model = parsed_urdf.model;
  robot::ArmParameters arm;
  std::string arm_source = "the URDF's values";
  if (options.arm.empty()) {
    arm.pi = robot::standard_parameters(model, arm.layout);
  } else {
    nlohmann::json json;
    try {
      json = nlohmann::json::parse(read_text(options.arm));
    } catch (const nlohmann::json::exception& error) {
      throw UsageError(input_name(options.arm) + ": not JSON (" + error.what() + "); --arm takes the output of "
                       "`manipid identify DATA --robot URDF --json`");
    }
    try {
      const api::ParameterValues values = api::parameters_from_json(model, json, "--arm");
      arm.layout = values.layout;
      arm.pi = values.values;
    } catch (const InputError& error) {
      rethrow_with_source(error, input_name(options.arm));
    }
    arm_source = "identified (" + input_name(options.arm) + ")";
  }

  robot::PayloadOptions payload;
  payload.preparation = parse_trim(options.trim);
  payload.preparation.uniform.dt = options.dt;
  payload.comparison_cutoff_hz = options.comparison_cutoff;
  payload.physical = options.physical;
  payload.weighting = options.weights == "per-joint" ? estimation::JointWeighting::per_joint : estimation::JointWeighting::unit;
  payload.judge.cutoff_hz = options.judge_cutoff;
  payload.judge.trim_seconds = options.judge_trim;
  if (!options.torque_joints.empty()) payload.torque_joints = joint_list(options.torque_joints, model.joint_count(), "--torque-joints");
  if (!options.mass.empty()) payload.known_mass = parse_number_option(options.mass, "--mass");
  if (!options.centre_of_mass.empty()) {
    const std::vector<std::string> parts = split_list(options.centre_of_mass);
    if (parts.size() != 3) throw InputError("--com", "--com needs X,Y,Z: the centre of mass in the tip link's frame, m");
    payload.known_centre_of_mass = Eigen::Vector3d(parse_number_option(parts[0], "--com"), parse_number_option(parts[1], "--com"),
                                                   parse_number_option(parts[2], "--com"));
  }

  api::LogFormat log = options.log;
  for (const robot::Joint& joint : model.joints) log.joint_names.push_back(joint.name);
  std::vector<Trajectory> runs;
  for (const std::string& path : options.inputs) runs.push_back(read_run(path, log, options.topic));
  robot::PayloadResult result;
  try {
    result = robot::identify_payload(model, arm, runs, payload);
  } catch (const InputError& error) {
    for (const auto& [field, option] : {std::pair{"judge_cutoff", "--judge-cutoff"}, {"judge_trim", "--judge-trim"},
                                        {"known_mass", "--mass"}, {"known_centre_of_mass", "--com"}, {"arm", "--arm"}}) {
      if (error.field() == field) rethrow_with_source(error, option);
    }
    rethrow_with_source(error, run_names(options.inputs));
  }
  std::optional<robot::PayloadValidation> validation;
  if (!options.validate.empty()) {
    std::vector<Trajectory> held_out;
    for (const std::string& path : options.validate) held_out.push_back(read_run(path, log, options.topic));
    try {
      validation = robot::validate_payload(model, arm, result, held_out, payload);
    } catch (const InputError& error) {
      rethrow_with_source(error, run_names(options.validate));
    }
  }
  if (!options.write_urdf.empty()) {
    if (!result.detected) {
      throw UsageError("--write-urdf: no payload to write (the mass is not distinguishable from 0)");
    }
    std::string document;
    try {
      document = robot::write_payload_urdf(read_text(options.urdf.urdf), model,
                                           robot::InertialParameters::from_vector(result.estimate),
                                           "payload identified by manipid payload from " + run_names(options.inputs) +
                                               ": mass " + format(result.mass, 6) + " kg");
    } catch (const InputError& error) {
      rethrow_with_source(error, "--write-urdf");
    }
    write_text(options.write_urdf, document);
    if (!result.consistent) {
      std::fprintf(stderr, "warning: --write-urdf: the payload written is not a real rigid body (simulators refuse or "
                           "misbehave on such a link); --physical makes it one\n");
    }
  }
  print_urdf_warnings(options.urdf, parsed_urdf);
  if (options.json) {
    write_text("-", api::payload_to_json(model, result, payload, arm_source, validation).dump(2) + "\n");
  } else {
    print_table(model, result, arm_source, validation);
  }
  return exit_success;
}

}  // namespace manipid::server::cli
