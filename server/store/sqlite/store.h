// store.h — the SQLite backend of the store: one database file, datasets, robots, jobs and
// histories in it (store.cpp), its schema and migrations (schema.cpp).
#pragma once

#include "store/store.h"

#include <memory>
#include <string>

namespace manipid::server::store::sqlite {

/// Opens (creating if missing) a SQLite database file with the current schema, migrating an
/// older one. Throws StoreError when the file cannot be opened or is from a newer manipid.
std::unique_ptr<Store> open_store(const std::string& path);

}  // namespace manipid::server::store::sqlite
