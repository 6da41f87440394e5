// connection.h — a thin RAII layer over the SQLite C API for the store: a connection
// with its cached prepared statements, a pool that lends each calling thread a connection of
// its own, and the transaction helper that runs a transaction again on SQLITE_BUSY.
#pragma once

#include "store/store.h"
#include "store/write_health.h"

#include <sqlite3.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <unordered_map>
#include <vector>

namespace manipid::server::store::sqlite {

/// SQLITE_BUSY or SQLITE_LOCKED: another connection holds a lock. run_transaction catches it
/// and runs the whole transaction again, so it never reaches the store's callers.
class BusyError : public StoreError {
 public:
  using StoreError::StoreError;
};

/// Throws BusyError for BUSY/LOCKED, StorageFull for SQLITE_FULL (the disk or quota is full),
/// std::bad_alloc for SQLITE_NOMEM, StoreError (with SQLite's message) for anything else.
[[noreturn]] void throw_sqlite_error(sqlite3* database, int code, std::string_view context);

/// One use of a cached prepared statement. Values are bound, never spliced into the SQL.
/// Destruction resets the statement and clears its bindings, so the cache can lend it again
/// and no read transaction is left open by a half-stepped query.
class Statement {
 public:
  Statement(sqlite3* database, sqlite3_stmt* statement) noexcept : database_(database), statement_(statement) {}
  Statement(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  Statement& operator=(Statement&&) = delete;
  ~Statement();

  Statement& bind_text(int index, std::string_view text);
  Statement& bind_text_or_null(int index, std::string_view text);  ///< NULL when empty
  Statement& bind_integer(int index, std::int64_t value);
  Statement& bind_real(int index, double value);
  Statement& bind_real_or_null(int index, std::optional<double> value);
  /// NULL when empty. Not copied (a dataset's blobs are as large as the dataset): the bytes must
  /// outlive the statement, which clears its bindings when it goes.
  Statement& bind_blob_or_null(int index, std::span<const unsigned char> bytes);
  Statement& bind_null(int index);

  bool step();  ///< true: a row is ready; false: the statement is done
  void run();   ///< steps to the end, ignoring any rows

  bool is_null(int column) const;
  std::string text(int column) const;  ///< "" for NULL
  std::int64_t integer(int column) const;
  double real(int column) const;
  std::optional<double> real_or_null(int column) const;
  std::span<const unsigned char> blob(int column) const;  ///< valid until the next step

 private:
  void check_bind(int code);

  sqlite3* database_;
  sqlite3_stmt* statement_;
};

/// One database connection, used by one thread at a time (it is opened NOMUTEX).
class Connection {
 public:
  /// Opens (creating) the file and applies the per-connection settings.
  explicit Connection(const std::string& path);
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;
  ~Connection();

  /// The statement for this SQL text, prepared once per connection and cached. The same text
  /// must not be in use twice at once on one connection.
  Statement prepare(const std::string& sql);
  /// Runs fixed SQL without values (transaction control, schema scripts).
  void execute(const char* sql);
  void rollback_quietly() noexcept;
  bool in_transaction() const { return sqlite3_get_autocommit(database_) == 0; }
  /// Rows changed by the last INSERT, UPDATE or DELETE on this connection.
  int changes() const { return sqlite3_changes(database_); }
  sqlite3* handle() const { return database_; }
  /// The store's WriteHealth, told by run_transaction how each write transaction ended (none
  /// for a connection outside a pool: start-up migrations, `manipid doctor`).
  void attach(WriteHealth* health) noexcept { health_ = health; }
  WriteHealth* health() const noexcept { return health_; }

