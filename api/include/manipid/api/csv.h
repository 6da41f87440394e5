// csv.h — CSV text to numeric tables and trajectories, and back.
//
// The format users exchange with manipid: a header row of column names, then rows of
// numbers, comma-separated, SI units. Trajectories use the columns
//     t, q1..qn, tau1..taun [, ref1..refn]
// (the layout `manipid simulate` writes). Parsing is strict and every failure is an
// InputError whose field names the column (or "csv" for structural problems) and whose
// message gives the line number, so users can fix their file from the message alone.
#pragma once

#include "manipid/api/limits.h"
#include "manipid/core/errors.h"
#include "manipid/core/signal/trajectory.h"

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace manipid::api {

/// What parse_csv accepts; the defaults are a dataset's limits (limits.h), so every dataset's
/// CSV export reads back.
struct CsvLimits {
  std::size_t max_columns = limits::max_csv_columns;
  std::size_t max_rows = static_cast<std::size_t>(limits::max_samples);
  std::size_t max_values = static_cast<std::size_t>(limits::max_values);  ///< rows × columns
};

struct CsvTable {
  std::vector<std::string> columns;
  Eigen::MatrixXd data;  ///< rows × columns
  char separator = ',';  ///< what parse_csv found between the fields (',', or ';' or a tab: see parse_csv)

  int rows() const { return static_cast<int>(data.rows()); }
  /// Index of a column, or -1.
  int column_index(std::string_view name) const;
  /// A column's values; throws InputError(name, "missing column ...") when absent.
  Eigen::VectorXd column(std::string_view name) const;
};

/// Parses CSV text: header of unique, non-empty names; every row the same number of fields;
/// every field a finite number (NaN and Inf are rejected). Blank lines and a trailing
/// newline are ignored; CRLF line ends are accepted. Fields are separated by commas, or — when the
/// header has none — by semicolons or tabs (spreadsheets in locales that write decimal commas
/// save with ';'; a decimal comma is refused naming it).
CsvTable parse_csv(std::string_view text, const CsvLimits& limits = {});
/// Formats with the shortest representation that reads back to the same double.
std::string format_csv(const CsvTable& table);

/// Columns t, q1..qn, tau1..taun, and ref1..refn when present. n is the number of q
/// columns; tau and ref, when given, must have the same count. With `require_torque` a
/// missing tau column is an error. The result is validated (Trajectory::validate).
Trajectory trajectory_from_csv(const CsvTable& table, bool require_torque = false);
CsvTable trajectory_to_csv(const Trajectory& trajectory);

}  // namespace manipid::api
