// literals.cpp — array literals and COPY text rows of the PostgreSQL store (see literals.h).
#include "store/postgres/literals.h"

#include "store/encoding.h"

#include <cmath>
#include <cstdio>

namespace manipid::server::store::postgres {

std::string array_literal(const std::vector<std::string>& texts) {
  std::string out = "{";
  for (std::size_t i = 0; i < texts.size(); ++i) {
    if (i > 0) out += ',';
    out += '"';
    for (char c : texts[i]) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
    out += '"';
  }
  return out + "}";
}

std::string array_literal(const std::vector<std::optional<double>>& numbers) {
  std::string out = "{";
  for (std::size_t i = 0; i < numbers.size(); ++i) {
    if (i > 0) out += ',';
    if (!numbers[i]) {
      out += "NULL";
    } else if (std::isnan(*numbers[i])) {
      out += "NaN";
    } else if (std::isinf(*numbers[i])) {
      out += *numbers[i] > 0 ? "Infinity" : "-Infinity";
    } else {
      char buffer[32];
      std::snprintf(buffer, sizeof buffer, "%.17g", *numbers[i]);
      out += buffer;
    }
  }
  return out + "}";
}

std::string id_array(const std::vector<std::string>& ids) { return array_literal(ids); }

namespace {

/// One row of history_rows.
void append_history_row(std::string& out, const std::string& id, const api::HistoryEntry& entry) {
  static constexpr char digits[] = "0123456789abcdef";
  out += id;
  out += '\t';
  out += std::to_string(entry.index);
  out += '\t';
  if (std::isnan(entry.cost)) {
    out += "\\N";
  } else if (std::isinf(entry.cost)) {
    out += entry.cost > 0 ? "Infinity" : "-Infinity";
  } else {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.17g", entry.cost);
    out += buffer;
  }
  out += '\t';
  if (entry.theta.empty()) {
    out += "\\N";
  } else {
    out += "\\\\x";
    for (unsigned char byte : encode_doubles(entry.theta.data(), entry.theta.size())) {
      out += digits[byte >> 4];
      out += digits[byte & 15];
    }
  }
  out += '\n';
}

}  // namespace

std::string history_rows(const std::string& id, const std::vector<api::HistoryEntry>& batch) {
  std::string rows;
  for (const auto& entry : batch) append_history_row(rows, id, entry);
  return rows;
}

}  // namespace manipid::server::store::postgres