 private:
  sqlite3* database_ = nullptr;
  WriteHealth* health_ = nullptr;
  std::unordered_map<std::string, sqlite3_stmt*> statements_;
};

/// Connections for many threads. Each store call checks one out for its duration and gives it
/// back, so no connection is ever used by two threads at once (SQLite gives no isolation
/// within one connection) and the count stays near the number of threads inside the store.
/// Chosen over thread_local connections because those would outlive a closed store in
/// long-lived pool threads (keeping the file open and its statements alive) and would need
/// per-instance bookkeeping; a pool closes everything deterministically when the store goes.
class ConnectionPool {
 public:
  class Lease {
   public:
    Lease(ConnectionPool* pool, std::unique_ptr<Connection> connection)
        : pool_(pool), connection_(std::move(connection)) {}
    Lease(Lease&&) noexcept = default;
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    Lease& operator=(Lease&&) = delete;
    ~Lease();
    Connection& operator*() const { return *connection_; }
    Connection* operator->() const { return connection_.get(); }

   private:
    ConnectionPool* pool_;
    std::unique_ptr<Connection> connection_;
  };

  /// `first` is the connection the store opened (and migrated with) at start-up.
  ConnectionPool(std::string path, std::unique_ptr<Connection> first);
  Lease checkout();
  const WriteHealth& health() const { return health_; }

 private:
  void give_back(std::unique_ptr<Connection> connection) noexcept;

  static constexpr std::size_t kMaxIdle = 32;  // beyond this, returned connections are closed
  std::string path_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Connection>> idle_;
  WriteHealth health_;
};

enum class TransactionKind {
  read,   ///< BEGIN (deferred): a consistent snapshot for multi-statement reads
  write,  ///< BEGIN IMMEDIATE: takes the write lock up front, so no read→write upgrade can deadlock
  /// A write of a few bytes in rows that exist (a lease's heartbeat, taking expired leases back):
  /// like `write`, and a full disk still marks the store troubled, but its commit never clears
  /// that — it fits in pages the file (or its WAL) already has, and says nothing about room for
  /// the result or upload that failed.
  write_in_place,
};

/// Retry policy: up to kMaxAttempts tries; each BEGIN IMMEDIATE already waits up to
/// busy_timeout (5 s) for the lock, so a retry only happens when SQLite refuses to wait
/// (deadlock avoidance, WAL recovery) or the lock stayed taken; between tries a jittered
/// backoff of 2, 4, 8 ... ≤ 100 ms.
inline constexpr int kMaxAttempts = 8;
void sleep_before_retry(int attempt);

/// Runs `body` inside one transaction and commits; on BusyError anywhere (BEGIN, a statement,
/// COMMIT) rolls back and runs the whole body again. Any other exception rolls back and
/// propagates. A write transaction tells the connection's WriteHealth whether it committed or
/// failed for want of space. `body` must therefore compute everything from the database, not from state
/// an earlier attempt left behind.
template <class Body>
auto run_transaction(Connection& connection, TransactionKind kind, Body&& body) -> std::invoke_result_t<Body&> {
  using Result = std::invoke_result_t<Body&>;
  for (int attempt = 1;; ++attempt) {
    try {
      connection.execute(kind == TransactionKind::read ? "BEGIN" : "BEGIN IMMEDIATE");
      // Only a commit that changed rows wrote pages, and so shows there is room again: an idle
      // worker's claim that found nothing commits too, and must not hide a full disk.
      const std::int64_t changes_before = sqlite3_total_changes64(connection.handle());
      const auto commit = [&] {
        connection.execute("COMMIT");
        if (kind == TransactionKind::write && connection.health() != nullptr &&
            sqlite3_total_changes64(connection.handle()) != changes_before) {
          connection.health()->succeeded();
        }
      };
      if constexpr (std::is_void_v<Result>) {
        body();
        commit();
        return;
      } else {
        Result result = body();
        commit();
        return result;
      }
    } catch (const StorageFull& full) {
      connection.rollback_quietly();
      if (connection.health() != nullptr) connection.health()->failed(full.what());
      throw;
    } catch (const BusyError& busy) {
      connection.rollback_quietly();
      if (attempt >= kMaxAttempts) {
        throw StoreError(std::string("database stayed locked after retries: ") + busy.what());
      }
    } catch (...) {
      connection.rollback_quietly();
      throw;
    }
    sleep_before_retry(attempt);
  }
}

}  // namespace manipid::server::store::sqlite
