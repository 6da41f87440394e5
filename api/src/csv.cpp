// csv.cpp — the CSV codec behind api/csv.h: strict parsing of numeric tables with
// line-numbered errors, shortest round-trip formatting, and the trajectory column layout.
//
// Parsing works on string_views into the caller's text and converts with std::from_chars,
// so no field allocates; each row's values go straight into the column-major table, sized
// for the lines left after the header. Each row first takes a fast path
// that only accepts plain finite numbers; anything else is re-read field by field by the
// careful path, which either accepts it (a '+' sign, a value that underflows) or throws the
// error that names the line and column.
#include "manipid/api/csv.h"

#include "manipid/api/log_format.h"

#include <algorithm>
#include <cassert>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <system_error>
#include <unordered_set>

namespace manipid::api {
namespace {

constexpr std::string_view structure_field = "csv";
// Quoted field text is cut to this length so a runaway field cannot flood the message; a
// number is cut shorter (a 300-digit number says nothing more at 20 digits than at 300).
constexpr std::size_t max_quoted_field = 40;
constexpr std::size_t max_quoted_number = 20;

std::string line_prefix(std::size_t line) { return "line " + std::to_string(line); }

std::string quote_field(std::string_view text, std::size_t most = max_quoted_field) {
  // Built by append: g++ 12 -O3 warns falsely (-Wrestrict, PR 105329) on "'" + std::string.
  std::string quoted(1, '\'');
  quoted.append(text.substr(0, most));
  quoted.append(text.size() > most ? "...'" : "'");
  return quoted;
}

bool is_blank_character(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view text) {
  while (!text.empty() && is_blank_character(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_blank_character(text.back())) text.remove_suffix(1);
  return text;
}

/// Splits text into lines on '\n', dropping a '\r' before it (CRLF files), and tracks
/// the 1-based line number for messages.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}

  /// The text not read yet.
  std::string_view rest() const { return text_.substr(position_); }

  /// The next line that has something other than blanks on it, or false at the end.
  bool next_nonblank(std::string_view& line, std::size_t& line_number) {
    while (position_ < text_.size()) {
      const std::size_t end = text_.find('\n', position_);
      const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
      std::string_view current = text_.substr(position_, stop - position_);
      position_ = end == std::string_view::npos ? text_.size() : end + 1;
      ++line_number_;
      if (!current.empty() && current.back() == '\r') current.remove_suffix(1);
      if (trim(current).empty()) continue;
      line = current;
      line_number = line_number_;
      return true;
    }
    return false;
  }

 private:
  std::string_view text_;
  std::size_t position_ = 0;
  std::size_t line_number_ = 0;
};

std::size_t count_fields(std::string_view line, char separator) {
  return static_cast<std::size_t>(std::count(line.begin(), line.end(), separator)) + 1;
}

/// The header's separator: ',' unless the header has none and has ';' (spreadsheets in locales with
/// decimal commas) or tabs.
char detect_separator(std::string_view header) {
  if (header.find(',') != std::string_view::npos) return ',';
  if (header.find(';') != std::string_view::npos) return ';';
  if (header.find('\t') != std::string_view::npos) return '\t';
  return ',';
}

/// Parses one trimmed field as a finite double, or explains why it is not one.
/// Returns an empty string on success.
std::string parse_number(std::string_view field, double& value) {
  if (field.empty()) return "empty field (every field must be a number)";
  std::string_view digits = field;
  // from_chars rejects a leading '+', which spreadsheets and printf("%+g") produce.
  if (digits.size() > 1 && digits.front() == '+' && digits[1] != '-' && digits[1] != '+') {
    digits.remove_prefix(1);
  }
  const char* first = digits.data();
  const char* last = first + digits.size();
  const auto [end, error] = std::from_chars(first, last, value, std::chars_format::general);
  if (error == std::errc::result_out_of_range && end == last) {
    // from_chars reports underflow and overflow alike; tiny magnitudes are just zero.
    const std::string copy(digits);
    const double approximate = std::strtod(copy.c_str(), nullptr);
    if (std::isfinite(approximate) && std::abs(approximate) < 1.0) {
      value = approximate;
      return {};
    }
    return quote_field(field, max_quoted_number) + " is out of range for a double";
  }
  if (error != std::errc() || end != last) return quote_field(field, max_quoted_number) + " is not a number";
  if (!std::isfinite(value)) return quote_field(field, max_quoted_number) + " is not a finite number";
  return {};
}

/// The common case: every field a plain finite number. Returns false on anything else
/// (including a '+' sign or NaN), leaving the verdict to parse_row_careful.
bool parse_row_fast(std::string_view line, double* out, std::size_t column_count, char separator) {
  const char* position = line.data();
  const char* const end = position + line.size();
  for (std::size_t column = 0; column < column_count; ++column) {
    while (position != end && is_blank_character(*position)) ++position;
    const auto [stop, error] = std::from_chars(position, end, out[column], std::chars_format::general);
    if (error != std::errc() || stop == position || !std::isfinite(out[column])) return false;
    position = stop;
    while (position != end && is_blank_character(*position)) ++position;
    if (column + 1 < column_count) {
      if (position == end || *position != separator) return false;
      ++position;
    }
  }
  return position == end;
}

/// Parses a row field by field with full checks; throws the InputError that describes the
/// first problem (wrong field count first, then the leftmost bad field).
void parse_row_careful(std::string_view line, std::size_t line_number,
                       const std::vector<std::string>& columns, double* out, char separator) {
  const std::size_t column_count = columns.size();
  const std::size_t field_count = count_fields(line, separator);
  if (field_count != column_count) {
    throw InputError(std::string(structure_field),
                     line_prefix(line_number) + ": expected " + std::to_string(column_count) +
                         " fields, got " + std::to_string(field_count));
  }
  std::size_t start = 0;
  for (std::size_t column = 0; column < column_count; ++column) {
    const std::size_t comma = line.find(separator, start);
    const std::size_t stop = comma == std::string_view::npos ? line.size() : comma;
    const std::string_view field = trim(line.substr(start, stop - start));
    const std::string problem = parse_number(field, out[column]);
    if (!problem.empty()) {
      // Fields separated by ';' with commas inside: a spreadsheet's decimal commas.
      const bool decimal_comma = separator != ',' && field.find(',') != std::string_view::npos;
      throw InputError(columns[column],
                       line_prefix(line_number) + ", column " + columns[column] + ": " + problem +
                           (decimal_comma ? " (a decimal comma: write numbers with a decimal point)" : ""));
    }
    start = stop + 1;
  }
}

void check_column_name(std::string_view name, std::size_t column, std::size_t line) {
  if (name.empty()) {
    throw InputError(std::string(structure_field),
                     line_prefix(line) + ": column " + std::to_string(column + 1) +
                         " of the header has an empty name");
  }
  // One mark at the start of the header is the file's encoding signature and was removed; a
  // second one (a file saved twice with "UTF-8 with BOM") would hide inside the name and make
  // "t" read as something else, so say what it is.
  if (name.find("\xEF\xBB\xBF") != std::string_view::npos) {
    throw InputError(std::string(structure_field),
                     line_prefix(line) + ": column " + std::to_string(column + 1) +
                         " of the header contains a UTF-8 byte-order mark (U+FEFF); save the file as plain UTF-8");
  }
}

std::vector<std::string> parse_header(std::string_view line, std::size_t line_number,
                                      const CsvLimits& limits, char separator) {
  const std::size_t field_count = count_fields(line, separator);
  if (field_count > limits.max_columns) {
    throw InputError(std::string(structure_field),
                     line_prefix(line_number) + ": " + std::to_string(field_count) +
                         " columns exceed the limit of " + std::to_string(limits.max_columns));
  }
  std::vector<std::string> names;
  names.reserve(field_count);
  std::unordered_set<std::string_view> seen;
  std::size_t start = 0;
  for (std::size_t column = 0; column < field_count; ++column) {
    const std::size_t comma = line.find(separator, start);
    const std::size_t stop = comma == std::string_view::npos ? line.size() : comma;
    std::string_view name = trim(line.substr(start, stop - start));
    // Some tools (R's write.csv) quote header names; accept a plain "name".
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') {
      name = trim(name.substr(1, name.size() - 2));
    }
    check_column_name(name, column, line_number);
    if (!seen.insert(name).second) {
      throw InputError(std::string(name), line_prefix(line_number) + ": duplicate column name " +
                                              quote_field(name));
    }
    names.emplace_back(name);
    start = stop + 1;
  }
  return names;
}

}  // namespace

