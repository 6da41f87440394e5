// connection.h — the PostgreSQL store's connections: RAII over libpq (PGconn, PGresult), bound
// parameters, a pool sized to the threads that use it, and run_transaction.
//
// libpq directly rather than libpqxx: the store needs a handful of calls (parameters bound out of
// line, COPY, SQLSTATE codes, connection reset), and libpq is the C library PostgreSQL itself
// ships; libpqxx 7.7 would add a second large C++ dependency whose headers cost every translation
// unit that includes them compile time, for conveniences these ~200 lines give. libpq is loaded
// when the store first connects, not at start-up (libpq.h says why), so its calls go through libpq().
//
// Every value travels as a bound parameter (PQexecParams), never inside the SQL text.
#pragma once

#include "store/store.h"
#include "store/write_health.h"

#include "store/postgres/libpq.h"

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <span>
#include <type_traits>
#include <unordered_map>
#include <vector>

namespace manipid::server::store::postgres {

/// The result of one statement (owns the PGresult). Text format: numbers as PostgreSQL prints
/// them (floats in their shortest exact form, so they read back bit for bit), bytea as hex.
class Result {
 public:
  explicit Result(PGresult* result) noexcept : result_(result) {}
  Result(Result&& other) noexcept : result_(other.result_) { other.result_ = nullptr; }
  Result& operator=(Result&&) = delete;
  Result(const Result&) = delete;
  ~Result() { libpq().PQclear(result_); }

  PGresult* get() const noexcept { return result_; }
  int rows() const { return libpq().PQntuples(result_); }
  /// Rows changed by an INSERT, UPDATE or DELETE.
  long changed() const;
  bool null(int row, int column) const { return libpq().PQgetisnull(result_, row, column) != 0; }
  std::string text(int row, int column) const;  ///< "" for NULL
  std::int64_t integer(int row, int column) const;
  double real(int row, int column) const;
  std::optional<double> real_or_null(int row, int column) const;
  bool boolean(int row, int column) const { return text(row, column) == "t"; }
  std::vector<unsigned char> bytes(int row, int column) const;  ///< bytea; empty for NULL
  // Binary-format results (exec(…, true)):
  std::int64_t binary_integer(int row, int column) const;  ///< int4 or int8
  bool binary_boolean(int row, int column) const { return !null(row, column) && *libpq().PQgetvalue(result_, row, column) != 0; }
  /// A bytea's raw bytes (empty for NULL), valid while this Result lives.
  std::span<const unsigned char> binary_bytes(int row, int column) const;

 private:
  PGresult* result_;
};

/// Parameters of one statement, $1, $2, … in the order added. Empty text or bytes given to the
/// *_or_null forms are NULL.
class Params {
 public:
  Params& text(std::string value);
  Params& text_or_null(const std::string& value);
  Params& integer(std::int64_t value) { return text(std::to_string(value)); }
  Params& real(double value);
  Params& real_or_null(std::optional<double> value);
  Params& boolean(bool value) { return text(value ? "true" : "false"); }
  /// bytea, sent in binary (no escaping).
  Params& bytes_or_null(std::vector<unsigned char> value);
  Params& null();

  int size() const { return static_cast<int>(values_.size()); }
  std::vector<const char*> pointers() const;
  std::vector<int> lengths() const;
  std::vector<int> formats() const;

 private:
  struct Value {
    std::string text;
    std::vector<unsigned char> binary;
    bool is_null = false;
    bool is_binary = false;
  };
  std::vector<Value> values_;
};

/// One connection, used by one thread at a time.
class Connection {
 public:
  /// Connects (libpq connection URI or key=value string). Throws StoreUnavailable when the
  /// server cannot be reached, StoreError when it refuses (password, missing database); the
  /// message never repeats the URI (it may carry a password).
  explicit Connection(const std::string& conninfo);
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;
  ~Connection() { libpq().PQfinish(connection_); }

