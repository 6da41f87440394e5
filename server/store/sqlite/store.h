// store.h — the SQLite backend of the store: one database file, datasets, robots, jobs and
// histories in it (store.cpp), its schema and migrations (schema.cpp).
#pragma once

#include "store/store.h"

#include <memory>
#include <string>
#include <vector>

namespace manipid::server::store::sqlite {

/// Opens (creating if missing) a SQLite database file with the current schema, migrating an
/// older one. Throws StoreError when the file cannot be opened or is from a newer manipid.
std::unique_ptr<Store> open_store(const std::string& path, const StoreOptions& options = {});

/// `manipid doctor`: a full check of an existing database file, changing nothing (no
/// migration, no WAL switch). `findings` empty: the file is sound.
struct FileCheck {
  int schema_version = 0;             ///< PRAGMA user_version; 0 when unreadable
  std::vector<std::string> findings;  ///< PRAGMA integrity_check and foreign_key_check, at most 100
  /// For a sound file: rows whose text is not UTF-8 ("robot rb_…: its name is not UTF-8"), at most 100 —
  /// stored before the service refused such text; it shows them with U+FFFD. Not damage: serve runs.
  std::vector<std::string> text_findings;
};
/// Throws StoreError when the file does not exist or cannot be opened at all.
FileCheck check_file(const std::string& path);

}  // namespace manipid::server::store::sqlite
