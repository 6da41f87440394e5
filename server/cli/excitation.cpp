// excitation.cpp — `manipid excitation`: designs an optimal excitation trajectory for a URDF robot
// (core/robot/excitation.h) and writes it sampled as t,q1..qn,qd1..qdn,qdd1..qddn — the states
// `manipid torque --robot` reads — and, on request, its Fourier coefficients as JSON.
#include "cli/excitation.h"

#include "manipid/api/csv.h"
#include "manipid/api/robot_json.h"
#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/urdf.h"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace manipid::server::cli {
namespace {

/// Core names its settings after the C++ fields; users know the options. A joint's or the model's
/// problem is the URDF's.
std::string excitation_option(const std::string& field, const std::string& urdf) {
  if (field == "period") return "--period";
  if (field == "harmonics") return "--harmonics";
  if (field == "max_acceleration") return "--max-acceleration";
  if (field == "max_velocity") return "--max-velocity";
  if (field == "max_jerk") return "--max-jerk";
  if (field == "max_torque") return "--max-torque";
  if (field == "torque_parameters") return "--params";
  if (field == "start_pose") return "--start-pose";
  if (field == "position_margin") return "--position-margin";
  if (field == "criterion") return "--criterion";
  if (field == "moving_joints") return "--moving-joints";
  if (field == "max_seconds") return "--max-seconds";
  if (field == "max_evaluations") return "--max-evaluations";
  if (field == "dt") return "--dt";
  if (field == "periods" || field == "duration") return "--duration";
  return urdf;
}

/// "V" or "V1,...,Vn" for `option` ("" = none given: an empty vector, the core's default).
Eigen::VectorXd parse_values(const std::string& text, const std::string& option) {
  const std::vector<std::string> items = split_list(text);
  Eigen::VectorXd values(static_cast<Eigen::Index>(items.size()));
  for (std::size_t i = 0; i < items.size(); ++i) {
    values[static_cast<Eigen::Index>(i)] = parse_number_option(items[i], option);
  }
  return values;
}

/// A progress line on stderr at most once a second: "design: 2400/8000 evaluations, best condition 5.61, 1.9 s".
class ProgressLine {
 public:
  ProgressLine(long budget, const char* criterion, bool terminal) : budget_(budget), criterion_(criterion), terminal_(terminal) {}
  void operator()(const robot::ExcitationProgress& progress) {
    if (progress.seconds < next_) return;
    next_ = progress.seconds + 1.0;
    std::fprintf(stderr, "%smanipid excitation: %ld/%ld evaluations, best %s %.6g, %.1f s%s", terminal_ ? "\r" : "",
                 progress.evaluation, budget_, criterion_, progress.best_value, progress.seconds, terminal_ ? "" : "\n");
    std::fflush(stderr);
    shown_ = true;
  }
  /// Ends a line left open on a terminal.
  void finish() const {
    if (terminal_ && shown_) std::fputc('\n', stderr);
  }

 private:
  long budget_;
  const char* criterion_;
  bool terminal_;
  double next_ = 1.0;
  bool shown_ = false;
};

/// --duration as a whole number of periods (default 1): any other length would not end at rest.
}  // namespace

