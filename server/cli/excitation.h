// excitation.h — `manipid excitation`: an optimal excitation trajectory for a URDF robot.
#pragma once

#include "cli/common.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace manipid::server::cli {

/// `manipid excitation`: an optimal excitation trajectory for a URDF robot (core/robot/excitation.h).
/// Not robot::ExcitationOptions (the core's design options), which run_excitation builds from these;
/// add_excitation_command sets the design's defaults from the core's, so they are stated once.
struct ExcitationOptions {
  UrdfRobotOptions urdf;            ///< --robot (required), --base, --tip, --gravity
  double period = 0.0;
  int harmonics = 0;
  std::string criterion;
  bool payload = false;             ///< --payload: excite a payload's ten parameters on the tip link
  std::string moving_joints;        ///< --moving-joints "4-6" or "4,5,6" (1-based), "" = all
  std::string max_acceleration;     ///< "A" or "A1,...,An" (rad/s^2)
  std::string max_velocity;         ///< "" (the URDF's), "V" or "V1,...,Vn" (rad/s)
  std::string max_jerk;             ///< "" (none), "J" or "J1,...,Jn" (rad/s^3)
  std::string max_torque;           ///< "" (the URDF's efforts), "T" or "T1,...,Tn" (N m)
  std::string parameters;           ///< --params: the torque model (an identify result or overrides), "" = the URDF's
  std::string start_pose;           ///< "q1,...,qn" (rad), "" = none
  bool progress = false;            ///< --progress: a line per second on stderr (also when stderr is a terminal)
  double position_margin = 0.0;
  std::string friction;             ///< comma list of viscous, coulomb, offset; or "none"
  bool armature = false;
  double dt = 0.001;
  std::optional<double> duration;   ///< a whole number of periods; default one period
  std::uint64_t seed = 0;
  double max_seconds = 0.0;
  int max_evaluations = 0;
  std::string output = "-";
  std::string coefficients;         ///< JSON path, empty = none
};
CLI::App* add_excitation_command(CLI::App& app, ExcitationOptions& options);
int run_excitation(const ExcitationOptions& options);

}  // namespace manipid::server::cli
