// torque.h — `manipid torque`: the inverse dynamics of a preset or URDF robot along given states.
#pragma once

#include "cli/common.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace manipid::server::cli {

struct TorqueOptions {
  RobotOptions robot;
  UrdfRobotOptions urdf;       ///< with --robot: a URDF robot instead of a preset
  std::string parameters;      ///< --params FILE: an identify --json result or {"name": value}
  bool with_states = false;    ///< write the input's columns before tau1..taun (a dataset)
  double noise_q = 0.0;        ///< with --with-states: measurement noise, as `simulate`'s options
  double noise_tau = 0.0;
  double noise_tau_relative = 0.0;
  int quantize_bits = 0;
  std::uint64_t seed = 1;
  std::string input;
  std::string output = "-";
};
CLI::App* add_torque_command(CLI::App& app, TorqueOptions& options);
int run_torque(const TorqueOptions& options);

}  // namespace manipid::server::cli
