// commands.h — the `manipid` subcommands: each one's options, how it registers with CLI11 and
// how it runs, plus the plumbing they share (files, CSV tables, robot selection, option
// validators and the error kinds that decide the exit status).
//
// A subcommand is a pair: add_X_command() declares its options on the application and returns
// the CLI11 subcommand; run_X() does the work once parsing succeeded. main.cpp dispatches.
#pragma once

#include "manipid/api/csv.h"
#include "manipid/core/model.h"
#include "manipid/core/presets.h"
#include "manipid/core/robot/model.h"
#include "manipid/core/robot/urdf.h"
#include "manipid/core/robot/parameters.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace manipid::server {

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

/// Rethrows an InputError about `source` (a file name or option) with `source` in front.
[[noreturn]] void rethrow_with_source(const InputError& error, const std::string& source);

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
/// "viscous,coulomb,offset" (a list, "none" for no friction) and --armature → the parameter layout.
robot::ParameterLayout parameter_layout(const std::string& friction, bool armature);

// ---- simulate ----------------------------------------------------------------------------

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

// ---- torque ------------------------------------------------------------------------------

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

// ---- filter ------------------------------------------------------------------------------

struct FilterOptions {
  int order = 0;
  int half_length = 100;
  double band = 0.2;
  std::optional<double> dt;
  std::string input;
  std::string output = "-";
};
CLI::App* add_filter_command(CLI::App& app, FilterOptions& options);
int run_filter(const FilterOptions& options);

// ---- identify ----------------------------------------------------------------------------

struct IdentifyOptions {
  std::string input;
  std::string preset = "cedro2009";
  std::string kinetic_energy = "complete";
  std::vector<std::string> free;     ///< comma lists of names
  std::vector<std::string> initial;  ///< comma lists of NAME=VALUE
  std::vector<std::string> truth;    ///< comma lists of NAME=VALUE: known true values, shown beside the estimates
  std::string method = "input-error";
  std::string algorithm = "LN_BOBYQA";
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
  std::string friction = "viscous,coulomb";
  bool armature = false;
  bool physical = false;
  std::string validate;              ///< a second run's CSV, empty = none
  std::string trim;                  ///< "START,END" seconds dropped, empty = none
  double dt = 0.0;                   ///< resampling period, 0 = the median step
  std::string comparison_half_length = "auto";
  std::string comparison_band = "auto";
  std::string write_urdf;            ///< write the estimate into a copy of the URDF, empty = none
};
CLI::App* add_identify_command(CLI::App& app, IdentifyOptions& options);
int run_identify(const IdentifyOptions& options);
/// identify --robot: a URDF robot's base parameters (command_identify_robot.cpp).
int run_identify_robot(const IdentifyOptions& options);

// ---- serve -------------------------------------------------------------------------------

struct ServeOptions {
  std::string host = "127.0.0.1";
  int port = 8080;
  std::string database = "./manipid.db";
  int workers = 0;            ///< 0 = hardware threads
  int queue_limit = 10000;
  std::string max_body = "64MiB";
  std::string token;
  double job_timeout = 3600.0;
  int http_threads = 32;
  int max_attempts = 3;       ///< worker deaths a job may cause before it is failed for good
};
CLI::App* add_serve_command(CLI::App& app, ServeOptions& options);
int run_serve(const ServeOptions& options);

// ---- excitation ----------------------------------------------------------------------------

/// `manipid excitation`: an optimal excitation trajectory for a URDF robot (core/robot/excitation.h).
/// Not robot::ExcitationOptions (the core's design options), which run_excitation builds from these;
/// add_excitation_command sets the design's defaults from the core's, so they are stated once.
struct ExcitationOptions {
  UrdfRobotOptions urdf;            ///< --robot (required), --base, --tip, --gravity
  double period = 0.0;
  int harmonics = 0;
  std::string criterion;
  std::string max_acceleration;     ///< "A" or "A1,...,An" (rad/s^2)
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

}  // namespace manipid::server