int CsvTable::column_index(std::string_view name) const {
  const auto found = std::find(columns.begin(), columns.end(), name);
  return found == columns.end() ? -1 : static_cast<int>(found - columns.begin());
}

Eigen::VectorXd CsvTable::column(std::string_view name) const {
  const int index = column_index(name);
  if (index < 0) throw InputError(std::string(name), "missing column " + std::string(name));
  return data.col(index);
}

CsvTable parse_csv(std::string_view text, const CsvLimits& limits) {
  // A UTF-8 byte-order mark (Excel's "CSV UTF-8") is not part of the first name.
  // One mark, at most: a second is refused as part of a name (check_column_name).
  const bool marked = text.substr(0, 3) == "\xEF\xBB\xBF";
  if (marked) text.remove_prefix(3);

  LineReader reader(text);
  std::string_view line;
  std::size_t line_number = 0;
  if (!reader.next_nonblank(line, line_number)) {
    throw InputError(std::string(structure_field), "empty input: expected a header line of column names");
  }
  // ...nor is one after leading blank lines; a header of nothing but the mark is empty.
  if (!marked && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);
  CsvTable table;
  table.separator = detect_separator(line);
  table.columns = parse_header(line, line_number, limits, table.separator);
  const std::size_t column_count = table.columns.size();

  // Column-major, as the table holds it, with room for as many rows as the text can hold: one
  // for every line left (blank ones included; memchr counts them in a thirtieth of the parse),
  // and no more than its bytes allow (a row of c numbers takes at least 2c − 1 of them and a
  // newline), so a wide header over many empty lines does not reserve gigabytes. The pages of
  // rows never written are never touched. Rows beyond max_rows, or beyond max_values numbers
  // in all for this width, are refused before they are stored. (Parsing row-major and
  // transposing at the end took a second copy of every number, a megabyte of fresh memory for
  // 10,000 rows of 13.)
  const std::size_t max_rows = std::min(limits.max_rows, limits.max_values / std::max<std::size_t>(column_count, 1));
  const std::string_view rest = reader.rest();
  std::size_t lines_left = !rest.empty() && rest.back() != '\n' ? 1 : 0;
  const char* const end = rest.data() + rest.size();
  for (const char* at = rest.data(); (at = static_cast<const char*>(std::memchr(at, '\n', static_cast<std::size_t>(end - at)))); ++at) {
    ++lines_left;
  }
  const std::size_t room = std::min({lines_left, max_rows, (rest.size() + 1) / (2 * std::max<std::size_t>(column_count, 1))});
  table.data.resize(static_cast<Eigen::Index>(room), static_cast<Eigen::Index>(column_count));
  std::vector<double> row(column_count);
  std::size_t row_count = 0;
  while (reader.next_nonblank(line, line_number)) {
    if (row_count == max_rows) {
      throw InputError(std::string(structure_field),
                       line_prefix(line_number) + ": more than " + std::to_string(max_rows) + " data rows (the limit" +
                           (max_rows < limits.max_rows ? " for " + std::to_string(column_count) + " columns" : "") + ")");
    }
    if (!parse_row_fast(line, row.data(), column_count, table.separator)) {
      parse_row_careful(line, line_number, table.columns, row.data(), table.separator);
    }
    assert(row_count < room);  // a row of c numbers is a line of at least 2c − 1 bytes
    for (std::size_t column = 0; column < column_count; ++column) {
      table.data(static_cast<Eigen::Index>(row_count), static_cast<Eigen::Index>(column)) = row[column];
    }
    ++row_count;
  }
  // Fewer rows than lines (blank lines): the rows written, in a table of their own size.
  if (static_cast<Eigen::Index>(row_count) < table.data.rows()) {
    table.data = Eigen::MatrixXd(table.data.topRows(static_cast<Eigen::Index>(row_count)));
  }
  return table;
}

