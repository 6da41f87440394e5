// schema.h — the PostgreSQL store's schema and its migrations, counted in a version table.
#pragma once

#include "store/postgres/connection.h"

namespace manipid::server::store::postgres {

/// The schema version this build writes.
int current_schema_version();

/// Brings the database to the current schema, under an advisory lock so that processes
/// starting together migrate once. Throws StoreError when the database was made by a newer
/// manipid (its version above ours).
void prepare_database(Connection& connection);

}  // namespace manipid::server::store::postgres
