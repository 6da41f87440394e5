// csv_test.cpp — the CSV codec (api/csv.h): exact round trips, tolerant whitespace and line
// ends, and, for every malformed input, an InputError that names the column and the line.
#include "manipid/api/csv.h"
#include "text_assertions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

namespace manipid::api {
namespace {

using test_support::contains;

/// Runs parse_csv expecting an InputError; returns it for inspection of field and message.
InputError parse_error(std::string_view text, const CsvLimits& limits = {}) {
  try {
    parse_csv(text, limits);
  } catch (const InputError& error) {
    return error;
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return InputError("", "");
}

InputError trajectory_error(std::string_view text, bool require_torque = false) {
  try {
    trajectory_from_csv(parse_csv(text), require_torque);
  } catch (const InputError& error) {
    return error;
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return InputError("", "");
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(Csv, ParsesHeaderAndRows) {
  const CsvTable table = parse_csv("t,q1\n0,1.5\n0.001,-2\n");
  ASSERT_EQ(table.columns, (std::vector<std::string>{"t", "q1"}));
  ASSERT_EQ(table.rows(), 2);
  EXPECT_EQ(table.data(0, 1), 1.5);
  EXPECT_EQ(table.data(1, 0), 0.001);
  EXPECT_EQ(table.data(1, 1), -2.0);
  EXPECT_EQ(table.column_index("q1"), 1);
  EXPECT_EQ(table.column_index("q2"), -1);
  EXPECT_EQ(table.column("q1")(1), -2.0);
}

TEST(Csv, RoundTripIsBitExact) {
  CsvTable table;
  table.columns = {"a", "b", "c"};
  table.data.resize(4, 3);
  table.data << 0.1, 1e-300, -0.1,                                          //
      -1.0 / 3.0, std::numeric_limits<double>::max(), 5e-324,                //
      -0.0, std::numeric_limits<double>::min(), 123456789.123456789,         //
      9.81, -std::numeric_limits<double>::denorm_min(), 2.0 / 3.0 * 1e17;
  const std::string text = format_csv(table);
  const CsvTable back = parse_csv(text);
  ASSERT_EQ(back.columns, table.columns);
  ASSERT_EQ(back.data.rows(), table.data.rows());
  ASSERT_EQ(back.data.cols(), table.data.cols());
  for (Eigen::Index row = 0; row < table.data.rows(); ++row) {
    for (Eigen::Index column = 0; column < table.data.cols(); ++column) {
      EXPECT_TRUE(same_bits(back.data(row, column), table.data(row, column)))
          << "row " << row << " column " << column << ": " << back.data(row, column);
    }
  }
  // Shortest form: 0.1 is written as "0.1", not 0.10000000000000001.
  EXPECT_TRUE(contains(text, "0.1,1e-300,-0.1\n"));
}

TEST(Csv, FormatsHeaderOnlyAndEmptyTable) {
  CsvTable table;
  table.columns = {"t", "q1"};
  table.data.resize(0, 2);
  EXPECT_EQ(format_csv(table), "t,q1\n");
  const CsvTable back = parse_csv("t,q1\n");
  EXPECT_EQ(back.rows(), 0);
  EXPECT_EQ(back.data.cols(), 2);
}

TEST(Csv, FormatRejectsWhatCannotBeReadBack) {
  CsvTable table;
  table.columns = {"t", "q1"};
  table.data.resize(1, 2);
  table.data << 0.0, std::nan("");
  EXPECT_THROW(format_csv(table), InputError);
  table.data << 0.0, 1.0;
  table.columns = {"t", "a,b"};
  EXPECT_THROW(format_csv(table), InputError);
  table.columns = {"t"};
  EXPECT_THROW(format_csv(table), InputError);
}

TEST(Csv, AcceptsCrlfBlankLinesSpacesAndNoTrailingNewline) {
  const CsvTable table = parse_csv("\r\n t , q1 \r\n\r\n0 , 1\r\n   \r\n\t2,\t+3e2 \r\n\r\n");
  ASSERT_EQ(table.columns, (std::vector<std::string>{"t", "q1"}));
  ASSERT_EQ(table.rows(), 2);  // room made for the 5 lines after the header, then cut to the rows
  EXPECT_EQ(table.data(0, 0), 0.0);
  EXPECT_EQ(table.data(0, 1), 1.0);
  EXPECT_EQ(table.data(1, 0), 2.0);
  EXPECT_EQ(table.data(1, 1), 300.0);
  EXPECT_EQ(parse_csv("x\n1\n2").rows(), 2);
}

TEST(Csv, AcceptsByteOrderMarkAndQuotedHeaderNames) {
  const CsvTable table = parse_csv("\xEF\xBB\xBF\"t\",\"q1\"\n0,1\n");
  EXPECT_EQ(table.columns, (std::vector<std::string>{"t", "q1"}));
}

TEST(Csv, TinyValuesUnderflowToZero) {
  const CsvTable table = parse_csv("x\n1e-400\n-1e-400\n");
  EXPECT_EQ(table.data(0, 0), 0.0);
  EXPECT_EQ(table.data(1, 0), 0.0);
}

TEST(CsvErrors, EmptyInput) {
  for (const char* text : {"", "\n\n", "  \r\n"}) {
    const InputError error = parse_error(text);
    EXPECT_EQ(error.field(), "csv");
    EXPECT_TRUE(contains(error.what(), "header"));
  }
}

TEST(CsvErrors, RaggedRowNamesItsLine) {
  const InputError fewer = parse_error("t,q1,q2\n0,1,2\n\n1,2\n");
  EXPECT_EQ(fewer.field(), "csv");
  EXPECT_STREQ(fewer.what(), "line 4: expected 3 fields, got 2");
  const InputError more = parse_error("t,q1\r\n0,1,2\r\n");
  EXPECT_STREQ(more.what(), "line 2: expected 2 fields, got 3");
}

TEST(CsvErrors, NonNumbersNameColumnAndLine) {
  struct Case {
    const char* field;
    const char* expected;
  };
  for (const Case& bad : {Case{"abc", "line 3, column tau1: 'abc' is not a number"},
                          Case{"nan", "line 3, column tau1: 'nan' is not a finite number"},
                          Case{"-inf", "line 3, column tau1: '-inf' is not a finite number"},
                          Case{"Infinity", "line 3, column tau1: 'Infinity' is not a finite number"},
                          Case{"1e400", "line 3, column tau1: '1e400' is out of range for a double"},
                          Case{"1.5x", "line 3, column tau1: '1.5x' is not a number"},
                          Case{"1 2", "line 3, column tau1: '1 2' is not a number"},
                          Case{"0x10", "line 3, column tau1: '0x10' is not a number"},
                          Case{"++1", "line 3, column tau1: '++1' is not a number"},
                          Case{"\"1\"", "line 3, column tau1: '\"1\"' is not a number"}}) {
    const InputError error = parse_error(std::string("t,tau1\n0,1\n1,") + bad.field + "\n");
    EXPECT_EQ(error.field(), "tau1");
    EXPECT_STREQ(error.what(), bad.expected);
  }
}

TEST(CsvErrors, EmptyField) {
  const InputError error = parse_error("t,q1\n0,\n");
  EXPECT_EQ(error.field(), "q1");
  EXPECT_TRUE(contains(error.what(), "line 2, column q1: empty field"));
  EXPECT_EQ(parse_error("t,q1\n ,1\n").field(), "t");
}

TEST(CsvErrors, LongFieldIsShortenedInTheMessage) {
  const InputError error = parse_error("x\n" + std::string(500, 'z') + "\n");
  EXPECT_LT(std::strlen(error.what()), 100u);
}

TEST(CsvErrors, BadHeader) {
  const InputError duplicate = parse_error("t,q1,q1\n0,1,2\n");
  EXPECT_EQ(duplicate.field(), "q1");
  EXPECT_TRUE(contains(duplicate.what(), "line 1: duplicate column name 'q1'"));
  const InputError empty_name = parse_error("\nt,,q2\n0,1,2\n");
  EXPECT_EQ(empty_name.field(), "csv");
  EXPECT_TRUE(contains(empty_name.what(), "line 2: column 2 of the header has an empty name"));
  EXPECT_EQ(parse_error("t,q1,\n").field(), "csv");
}

TEST(CsvErrors, Limits) {
  CsvLimits limits;
  limits.max_columns = 2;
  limits.max_rows = 2;
  const InputError columns = parse_error("a,b,c\n1,2,3\n", limits);
  EXPECT_EQ(columns.field(), "csv");
  EXPECT_TRUE(contains(columns.what(), "3 columns exceed the limit of 2"));
  EXPECT_NO_THROW(parse_csv("a,b\n1,2\n3,4\n", limits));
  const InputError rows = parse_error("a,b\n1,2\n3,4\n\n5,6\n", limits);
  EXPECT_EQ(rows.field(), "csv");
  EXPECT_TRUE(contains(rows.what(), "line 5: more than 2 data rows"));
  // Rows are also bounded by the numbers they hold in all (a dataset's max_values).
  limits.max_rows = 10;
  limits.max_values = 5;
  const InputError values = parse_error("a,b\n1,2\n3,4\n5,6\n", limits);
  EXPECT_TRUE(contains(values.what(), "line 4: more than 2 data rows (the limit for 2 columns)"));
}

TEST(CsvErrors, DefaultsReadBackEveryDataset) {
  // One joint limit everywhere: a dataset at max_joints with all five blocks fits the reader.
  EXPECT_EQ(CsvLimits{}.max_columns, 1u + 5u * static_cast<std::size_t>(limits::max_joints));
  EXPECT_LE(limits::max_dataset_bytes, 1'000'000'000 - (1 << 20));  // SQLite's default SQLITE_MAX_LENGTH, a row
}

TEST(CsvErrors, MissingColumn) {
  const CsvTable table = parse_csv("t,q1\n0,1\n");
  try {
    table.column("q3");
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_EQ(error.field(), "q3");
    EXPECT_STREQ(error.what(), "missing column q3");
  }
}

TEST(CsvTrajectory, WithTorqueAndReference) {
  const Trajectory trajectory = trajectory_from_csv(parse_csv(
      "ref2,t,q1,q2,tau1,tau2,ref1,comment\n"
      "0.5,0,0.1,0.2,10,20,0.4,7\n"
      "0.6,0.001,0.11,0.21,11,21,0.41,7\n"
      "0.7,0.002,0.12,0.22,12,22,0.42,7\n"));
  EXPECT_EQ(trajectory.samples(), 3);
  EXPECT_EQ(trajectory.joint_count(), 2);
  ASSERT_TRUE(trajectory.has_torque());
  ASSERT_TRUE(trajectory.has_reference());
  EXPECT_EQ(trajectory.t(2), 0.002);
  EXPECT_EQ(trajectory.q(1, 1), 0.21);
  EXPECT_EQ(trajectory.tau(2, 0), 12.0);
  EXPECT_EQ(trajectory.ref(0, 1), 0.5);
  EXPECT_EQ(trajectory.ref(2, 0), 0.42);
}

TEST(CsvTrajectory, WithoutTorqueOrReference) {
  const Trajectory trajectory = trajectory_from_csv(parse_csv("t,q1\n0,1\n0.5,2\n1,3\n"));
  EXPECT_EQ(trajectory.joint_count(), 1);
  EXPECT_FALSE(trajectory.has_torque());
  EXPECT_FALSE(trajectory.has_reference());
  EXPECT_EQ(trajectory.tau.rows(), 3);
  const InputError error = trajectory_error("t,q1\n0,1\n0.5,2\n", true);
  EXPECT_EQ(error.field(), "tau1");
  EXPECT_TRUE(contains(error.what(), "missing column tau1"));
}

TEST(CsvTrajectory, RoundTrip) {
  Trajectory trajectory;
  trajectory.t = Eigen::VectorXd::LinSpaced(5, 0.0, 0.004);
  trajectory.q = Eigen::MatrixXd::Random(5, 3);
  trajectory.tau = Eigen::MatrixXd::Random(5, 3) * 100.0;
  const CsvTable table = trajectory_to_csv(trajectory);
  EXPECT_EQ(table.columns, (std::vector<std::string>{"t", "q1", "q2", "q3", "tau1", "tau2", "tau3"}));
  const Trajectory back = trajectory_from_csv(parse_csv(format_csv(table)));
  EXPECT_EQ(back.t, trajectory.t);
  EXPECT_EQ(back.q, trajectory.q);
  EXPECT_EQ(back.tau, trajectory.tau);
  EXPECT_FALSE(back.has_reference());

  trajectory.ref = Eigen::MatrixXd::Random(5, 3);
  EXPECT_EQ(trajectory_to_csv(trajectory).columns.back(), "ref3");
  trajectory.ref.resize(4, 3);
  EXPECT_THROW(trajectory_to_csv(trajectory), InputError);
}

TEST(CsvTrajectory, MissingTimeOrAngles) {
  EXPECT_EQ(trajectory_error("q1,tau1\n0,1\n").field(), "t");
  const InputError no_angles = trajectory_error("t,tau1\n0,1\n");
  EXPECT_EQ(no_angles.field(), "q1");
  EXPECT_TRUE(contains(no_angles.what(), "missing column q1"));
}

TEST(CsvTrajectory, MismatchedCounts) {
  const InputError fewer_torques = trajectory_error("t,q1,q2,q3,tau1,tau2\n0,1,2,3,4,5\n");
  EXPECT_EQ(fewer_torques.field(), "tau3");
  EXPECT_TRUE(contains(fewer_torques.what(), "missing column tau3"));
  const InputError more_references = trajectory_error("t,q1,ref1,ref2\n0,1,2,3\n");
  EXPECT_EQ(more_references.field(), "ref2");
  EXPECT_TRUE(contains(more_references.what(), "ref2 has no matching q2"));
  const InputError gap = trajectory_error("t,q1,q2,q4\n0,1,2,3\n");
  EXPECT_EQ(gap.field(), "q3");
  EXPECT_TRUE(contains(gap.what(), "missing column q3"));
  // qd1 (a rate), q_offset and q01 are not angle columns and do not disturb the numbering.
  EXPECT_EQ(trajectory_from_csv(parse_csv("t,q1,qd1,q_offset,q01\n0,1,2,3,4\n1,1,2,3,4\n")).joint_count(), 1);
}

TEST(CsvTrajectory, TimeIsValidated) {
  // Trajectory::validate (core) checks that time strictly increases; jittery steps are accepted
  // (real loggers), and qd columns are read.
  const Trajectory jittery = trajectory_from_csv(parse_csv("t,q1,qd1\n0,1,5\n0.1,1,6\n0.25,1,7\n"));
  EXPECT_EQ(jittery.qd, (Eigen::MatrixXd(3, 1) << 5, 6, 7).finished());
  EXPECT_EQ(format_csv(trajectory_to_csv(jittery)), "t,q1,qd1\n0,1,5\n0.1,1,6\n0.25,1,7\n");
  EXPECT_THROW(trajectory_from_csv(parse_csv("t,q1\n0,1\n0,1\n")), InputError);
  EXPECT_THROW(trajectory_from_csv(parse_csv("t,q1\n0,1\n")), InputError);  // one sample has no dt
}

TEST(CsvPerformance, ManyRowsParse) {
  // 10^5 rows × 13 columns: a correctness check on a large input (timing is benchmarked
  // separately); the values must survive the row-major to column-major transpose.
  const int rows = 100'000;
  CsvTable table;
  for (const char* name : {"t", "q1", "q2", "q3", "q4", "tau1", "tau2", "tau3", "tau4", "ref1", "ref2",
                           "ref3", "ref4"}) {
    table.columns.emplace_back(name);
  }
  table.data.resize(rows, 13);
  for (int row = 0; row < rows; ++row) {
    for (int column = 0; column < 13; ++column) table.data(row, column) = row * 0.001 + column * 1e-7;
  }
  const CsvTable back = parse_csv(format_csv(table));
  EXPECT_EQ(back.data, table.data);
}

}  // namespace
}  // namespace manipid::api
