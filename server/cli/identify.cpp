// identify.cpp — `manipid identify`: estimates a preset robot's parameters from a
// trajectory CSV and prints a table with the identifiability findings, or (--json) the
// result object the service returns.
#include "cli/identify.h"

#include "manipid/api/csv.h"
#include "manipid/api/result_json.h"
#include "manipid/core/paper/identification.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace manipid::server::cli {
namespace {

std::string list(const Eigen::VectorXd& values, int digits = 6, const char* unit = "") {
  std::string text = "(";
  for (Eigen::Index j = 0; j < values.size(); ++j) text += (j ? ", " : "") + format(values[j], digits) + unit;
  return text + ")";
}

/// `truth`: empty when no true value is known (then no "true" column), else 2n entries with NaN
/// for the values not given.
void print_table(const IdentificationResult& result, const Eigen::VectorXd& truth) {
  const auto& unidentifiable = result.identifiability.unidentifiable;
  const bool known_truth = truth.size() > 0;
  std::printf("%s, %s; filter M = %d, band = %g rad/sample%s; torque from %s\n", to_string(result.method),
              result.algorithm.c_str(), result.filter.half_length, result.filter.band,
              result.filter_chosen_automatically ? " (chosen from the data)" : "",
              result.torque_source == TorqueSource::reference ? "ref and the PD gains" : "the measured tau");
  if (result.controller) {
    std::printf("PD gains (%s): Kp = %s, Kd = %s\n",
                result.gain_source == GainSource::given       ? "given"
                : result.gain_source == GainSource::estimated ? "estimated from the data"
                                                              : "assumed: the preset's",
                list(result.controller->kp).c_str(), list(result.controller->kd).c_str());
  }
  if (result.estimated_gains && result.gain_source != GainSource::estimated) {
    std::printf("PD gains the data suggest: Kp = %s, Kd = %s\n", list(result.estimated_gains->gains.kp).c_str(),
                list(result.estimated_gains->gains.kd).c_str());
  }
  if (result.estimated_gains) {
    std::printf("PD law fit: %s of each joint's filtered torque unexplained by the estimated gains\n",
                list(100.0 * result.estimated_gains->relative_residual, 3, " %").c_str());
  }
  std::printf("\n%-10s %12s %14s %12s", "parameter", "initial", "estimate", "std error");
  if (known_truth) std::printf(" %10s", "true");
  std::printf("\n");
  for (std::size_t i = 0; i < result.names.size(); ++i) {
    const std::string& name = result.names[i];
    std::string estimate = format(result.estimate[static_cast<Eigen::Index>(i)]);
    std::string error = format(result.std_errors[static_cast<Eigen::Index>(i)], 3);
    if (!result.free[i]) {
      error = "fixed";
    } else if (std::find(unidentifiable.begin(), unidentifiable.end(), name) != unidentifiable.end()) {
      estimate = "not alone";  // never a confident number for what the data cannot tell
      error = "-";
    }
    std::printf("%-10s %12s %14s %12s", name.c_str(), format(result.initial[static_cast<Eigen::Index>(i)]).c_str(),
                estimate.c_str(), error.c_str());
    if (known_truth) std::printf(" %10s", format(truth[static_cast<Eigen::Index>(i)]).c_str());
    std::printf("\n");
  }
  const int joints = static_cast<int>(result.names.size() / 2);
  for (const IdentifiableCombination& combination : result.identifiability.combinations) {
    std::printf("%-10s %12s %14s %12s", combination.name.c_str(), "", format(combination.value).c_str(),
                format(combination.std_error, 3).c_str());
    if (known_truth) {
      // The true value of a product term, from its factors' true values (NaN when one is not given).
      double true_value = 1.0;
      std::stringstream stream(combination.name);
      std::string factor;
      while (std::getline(stream, factor, '*')) {
        int power = 1;
        if (const auto caret = factor.find('^'); caret != std::string::npos) {
          power = std::stoi(factor.substr(caret + 1));
          factor = factor.substr(0, caret);
        }
        const int index = parameter_index(factor, joints);
        true_value *= index < 0 ? std::numeric_limits<double>::quiet_NaN() : std::pow(truth[index], power);
      }
      std::printf(" %10s", format(true_value).c_str());
    }
    std::printf("\n");
  }
  std::printf("\ncost %s -> %s after %ld evaluations", format(result.initial_cost).c_str(),
              format(result.final_cost).c_str(), result.evaluations);
  if (result.simulations) std::printf(" (%ld simulations)", result.simulations);
  std::printf(" in %.3f s; stopped: %s", result.wall_seconds, result.stop_reason.c_str());
  if (result.refinement_steps) std::printf(" (+%d Gauss-Newton polish steps)", result.refinement_steps);
  std::printf("\n");
  if (result.method == IdentificationMethod::two_stage) {
    std::printf("(the first cost is input-error's, N*m^2; the final one the output error, rad^2)\n");
  }
  if (!result.identifiability.findings.empty()) {
    std::printf("\nidentifiability:\n");
    for (const std::string& finding : result.identifiability.findings) std::printf("  - %s\n", finding.c_str());
  } else {
    std::printf("\nidentifiability: every free parameter is determined by the data\n");
  }
  for (const std::string& warning : result.warnings) std::printf("\nwarning: %s\n", warning.c_str());
}

}  // namespace

