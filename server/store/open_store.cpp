// open_store.cpp — open_store(url) and sqlite_path(url): the one place a `--db` value is read.
#include "store/store.h"

#include "store/postgres/store.h"
#include "store/sqlite/store.h"

#include <string_view>

namespace manipid::server::store {

std::string sqlite_path(const std::string& url) {
  const std::string_view text = url;
  if (is_postgres_url(url)) {
    // The URL is not repeated: it may carry a password.
    throw StoreError("--db names a PostgreSQL database, not a SQLite file");
  }
  const std::string_view path = text.starts_with("sqlite:") ? text.substr(7) : text;
  if (path.empty()) throw StoreError("--db names no file (give a path, or sqlite:PATH)");
  return std::string(path);
}

bool is_postgres_url(const std::string& url) {
  return url.starts_with("postgresql://") || url.starts_with("postgres://");
}

std::string display_name(const std::string& url) {
  if (!is_postgres_url(url)) return url;
  // libpq takes a password in two places: postgresql://USER:PASSWORD@HOST/DB and ?password=…
  // Both go; everything else stays as given.
  std::string shown = url;
  const std::size_t authority = shown.find("://") + 3;
  const std::size_t end = shown.find_first_of("/?", authority);
  const std::size_t at = shown.rfind('@', end == std::string::npos ? std::string::npos : end);
  if (at != std::string::npos && at >= authority) {
    const std::size_t colon = shown.find(':', authority);
    if (colon != std::string::npos && colon < at) shown.erase(colon, at - colon);
  }
  const std::size_t query = shown.find('?');
  if (query == std::string::npos) return shown;
  std::string kept;
  std::string_view rest = std::string_view(shown).substr(query + 1);
  while (!rest.empty()) {
    const std::size_t amp = rest.find('&');
    const std::string_view parameter = rest.substr(0, amp);
    rest = amp == std::string_view::npos ? std::string_view() : rest.substr(amp + 1);
    if (parameter.starts_with("password=") || parameter == "password") continue;
    kept += kept.empty() ? "" : "&";
    kept += parameter;
  }
  return shown.substr(0, query) + (kept.empty() ? "" : "?" + kept);
}

std::unique_ptr<Store> open_store(const std::string& url, const StoreOptions& options) {
  if (is_postgres_url(url)) return postgres::open_store(url, options, options.connections);
  return sqlite::open_store(sqlite_path(url), options);
}

}  // namespace manipid::server::store
