// simulate.h — `manipid simulate`: the paper's closed loop simulated to a dataset CSV.
#pragma once

#include "cli/common.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace manipid::server::cli {

struct SimulateOptions {
  RobotOptions robot;
  double noise_q = 0.0;
  double noise_tau = 0.0;
  double noise_tau_relative = 0.0;
  int quantize_bits = 0;
  std::uint64_t seed = 1;
  std::optional<double> relative_tolerance;
  std::optional<double> absolute_tolerance;
  std::optional<double> duration;
  std::string kp, kd;  ///< comma lists; empty = the preset's gains
  std::string output = "-";
};
CLI::App* add_simulate_command(CLI::App& app, SimulateOptions& options);
int run_simulate(const SimulateOptions& options);

}  // namespace manipid::server::cli