std::string format_csv(const CsvTable& table) {
  const auto column_count = static_cast<std::size_t>(table.data.cols());
  if (table.columns.size() != column_count) {
    throw InputError(std::string(structure_field),
                     "table has " + std::to_string(table.columns.size()) + " column names but " +
                         std::to_string(column_count) + " data columns");
  }
  std::string text;
  for (std::size_t column = 0; column < column_count; ++column) {
    const std::string& name = table.columns[column];
    if (name.empty() || name.find_first_of(",\r\n") != std::string::npos ||
        trim(name).size() != name.size()) {
      throw InputError(name, "column name " + quote_field(name) + " cannot be written to CSV");
    }
    if (column > 0) text += ',';
    text += name;
  }
  text += '\n';

  // 24 characters hold any shortest double ("-2.2250738585072014e-308" is the longest).
  constexpr std::size_t max_number_length = 24;
  text.reserve(text.size() + static_cast<std::size_t>(table.data.size()) * (max_number_length + 1));
  char buffer[max_number_length + 8];
  for (Eigen::Index row = 0; row < table.data.rows(); ++row) {
    for (Eigen::Index column = 0; column < table.data.cols(); ++column) {
      const double value = table.data(row, column);
      if (!std::isfinite(value)) {
        // The parser rejects NaN and Inf, so writing them would produce an unreadable file.
        throw InputError(table.columns[static_cast<std::size_t>(column)],
                         "row " + std::to_string(row + 1) + ", column " +
                             table.columns[static_cast<std::size_t>(column)] + ": value is not finite");
      }
      const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
      if (column > 0) text += ',';
      text.append(buffer, result.ptr);
    }
    text += '\n';
  }
  return text;
}

