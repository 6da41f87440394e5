// schema.h — the SQLite store's schema and its migrations (PRAGMA user_version).
#pragma once

#include "store/sqlite/connection.h"

namespace manipid::server::store::sqlite {

/// The schema version this build writes.
int current_schema_version();

/// Switches the file to WAL, then brings the schema to the current version in one
/// BEGIN IMMEDIATE transaction (so concurrent openers migrate once). Throws StoreError when
/// the file is from a newer manipid or is not a database.
void prepare_database(Connection& connection);

}  // namespace manipid::server::store::sqlite
