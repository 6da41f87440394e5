// torque.cpp — `manipid torque`: inverse dynamics τ(q, q̇, q̈) row by row for a CSV of states
// with columns q1..qn, qd1..qdn, qdd1..qddn, of a preset robot or (--robot) a URDF robot; writes
// [t,] tau1..taun.
#include "cli/torque.h"

#include "manipid/api/csv.h"
#include "manipid/api/robot_json.h"
#include "manipid/core/paper/dynamics.h"
#include "manipid/core/robot/consistency.h"
#include "manipid/core/robot/data.h"
#include "manipid/core/robot/identification.h"
#include "manipid/core/robot/rnea.h"
#include "manipid/core/paper/simulation.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <string>
#include <vector>

namespace manipid::server::cli {
namespace {

/// Column indices of prefix1..prefixN; throws InputError for a missing column or for a
/// column beyond the robot's joints (q5 for a 4-joint robot is a wrong robot, not extra data).
std::vector<int> joint_columns(const api::CsvTable& table, const std::string& prefix, int joint_count,
                               const std::string& needs) {
  std::vector<int> indices;
  for (int joint = 1; joint <= joint_count; ++joint) {
    const std::string name = prefix + std::to_string(joint);
    const int index = table.column_index(name);
    if (index < 0) throw InputError(name, "missing column " + name + " (" + needs + ")");
    indices.push_back(index);
  }
  const std::string beyond = prefix + std::to_string(joint_count + 1);
  if (table.column_index(beyond) >= 0) {
    throw InputError(beyond, "unexpected column " + beyond + " (" + needs + ")");
  }
  return indices;
}

}  // namespace

CLI::App* add_torque_command(CLI::App& app, TorqueOptions& options) {
  CLI::App* command = app.add_subcommand(
      "torque",
      "Inverse dynamics: read q1..qn, qd1..qdn, qdd1..qddn (rad, rad/s, rad/s^2) per row and "
      "write tau1..taun (N*m); a t column is passed through.");
  add_robot_options(*command, options.robot);
  add_urdf_options(*command, options.urdf, false);
  CLI::Option* robot = command->get_option("--robot");
  for (const char* preset_only : {"--preset", "--param", "--kinetic-energy"}) command->get_option(preset_only)->excludes(robot);
  command->add_option("--params", options.parameters,
                      "With --robot: the parameters, as an 'identify --json' result (its point) or a JSON object "
                      "{\"m1\": ..., \"fv1\": ...}; parameters not given keep the URDF's values")
      ->needs(robot);
  CLI::Option* with_states =
      command
          ->add_flag("--with-states", options.with_states,
                     "With --robot: write the input's columns (t, q, qd, qdd) before tau1..taun: a dataset that "
                     "'manipid identify' reads")
          ->needs(robot);
  command->add_option("--noise-q", options.noise_q, "With --with-states: Gaussian noise on q, rad")
      ->check(non_negative_number())
      ->needs(with_states);
  command->add_option("--quantize-q", options.quantize_bits, "With --with-states: encoder resolution 2*pi/2^BITS on q")
      ->check(integer_between(1, 62))
      ->needs(with_states);
  command->add_option("--noise-tau", options.noise_tau, "With --with-states: Gaussian noise on tau, N*m")
      ->check(non_negative_number())
      ->needs(with_states);
  command->add_option("--noise-tau-relative", options.noise_tau_relative,
                      "With --with-states: Gaussian noise on tau as a fraction of each joint's torque standard deviation")
      ->check(non_negative_number())
      ->needs(with_states);
  command->add_option("--seed", options.seed, "Seed of the measurement noise")->needs(with_states)->capture_default_str();
  command->add_option("--in", options.input, "Input CSV file of states, '-' for stdin")->required();
  command->add_option("--out", options.output, "Output CSV file, '-' for stdout")->capture_default_str();
  return command;
}

namespace {

/// The URDF robot's torque for every row: parameters from --params, else the URDF's own.
int run_urdf_torque(const TorqueOptions& options) {
  const robot::ParsedUrdf parsed_urdf = load_urdf_robot(options.urdf);
  const robot::Model& model = parsed_urdf.model;
  api::ParameterValues parameters;
  if (options.parameters.empty()) {
    parameters.values = robot::standard_parameters(model, parameters.layout);  // the URDF's damping and friction
  } else {
    nlohmann::json json;
    try {
      json = nlohmann::json::parse(read_text(options.parameters));
    } catch (const nlohmann::json::exception&) {
      throw InputError("params", input_name(options.parameters) + ": not a JSON document");
    }
    parameters = api::parameters_from_json(model, json, input_name(options.parameters));
  }
  // Torques of a body no matter could make (a lighter link whose inertia was not changed with it) are
  // still computed, but the user hears why they may look odd.
  const robot::ConsistencyReport consistency =
      robot::check_consistency(robot::parameter_structure(model, parameters.layout), parameters.values);
  const int joint_count = model.joint_count();
  const api::CsvTable states = read_table(options.input);
  const std::string last = std::to_string(joint_count);
  const std::string needs = "the " + std::to_string(joint_count) + "-joint robot " + model.name + " needs q1..q" + last +
                            ", qd1..qd" + last + ", qdd1..qdd" + last;
  std::vector<int> q_columns, qd_columns, qdd_columns;
  try {
    q_columns = joint_columns(states, "q", joint_count, needs);
    qd_columns = joint_columns(states, "qd", joint_count, needs);
    qdd_columns = joint_columns(states, "qdd", joint_count, needs);
  } catch (const InputError& error) {
    rethrow_with_source(error, input_name(options.input));
  }
  // The URDF's warnings once the call is known to work: a refused call prints one line.
  print_urdf_warnings(options.urdf, parsed_urdf);
  for (const std::string& finding : consistency.findings) {
    std::fprintf(stderr, "manipid: warning: %s: not a physical robot: %s\n", input_name(options.parameters).c_str(),
                 finding.c_str());
  }
  const int time_column = states.column_index("t");
  api::CsvTable torques;
  if (time_column >= 0) torques.columns.emplace_back("t");
  for (int joint = 1; joint <= joint_count; ++joint) torques.columns.push_back("tau" + std::to_string(joint));
  const int first_torque = time_column >= 0 ? 1 : 0;
  torques.data.resize(states.rows(), static_cast<Eigen::Index>(torques.columns.size()));
  robot::Data workspace(model);
  Eigen::VectorXd q(joint_count), qd(joint_count), qdd(joint_count), tau(joint_count);
  for (int row = 0; row < states.rows(); ++row) {
    for (int joint = 0; joint < joint_count; ++joint) {
      q[joint] = states.data(row, q_columns[static_cast<std::size_t>(joint)]);
      qd[joint] = states.data(row, qd_columns[static_cast<std::size_t>(joint)]);
      qdd[joint] = states.data(row, qdd_columns[static_cast<std::size_t>(joint)]);
    }
    robot::inverse_dynamics(model, workspace, parameters.layout, parameters.values, q, qd, qdd, tau);
    if (time_column >= 0) torques.data(row, 0) = states.data(row, time_column);
    torques.data.row(row).segment(first_torque, joint_count) = tau.transpose();
  }
  MeasurementNoise noise;
  noise.q_sigma = options.noise_q;
  noise.tau_sigma = options.noise_tau;
  noise.tau_relative_sigma = options.noise_tau_relative;
  noise.quantize_bits = options.quantize_bits;
  noise.seed = options.seed;
  if (options.with_states) {
    // The input's columns, then the torques; noise (if asked) on q and tau only.
    api::CsvTable dataset;
    dataset.columns = states.columns;
    for (int joint = 1; joint <= joint_count; ++joint) dataset.columns.push_back("tau" + std::to_string(joint));
    dataset.data.resize(states.rows(), static_cast<Eigen::Index>(dataset.columns.size()));
    dataset.data.leftCols(states.data.cols()) = states.data;
    dataset.data.rightCols(joint_count) = torques.data.rightCols(joint_count);
    if (noise.any()) {
      Trajectory measured;
      measured.t = Eigen::VectorXd::LinSpaced(states.rows(), 0.0, 1.0);  // not used by the noise
      measured.q.resize(states.rows(), joint_count);
      for (int joint = 0; joint < joint_count; ++joint) measured.q.col(joint) = states.data.col(q_columns[static_cast<std::size_t>(joint)]);
      measured.tau = torques.data.rightCols(joint_count);
      apply_measurement_noise(measured, noise);
      for (int joint = 0; joint < joint_count; ++joint) dataset.data.col(q_columns[static_cast<std::size_t>(joint)]) = measured.q.col(joint);
      dataset.data.rightCols(joint_count) = measured.tau;
    }
    write_table(options.output, dataset);
  } else {
    write_table(options.output, torques);
  }
  std::fprintf(stderr, "manipid torque: %s (%s): %d rows%s -> %s\n", model.name.c_str(), input_name(options.urdf.urdf).c_str(),
               states.rows(), noise.any() ? ", measurement noise added" : "", output_name(options.output).c_str());
  return exit_success;
}

}  // namespace

int run_torque(const TorqueOptions& options) {
  if (!options.urdf.urdf.empty()) return run_urdf_torque(options);
  const Robot robot = resolve_robot(options.robot);
  const RobotModel& model = robot.preset.model;
  const int joint_count = model.joint_count();
  const api::CsvTable states = read_table(options.input);

  const std::string last = std::to_string(joint_count);
  const std::string needs = "the " + std::to_string(joint_count) + "-joint " + robot.preset.name +
                            " robot needs q1..q" + last + ", qd1..qd" + last + ", qdd1..qdd" + last;
  std::vector<int> q_columns, qd_columns, qdd_columns;
  try {
    q_columns = joint_columns(states, "q", joint_count, needs);
    qd_columns = joint_columns(states, "qd", joint_count, needs);
    qdd_columns = joint_columns(states, "qdd", joint_count, needs);
  } catch (const InputError& error) {
    rethrow_with_source(error, input_name(options.input));
  }
  const int time_column = states.column_index("t");

  api::CsvTable torques;
  if (time_column >= 0) torques.columns.emplace_back("t");
  for (int joint = 1; joint <= joint_count; ++joint) torques.columns.push_back("tau" + std::to_string(joint));
  const int first_torque = time_column >= 0 ? 1 : 0;
  torques.data.resize(states.rows(), static_cast<Eigen::Index>(torques.columns.size()));

  // One workspace for all rows: inverse_dynamics does not allocate once it exists.
  DynamicsWorkspace workspace(model);
  Eigen::VectorXd q(joint_count), qd(joint_count), qdd(joint_count), tau(joint_count);
  for (int row = 0; row < states.rows(); ++row) {
    for (int joint = 0; joint < joint_count; ++joint) {
      q[joint] = states.data(row, q_columns[joint]);
      qd[joint] = states.data(row, qd_columns[joint]);
      qdd[joint] = states.data(row, qdd_columns[joint]);
    }
    inverse_dynamics(model, robot.parameters, workspace, q, qd, qdd, tau);
    if (time_column >= 0) torques.data(row, 0) = states.data(row, time_column);
    torques.data.row(row).segment(first_torque, joint_count) = tau.transpose();
  }

  write_table(options.output, torques);
  std::fprintf(stderr, "manipid torque: %s, %s kinetic energy: %d rows -> %s\n", robot.preset.name.c_str(),
               to_string(model.kinetic_energy), states.rows(), output_name(options.output).c_str());
  return exit_success;
}

}  // namespace manipid::server::cli
