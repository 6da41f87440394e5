// log_format.cpp — column maps, units and the hint for a log without manipid's columns (log_format.h).
#include "manipid/api/log_format.h"

#include "manipid/core/errors.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <numbers>
#include <optional>
#include <string_view>

namespace manipid::api {
namespace {

constexpr std::string_view kJointNumber = "{j}";
constexpr std::string_view kJointName = "{joint}";
const char* const kAccepted = "FILE=MANIPID rules, e.g. time=t,position_{j}=q{j},effort_{j}=tau{j} ({j} a joint number, "
                              "{joint} a joint name; manipid's names: t, q{j}, qd{j}, qdd{j}, tau{j}, ref{j})";

std::string trim_spaces(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  return std::string(text);
}

/// One FILE=MANIPID rule: the file side split at its placeholder.
struct Rule {
  std::string text;         ///< as given, for messages
  std::string prefix, suffix;
  std::string placeholder;  ///< "", "{j}" or "{joint}"
  std::string target;       ///< manipid's name, with {j} where the joint goes
  bool used = false;
};

Rule parse_rule(const std::string& text) {
  const auto equals = text.find('=');
  if (equals == std::string::npos || text.find('=', equals + 1) != std::string::npos) {
    throw InputError("columns", "column map rule '" + text + "' is not FILE=MANIPID; give " + kAccepted);
  }
  Rule rule;
  rule.text = text;
  const std::string file = trim_spaces(std::string_view(text).substr(0, equals));
  rule.target = trim_spaces(std::string_view(text).substr(equals + 1));
  if (file.empty() || rule.target.empty()) throw InputError("columns", "column map rule '" + text + "' has an empty side");
  for (std::string_view placeholder : {kJointName, kJointNumber}) {
    const auto at = file.find(placeholder);
    if (at == std::string::npos) continue;
    rule.placeholder = std::string(placeholder);
    rule.prefix = file.substr(0, at);
    rule.suffix = file.substr(at + placeholder.size());
    break;
  }
  if (rule.placeholder.empty()) rule.prefix = file;
  if (rule.suffix.find('{') != std::string::npos || (rule.placeholder.empty() && file.find('{') != std::string::npos)) {
    throw InputError("columns", "column map rule '" + text + "': one placeholder at most, {j} or {joint}");
  }
  // manipid's side: t, or a group name with {j} (or a joint number when the file side names one column).
  std::string group = rule.target;
  const bool numbered = group.size() > kJointNumber.size() && group.ends_with(kJointNumber);
  if (numbered) group.resize(group.size() - kJointNumber.size());
  std::size_t digits = group.size();
  while (digits > 0 && std::isdigit(static_cast<unsigned char>(group[digits - 1]))) --digits;
  const bool literal_joint = !numbered && digits < group.size() && group[digits] != '0';
  const std::string stem = group.substr(0, digits);
  const bool known_group = stem == "q" || stem == "qd" || stem == "qdd" || stem == "tau" || stem == "ref";
  const bool valid = (rule.target == "t" && rule.placeholder.empty()) ||
                     (known_group && numbered && !rule.placeholder.empty() && digits == group.size()) ||
                     (known_group && literal_joint && rule.placeholder.empty());
  if (!valid) {
    throw InputError("columns", "column map rule '" + text + "': the manipid side must be t, or one of q{j}, qd{j}, qdd{j}, "
                                "tau{j}, ref{j} when the file side has a placeholder (q3 when it names one column)");
  }
  return rule;
}

/// The joint number a column's middle part stands for, or nothing.
std::optional<int> joint_of(const Rule& rule, std::string_view middle, const std::vector<std::string>& joint_names) {
  if (rule.placeholder == kJointNumber) {
    if (middle.empty() || middle.front() == '0') return std::nullopt;
    int number = 0;
    const auto [end, error] = std::from_chars(middle.data(), middle.data() + middle.size(), number);
    if (error != std::errc() || end != middle.data() + middle.size() || number < 1) return std::nullopt;
    return number;
  }
  const auto found = std::find(joint_names.begin(), joint_names.end(), middle);
  if (found == joint_names.end()) return std::nullopt;
  return static_cast<int>(found - joint_names.begin()) + 1;
}

/// What `rule` renames `column` to, or nothing when it does not match.
std::optional<std::string> rename(const Rule& rule, const std::string& column, const std::vector<std::string>& joint_names) {
  if (rule.placeholder.empty()) return column == rule.prefix ? std::optional<std::string>(rule.target) : std::nullopt;
  if (column.size() < rule.prefix.size() + rule.suffix.size() || !column.starts_with(rule.prefix) ||
      !column.ends_with(rule.suffix)) {
    return std::nullopt;
  }
  const std::string_view middle =
      std::string_view(column).substr(rule.prefix.size(), column.size() - rule.prefix.size() - rule.suffix.size());
  const auto joint = joint_of(rule, middle, joint_names);
  if (!joint) return std::nullopt;
  std::string target = rule.target;
  target.replace(target.size() - kJointNumber.size(), kJointNumber.size(), std::to_string(*joint));
  return target;
}

std::string column_list(const std::vector<std::string>& columns) {
  std::string text;
  const std::size_t shown = std::min<std::size_t>(columns.size(), 12);
  for (std::size_t i = 0; i < shown; ++i) text += (i ? ", " : "") + columns[i];
  if (shown < columns.size()) text += ", … (" + std::to_string(columns.size()) + " in all)";
  return text;
}

std::vector<Rule> parse_rules(const std::string& spec) {
  std::vector<Rule> rules;
  std::size_t start = 0;
  while (start <= spec.size()) {
    const auto comma = spec.find(',', start);
    const std::string part = trim_spaces(std::string_view(spec).substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (!part.empty()) rules.push_back(parse_rule(part));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (rules.empty()) throw InputError("columns", "the column map is empty; give " + std::string(kAccepted));
  return rules;
}

double time_scale(const std::string& unit) {
  if (unit == "s") return 1.0;
  if (unit == "ms") return 1e-3;
  if (unit == "us") return 1e-6;
  if (unit == "ns") return 1e-9;
  throw InputError("time_unit", "the time unit must be s, ms, us or ns, not '" + unit + "'");
}

double angle_scale(const std::string& unit) {
  if (unit == "rad") return 1.0;
  if (unit == "deg") return std::numbers::pi / 180.0;
  throw InputError("angle_unit", "the angle unit must be rad or deg, not '" + unit + "'");
}

/// "position_3" → {"position_", 3, ""}; "pos[3]" → {"pos[", 3, "]"}; no trailing number: nothing.
struct Numbered {
  std::string stem, separator_after;
  std::string prefix;  ///< the name up to the number
  int number = 0;
};
std::optional<Numbered> split_number(const std::string& name) {
  std::string body = name, closing;
  if (!body.empty() && body.back() == ']') {
    body.pop_back();
    closing = "]";
  }
  std::size_t digits = body.size();
  while (digits > 0 && std::isdigit(static_cast<unsigned char>(body[digits - 1]))) --digits;
  if (digits == body.size() || digits == 0) return std::nullopt;
  Numbered result;
  result.prefix = body.substr(0, digits);
  result.separator_after = closing;
  std::from_chars(body.data() + digits, body.data() + body.size(), result.number);
  result.stem = result.prefix;
  while (!result.stem.empty() && std::string_view("_-. [").find(result.stem.back()) != std::string_view::npos) result.stem.pop_back();
  for (char& c : result.stem) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return result;
}

}  // namespace

void check_log_format(const LogFormat& format) {
  (void)time_scale(format.time_unit);
  (void)angle_scale(format.angle_unit);
  if (format.columns.empty()) return;
  for (const Rule& rule : parse_rules(format.columns)) {
    if (rule.placeholder == kJointName && format.joint_names.empty()) {
      throw InputError("columns", "column map rule '" + rule.text + "' uses {joint}, which needs the robot's joint names: "
                                  "give the robot (--robot, robot_id), or use {j}, the joint number");
    }
  }
}

CsvTable apply_log_format(CsvTable table, const LogFormat& format) {
  check_log_format(format);
  if (!format.columns.empty()) {
    std::vector<Rule> rules = parse_rules(format.columns);
    const std::vector<std::string> original = table.columns;
    for (std::string& column : table.columns) {
      for (Rule& rule : rules) {
        if (const auto renamed = rename(rule, column, format.joint_names)) {
          column = *renamed;
          rule.used = true;
          break;
        }
      }
    }
    for (const Rule& rule : rules) {
      if (!rule.used) {
        throw InputError("columns", "column map rule '" + rule.text + "' matches no column; the file's columns are " +
                                        column_list(original));
      }
    }
    for (std::size_t a = 0; a < table.columns.size(); ++a) {
      for (std::size_t b = a + 1; b < table.columns.size(); ++b) {
        if (table.columns[a] == table.columns[b]) {
          throw InputError("columns", "the column map makes both '" + original[a] + "' and '" + original[b] + "' into " +
                                          table.columns[a]);
        }
      }
    }
  }
  const double seconds = time_scale(format.time_unit), radians = angle_scale(format.angle_unit);
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    const std::string& name = table.columns[c];
    const auto numbered = split_number(name);
    const std::string stem = numbered ? name.substr(0, name.size() - std::to_string(numbered->number).size()) : name;
    if (name == "t" && seconds != 1.0 && table.data.rows() > 0) {
      // From the first stamp: an epoch in nanoseconds (1.7e18) scaled to seconds keeps only ~0.2 µs of
      // resolution, and subtracting first loses nothing more.
      auto t = table.data.col(static_cast<Eigen::Index>(c));
      t = (t.array() - t[0]) * seconds;
    }
    if (numbered && radians != 1.0 && (stem == "q" || stem == "qd" || stem == "qdd" || stem == "ref")) {
      table.data.col(static_cast<Eigen::Index>(c)) *= radians;
    }
  }
  return table;
}

std::string column_hint(const CsvTable& table) {
  if (table.column_index("t") >= 0 && table.column_index("q1") >= 0) return {};
  std::string text = "the file's columns are " + column_list(table.columns);
  // A map for names that look like a log's: one time column, numbered positions (and torques).
  std::string time;
  std::vector<std::pair<std::string, std::string>> groups;  // file pattern, manipid group
  for (const std::string& name : table.columns) {
    std::string lower = name;
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const auto numbered = split_number(name);
    if (!numbered) {
      if (time.empty() && (lower.find("time") != std::string::npos || lower.find("stamp") != std::string::npos)) time = name;
      continue;
    }
    const std::string& stem = numbered->stem;
    std::string group;
    if (stem.find("pos") != std::string::npos || stem == "q" || stem.find("angle") != std::string::npos) group = "q";
    else if (stem.find("vel") != std::string::npos || stem == "qd") group = "qd";
    else if (stem.find("acc") != std::string::npos || stem == "qdd") group = "qdd";
    else if (stem.find("eff") != std::string::npos || stem.find("torq") != std::string::npos || stem == "tau") group = "tau";
    if (group.empty()) continue;
    const std::string pattern = numbered->prefix + "{j}" + numbered->separator_after;
    if (std::none_of(groups.begin(), groups.end(), [&](const auto& g) { return g.first == pattern || g.second == group; })) {
      groups.emplace_back(pattern, group);
    }
  }
  const bool has_q = std::any_of(groups.begin(), groups.end(), [](const auto& g) { return g.second == "q"; });
  if (!time.empty() && has_q) {
    std::string map = time + "=t";
    for (const auto& [pattern, group] : groups) map += "," + pattern + "=" + group + "{j}";
    text += "; read them with the column map " + map + " (--columns in the command line, columns= in the API)";
  } else {
    text += "; manipid reads t, q1..qn, tau1..taun (a column map renames a log's own: --columns in the command line, "
            "columns= in the API, e.g. time=t,position_{j}=q{j},effort_{j}=tau{j})";
  }
  return text;
}

}  // namespace manipid::api
