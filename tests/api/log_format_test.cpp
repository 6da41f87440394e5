// log_format_test.cpp — logs as labs record them (api/log_format.h, the CSV separators): column maps with
// {j} and {joint}, time and angle units, and the hints for a log read without them.
#include "manipid/api/csv.h"
#include "manipid/api/log_format.h"
#include "text_assertions.h"

#include <gtest/gtest.h>

#include <numbers>
#include <string>

namespace manipid::api {
namespace {

using test_support::contains;

InputError format_error(const CsvTable& table, const LogFormat& format) {
  try {
    apply_log_format(table, format);
  } catch (const InputError& error) {
    return error;
  }
  ADD_FAILURE() << "no InputError for the map '" << format.columns << "'";
  return InputError("", "");
}

InputError log_read_error(std::string_view text) {
  try {
    trajectory_from_csv(parse_csv(text), true);
  } catch (const InputError& error) {
    return error;
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return InputError("", "");
}

constexpr std::string_view kRosLog =
    "time,position_1,position_2,effort_1,effort_2,temperature_1\n"
    "1700000000000000000,90,-45,1.5,-2,30\n"
    "1700000000001000000,91,-44,1.6,-2.1,30\n"
    "1700000000002000000,92,-43,1.7,-2.2,30\n";

TEST(LogFormat, NumberedMapRenamesAndConvertsUnits) {
  LogFormat format;
  format.columns = "time=t,position_{j}=q{j},effort_{j}=tau{j}";
  format.time_unit = "ns";
  format.angle_unit = "deg";
  const CsvTable table = apply_log_format(parse_csv(kRosLog), format);
  EXPECT_EQ(table.columns, (std::vector<std::string>{"t", "q1", "q2", "tau1", "tau2", "temperature_1"}));
  // Time from the first stamp, in seconds; angles in radians; torques and other columns untouched.
  EXPECT_DOUBLE_EQ(table.data(0, 0), 0.0);
  // An epoch in nanoseconds (1.7e18) read as a double keeps 256 ns of resolution: within it.
  EXPECT_NEAR(table.data(2, 0), 0.002, 256e-9);
  EXPECT_DOUBLE_EQ(table.data(0, 1), std::numbers::pi / 2);
  EXPECT_DOUBLE_EQ(table.data(1, 2), -44.0 * std::numbers::pi / 180.0);
  EXPECT_DOUBLE_EQ(table.data(2, 3), 1.7);
  EXPECT_DOUBLE_EQ(table.data(0, 5), 30.0);

  const Trajectory trajectory = trajectory_from_csv(table, true);
  EXPECT_EQ(trajectory.joint_count(), 2);
  EXPECT_NEAR(trajectory.dt(), 0.001, 256e-9);
}

TEST(LogFormat, JointNamesFromTheRobot) {
  const CsvTable log = parse_csv(
      "stamp,elbow/position,shoulder/position,shoulder/effort,elbow/effort\n"
      "0,0.2,0.1,1,2\n0.001,0.3,0.2,1,2\n");
  LogFormat format;
  format.columns = "stamp=t,{joint}/position=q{j},{joint}/effort=tau{j}";
  format.joint_names = {"shoulder", "elbow"};
  const CsvTable table = apply_log_format(log, format);
  // Matched by name, not by column order: elbow is joint 2.
  EXPECT_EQ(table.columns, (std::vector<std::string>{"t", "q2", "q1", "tau1", "tau2"}));

  format.joint_names.clear();
  const InputError error = format_error(log, format);
  EXPECT_EQ(error.field(), "columns");
  EXPECT_TRUE(contains(error.what(), "needs the robot's joint names"));
}

TEST(LogFormat, OneColumnRulesAndUntouchedDefaults) {
  LogFormat format;
  format.columns = "time=t, a=q1 ,b=q2";
  const CsvTable table = apply_log_format(parse_csv("time,a,b\n0,1,2\n1,3,4\n"), format);
  EXPECT_EQ(table.columns, (std::vector<std::string>{"t", "q1", "q2"}));
  EXPECT_DOUBLE_EQ(table.data(1, 2), 4.0);  // rad and s: nothing scaled

  const CsvTable plain = parse_csv("t,q1\n5,1\n6,2\n");
  const CsvTable same = apply_log_format(plain, LogFormat{});
  EXPECT_EQ(same.data, plain.data);  // no map, SI units: the table as read (t not shifted)
}

TEST(LogFormat, BadMapsAndUnitsNameWhatIsWrong) {
  const CsvTable log = parse_csv(kRosLog);
  LogFormat format;
  format.columns = "time=t,velocity_{j}=qd{j}";
  InputError error = format_error(log, format);
  EXPECT_EQ(error.field(), "columns");
  EXPECT_TRUE(contains(error.what(), "'velocity_{j}=qd{j}' matches no column"));
  EXPECT_TRUE(contains(error.what(), "position_1"));

  format.columns = "time=t,position_{j}=q{j},effort_{j}=q{j}";
  EXPECT_TRUE(contains(format_error(log, format).what(), "makes both 'position_1' and 'effort_1' into q1"));
  format.columns = "time=seconds";
  EXPECT_TRUE(contains(format_error(log, format).what(), "the manipid side must be t"));
  format.columns = "time";
  EXPECT_TRUE(contains(format_error(log, format).what(), "is not FILE=MANIPID"));
  format.columns = "position_{j}_{j}=q{j}";
  EXPECT_TRUE(contains(format_error(log, format).what(), "one placeholder at most"));
  format.columns = " , ";
  EXPECT_TRUE(contains(format_error(log, format).what(), "the column map is empty"));

  format = LogFormat{};
  format.time_unit = "h";
  error = format_error(log, format);
  EXPECT_EQ(error.field(), "time_unit");
  EXPECT_TRUE(contains(error.what(), "s, ms, us or ns"));
  format = LogFormat{};
  format.angle_unit = "grad";
  EXPECT_EQ(format_error(log, format).field(), "angle_unit");
}

TEST(LogFormat, ALogReadWithoutAMapGetsTheMapThatFits) {
  const InputError error = log_read_error(kRosLog);
  EXPECT_EQ(error.field(), "t");
  EXPECT_TRUE(contains(error.what(), "the file's columns are time, position_1"));
  EXPECT_TRUE(contains(error.what(), "time=t,position_{j}=q{j},effort_{j}=tau{j}"));

  // Names that look like nothing known: the columns and how a map is written.
  const InputError other = log_read_error("a,b\n0,1\n1,2\n");
  EXPECT_TRUE(contains(other.what(), "the file's columns are a, b"));
  EXPECT_TRUE(contains(other.what(), "--columns"));
}

TEST(LogFormat, NanosecondStampsReadAsSecondsGetAHint) {
  const InputError error = log_read_error(
      "t,q1,tau1\n"
      "1700000000000000000,0,0\n1700000000001000000,0,0\n1700000000002000000,0,0\n");
  EXPECT_EQ(error.field(), "t");
  EXPECT_TRUE(contains(error.what(), "if t is in nanoseconds"));
  EXPECT_TRUE(contains(error.what(), "--time-unit ns"));
}

TEST(CsvSeparators, SemicolonsAndTabsAreRead) {
  const CsvTable semicolons = parse_csv("t;q1;tau1\n0;0.5;1\n0.001;0.25;2\n");
  EXPECT_EQ(semicolons.separator, ';');
  EXPECT_EQ(semicolons.columns, (std::vector<std::string>{"t", "q1", "tau1"}));
  EXPECT_DOUBLE_EQ(semicolons.data(1, 1), 0.25);

  const CsvTable tabs = parse_csv("t\tq1\n0\t1.5\n");
  EXPECT_EQ(tabs.separator, '\t');
  EXPECT_DOUBLE_EQ(tabs.data(0, 1), 1.5);

  EXPECT_EQ(parse_csv("t,q1\n0,1\n").separator, ',');
}

TEST(CsvSeparators, DecimalCommasAreNamed) {
  try {
    parse_csv("t;q1\n0;0,5\n");
    ADD_FAILURE() << "a decimal comma was read";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "q1");
    EXPECT_TRUE(contains(error.what(), "decimal comma"));
  }
}

}  // namespace
}  // namespace manipid::api