CLI::App* add_identify_command(CLI::App& app, IdentifyOptions& options) {
  CLI::App* command = app.add_subcommand(
      "identify",
      "Estimate a robot's parameters from a trajectory CSV (t,q1..qn,tau1..taun[,ref1..refn]) with "
      "the input-error method (default), output-error, or the two-stage method.");
  command->add_option("data", options.inputs,
                      "Trajectory CSV file, '-' for stdin, or a ROS 2 bag of sensor_msgs/JointState (a .db3 file or a "
                      "bag's directory); with --robot, one or more runs (each filtered alone, then fitted together)")
      ->required();
  add_log_options(*command, options.log, options.topic);
  command->add_option("--preset", options.preset, "Robot model")->capture_default_str();
  command->add_option("--kinetic-energy", options.kinetic_energy,
                      "complete (default) or paper (the paper's simplified model)")
      ->check(CLI::IsMember({"complete", "paper"}))
      ->capture_default_str();
  command->add_option("--free", options.free, "Comma-separated free parameters (default: all)");
  command->add_option("--init", options.initial,
                      "Start values NAME=VALUE, comma-separated or repeated (default: the paper's)");
  command->add_option("--truth", options.truth,
                      "Known true values NAME=VALUE, comma-separated or repeated, shown beside the estimates (default: "
                      "none; a CSV does not say which robot made it)");
  command->add_option("--method", options.method, "input-error, output-error or two-stage")
      ->check(CLI::IsMember({"input-error", "output-error", "two-stage"}))
      ->capture_default_str();
  command->add_option("--algorithm", options.algorithm,
                      "LM (Levenberg-Marquardt on the least-squares form) or an NLopt algorithm (default: LM; "
                      "LN_BOBYQA for output-error, which needs a derivative-free one)")
      ->check(CLI::IsMember(identification_algorithms()));
  command->add_option("--kp", options.kp,
                      "PD gains Kp, comma-separated (default: estimated from the data's tau, q and ref; without tau, "
                      "the preset's)");
  command->add_option("--kd", options.kd, "PD gains Kd, comma-separated (default: as --kp)");
  command->add_option("--half-length", options.half_length,
                      "Filter half-length M, or 'auto' (with --robot: the differentiation filter's)")
      ->capture_default_str();
  command->add_option("--band", options.band, "Filter band edge in rad/sample, or 'auto'")->capture_default_str();
  command->add_option("--torque-source", options.torque_source,
                      "auto (measured tau if present), measured, or reference (tau = Kp(r-q) - Kd qd)")
      ->check(CLI::IsMember({"auto", "measured", "reference"}))
      ->capture_default_str();
  command->add_option("--weights", options.weights,
                      "unit (the paper), inverse-variance (each joint by its filtered torque's variance) or, with "
                      "--robot, per-joint (each joint by its residual's variance)")
      ->check(CLI::IsMember({"unit", "inverse-variance", "per-joint"}))
      ->capture_default_str();
  command->add_option("--max-evaluations", options.max_evaluations, "Evaluation budget")
      ->check(integer_between(1, 100'000'000))
      ->capture_default_str();
  command->add_option("--max-seconds", options.max_seconds, "Time budget in s")->check(positive_number())->capture_default_str();
  command->add_option("--history", options.history, "Write the cost history (index,cost,m1..ln) as CSV");
  command->add_flag("--json", options.json, "Print the result as JSON (the service's result object)");

  // A URDF robot: its base parameters by linear input-error; the paper model's options do not apply.
  add_urdf_options(*command, options.urdf, false);
  CLI::Option* robot = command->get_option("--robot");
  for (const char* paper_only : {"--preset", "--kinetic-energy", "--free", "--init", "--truth", "--algorithm", "--kp", "--kd",
                                 "--torque-source", "--max-evaluations", "--max-seconds", "--history"}) {
    command->get_option(paper_only)->excludes(robot);
  }
  command->add_option("--friction", options.friction,
                      "With --robot: friction terms per joint, any of viscous,coulomb,offset, none, or auto (chosen by "
                      "held-out prediction among none, viscous, viscous+coulomb and viscous+coulomb+offset)")
      ->capture_default_str()
      ->needs(robot);
  command->add_flag("--armature", options.armature, "With --robot: estimate each joint's rotor inertia Ia (tau += Ia qdd)")
      ->needs(robot);
  command->add_flag("--physical", options.physical,
                    "With --robot: a physically consistent estimate (every link a real rigid body, friction >= 0)")
      ->needs(robot);
  command->add_option("--validate", options.validate,
                      "With --robot: runs' CSVs to predict with the estimate (and with the URDF's values), judged under "
                      "--judge-cutoff; repeat it for several runs")
      ->expected(1)
      ->take_all()
      ->needs(robot);
  command->add_option("--trim", options.trim, "With --robot: seconds dropped at the start and the end, START,END")
      ->needs(robot);
  command->add_option("--dt", options.dt, "With --robot: resample onto this period, s (default: the median time step)")
      ->check(positive_number())
      ->needs(robot);
  command->add_option("--comparison-cutoff", options.comparison_cutoff,
                      "With --robot: the cut-off (Hz) of the zero-phase low-pass applied to tau and the regressor alike, or "
                      "'auto' (chosen by held-out prediction)")
      ->capture_default_str()
      ->needs(robot);
  command->add_option("--ridge", options.ridge,
                      "With --robot: the relative ridge toward the URDF's values (0 = least squares), or 'auto' (chosen by "
                      "held-out prediction)")
      ->capture_default_str()
      ->needs(robot);
  command->add_option("--torque-joints", options.torque_joints,
                      "With --robot: the joints with torque sensors, 1-based, e.g. 1-6 or 1,2,4 (default: every joint whose "
                      "torque is not zero throughout)")
      ->needs(robot);
  command->add_option("--judge-cutoff", options.judge_cutoff,
                      "With --robot: the cut-off (Hz) of the fixed low-pass every torque figure is judged under")
      ->check(positive_number())
      ->capture_default_str()
      ->needs(robot);
  command->add_option("--judge-trim", options.judge_trim, "With --robot: seconds the judge drops at each end of a run")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->needs(robot);
  // The former comparison filter (a finite window): refused, naming what replaced it.
  for (const char* removed : {"--comparison-half-length", "--comparison-band"}) {
    command->add_option_function<std::string>(removed, [&options, removed](const std::string&) { options.removed_option = removed; })
        ->group("");
  }
  command->add_option("--write-urdf", options.write_urdf,
                      "With --robot: write the estimate (its point) into a copy of the URDF: each link's <inertial>, each "
                      "joint's <dynamics>; everything else as it was")
      ->needs(robot);
  return command;
}

