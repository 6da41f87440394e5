// literals.h — values spelled as PostgreSQL's text input reads them, for the statements that
// carry many values in one parameter or one COPY: array literals and COPY text rows of a job's
// history. Pure functions: no connection.
#pragma once

#include "manipid/api/records.h"

#include <optional>
#include <string>
#include <vector>

namespace manipid::server::store::postgres {

/// A PostgreSQL array literal of texts, every element quoted.
std::string array_literal(const std::vector<std::string>& texts);
/// A PostgreSQL array literal of doubles (17 significant digits: exact), NULL for none.
std::string array_literal(const std::vector<std::optional<double>>& numbers);
/// A PostgreSQL array literal of ids ({"a","b"}); ids are letters, digits and '_', quoted anyway.
std::string id_array(const std::vector<std::string>& ids);

/// History entries of job `id` as COPY text rows (made before the transaction), one a line: job
/// id, index, cost (\N for NaN, as NULL), θ as bytea hex (the backslash doubled: COPY reads
/// "\\x…" as "\x…"), \N when θ is empty.
std::string history_rows(const std::string& id, const std::vector<api::HistoryEntry>& batch);

}  // namespace manipid::server::store::postgres
