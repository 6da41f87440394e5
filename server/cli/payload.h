// payload.h — `manipid payload`: a tool's or load's mass, centre of mass and inertia from a run of an identified arm carrying it.
#pragma once

#include "cli/common.h"
#include "manipid/api/log_format.h"

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace manipid::server::cli {

struct PayloadOptions {
  std::vector<std::string> inputs;    ///< runs with the payload on the tip link
  api::LogFormat log;                 ///< --columns, --time-unit, --angle-unit
  std::string topic;                  ///< --topic for a ROS 2 bag
  UrdfRobotOptions urdf;              ///< --robot (required), --base, --tip, --gravity
  std::string arm;                    ///< --arm: the arm's identification (identify --robot --json); empty = the URDF's values
  std::string mass;                   ///< --mass KG: known, empty = estimated
  std::string centre_of_mass;         ///< --com X,Y,Z in the tip link's frame, m; empty = estimated
  std::vector<std::string> validate;  ///< runs with the payload to predict without and with it
  std::string trim;                   ///< "START,END" seconds dropped, empty = none
  double dt = 0.0;                    ///< resampling period, 0 = the median step
  double comparison_cutoff = 0.0;     ///< Hz, 0 = the judge's
  std::string torque_joints;          ///< "1-6"; empty = all
  double judge_cutoff = 5.0;
  double judge_trim = 0.3;
  bool physical = false;
  std::string weights = "unit";     ///< --weights unit | per-joint
  bool json = false;
  std::string write_urdf;             ///< the URDF with the payload as a fixed link on the tip, empty = none
};
CLI::App* add_payload_command(CLI::App& app, PayloadOptions& options);
int run_payload(const PayloadOptions& options);

}  // namespace manipid::server::cli