namespace {

/// Number of consecutive columns prefix1, prefix2, ... present in the table.
int count_numbered(const CsvTable& table, std::string_view prefix) {
  int count = 0;
  while (table.column_index(std::string(prefix) + std::to_string(count + 1)) >= 0) ++count;
  return count;
}

/// Largest k such that a column named prefix<k> exists (k ≥ 1 written without leading zeros),
/// or 0. Finds strays beyond a gap, such as q4 with no q3.
int highest_numbered(const CsvTable& table, std::string_view prefix) {
  int highest = 0;
  for (const std::string& name : table.columns) {
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string_view digits = std::string_view(name).substr(prefix.size());
    if (digits.front() == '0') continue;
    int number = 0;
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), number);
    if (error == std::errc() && end == digits.data() + digits.size()) highest = std::max(highest, number);
  }
  return highest;
}

std::string numbered(std::string_view prefix, int number) {
  return std::string(prefix) + std::to_string(number);
}

/// The group prefix1..prefixN: its size, or 0 when absent. Throws when the group has a gap
/// or, when `expected` > 0, a size other than `expected`.
int numbered_group(const CsvTable& table, std::string_view prefix, int expected) {
  const int count = count_numbered(table, prefix);
  const int highest = highest_numbered(table, prefix);
  if (highest > count) {
    throw InputError(numbered(prefix, count + 1),
                     "missing column " + numbered(prefix, count + 1) + " (column " +
                         numbered(prefix, highest) + " is present; numbering must be consecutive from " +
                         numbered(prefix, 1) + ")");
  }
  if (expected > 0 && count > 0 && count != expected) {
    const std::string range = numbered(prefix, 1) + ".." + numbered(prefix, expected);
    if (count < expected) {
      throw InputError(numbered(prefix, count + 1),
                       "missing column " + numbered(prefix, count + 1) + ": expected " + range +
                           " to match q1..q" + std::to_string(expected) + ", got " +
                           std::to_string(count) + " " + std::string(prefix) + " columns");
    }
    throw InputError(numbered(prefix, expected + 1),
                     "column " + numbered(prefix, expected + 1) + " has no matching q" +
                         std::to_string(expected + 1) + ": expected " + range + " to match q1..q" +
                         std::to_string(expected));
  }
  return count;
}

