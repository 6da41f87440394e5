// schema.h — the SQLite store's schema and its migrations (PRAGMA user_version).
#pragma once

#include "store/sqlite/connection.h"

#include <string>
#include <vector>

namespace manipid::server::store::sqlite {

/// The schema version this build writes.
int current_schema_version();

/// Switches the file to WAL, checks its structure (PRAGMA quick_check), then brings the schema
/// to the current version in one BEGIN IMMEDIATE transaction (so concurrent openers migrate
/// once). Throws StoreError when the file is damaged, from a newer manipid or not a database.
/// `version` below the current one stops there: how the migration tests make a database of an older schema.
void prepare_database(Connection& connection, int version = current_schema_version());

/// What is wrong with the file, at most `limit` findings; empty when it is sound. `full`: PRAGMA
/// integrity_check (every index against its table, every row's fields) and foreign_key_check —
/// `manipid doctor`; else PRAGMA quick_check, the b-tree structure only, O(file size) but without
/// the index cross-checks: what every start-up can afford. A file SQLite cannot read at all
/// (SQLITE_CORRUPT, SQLITE_NOTADB) is one finding with SQLite's text, not an exception.
std::vector<std::string> integrity_findings(Connection& connection, bool full, int limit = 20);

}  // namespace manipid::server::store::sqlite
