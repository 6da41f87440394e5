// command_excitation.cpp — `manipid excitation`: designs an optimal excitation trajectory for a URDF robot
// (core/robot/excitation.h) and writes it sampled as t,q1..qn,qd1..qdn,qdd1..qddn — the states
// `manipid torque --robot` reads — and, on request, its Fourier coefficients as JSON.
#include "commands.h"

#include "manipid/api/csv.h"
#include "manipid/api/robot_json.h"
#include "manipid/core/robot/excitation.h"
#include "manipid/core/robot/urdf.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace manipid::server {
namespace {

/// Core names its settings after the C++ fields; users know the options. A joint's or the model's
/// problem is the URDF's.
std::string option_for_field(const std::string& field, const std::string& urdf) {
  if (field == "period") return "--period";
  if (field == "harmonics") return "--harmonics";
  if (field == "max_acceleration") return "--max-acceleration";
  if (field == "position_margin") return "--position-margin";
  if (field == "criterion") return "--criterion";
  if (field == "max_seconds") return "--max-seconds";
  if (field == "max_evaluations") return "--max-evaluations";
  if (field == "dt") return "--dt";
  if (field == "periods") return "--duration";
  return urdf;
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

Eigen::VectorXd parse_accelerations(const std::string& text) {
  const std::vector<std::string> items = split_list(text);
  if (items.empty()) throw InputError("max_acceleration", "--max-acceleration: expected A or A1,...,An in rad/s^2");
  Eigen::VectorXd values(static_cast<Eigen::Index>(items.size()));
  for (std::size_t i = 0; i < items.size(); ++i) {
    values[static_cast<Eigen::Index>(i)] = parse_number_option(items[i], "--max-acceleration");
  }
  return values;
}

/// --duration as a whole number of periods (default 1): any other length would not end at rest.
int periods_for(const std::optional<double>& duration, double period) {
  if (!duration) return 1;
  const double ratio = *duration / period;
  const double periods = std::round(ratio);
  if (!(periods >= 1.0) || std::abs(ratio - periods) > 1e-9 * ratio || periods > 1e6) {
    std::ostringstream message;
    message << "--duration: " << *duration << " s is not a whole number of periods (--period " << period
            << " s); the trajectory ends at rest only after whole periods";
    throw InputError("duration", message.str());
  }
  return static_cast<int>(periods);
}

nlohmann::ordered_json vector_json(const Eigen::VectorXd& v) {
  nlohmann::ordered_json array = nlohmann::ordered_json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) array.push_back(v[i]);  // ±∞ becomes null
  return array;
}

nlohmann::ordered_json rows_json(const Eigen::MatrixXd& m) {
  nlohmann::ordered_json array = nlohmann::ordered_json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) array.push_back(vector_json(m.row(r).transpose()));
  return array;
}

nlohmann::ordered_json coefficients_json(const robot::Model& model, const robot::ExcitationOptions& design_options,
                                         const robot::ExcitationLimits& limits, const robot::ExcitationDesign& design) {
  const robot::FourierTrajectory& trajectory = design.trajectory;
  const robot::ExcitationSummary& summary = design.summary;
  nlohmann::ordered_json joints = nlohmann::ordered_json::array();
  for (const robot::Joint& joint : model.joints) joints.push_back(joint.name);
  nlohmann::ordered_json active = nlohmann::ordered_json::array();
  for (const robot::ActiveLimit& limit : summary.active_limits) {
    active.push_back({{"joint", limit.joint_name},
                      {"index", limit.joint},
                      {"kind", robot::to_string(limit.kind)},
                      {"peak", limit.peak},
                      {"limit", limit.limit}});
  }
  const robot::ParameterLayout& layout = design_options.layout;
  return nlohmann::ordered_json{
      {"robot", model.name},
      {"joints", joints},
      {"series", "q_k(t) = q0_k + sum_{l=1..L} [a_kl/(w l) sin(w l t) - b_kl/(w l) cos(w l t)], w = 2 pi / period; "
                 "qd_k(t) = sum_l [a_kl cos(w l t) + b_kl sin(w l t)]"},
      {"period", trajectory.period},
      {"harmonics", trajectory.harmonics()},
      {"angular_frequency", trajectory.angular_frequency()},
      {"q0", vector_json(trajectory.q0)},
      {"a", rows_json(trajectory.a)},
      {"b", rows_json(trajectory.b)},
      {"start", vector_json(trajectory.start())},
      {"criterion", robot::to_string(summary.criterion)},
      {"criterion_value", summary.final_value},
      {"initial_criterion_value", summary.initial_value},
      {"condition_number", summary.condition_number},
      {"log_det", summary.log_det},
      {"base_parameters", summary.base_parameters},
      {"samples", summary.samples},
      {"layout",
       {{"viscous", layout.viscous}, {"coulomb", layout.coulomb}, {"offset", layout.offset}, {"armature", layout.armature}}},
      {"limits",
       {{"lower", vector_json(limits.lower)},
        {"upper", vector_json(limits.upper)},
        {"velocity", vector_json(limits.velocity)},
        {"acceleration", vector_json(limits.acceleration)},
        {"position_margin", design_options.position_margin}}},
      {"active_limits", active},
      {"seed", design_options.seed},
      {"evaluations", summary.evaluations},
      {"wall_seconds", summary.wall_seconds},
      {"termination", robot::to_string(summary.termination)},
      {"message", summary.message},
  };
}