int run_identify(const IdentifyOptions& options) {
  if (!options.urdf.urdf.empty()) return run_identify_robot(options);
  if (options.inputs.size() != 1) {
    throw UsageError("the paper's model is identified from one run; several runs (" + std::to_string(options.inputs.size()) +
                     " given) are for a URDF robot (--robot)");
  }
  const std::string& input = options.inputs.front();
  const KineticEnergy energy = parse_kinetic_energy(options.kinetic_energy);
  const Preset preset = find_preset(options.preset, energy);
  const int n = preset.model.joint_count();
  Trajectory data;
  const api::CsvTable table = read_run_table(input, options.log, options.topic);
  try {
    data = api::trajectory_from_csv(table);
  } catch (const InputError& error) {
    rethrow_with_source(error, input_name(input));
  }

  IdentificationOptions identification;
  identification.method = parse_identification_method(options.method);
  identification.algorithm = options.algorithm;
  identification.initial = preset.initial_parameters;
  for (const std::string& list : options.initial) {
    for (const std::string& item : split_list(list)) apply_parameter(item, identification.initial, "--init");
  }
  try {
    check_parameter_ranges(identification.initial, "");
  } catch (const InputError& error) {
    rethrow_with_source(error, "--init");
  }
  // Known true values: only what the user gives (NaN = not given).
  Eigen::VectorXd truth;
  if (!options.truth.empty()) {
    Parameters given = Parameters::from_vector(Eigen::VectorXd::Constant(2 * n, std::numeric_limits<double>::quiet_NaN()));
    for (const std::string& list : options.truth) {
      for (const std::string& item : split_list(list)) apply_parameter(item, given, "--truth");
    }
    truth = given.vector();
  }
  for (const std::string& list : options.free) {
    for (const std::string& name : split_list(list)) identification.free.push_back(name);
  }
  // Gains: given (one of --kp/--kd given completes the other from the preset's), else estimated
  // from the data when they carry tau and ref, else the preset's, with a warning (core).
  identification.assumed_controller = preset.controller;
  if (!options.kp.empty() || !options.kd.empty()) {
    identification.controller = preset.controller;
    if (!options.kp.empty()) identification.controller->kp = parse_gain_list(options.kp, n, "--kp");
    if (!options.kd.empty()) identification.controller->kd = parse_gain_list(options.kd, n, "--kd");
  }
  identification.half_length =
      options.half_length == "auto" ? 0 : static_cast<int>(parse_integer_option(options.half_length, "--half-length", 2, 1'000'000));
  identification.band = options.band == "auto" ? 0.0 : parse_number_option(options.band, "--band");
  identification.torque_source = options.torque_source == "measured"    ? TorqueSource::measured
                                 : options.torque_source == "reference" ? TorqueSource::reference
                                                                        : TorqueSource::automatic;
  if (options.weights == "per-joint") {
    throw UsageError("--weights per-joint weighs a URDF robot's joints by their residuals (with --robot); the paper's "
                     "model takes unit or inverse-variance");
  }
  identification.weighting =
      options.weights == "inverse-variance" ? JointWeighting::inverse_variance : JointWeighting::unit;
  identification.max_evaluations = options.max_evaluations;
  identification.max_seconds = options.max_seconds;

  const IdentificationResult result = identify(preset.model, data, identification);

  if (!options.history.empty()) {
    api::CsvTable table;
    table.columns = {"index", "cost"};
    for (const std::string& name : result.names) table.columns.push_back(name);
    table.data.resize(static_cast<Eigen::Index>(result.history.size()), static_cast<Eigen::Index>(table.columns.size()));
    for (std::size_t r = 0; r < result.history.size(); ++r) {
      const HistoryRecord& record = result.history[r];
      table.data(static_cast<Eigen::Index>(r), 0) = static_cast<double>(record.index);
      table.data(static_cast<Eigen::Index>(r), 1) = record.cost;
      table.data.row(static_cast<Eigen::Index>(r)).tail(record.theta.size()) = record.theta.transpose();
    }
    write_table(options.history, table);
  }
  if (options.json) {
    std::printf("%s\n", api::result_to_json(result, truth).dump(2).c_str());
  } else {
    print_table(result, truth);
  }
  return result.cancelled ? exit_failure : exit_success;
}

}  // namespace manipid::server::cli
