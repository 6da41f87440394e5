// common.h — what the `manipid` subcommands share: files, CSV tables, robot selection, option
// validators and the error kinds that decide the exit status.
//
// A subcommand lives in cli/NAME.h and cli/NAME.cpp: its options struct, add_NAME_command(),
// which declares them on the application and returns the CLI11 subcommand, and run_NAME(),
// which does the work once parsing succeeded. main.cpp dispatches.
#pragma once

#include "manipid/api/csv.h"
#include "manipid/api/log_format.h"
#include "manipid/core/paper/model.h"
#include "manipid/core/paper/presets.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/urdf.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/signal/resample.h"
#include "manipid/core/signal/trajectory.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace manipid::server::cli {

// ---- Exit statuses and error kinds -------------------------------------------------------

inline constexpr int exit_success = 0;
inline constexpr int exit_failure = 1;  ///< the program failed (I/O while writing, internal)
inline constexpr int exit_usage = 2;    ///< the call or its input is wrong (options, files, data)

/// The program was called wrongly: an unreadable input file, options that contradict each
/// other or the data. Exit status 2, like InputError.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Output could not be written (full disk, closed pipe, missing directory). Exit status 1.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// ---- Files ("-" means standard input or output) ------------------------------------------

/// How a path appears in messages: the path itself, or "stdin"/"stdout" for "-".
std::string input_name(const std::string& path);
std::string output_name(const std::string& path);

/// Whole file (or stdin) as text; UsageError when it cannot be read.
std::string read_text(const std::string& path);
/// Writes text to the file (replacing it) or stdout; OutputError on failure, and a
/// partially written file is removed.
void write_text(const std::string& path, std::string_view text);

/// Reads and parses a CSV file. Errors keep their field and gain the file name:
/// "run.csv line 12: expected 13 fields, got 12", "states.csv: missing column qd3".
api::CsvTable read_table(const std::string& path);
void write_table(const std::string& path, const api::CsvTable& table);

/// A run as a table: a CSV log read through `log` (its column map and units), or a ROS 2 bag — a .db3
/// file, or a bag's directory of them — whose JointState messages on `topic` (empty: the only such topic)
/// give t, q, qd and tau, the joints matched by `log.joint_names` (a URDF's; empty: the bag's order).
/// A bag's summary goes to stderr as a note. Errors as read_table's, the source in front.
api::CsvTable read_run_table(const std::string& path, const api::LogFormat& log, const std::string& topic);

/// Declares --columns, --time-unit, --angle-unit (how a CSV log names and scales things) and --topic (a ROS 2
/// bag's JointState topic) on `command`.
void add_log_options(CLI::App& command, api::LogFormat& log, std::string& topic);
/// A run read as read_run_table() reads it, as a trajectory with torque columns; errors name the file.
Trajectory read_run(const std::string& path, const api::LogFormat& log, const std::string& topic);
/// The runs' names for messages: "a.csv + b.csv".
std::string run_names(const std::vector<std::string>& paths);
/// --trim START,END (seconds dropped at each end; empty: none) as a data preparation.
DataPreparation parse_trim(const std::string& text);
/// "1-6", "1,2,4", "1-3,5" (1-based, of `n` joints) → 0-based joint indices; errors name `option`.
std::vector<int> joint_list(const std::string& text, int n, const std::string& option);

/// Rethrows an InputError about `source` (a file name or option) with `source` in front.
[[noreturn]] void rethrow_with_source(const InputError& error, const std::string& source);

// ---- Tables printed to the terminal --------------------------------------------------------

/// A value in a printed table: `digits` significant digits (printf's %g), "-" when not finite.
std::string format(double value, int digits = 6);

// ---- Option validators (numbers parsed like the CSV reader: strict, finite) --------------

CLI::Validator finite_number();
CLI::Validator positive_number();
CLI::Validator non_negative_number();
CLI::Validator integer_between(long long lowest, long long highest);
CLI::Validator unsigned_integer();

// ---- Values given inside option strings ("m2=24", "3800,40000,...", "auto" or a number) ----

/// Applies one NAME=VALUE item to the parameters; errors name `option` (e.g. "--param").
/// Negative masses and lengths are rejected.
void apply_parameter(const std::string& item, Parameters& parameters, const std::string& option);
/// A finite number, or InputError naming the option.
double parse_number_option(const std::string& text, const std::string& option);
/// One value per joint from a comma list (--kp, --kd): exactly `joints` finite numbers, else
/// InputError naming the option.
Eigen::VectorXd parse_gain_list(const std::string& text, int joints, const char* option);
long long parse_integer_option(const std::string& text, const std::string& option, long long lowest, long long highest);

// ---- Robot selection (simulate, torque; later identify) ----------------------------------

struct RobotOptions {
  std::string preset = "cedro2009";
  std::vector<std::string> parameters;  ///< "NAME=VALUE" items from --param
  std::string kinetic_energy = "complete";
};
void add_robot_options(CLI::App& command, RobotOptions& options);

/// The chosen preset (with the chosen kinetic-energy variant) and its true parameters
/// overridden by every --param. Throws InputError naming the bad option.
struct Robot {
  Preset preset;
  Parameters parameters;
};
Robot resolve_robot(const RobotOptions& options);

// ---- A robot from a URDF file (identify --robot, torque --robot, excitation) ---------------

struct UrdfRobotOptions {
  std::string urdf;     ///< --robot FILE
  std::string base;     ///< --base LINK (default: the URDF's root)
  std::string tip;      ///< --tip LINK (default: the only leaf)
  std::string gravity;  ///< --gravity GX,GY,GZ in the root frame, m/s² (default 0,0,-9.81)
};
/// Declares --robot, --base, --tip, --gravity on `command`; --robot is required when `required`.
void add_urdf_options(CLI::App& command, UrdfRobotOptions& options, bool required);
/// Reads and parses the URDF. Errors name the file ("arm.urdf: joint j3: ...") or the option (--base,
/// --tip, --gravity).
robot::ParsedUrdf load_urdf_robot(const UrdfRobotOptions& options);
/// The parser's warnings on stderr, one "manipid: warning: FILE: ..." line each.
void print_urdf_warnings(const UrdfRobotOptions& options, const robot::ParsedUrdf& parsed);
/// The items of a comma-separated list, empty items skipped: "a,,b" → {"a", "b"}.
std::vector<std::string> split_list(const std::string& text);
/// "viscous,coulomb,offset" (a list, "none" for no friction) and --armature → the parameter layout.
robot::ParameterLayout parameter_layout(const std::string& friction, bool armature);

}  // namespace manipid::server::cli