Eigen::MatrixXd gather(const CsvTable& table, std::string_view prefix, int count) {
  Eigen::MatrixXd result(table.data.rows(), count);
  for (int joint = 0; joint < count; ++joint) {
    result.col(joint) = table.data.col(table.column_index(numbered(prefix, joint + 1)));
  }
  return result;
}

}  // namespace

Trajectory trajectory_from_csv(const CsvTable& table, bool require_torque) {
  if (table.column_index("t") < 0) throw InputError("t", "missing column t: " + column_hint(table));
  const int joint_count = numbered_group(table, "q", 0);
  if (joint_count == 0) throw InputError("q1", "missing column q1 (joint angles q1..qn): " + column_hint(table));
  limits::check_joints(joint_count, numbered("q", limits::max_joints + 1), "the CSV");
  const int torque_count = numbered_group(table, "tau", joint_count);
  if (require_torque && torque_count == 0) {
    throw InputError("tau1", "missing column tau1 (joint torques tau1..tau" +
                                 std::to_string(joint_count) + " are required)");
  }
  const int reference_count = numbered_group(table, "ref", joint_count);
  const int rate_count = numbered_group(table, "qd", joint_count);
  const int acceleration_count = numbered_group(table, "qdd", joint_count);

  Trajectory trajectory;
  trajectory.t = table.column("t");
  trajectory.q = gather(table, "q", joint_count);
  trajectory.tau = gather(table, "tau", torque_count);
  trajectory.ref = gather(table, "ref", reference_count);
  trajectory.qd = gather(table, "qd", rate_count);
  trajectory.qdd = gather(table, "qdd", acceleration_count);
  trajectory.validate();
  return trajectory;
}

CsvTable trajectory_to_csv(const Trajectory& trajectory) {
  const int joint_count = trajectory.joint_count();
  const Eigen::Index samples = trajectory.t.size();
  const auto check_rows = [&](const Eigen::MatrixXd& block, const char* name) {
    if (block.cols() > 0 && (block.rows() != samples || block.cols() != joint_count)) {
      throw InputError(name, std::string("trajectory ") + name + " is " + std::to_string(block.rows()) +
                                 "x" + std::to_string(block.cols()) + ", expected " +
                                 std::to_string(samples) + "x" + std::to_string(joint_count));
    }
  };
  check_rows(trajectory.q, "q");
  check_rows(trajectory.tau, "tau");
  check_rows(trajectory.ref, "ref");
  check_rows(trajectory.qd, "qd");
  check_rows(trajectory.qdd, "qdd");

  CsvTable table;
  table.columns.emplace_back("t");
  for (int joint = 1; joint <= joint_count; ++joint) table.columns.push_back(numbered("q", joint));
  if (trajectory.has_torque()) {
    for (int joint = 1; joint <= joint_count; ++joint) table.columns.push_back(numbered("tau", joint));
  }
  if (trajectory.has_reference()) {
    for (int joint = 1; joint <= joint_count; ++joint) table.columns.push_back(numbered("ref", joint));
  }
  if (trajectory.has_rates()) {
    for (int joint = 1; joint <= joint_count; ++joint) table.columns.push_back(numbered("qd", joint));
  }
  if (trajectory.has_accelerations()) {
    for (int joint = 1; joint <= joint_count; ++joint) table.columns.push_back(numbered("qdd", joint));
  }
  table.data.resize(samples, static_cast<Eigen::Index>(table.columns.size()));
  Eigen::Index column = 0;
  table.data.col(column++) = trajectory.t;
  table.data.middleCols(column, joint_count) = trajectory.q;
  column += joint_count;
  if (trajectory.has_torque()) {
    table.data.middleCols(column, joint_count) = trajectory.tau;
    column += joint_count;
  }
  if (trajectory.has_reference()) {
    table.data.middleCols(column, joint_count) = trajectory.ref;
    column += joint_count;
  }
  if (trajectory.has_rates()) {
    table.data.middleCols(column, joint_count) = trajectory.qd;
    column += joint_count;
  }
  if (trajectory.has_accelerations()) table.data.middleCols(column, joint_count) = trajectory.qdd;
  return table;
}

}  // namespace manipid::api