CLI::App* add_excitation_command(CLI::App& app, ExcitationOptions& options) {
  // The design's defaults are the core's (one place states them).
  const robot::ExcitationOptions defaults;
  options.period = defaults.period;
  options.harmonics = defaults.harmonics;
  options.criterion = robot::to_string(defaults.criterion);
  char acceleration[32];
  std::snprintf(acceleration, sizeof acceleration, "%g", defaults.max_acceleration[0]);
  options.max_acceleration = acceleration;
  options.position_margin = defaults.position_margin;
  std::string friction;
  for (const std::string& term : api::friction_names(defaults.layout)) friction += (friction.empty() ? "" : ",") + term;
  options.friction = friction.empty() ? "none" : friction;
  options.seed = defaults.seed;
  options.max_seconds = defaults.max_seconds;
  options.max_evaluations = defaults.max_evaluations;

  CLI::App* command = app.add_subcommand(
      "excitation",
      "Design an optimal excitation trajectory for a URDF robot (Swevers et al. 1997): per joint a Fourier "
      "series of one period, at rest at both ends, within the URDF's position and velocity limits and an "
      "acceleration limit, minimising the condition number of the base regressor (or maximising its log det). "
      "Writes t,q1..qn,qd1..qdn,qdd1..qddn (rad, rad/s, rad/s^2) as CSV.");
  add_urdf_options(*command, options.urdf, true);
  command->add_option("--period", options.period, "Period T of the trajectory, s")->check(finite_number())->capture_default_str();
  command->add_option("--harmonics", options.harmonics, "Harmonics L per joint, 2..20")->capture_default_str();
  command->add_option("--criterion", options.criterion, "condition (minimise) or logdet (maximise)")
      ->check(CLI::IsMember({"condition", "logdet"}))
      ->capture_default_str();
  command
      ->add_option("--max-acceleration", options.max_acceleration,
                   "Acceleration limit, rad/s^2 (m/s^2 prismatic): one value, or one per joint comma-separated")
      ->capture_default_str();
  command->add_option("--max-velocity", options.max_velocity,
                      "Velocity limit, rad/s (m/s): one value, or one per joint comma-separated; never above the "
                      "URDF's (default: the URDF's)");
  command->add_option("--max-jerk", options.max_jerk,
                      "Jerk limit, rad/s^3 (m/s^3): one value, or one per joint comma-separated (default: none)");
  command->add_option("--max-torque", options.max_torque,
                      "Torque limit, N m (N): one value, or one per joint comma-separated; never above the URDF's "
                      "effort (default: the URDF's efforts)");
  command->add_option("--params", options.parameters,
                      "The model whose torque the limits hold, as `manipid torque --params` takes it (an identify "
                      "result JSON, or {\"name\": value} overrides); default: the URDF's inertial parameters");
  command->add_option("--start-pose", options.start_pose,
                      "Where the arm stands before and after, q1,...,qn in rad (m): the output then ramps from it to "
                      "the trajectory and back (default: none; the output starts at the trajectory's own start)");
  command->add_flag("--payload", options.payload,
                    "Excite a payload's ten parameters on the tip link (for `manipid payload`) instead of the arm's base "
                    "parameters: often a few seconds of wrist motion (--moving-joints)");
  command->add_option("--moving-joints", options.moving_joints,
                      "Joints that move, e.g. 4-6 (default: all); the others hold the mean pose the design chooses");
  command->add_flag("--progress", options.progress,
                    "Report the design's progress on stderr once a second (on by default when stderr is a terminal)");
  command
      ->add_option("--position-margin", options.position_margin,
                   "Distance kept from each position limit, rad (m prismatic)")
      ->check(finite_number())
      ->capture_default_str();
  command
      ->add_option("--friction", options.friction,
                   "Friction and offset terms of the model to identify: viscous, coulomb, offset (comma-separated), or none")
      ->capture_default_str();
  command->add_flag("--armature", options.armature, "The model to identify has a rotor inertia per joint");
  command->add_option("--dt", options.dt, "Sample step of the output, s; must divide the period")
      ->check(finite_number())
      ->capture_default_str();
  command->add_option("--duration", options.duration, "Length of the output, s: a whole number of periods (default: one)")
      ->check(positive_number());
  command->add_option("--seed", options.seed, "Seed of the random starts (same seed, same trajectory)")
      ->check(unsigned_integer())
      ->capture_default_str();
  command->add_option("--max-seconds", options.max_seconds, "Time budget of the design, s (a backstop)")
      ->check(finite_number())
      ->capture_default_str();
  command->add_option("--max-evaluations", options.max_evaluations, "Evaluation budget of the design")
      ->check(integer_between(1, 100'000'000))
      ->capture_default_str();
  command->add_option("--out", options.output, "Output CSV file, '-' for stdout")->capture_default_str();
  command->add_option("--coefficients", options.coefficients, "Also write the Fourier coefficients as JSON to this file");
  return command;
}

