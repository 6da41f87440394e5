// store.h — the PostgreSQL backend of the store: one database shared by any number of
// `manipid serve` and `manipid worker` processes on any number of machines (store.cpp), the rows
// its methods share (rows.cpp), its job announcements and listener (events.cpp), array and COPY
// literals (literals.cpp), recent samples in memory (recent_datasets.cpp), its schema and
// migrations (schema.cpp), libpq connections (connection.cpp, libpq.cpp).
#pragma once

#include "store/store.h"

#include <cstddef>
#include <memory>
#include <string>

namespace manipid::server::store::postgres {

/// Connects to the database a libpq connection URI names ("postgresql://USER@HOST/DB"; the
/// password from the URI, PGPASSWORD or ~/.pgpass), creating or migrating the schema. At most
/// `connections` connections are open at once (size it to the threads that use the store).
/// Throws StoreUnavailable when the server cannot be reached, StoreError when it refuses or the
/// database was written by a newer manipid.
std::unique_ptr<Store> open_store(const std::string& uri, const StoreOptions& options = {},
                                  std::size_t connections = 16);

}  // namespace manipid::server::store::postgres
