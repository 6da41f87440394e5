// identify.h — `manipid identify`: the paper's preset or a URDF robot identified from a measured run.
#pragma once

#include "cli/common.h"
#include "manipid/api/log_format.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace manipid::server::cli {

struct IdentifyOptions {
  std::vector<std::string> inputs;   ///< one run; with --robot, one or more
  api::LogFormat log;                ///< --columns, --time-unit, --angle-unit: how the CSVs name and scale things
  std::string topic;                 ///< --topic: a ROS 2 bag's JointState topic (empty: its only one)
  std::string preset = "cedro2009";
  std::string kinetic_energy = "complete";
  std::vector<std::string> free;     ///< comma lists of names
  std::vector<std::string> initial;  ///< comma lists of NAME=VALUE
  std::vector<std::string> truth;    ///< comma lists of NAME=VALUE: known true values, shown beside the estimates
  std::string method = "input-error";
  std::string algorithm;             ///< empty = the method's default (LM; LN_BOBYQA for output-error)
  std::string kp, kd;                ///< comma lists; empty = the preset's
  std::string half_length = "auto";
  std::string band = "auto";
  std::string torque_source = "auto";
  std::string weights = "unit";
  int max_evaluations = 20000;
  double max_seconds = 120.0;
  std::string history;               ///< CSV path, empty = none
  bool json = false;
  // A URDF robot (--robot): linear input-error identification of its base parameters.
  UrdfRobotOptions urdf;
  std::string friction = "auto";     ///< "auto" (chosen by held-out prediction) or a list of terms
  bool armature = false;
  bool physical = false;
  std::vector<std::string> validate; ///< runs' CSVs judged with the estimate, none = no validation
  std::string trim;                  ///< "START,END" seconds dropped, empty = none
  double dt = 0.0;                   ///< resampling period, 0 = the median step
  std::string comparison_cutoff = "auto";
  std::string ridge = "auto";
  std::string torque_joints;         ///< "1-6", "1,2,4"; empty = every joint with torque
  double judge_cutoff = 5.0;
  double judge_trim = 0.3;
  std::string removed_option;        ///< a former option given (hidden, refused naming its replacement)
  std::string write_urdf;            ///< write the estimate into a copy of the URDF, empty = none
};
CLI::App* add_identify_command(CLI::App& app, IdentifyOptions& options);
int run_identify(const IdentifyOptions& options);
/// identify --robot: a URDF robot's base parameters (identify_robot.cpp).
int run_identify_robot(const IdentifyOptions& options);

}  // namespace manipid::server::cli