  /// Runs one statement. Throws StorageFull (a full disk), StoreUnavailable (the connection is
  /// gone or the server is shutting down), ConflictRetry (serialization failure, deadlock) or
  /// StoreError.
  /// Each SQL text is prepared once per connection (its plan kept, as the SQLite store keeps its
  /// statements); `binary_results`: the result in PostgreSQL's binary format (bytea as raw bytes).
  Result exec(const std::string& sql, const Params& params = {}, bool binary_results = false);
  /// Runs SQL without parameters (transaction control, schema scripts; several statements allowed).
  void execute(const std::string& sql);
  /// COPY … FROM STDIN with `data` in COPY's text format.
  void copy_in(const std::string& sql, const std::string& data);
  /// False once the server connection is gone (the pool then opens a new one).
  bool usable() const { return libpq().PQstatus(connection_) == CONNECTION_OK; }
  /// LISTEN: waits up to `timeout` for the server to send something; then the payloads of the
  /// notifications that arrived. Throws StoreUnavailable when the connection is lost.
  std::vector<std::string> notifications(std::chrono::milliseconds timeout);
  void rollback_quietly() noexcept;
  void attach(WriteHealth* health) noexcept { health_ = health; }
  WriteHealth* health() const noexcept { return health_; }
  /// Rows inserted, updated or deleted since the count was last reset (by BEGIN): a commit
  /// that changed nothing proves nothing about the disk's space.
  long changes() const noexcept { return changes_; }
  void reset_changes() noexcept { changes_ = 0; }

 private:
  [[noreturn]] void fail(const PGresult* result, const std::string& what);

  PGconn* connection_ = nullptr;
  WriteHealth* health_ = nullptr;
  long changes_ = 0;
  std::unordered_map<std::string, std::string> prepared_;  ///< SQL text → statement name

 public:
  /// Set once the session's temporary tables exist (they live as long as the connection).
  bool staging_ready = false;
};

/// A transaction PostgreSQL aborted for a conflict with another (SQLSTATE 40001, 40P01): running
/// it again is expected to succeed (run_transaction does, a few times).
class ConflictRetry : public StoreError {
 public:
  using StoreError::StoreError;
};

/// Up to `size` connections opened on demand, handed to one thread at a time (checkout waits
/// while all are out); a broken connection is dropped when given back and replaced on demand.
class ConnectionPool {
 public:
  ConnectionPool(std::string conninfo, std::size_t size);
  ConnectionPool(const ConnectionPool&) = delete;
  ConnectionPool& operator=(const ConnectionPool&) = delete;

  class Handle {
   public:
    Handle(ConnectionPool& pool, std::unique_ptr<Connection> connection) noexcept
        : pool_(&pool), connection_(std::move(connection)) {}
    Handle(Handle&& other) noexcept = default;
    Handle& operator=(Handle&&) = delete;
    ~Handle() {
      if (connection_) pool_->give_back(std::move(connection_));
    }
    Connection& operator*() const noexcept { return *connection_; }
    Connection* operator->() const noexcept { return connection_.get(); }

   private:
    ConnectionPool* pool_;
    std::unique_ptr<Connection> connection_;
  };

  Handle checkout();
  const WriteHealth& health() const { return health_; }
  const std::string& conninfo() const { return conninfo_; }

 private:
  void give_back(std::unique_ptr<Connection> connection) noexcept;

  std::string conninfo_;
  std::size_t size_;
  std::size_t open_ = 0;  ///< connections in use or idle
  std::vector<std::unique_ptr<Connection>> idle_;
  std::mutex mutex_;
  std::condition_variable returned_;
  WriteHealth health_;
};

enum class TransactionKind {
  read,            ///< a consistent snapshot of several statements (REPEATABLE READ, READ ONLY)
  write,           ///< READ COMMITTED with the row locks each statement takes; a commit clears a full disk
  write_in_place,  ///< the same, but its commit proves nothing about space (lease heartbeats, recovery)
  statement,       ///< one write statement that is its own transaction (autocommit): no BEGIN and
                   ///< COMMIT round trips; a change it makes clears a full disk as a write's commit does
};

namespace detail {
void begin(Connection& connection, TransactionKind kind);
void commit(Connection& connection, TransactionKind kind);
}  // namespace detail

/// Runs `body` in one transaction, retried (a few times) on a serialization failure or
/// deadlock; rolled back on any exception. A lost connection is StoreUnavailable, a full disk
/// StorageFull (and marks the store's health).
template <class Body>
auto run_transaction(Connection& connection, TransactionKind kind, Body&& body) -> decltype(body()) {
  using Value = decltype(body());
  constexpr int attempts = 5;
  for (int attempt = 1;; ++attempt) {
    try {
      detail::begin(connection, kind);
      if constexpr (std::is_void_v<Value>) {
        body();
        detail::commit(connection, kind);
        return;
      } else {
        Value value = body();
        detail::commit(connection, kind);
        return value;
      }
    } catch (const ConflictRetry&) {
      connection.rollback_quietly();
      if (attempt < attempts) continue;
      throw;
    } catch (const StorageFull& full) {
      connection.rollback_quietly();
      if (connection.health() != nullptr) connection.health()->failed(full.what());
      throw;
    } catch (...) {
      connection.rollback_quietly();
      throw;
    }
  }
}

}  // namespace manipid::server::store::postgres
