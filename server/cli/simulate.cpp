// simulate.cpp — `manipid simulate`: runs a preset's closed-loop experiment (the
// paper's scenario by default) and writes t, q1..qn, tau1..taun, ref1..refn as CSV.
#include "cli/simulate.h"

#include "manipid/api/csv.h"
#include "manipid/core/paper/simulation.h"

#include <chrono>
#include <cstdio>
#include <limits>

namespace manipid::server::cli {
namespace {

/// Core names its settings after the C++ fields; users know the options.
std::string simulate_option(const std::string& field) {
  if (field == "relative_tolerance") return "--rtol";
  if (field == "absolute_tolerance") return "--atol";
  if (field == "duration") return "--duration";
  if (field == "q_sigma") return "--noise-q";
  if (field == "tau_sigma") return "--noise-tau";
  if (field == "tau_relative_sigma") return "--noise-tau-relative";
  if (field == "quantize_bits") return "--quantize-q";
  return "simulate";
}

}  // namespace

CLI::App* add_simulate_command(CLI::App& app, SimulateOptions& options) {
  CLI::App* command = app.add_subcommand(
      "simulate",
      "Simulate a preset's robot under PD control and write t, q1..qn, tau1..taun, ref1..refn "
      "(SI units) as CSV. Without options: the paper's experiment.");
  add_robot_options(*command, options.robot);
  command->add_option("--noise-q", options.noise_q, "Gaussian noise on q, standard deviation in rad")
      ->check(non_negative_number());
  command->add_option("--noise-tau", options.noise_tau, "Gaussian noise on tau, standard deviation in N*m")
      ->check(non_negative_number());
  command
      ->add_option("--noise-tau-relative", options.noise_tau_relative,
                   "More Gaussian noise on tau, as a fraction of each joint's torque standard deviation (0.01 = 1 %)")
      ->check(non_negative_number());
  command->add_option("--quantize-q", options.quantize_bits, "Encoder resolution 2*pi/2^BITS on q (0 = none)")
      ->check(integer_between(0, 62));
  command->add_option("--seed", options.seed, "Seed of the measurement noise (same seed, same data)")
      ->check(unsigned_integer())
      ->capture_default_str();
  command
      ->add_option("--rtol", options.relative_tolerance,
                   "Relative tolerance of the integrator (preset: 1e-8)")
      ->check(positive_number());
  command
      ->add_option("--atol", options.absolute_tolerance,
                   "Absolute tolerance of the integrator (preset: 1e-8)")
      ->check(positive_number());
  command->add_option("--duration", options.duration, "Simulated time in s (preset: 9.7)")
      ->check(positive_number());
  command->add_option("--kp", options.kp, "PD gains Kp, comma-separated, one per joint (default: the preset's)");
  command->add_option("--kd", options.kd, "PD gains Kd, comma-separated, one per joint (default: the preset's)");
  command->add_option("--out", options.output, "Output CSV file, '-' for stdout")->capture_default_str();
  return command;
}

int run_simulate(const SimulateOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  const Robot robot = resolve_robot(options.robot);
  const Preset& preset = robot.preset;

  SimulationOptions simulation = preset.simulation;
  if (options.relative_tolerance) simulation.relative_tolerance = *options.relative_tolerance;
  if (options.absolute_tolerance) simulation.absolute_tolerance = *options.absolute_tolerance;
  if (options.duration) simulation.duration = *options.duration;

  MeasurementNoise noise;
  noise.q_sigma = options.noise_q;
  noise.tau_sigma = options.noise_tau;
  noise.tau_relative_sigma = options.noise_tau_relative;
  noise.quantize_bits = options.quantize_bits;
  noise.seed = options.seed;

  PdController controller = preset.controller;
  const int joints = preset.model.joint_count();
  if (!options.kp.empty()) controller.kp = parse_gain_list(options.kp, joints, "--kp");
  if (!options.kd.empty()) controller.kd = parse_gain_list(options.kd, joints, "--kd");

  SimulationSummary summary;
  Trajectory trajectory;
  try {
    const SampledReference reference = make_step_reference(preset.reference);
    trajectory = simulate_closed_loop(preset.model, robot.parameters, controller, reference,
                                      simulation, &summary);
    if (noise.any()) apply_measurement_noise(trajectory, noise);
  } catch (const InputError& error) {
    rethrow_with_source(error, simulate_option(error.field()));
  }

  write_table(options.output, api::trajectory_to_csv(trajectory));

  const double wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::fprintf(stderr,
               "manipid simulate: %s, %s kinetic energy: %d samples (t = 0..%g s), %ld integrator steps, "
               "%ld dynamics evaluations%s, %.2f s wall -> %s\n",
               preset.name.c_str(), to_string(preset.model.kinetic_energy), trajectory.samples(),
               trajectory.samples() > 0 ? trajectory.t[trajectory.samples() - 1] : 0.0, summary.steps,
               summary.rhs_evaluations, noise.any() ? ", measurement noise added" : "", wall_seconds,
               output_name(options.output).c_str());
  return exit_success;
}

}  // namespace manipid::server::cli
