// common.cpp — plumbing shared by the `manipid` subcommands: reading and writing files (or
// stdin/stdout), CSV tables with file-named errors, strict option validators, and turning
// --preset/--param/--kinetic-energy into a robot model with parameters.
#include "cli/common.h"

#include "manipid/api/ros2_bag.h"

#include "manipid/api/robot_json.h"
#include "manipid/core/robot/urdf.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <sstream>
#include <system_error>

namespace manipid::server::cli {
namespace {

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

std::string system_message(int error_number) { return std::strerror(error_number); }

std::string read_stream(std::FILE* stream, const std::string& name, std::size_t expected_size) {
  std::string text;
  text.reserve(expected_size);
  char buffer[1 << 16];
  std::size_t count = 0;
  errno = 0;
  while ((count = std::fread(buffer, 1, sizeof buffer, stream)) > 0) text.append(buffer, count);
  if (std::ferror(stream)) throw UsageError("cannot read " + name + ": " + system_message(errno));
  return text;
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

/// A finite double written in full (no trailing characters), as the CSV reader accepts.
std::optional<double> parse_double(std::string_view text) {
  text = trim(text);
  if (text.size() > 1 && text.front() == '+' && text[1] != '-' && text[1] != '+') text.remove_prefix(1);
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<long long> parse_integer(std::string_view text) {
  text = trim(text);
  if (text.size() > 1 && text.front() == '+') text.remove_prefix(1);
  long long value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

std::string in_quotes(const std::string& text) { return "'" + text + "'"; }

}  // namespace

void apply_parameter(const std::string& item, Parameters& parameters, const std::string& option) {
  const std::size_t equals = item.find('=');
  if (equals == std::string::npos) {
    throw InputError("param", option + " " + in_quotes(item) + ": expected NAME=VALUE, e.g. m2=24");
  }
  const std::string name(trim(std::string_view(item).substr(0, equals)));
  const std::string value_text(trim(std::string_view(item).substr(equals + 1)));
  const std::optional<double> value = parse_double(value_text);
  if (!value) {
    throw InputError(name, option + " " + item + ": " + in_quotes(value_text) + " is not a finite number");
  }
  try {
    parameters.set(name, *value);
  } catch (const InputError& error) {
    throw InputError(error.field(), option + " " + item + ": " + error.what());
  }
  // Negative masses or lengths have no physical meaning (and make the mass matrix indefinite).
  if (*value < 0.0) {
    throw InputError(name, option + " " + item + ": " + name + " must not be negative");
  }
}

Eigen::VectorXd parse_gain_list(const std::string& text, int joints, const char* option) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  if (static_cast<int>(items.size()) != joints) {
    throw InputError(option + 2, std::string(option) + " needs " + std::to_string(joints) +
                                     " comma-separated values, one per joint");
  }
  Eigen::VectorXd values(joints);
  for (int j = 0; j < joints; ++j) values[j] = parse_number_option(items[static_cast<std::size_t>(j)], option);
  return values;
}

double parse_number_option(const std::string& text, const std::string& option) {
  const std::optional<double> value = parse_double(text);
  if (!value) throw InputError(option.substr(2), option + ": " + in_quotes(text) + " is not a finite number");
  return *value;
}

long long parse_integer_option(const std::string& text, const std::string& option, long long lowest, long long highest) {
  const std::optional<long long> value = parse_integer(text);
  if (!value || *value < lowest || *value > highest) {
    throw InputError(option.substr(2), option + ": " + in_quotes(text) + " is not a whole number in " +
                                           std::to_string(lowest) + ".." + std::to_string(highest));
  }
  return *value;
}

// ---- Tables printed to the terminal --------------------------------------------------------

std::string format(double value, int digits) {
  if (!std::isfinite(value)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
  return buffer;
}

// ---- Files -------------------------------------------------------------------------------

std::string input_name(const std::string& path) { return path == "-" ? "stdin" : path; }
std::string output_name(const std::string& path) { return path == "-" ? "stdout" : path; }

std::string read_text(const std::string& path) {
  if (path == "-") return read_stream(stdin, "stdin", 0);
  if (path.empty()) throw UsageError("the input file name is empty");
  errno = 0;
  const File file(std::fopen(path.c_str(), "rb"));
  if (!file) throw UsageError("cannot read " + path + ": " + system_message(errno));
  std::error_code size_error;
  const auto size = std::filesystem::file_size(path, size_error);
  return read_stream(file.get(), path, size_error ? 0 : static_cast<std::size_t>(size));
}

void write_text(const std::string& path, std::string_view text) {
  if (path == "-") {
    errno = 0;
    const bool written = std::fwrite(text.data(), 1, text.size(), stdout) == text.size();
    if (!written || std::fflush(stdout) != 0) {
      throw OutputError("cannot write to stdout: " + system_message(errno));
    }
    return;
  }
  if (path.empty()) throw UsageError("the output file name is empty");
  errno = 0;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw OutputError("cannot write " + path + ": " + system_message(errno));
  const bool written = std::fwrite(text.data(), 1, text.size(), file) == text.size();
  const int write_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) {
    const int error_number = !written ? write_errno : errno;
    std::remove(path.c_str());  // a truncated result is worse than none
    throw OutputError("cannot write " + path + ": " + system_message(error_number));
  }
}

void rethrow_with_source(const InputError& error, const std::string& source) {
  const std::string_view message = error.what();
  // "line 12: ..." reads naturally as "run.csv line 12: ..."; anything else gets a colon.
  const bool has_line = message.substr(0, 5) == "line ";
  throw InputError(error.field(), source + (has_line ? " " : ": ") + std::string(message));
}

api::CsvTable read_table(const std::string& path) {
  const std::string text = read_text(path);
  try {
    return api::parse_csv(text);
  } catch (const InputError& error) {
    rethrow_with_source(error, input_name(path));
  }
}

void add_log_options(CLI::App& command, api::LogFormat& log, std::string& topic) {
  command.add_option("--columns", log.columns,
                     "The log's own column names mapped onto manipid's: FILE=MANIPID rules, e.g. "
                     "time=t,position_{j}=q{j},effort_{j}=tau{j} ({j} a joint number; with --robot also {joint}, a "
                     "joint's name in the URDF)");
  command.add_option("--time-unit", log.time_unit, "The time column's unit: s, ms, us or ns (ROS stamps)")
      ->check(CLI::IsMember({"s", "ms", "us", "ns"}))
      ->capture_default_str();
  command.add_option("--angle-unit", log.angle_unit, "The angles' unit (q, qd, qdd, ref): rad or deg")
      ->check(CLI::IsMember({"rad", "deg"}))
      ->capture_default_str();
  command.add_option("--topic", topic,
                     "For a ROS 2 bag (a .db3 file or a bag's directory): its sensor_msgs/JointState topic, when it has "
                     "several");
}

Trajectory read_run(const std::string& path, const api::LogFormat& log, const std::string& topic) {
  const api::CsvTable table = read_run_table(path, log, topic);
  try {
    return api::trajectory_from_csv(table, true);
  } catch (const InputError& error) {
    rethrow_with_source(error, input_name(path));
  }
}

std::string run_names(const std::vector<std::string>& paths) {
  std::string text;
  for (const std::string& path : paths) text += (text.empty() ? "" : " + ") + input_name(path);
  return text;
}

DataPreparation parse_trim(const std::string& text) {
  DataPreparation preparation;
  if (text.empty()) return preparation;
  const auto comma = text.find(',');
  if (comma == std::string::npos) throw InputError("trim", "--trim needs START,END: the seconds dropped at each end");
  preparation.trim_start = parse_number_option(text.substr(0, comma), "--trim");
  preparation.trim_end = parse_number_option(text.substr(comma + 1), "--trim");
  return preparation;
}

std::vector<int> joint_list(const std::string& text, int n, const std::string& option) {
  std::vector<int> joints;
  for (const std::string& part : split_list(text)) {
    const auto dash = part.find('-');
    const long first = parse_integer_option(part.substr(0, dash), option, 1, n);
    const long last = dash == std::string::npos ? first : parse_integer_option(part.substr(dash + 1), option, 1, n);
    if (last < first) throw InputError(option, option + ": the range " + part + " runs backwards (write " +
                                                   std::to_string(last) + "-" + std::to_string(first) + ")");
    for (long k = first; k <= last; ++k) joints.push_back(static_cast<int>(k - 1));
  }
  if (joints.empty()) throw InputError(option, option + " needs joint numbers, e.g. 1-6 or 1,2,4");
  return joints;
}

api::CsvTable read_run_table(const std::string& path, const api::LogFormat& log, const std::string& topic) {
  std::vector<std::string> contents;
  std::error_code error;
  if (path != "-" && std::filesystem::is_directory(path, error)) {
    // A bag's directory (metadata.yaml and name_0.db3, name_1.db3, … when split): its .db3 files in order.
    std::vector<std::filesystem::path> files;
    for (const auto& entry : std::filesystem::directory_iterator(path, error)) {
      if (entry.path().extension() == ".db3") files.push_back(entry.path());
    }
    if (files.empty()) throw UsageError(path + " is a directory without .db3 files (a ROS 2 bag in the sqlite3 storage)");
    // name_2.db3 before name_10.db3: by length, then by name.
    std::sort(files.begin(), files.end(), [](const auto& a, const auto& b) {
      const std::string x = a.filename().string(), y = b.filename().string();
      return x.size() != y.size() ? x.size() < y.size() : x < y;
    });
    for (const auto& file : files) contents.push_back(read_text(file.string()));
  } else {
    contents.push_back(read_text(path));
    if (!api::is_sqlite_database(contents.front())) {
      if (!topic.empty()) throw UsageError("--topic is for ROS 2 bags; " + input_name(path) + " is not one");
      try {
        return api::apply_log_format(api::parse_csv(contents.front()), log);
      } catch (const InputError& failure) {
        rethrow_with_source(failure, failure.field() == "columns" ? "--columns: " + input_name(path) : input_name(path));
      }
    }
  }
  if (!log.columns.empty() || log.time_unit != "s" || log.angle_unit != "rad") {
    throw UsageError(input_name(path) + " is a ROS 2 bag: its JointState messages name their joints and are in SI "
                     "units, so --columns, --time-unit and --angle-unit (for CSV logs) do not apply");
  }
  try {
    std::vector<std::string_view> files(contents.begin(), contents.end());
    api::BagOptions options;
    options.topic = topic;
    options.joint_names = log.joint_names;
    api::BagRead read = api::read_joint_states(files, options);
    std::fprintf(stderr, "manipid: note: %s: %s\n", input_name(path).c_str(), read.summary().c_str());
    return std::move(read.table);
  } catch (const InputError& failure) {
    rethrow_with_source(failure, failure.field() == "topic" ? "--topic: " + input_name(path) : input_name(path));
  }
}

void write_table(const std::string& path, const api::CsvTable& table) {
  write_text(path, api::format_csv(table));
}

// ---- Validators --------------------------------------------------------------------------

CLI::Validator finite_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        return parse_double(text) ? std::string() : "expected a finite number, got " + in_quotes(text);
      },
      "NUMBER");
}