api::CsvTable states_table(const robot::SampledExcitation& sampled) {
  const Eigen::Index n = sampled.q.rows();
  api::CsvTable table;
  table.columns.emplace_back("t");
  for (const char* prefix : {"q", "qd", "qdd"}) {
    for (Eigen::Index k = 1; k <= n; ++k) table.columns.push_back(std::string(prefix).append(std::to_string(k)));
  }
  table.data.resize(sampled.t.size(), 1 + 3 * n);
  table.data.col(0) = sampled.t;
  table.data.middleCols(1, n) = sampled.q.transpose();
  table.data.middleCols(1 + n, n) = sampled.qd.transpose();
  table.data.middleCols(1 + 2 * n, n) = sampled.qdd.transpose();
  return table;
}

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
  design_options.layout = parameter_layout(options.friction, options.armature);
  design_options.max_acceleration = parse_accelerations(options.max_acceleration);

  // Everything is checked before the design's seconds are spent, and before the parser's warnings are
  // printed: a refused call prints one line.
  robot::ExcitationLimits limits;
  int periods = 1;
  try {
    periods = periods_for(options.duration, options.period);
    limits = robot::excitation_limits(model, design_options);
    robot::check_sampling(options.period, options.harmonics, options.dt, periods);
  } catch (const InputError& error) {
    if (error.field() == "duration") throw;  // already names --duration
    rethrow_with_source(error, option_for_field(error.field(), urdf_name));
  }
  print_urdf_warnings(options.urdf, parsed);

  robot::ExcitationDesign design;
  robot::SampledExcitation sampled;
  try {
    design = robot::design_excitation(model, design_options);
    sampled = robot::sample_excitation(design.trajectory, options.dt, periods);
  } catch (const InputError& error) {
    rethrow_with_source(error, option_for_field(error.field(), urdf_name));  // "model": no parameter to see
  }

  // What is written never leaves a limit: the design guarantees it for every t; this checks the rows.
  if (const std::optional<robot::LimitViolation> violation = robot::first_limit_violation(limits, sampled)) {
    throw std::logic_error("the designed trajectory leaves the " + std::string(robot::to_string(violation->kind)) +
                           " limit of joint " + std::to_string(violation->joint) + " at t = " +
                           std::to_string(violation->t) + " s; nothing was written");
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

  write_table(options.output, states_table(sampled));
  if (!options.coefficients.empty()) {
    write_text(options.coefficients, coefficients_json(model, design_options, limits, design).dump(2) + "\n");
  }
  std::fprintf(stderr, "manipid excitation: %s, %d joints, %d harmonics, period %g s: %s; %ld samples (t = 0..%g s) -> %s\n",
               model.name.c_str(), model.joint_count(), options.harmonics, options.period,
               summary.brief_report().c_str(), static_cast<long>(sampled.t.size()),
               sampled.t.size() > 0 ? sampled.t[sampled.t.size() - 1] : 0.0, output_name(options.output).c_str());
  return exit_success;
}

}  // namespace manipid::server
