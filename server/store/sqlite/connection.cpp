// connection.cpp — the RAII wrappers over sqlite3* and sqlite3_stmt*, the connection
// pool and the retry backoff used by run_transaction.
#include "store/sqlite/connection.h"

#include <algorithm>
#include <chrono>
#include <random>
#include <new>
#include <thread>

namespace manipid::server::store::sqlite {

namespace {

/// The one mapping of SQLite's result codes to the store's errors (connection.h).
[[noreturn]] void throw_for(int code, const std::string& message) {
  const int primary = code & 0xff;  // extended result codes are on
  if (primary == SQLITE_BUSY || primary == SQLITE_LOCKED) throw BusyError(message);
  if (primary == SQLITE_FULL) throw StorageFull(message);
  // Out of memory is what it says: every caller already answers std::bad_alloc (503
  // MEMORY_BUSY for a request, "out of memory" for a job), never as a storage fault.
  if (primary == SQLITE_NOMEM) throw std::bad_alloc();
  throw StoreError(message);
}

}  // namespace

void throw_sqlite_error(sqlite3* database, int code, std::string_view context) {
  std::string message = database != nullptr ? sqlite3_errmsg(database) : sqlite3_errstr(code);
  if (!context.empty()) message = std::string(context) + ": " + message;
  throw_for(code, message);
}

// ---- WriteHealth ----

// ---- Statement ----

Statement::Statement(Statement&& other) noexcept : database_(other.database_), statement_(other.statement_) {
  other.statement_ = nullptr;
}

Statement::~Statement() {
  if (statement_ == nullptr) return;
  sqlite3_reset(statement_);
  sqlite3_clear_bindings(statement_);
}

void Statement::check_bind(int code) {
  if (code != SQLITE_OK) throw_sqlite_error(database_, code, "binding a value");
}

Statement& Statement::bind_text(int index, std::string_view text) {
  check_bind(sqlite3_bind_text64(statement_, index, text.data(), text.size(), SQLITE_TRANSIENT, SQLITE_UTF8));
  return *this;
}

Statement& Statement::bind_text_or_null(int index, std::string_view text) {
  return text.empty() ? bind_null(index) : bind_text(index, text);
}

Statement& Statement::bind_integer(int index, std::int64_t value) {
  check_bind(sqlite3_bind_int64(statement_, index, value));
  return *this;
}

Statement& Statement::bind_real(int index, double value) {
  check_bind(sqlite3_bind_double(statement_, index, value));
  return *this;
}

Statement& Statement::bind_real_or_null(int index, std::optional<double> value) {
  return value ? bind_real(index, *value) : bind_null(index);
}

Statement& Statement::bind_blob_or_null(int index, std::span<const unsigned char> bytes) {
  if (bytes.empty()) return bind_null(index);
  check_bind(sqlite3_bind_blob64(statement_, index, bytes.data(), bytes.size(), SQLITE_STATIC));
  return *this;
}

Statement& Statement::bind_null(int index) {
  check_bind(sqlite3_bind_null(statement_, index));
  return *this;
}

bool Statement::step() {
  const int code = sqlite3_step(statement_);
  if (code == SQLITE_ROW) return true;
  if (code == SQLITE_DONE) return false;
  throw_sqlite_error(database_, code, "");
}

void Statement::run() {
  while (step()) {
  }
}

bool Statement::is_null(int column) const { return sqlite3_column_type(statement_, column) == SQLITE_NULL; }

std::string Statement::text(int column) const {
  const auto* characters = sqlite3_column_text(statement_, column);
  if (characters == nullptr) return {};
  return std::string(reinterpret_cast<const char*>(characters),
                     static_cast<std::size_t>(sqlite3_column_bytes(statement_, column)));
}

std::int64_t Statement::integer(int column) const { return sqlite3_column_int64(statement_, column); }

double Statement::real(int column) const { return sqlite3_column_double(statement_, column); }

std::optional<double> Statement::real_or_null(int column) const {
  if (is_null(column)) return std::nullopt;
  return real(column);
}

std::span<const unsigned char> Statement::blob(int column) const {
  const void* bytes = sqlite3_column_blob(statement_, column);
  const int size = sqlite3_column_bytes(statement_, column);  // after column_blob, per the docs
  if (bytes == nullptr || size <= 0) return {};
  return {static_cast<const unsigned char*>(bytes), static_cast<std::size_t>(size)};
}

// ---- Connection ----

Connection::Connection(const std::string& path) {
  const int code =
      sqlite3_open_v2(path.c_str(), &database_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr);
  if (code != SQLITE_OK) {
    std::string message = database_ != nullptr ? sqlite3_errmsg(database_) : sqlite3_errstr(code);
    sqlite3_close_v2(database_);
    database_ = nullptr;
    throw StoreError("cannot open database '" + path + "': " + message);
  }
  try {
    sqlite3_extended_result_codes(database_, 1);
    sqlite3_busy_timeout(database_, 5000);
    // NORMAL in WAL mode: consistent always and durable across crashes of the process (what
    // the store promises); only an OS crash or power cut may lose the last commits.
    execute("PRAGMA synchronous = NORMAL");
    execute("PRAGMA foreign_keys = ON");
  } catch (...) {
    sqlite3_close_v2(database_);
    throw;
  }
}

Connection::~Connection() {
  for (auto& [sql, statement] : statements_) sqlite3_finalize(statement);
  sqlite3_close_v2(database_);
}

Statement Connection::prepare(const std::string& sql) {
  auto found = statements_.find(sql);
  if (found == statements_.end()) {
    sqlite3_stmt* statement = nullptr;
    const int code = sqlite3_prepare_v3(database_, sql.c_str(), static_cast<int>(sql.size()), SQLITE_PREPARE_PERSISTENT,
                                        &statement, nullptr);
    if (code != SQLITE_OK) {
      sqlite3_finalize(statement);
      throw_sqlite_error(database_, code, "preparing a statement");
    }
    found = statements_.emplace(sql, statement).first;
  }
  return Statement(database_, found->second);
}

void Connection::execute(const char* sql) {
  char* error = nullptr;
  const int code = sqlite3_exec(database_, sql, nullptr, nullptr, &error);
  if (code == SQLITE_OK) return;
  const std::string message = error != nullptr ? error : sqlite3_errstr(code);
  sqlite3_free(error);
  throw_for(code, message);
}

void Connection::rollback_quietly() noexcept {
  if (in_transaction()) sqlite3_exec(database_, "ROLLBACK", nullptr, nullptr, nullptr);
}

// ---- ConnectionPool ----

ConnectionPool::ConnectionPool(std::string path, std::unique_ptr<Connection> first) : path_(std::move(path)) {
  first->attach(&health_);
  idle_.push_back(std::move(first));
}

ConnectionPool::Lease ConnectionPool::checkout() {
  {
    std::lock_guard lock(mutex_);
    if (!idle_.empty()) {
      auto connection = std::move(idle_.back());
      idle_.pop_back();
      return Lease(this, std::move(connection));
    }
  }
  // Opening touches the file system: done outside the lock.
  auto connection = std::make_unique<Connection>(path_);
  connection->attach(&health_);
  return Lease(this, std::move(connection));
}

void ConnectionPool::give_back(std::unique_ptr<Connection> connection) noexcept {
  // A connection still inside a transaction (a failed ROLLBACK) is not lent again.
  connection->rollback_quietly();
  if (connection->in_transaction()) return;
  std::lock_guard lock(mutex_);
  if (idle_.size() < kMaxIdle) idle_.push_back(std::move(connection));
}

ConnectionPool::Lease::~Lease() {
  if (connection_) pool_->give_back(std::move(connection_));
}

// ---- retries ----

void sleep_before_retry(int attempt) {
  thread_local std::minstd_rand jitter(std::random_device{}());
  const int ceiling_ms = std::min(100, 2 << std::min(attempt - 1, 10));
  std::uniform_int_distribution<int> pick(ceiling_ms / 2, ceiling_ms);
  std::this_thread::sleep_for(std::chrono::milliseconds(pick(jitter)));
}

}  // namespace manipid::server::store::sqlite