CLI::Validator positive_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::optional<double> value = parse_double(text);
        return value && *value > 0.0 ? std::string() : "expected a positive number, got " + in_quotes(text);
      },
      "POSITIVE");
}

CLI::Validator non_negative_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::optional<double> value = parse_double(text);
        return value && *value >= 0.0 ? std::string()
                                      : "expected a number >= 0, got " + in_quotes(text);
      },
      "NONNEGATIVE");
}

CLI::Validator integer_between(long long lowest, long long highest) {
  const std::string range = std::to_string(lowest) + ".." + std::to_string(highest);
  return CLI::Validator(
      [lowest, highest, range](std::string& text) -> std::string {
        const std::optional<long long> value = parse_integer(text);
        if (value && *value >= lowest && *value <= highest) return {};
        return "expected an integer in " + range + ", got " + in_quotes(text);
      },
      range);
}

CLI::Validator unsigned_integer() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::string_view digits = trim(text);
        std::uint64_t value = 0;
        const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
        if (error == std::errc() && end == digits.data() + digits.size()) return {};
        return "expected an integer in 0..18446744073709551615, got " + in_quotes(text);
      },
      "UINT64");
}

// ---- Robot selection ---------------------------------------------------------------------

void add_robot_options(CLI::App& command, RobotOptions& options) {
  std::string presets;
  for (const std::string& name : preset_names()) presets += (presets.empty() ? "" : ", ") + name;
  command.add_option("--preset", options.preset, "Robot and experiment (known: " + presets + ")")
      ->capture_default_str();
  command
      .add_option("--param", options.parameters,
                  "Override a true parameter, NAME=VALUE (m1..mn kg, l1..ln m); repeatable or "
                  "comma-separated")
      ->delimiter(',')
      ->type_name("NAME=VALUE");
  command
      .add_option("--kinetic-energy", options.kinetic_energy,
                  "Kinetic energy: complete (physics) or paper (as printed, no cross terms)")
      ->capture_default_str()
      ->type_name("complete|paper");
}