int run_excitation(const ExcitationOptions& options) {
  if (options.output == "-" && options.coefficients == "-") {
    throw UsageError("--out and --coefficients cannot both be stdout");
  }
  const std::string urdf_name = input_name(options.urdf.urdf);
  const robot::ParsedUrdf parsed = load_urdf_robot(options.urdf);
  const robot::Model& model = parsed.model;

  robot::ExcitationOptions design_options;
  design_options.period = options.period;
  design_options.harmonics = options.harmonics;
  design_options.position_margin = options.position_margin;
  design_options.seed = options.seed;
  design_options.max_seconds = options.max_seconds;
  design_options.max_evaluations = options.max_evaluations;
  design_options.criterion = robot::parse_excitation_criterion(options.criterion, "criterion");
  design_options.target = options.payload ? robot::ExcitationTarget::payload : robot::ExcitationTarget::arm;
  if (!options.moving_joints.empty()) {
    design_options.moving_joints = joint_list(options.moving_joints, model.joint_count(), "--moving-joints");
  }
  design_options.layout = parameter_layout(options.friction, options.armature);
  design_options.max_acceleration = parse_values(options.max_acceleration, "--max-acceleration");
  if (design_options.max_acceleration.size() == 0) {
    throw InputError("max_acceleration", "--max-acceleration: expected A or A1,...,An in rad/s^2");
  }
  design_options.max_velocity = parse_values(options.max_velocity, "--max-velocity");
  design_options.max_jerk = parse_values(options.max_jerk, "--max-jerk");
  design_options.max_torque = parse_values(options.max_torque, "--max-torque");
  design_options.start_pose = parse_values(options.start_pose, "--start-pose");
  if (!options.parameters.empty()) {
    nlohmann::json json;
    try {
      json = nlohmann::json::parse(read_text(options.parameters));
    } catch (const nlohmann::json::exception&) {
      throw InputError("params", input_name(options.parameters) + ": not a JSON document");
    }
    const api::ParameterValues torque_model = api::parameters_from_json(model, json, input_name(options.parameters));
    design_options.torque_layout = torque_model.layout;
    design_options.torque_parameters = torque_model.values;
  }

  // Everything is checked before the design's seconds are spent, and before the parser's warnings are
  // printed: a refused call prints one line.
  robot::ExcitationLimits limits;
  int periods = 1;
  try {
    periods = options.duration ? robot::whole_periods(*options.duration, options.period) : 1;
    limits = robot::excitation_limits(model, design_options);
    robot::check_sampling(options.period, options.harmonics, options.dt, periods);
  } catch (const InputError& error) {
    rethrow_with_source(error, excitation_option(error.field(), urdf_name));
  }
  print_urdf_warnings(options.urdf, parsed);

  ProgressLine progress(options.max_evaluations, robot::to_string(design_options.criterion), isatty(fileno(stderr)) != 0);
  if (options.progress || isatty(fileno(stderr))) {
    design_options.progress = [&progress](const robot::ExcitationProgress& step) { progress(step); };
  }
  robot::ExcitationDesign design;
  robot::SampledExcitation sampled;
  try {
    design = robot::design_excitation(model, design_options);
    progress.finish();
    sampled = robot::sample_excitation(design, options.dt, periods);
  } catch (const InputError& error) {
    progress.finish();
    rethrow_with_source(error, excitation_option(error.field(), urdf_name));  // "model": no parameter to see
  }

  // What is written never leaves a limit: the design guarantees the kinematic ones for every t and the
  // torque with a margin; this checks the rows, the torque by inverse dynamics at each.
  if (const std::optional<robot::LimitViolation> violation = robot::first_limit_violation(limits, sampled, &model)) {
    throw std::logic_error("the designed trajectory leaves " + robot::describe(*violation) + "; nothing was written");
  }

  const robot::ExcitationSummary& summary = design.summary;
  if (summary.termination == robot::ExcitationTermination::max_seconds) {
    std::fprintf(stderr,
                 "manipid: warning: the time budget (--max-seconds %g) ran out before the evaluation budget: the "
                 "result depends on this machine's speed\n",
                 options.max_seconds);
  } else if (summary.termination == robot::ExcitationTermination::failure) {
    std::fprintf(stderr, "manipid: warning: %s\n", summary.message.c_str());
  }

  write_table(options.output, api::trajectory_to_csv(robot::to_trajectory(sampled)));
  if (!options.coefficients.empty()) {
    write_text(options.coefficients, api::excitation_to_json(model, design_options, limits, design).dump(2) + "\n");
  }
  std::fprintf(stderr, "manipid excitation: %s, %d joints, %d harmonics, period %g s: %s; %ld samples (t = 0..%g s) -> %s\n",
               model.name.c_str(), model.joint_count(), options.harmonics, options.period,
               summary.brief_report().c_str(), static_cast<long>(sampled.t.size()),
               sampled.t.size() > 0 ? sampled.t[sampled.t.size() - 1] : 0.0, output_name(options.output).c_str());
  if (sampled.ramp_duration > 0.0) {
    std::fprintf(stderr, "manipid excitation: ramps of %g s from the start pose to the trajectory (t = 0..%g s) and back\n",
                 sampled.ramp_duration, sampled.ramp_duration);
  }
  if (summary.torque_scale < 1.0) {
    std::fprintf(stderr, "manipid excitation: the torque limits cut the motion to %.3g of what the kinematic limits allow\n",
                 summary.torque_scale);
  }
  return exit_success;
}

}  // namespace manipid::server::cli
