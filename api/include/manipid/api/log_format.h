// log_format.h — logs as labs record them: their column names mapped onto manipid's, their units made SI,
// and a log without manipid's columns answered with the columns it has and a map that would fit.
//
// A column map is a comma-separated list of FILE=MANIPID rules. A rule's file side may hold one
// placeholder: {j}, a joint number (1, 2, …), or {joint}, one of the robot's joint names (a URDF's);
// its manipid side names t, q{j}, qd{j}, qdd{j}, tau{j} or ref{j}:
//
//     time=t,position_{j}=q{j},velocity_{j}=qd{j},effort_{j}=tau{j}
//     stamp=t,{joint}/position=q{j},{joint}/effort=tau{j}
//
// Every rule must match at least one column; columns no rule matches keep their names (and are ignored
// unless they are manipid's). Units: the time column in s, ms, us or ns (ROS stamps nanoseconds; a
// converted time column starts at 0), angles (q, qd, qdd, ref) in rad or deg.
#pragma once

#include "manipid/api/csv.h"

#include <string>
#include <vector>

namespace manipid::api {

struct LogFormat {
  std::string columns;             ///< the column map (see the file comment); empty: the file's own names
  std::string time_unit = "s";     ///< s, ms, us or ns
  std::string angle_unit = "rad";  ///< rad or deg
  /// What {joint} matches, in joint order (a robot's joints); empty: {joint} is refused.
  std::vector<std::string> joint_names;
  bool empty() const { return columns.empty() && time_unit == "s" && angle_unit == "rad"; }
};

/// Throws InputError("columns", "time_unit" or "angle_unit") for a map or a unit that cannot be used,
/// naming what is wrong and what is accepted.
void check_log_format(const LogFormat& format);

/// `table` with its columns renamed by the map and its values in SI units. Throws InputError("columns")
/// for a rule that matches no column (listing the file's columns), two columns mapped onto one name, or
/// {joint} without joint names.
CsvTable apply_log_format(CsvTable table, const LogFormat& format);

/// For a table that lacks manipid's t or q1: the sentence that lists its columns and, when its names look
/// like a log's (time/stamp, position, velocity, effort/torque, each numbered), a column map that would
/// read it; "" when the table has both.
std::string column_hint(const CsvTable& table);

}  // namespace manipid::api