Robot resolve_robot(const RobotOptions& options) {
  KineticEnergy kinetic_energy = KineticEnergy::complete;
  Robot robot;
  try {
    kinetic_energy = parse_kinetic_energy(options.kinetic_energy, "kinetic_energy");
    robot.preset = find_preset(options.preset, kinetic_energy);
  } catch (const InputError& error) {
    rethrow_with_source(error, error.field() == "preset" ? "--preset" : "--kinetic-energy");
  }
  robot.parameters = robot.preset.true_parameters;
  for (const std::string& item : options.parameters) apply_parameter(item, robot.parameters, "--param");
  check_parameters(robot.preset.model, robot.parameters);
  try {
    check_parameter_ranges(robot.parameters, "");
  } catch (const InputError& error) {
    rethrow_with_source(error, "--param");
  }
  return robot;
}

void add_urdf_options(CLI::App& command, UrdfRobotOptions& options, bool required) {
  CLI::Option* robot = command.add_option("--robot", options.urdf, "The robot's URDF file (a serial arm)");
  if (required) robot->required();
  command.add_option("--base", options.base, "URDF link fixed to the world (default: the root)")->needs(robot);
  command.add_option("--tip", options.tip, "URDF link that ends the chain (default: the only leaf)")->needs(robot);
  command.add_option("--gravity", options.gravity, "Gravity in the root link's frame, GX,GY,GZ m/s^2 (default 0,0,-9.81)")
      ->needs(robot);
}

