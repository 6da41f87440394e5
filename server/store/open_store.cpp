// open_store.cpp — open_store(url): the one place a `--db` value becomes a backend.
#include "store/store.h"

#include "store/sqlite/store.h"

#include <string_view>

namespace manipid::server::store {

std::unique_ptr<Store> open_store(const std::string& url) {
  const std::string_view text = url;
  if (text.starts_with("postgresql://") || text.starts_with("postgres://")) {
    // The URL is not repeated: it may carry a password.
    throw StoreError("PostgreSQL databases are not supported by this build yet; use a SQLite file (--db PATH)");
  }
  const std::string_view path = text.starts_with("sqlite:") ? text.substr(7) : text;
  if (path.empty()) throw StoreError("--db names no file (give a path, or sqlite:PATH)");
  return sqlite::open_store(std::string(path));
}

}  // namespace manipid::server::store
