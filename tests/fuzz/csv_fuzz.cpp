// csv_fuzz.cpp — libFuzzer target for the CSV codec of api/csv.h: parse_csv, then
// trajectory_from_csv (requiring torque), and dataset_from_csv on the same
// text. Every input must end in a value or a clean InputError / ApiError; any other exception
// escapes (libFuzzer reports it as a crash), as do ASan/UBSan findings.
// A table that parses is also formatted and parsed again, which must give the same numbers.
#include "manipid/api/csv.h"
#include "manipid/api/problem.h"
#include "manipid/api/requests.h"
#include "manipid/core/errors.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

namespace {

using manipid::InputError;
using manipid::api::ApiError;

// Small limits keep every exec fast; dataset_from_csv uses the service's own (default) limits.
constexpr manipid::api::CsvLimits limits{.max_columns = 64, .max_rows = 512};

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "csv_fuzz: %s\n", what);
  std::abort();
}

/// Runs one parser; only the two documented exception types count as a clean rejection.
template <class Parse>
void clean(Parse parse) {
  try {
    parse();
  } catch (const InputError&) {
  } catch (const ApiError&) {
  }
}

/// The header reader strips one pair of quotes ("a" → a), so a name that is itself quoted
/// after stripping (""a"" → "a") legitimately reads back as a different name.
bool quoted(const std::string& name) { return name.size() >= 2 && name.front() == '"' && name.back() == '"'; }

/// format_csv may refuse names it cannot write (a '\r' inside one); what it writes must read
/// back to the same numbers (shortest round-trip formatting) and the same names.
void check_round_trip(const manipid::api::CsvTable& table) {
  std::string text;
  try {
    text = manipid::api::format_csv(table);
  } catch (const InputError&) {
    return;
  }
  // Names that read back differently can also come back empty or duplicated: not a failure.
  const bool renamed = std::any_of(table.columns.begin(), table.columns.end(), quoted);
  manipid::api::CsvTable back;
  try {
    back = manipid::api::parse_csv(text, limits);
  } catch (const InputError& error) {
    if (renamed) return;
    std::fprintf(stderr, "csv_fuzz: %s\n", error.what());
    fail("format_csv wrote a table parse_csv rejects");
  }
  if (back.data.rows() != table.data.rows() || back.data.cols() != table.data.cols() || back.data != table.data) {
    fail("format_csv/parse_csv round trip changed the numbers");
  }
  if (back.columns.size() != table.columns.size()) fail("round trip changed the column count");
  for (std::size_t i = 0; i < table.columns.size(); ++i) {
    if (back.columns[i] != table.columns[i] && !quoted(table.columns[i])) fail("round trip changed a column name");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  clean([&] {
    const manipid::api::CsvTable table = manipid::api::parse_csv(text, limits);
    check_round_trip(table);
    // dataset_from_csv below takes the require_torque = false path.
    (void)manipid::api::trajectory_from_csv(table, /*require_torque=*/true);
  });
  clean([&] { (void)manipid::api::dataset_from_csv(text); });
  return 0;
}