robot::ParsedUrdf load_urdf_robot(const UrdfRobotOptions& options) {
  const std::string text = read_text(options.urdf);
  robot::UrdfOptions parse;
  parse.base = options.base;
  parse.tip = options.tip;
  if (!options.gravity.empty()) {
    const std::vector<std::string> items = [&] {
      std::vector<std::string> parts;
      std::string part;
      for (char c : options.gravity + ",") {
        if (c == ',') {
          parts.push_back(part);
          part.clear();
        } else {
          part += c;
        }
      }
      return parts;
    }();
    if (items.size() != 3) throw InputError("gravity", "--gravity needs three comma-separated numbers GX,GY,GZ (m/s^2)");
    for (int i = 0; i < 3; ++i) parse.gravity[i] = parse_number_option(items[static_cast<std::size_t>(i)], "--gravity");
  }
  try {
    return robot::parse_urdf(text, parse);
  } catch (const InputError& error) {
    const std::string& field = error.field();
    rethrow_with_source(error, field == "base" ? "--base" : field == "tip" ? "--tip" : field == "gravity" ? "--gravity"
                                                                                                       : input_name(options.urdf));
  }
}

void print_urdf_warnings(const UrdfRobotOptions& options, const robot::ParsedUrdf& parsed) {
  for (const std::string& warning : parsed.warnings) {
    std::fprintf(stderr, "manipid: warning: %s: %s\n", input_name(options.urdf).c_str(), warning.c_str());
  }
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

robot::ParameterLayout parameter_layout(const std::string& friction, bool armature) {
  std::vector<std::string> terms;
  std::string term;
  for (char c : friction + ",") {
    if (c == ',') {
      if (!term.empty()) terms.push_back(term);
      term.clear();
    } else if (c != ' ') {
      term += c;
    }
  }
  robot::ParameterLayout layout;
  api::parse_friction(terms, layout, "--friction");
  layout.armature = armature;
  return layout;
}

}  // namespace manipid::server::cli
