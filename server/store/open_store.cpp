// open_store.cpp — open_store(url) and sqlite_path(url): the one place a `--db` value is read.
#include "store/store.h"

#include "store/sqlite/store.h"

#include <string_view>

namespace manipid::server::store {

std::string sqlite_path(const std::string& url) {
  const std::string_view text = url;
  if (text.starts_with("postgresql://") || text.starts_with("postgres://")) {
    // The URL is not repeated: it may carry a password.
    throw StoreError("PostgreSQL databases are not supported by this build yet; use a SQLite file (--db PATH)");
  }
  const std::string_view path = text.starts_with("sqlite:") ? text.substr(7) : text;
  if (path.empty()) throw StoreError("--db names no file (give a path, or sqlite:PATH)");
  return std::string(path);
}

std::unique_ptr<Store> open_store(const std::string& url, const StoreOptions& options) {
  return sqlite::open_store(sqlite_path(url), options);
}

}  // namespace manipid::server::store
