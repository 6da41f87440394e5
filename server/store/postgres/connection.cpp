// connection.cpp — libpq connections, results, parameters and the pool (see connection.h).
#include "store/postgres/connection.h"

#include <poll.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace manipid::server::store::postgres {

namespace {

/// What a failed statement means for the caller: class 08 (connection exception) and 57P0x (the
/// server shutting down or restarting) are "try again soon", as is no answer at all; 53100 is a
/// full disk; 40001 and 40P01 (serialization failure, deadlock) are retried by run_transaction.
enum class Failure { other, retry, disk_full, unavailable };

Failure classify(const char* sqlstate) {
  if (sqlstate == nullptr) return Failure::unavailable;
  const std::string_view state(sqlstate);
  if (state == "40001" || state == "40P01") return Failure::retry;
  if (state == "53100") return Failure::disk_full;
  if (state.starts_with("08") || state == "57P01" || state == "57P02" || state == "57P03") return Failure::unavailable;
  return Failure::other;
}

/// libpq's message, first line only (the rest repeats the statement or gives hints).
std::string first_line(const char* message) {
  std::string text = message == nullptr ? "" : message;
  if (const auto end = text.find('\n'); end != std::string::npos) text.resize(end);
  return text;
}

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

// ---- Result ----

long Result::changed() const {
  const char* count = libpq().PQcmdTuples(result_);
  return count == nullptr || *count == '\0' ? 0 : std::atol(count);
}

std::string Result::text(int row, int column) const {
  if (null(row, column)) return {};
  return std::string(libpq().PQgetvalue(result_, row, column), static_cast<std::size_t>(libpq().PQgetlength(result_, row, column)));
}

std::int64_t Result::integer(int row, int column) const {
  if (null(row, column)) return 0;
  const char* value = libpq().PQgetvalue(result_, row, column);
  std::int64_t number = 0;
  const auto [end, error] = std::from_chars(value, value + libpq().PQgetlength(result_, row, column), number);
  if (error != std::errc()) throw StoreError("a whole number in the database does not read as one");
  return number;
}

double Result::real(int row, int column) const { return real_or_null(row, column).value_or(0.0); }

std::optional<double> Result::real_or_null(int row, int column) const {
  if (null(row, column)) return std::nullopt;
  // strtod reads PostgreSQL's shortest exact digits back to the same double, and its
  // "Infinity", "-Infinity" and "NaN".
  return std::strtod(libpq().PQgetvalue(result_, row, column), nullptr);
}

std::vector<unsigned char> Result::bytes(int row, int column) const {
  if (null(row, column)) return {};
  const char* value = libpq().PQgetvalue(result_, row, column);
  const auto length = static_cast<std::size_t>(libpq().PQgetlength(result_, row, column));
  // bytea_output = hex (the default since 9.0, set per connection): "\x" then two digits a byte.
  if (length < 2 || value[0] != '\\' || value[1] != 'x' || length % 2 != 0) {
    throw StoreError("a binary column in the database is not in hex form");
  }
  std::vector<unsigned char> out((length - 2) / 2);
  for (std::size_t i = 0; i < out.size(); ++i) {
    const int high = hex_value(value[2 + 2 * i]), low = hex_value(value[3 + 2 * i]);
    if (high < 0 || low < 0) throw StoreError("a binary column in the database is not in hex form");
    out[i] = static_cast<unsigned char>(high * 16 + low);
  }
  return out;
}

std::int64_t Result::binary_integer(int row, int column) const {
  if (null(row, column)) return 0;
  const auto* bytes = reinterpret_cast<const unsigned char*>(libpq().PQgetvalue(result_, row, column));
  const int length = libpq().PQgetlength(result_, row, column);
  std::uint64_t value = 0;
  for (int i = 0; i < length; ++i) value = (value << 8) | bytes[i];  // network byte order
  if (length == 4) return static_cast<std::int32_t>(static_cast<std::uint32_t>(value));
  return static_cast<std::int64_t>(value);
}

std::span<const unsigned char> Result::binary_bytes(int row, int column) const {
  if (null(row, column)) return {};
  return {reinterpret_cast<const unsigned char*>(libpq().PQgetvalue(result_, row, column)),
          static_cast<std::size_t>(libpq().PQgetlength(result_, row, column))};
}

// ---- Params ----

Params& Params::text(std::string value) {
  values_.push_back({std::move(value), {}, false, false});
  return *this;
}

Params& Params::text_or_null(const std::string& value) { return value.empty() ? null() : text(value); }

Params& Params::real(double value) {
  if (std::isnan(value)) return text("NaN");
  if (std::isinf(value)) return text(value > 0 ? "Infinity" : "-Infinity");
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);  // 17 significant digits: exact
  return text(buffer);
}

Params& Params::real_or_null(std::optional<double> value) { return value ? real(*value) : null(); }

Params& Params::bytes_or_null(std::vector<unsigned char> value) {
  if (value.empty()) return null();
  values_.push_back({{}, std::move(value), false, true});
  return *this;
}

Params& Params::null() {
  values_.push_back({{}, {}, true, false});
  return *this;
}

std::vector<const char*> Params::pointers() const {
  std::vector<const char*> out;
  out.reserve(values_.size());
  for (const auto& value : values_) {
    if (value.is_null) out.push_back(nullptr);
    else if (value.is_binary) out.push_back(reinterpret_cast<const char*>(value.binary.data()));
    else out.push_back(value.text.c_str());
  }
  return out;
}

std::vector<int> Params::lengths() const {
  std::vector<int> out;
  out.reserve(values_.size());
  for (const auto& value : values_) out.push_back(value.is_binary ? static_cast<int>(value.binary.size()) : 0);
  return out;
}

std::vector<int> Params::formats() const {
  std::vector<int> out;
  out.reserve(values_.size());
  for (const auto& value : values_) out.push_back(value.is_binary ? 1 : 0);
  return out;
}

// ---- Connection ----

Connection::Connection(const std::string& conninfo) : connection_(libpq().PQconnectdb(conninfo.c_str())) {
  if (connection_ == nullptr) throw StoreError("cannot connect to PostgreSQL: out of memory");
  try {
    if (libpq().PQstatus(connection_) != CONNECTION_OK) {
      // libpq's reason names host, port and user, never the password.
      const std::string reason = first_line(libpq().PQerrorMessage(connection_));
      const bool refused = reason.find("password") != std::string::npos ||
                           reason.find("does not exist") != std::string::npos ||
                           reason.find("authentication") != std::string::npos;
      if (refused) throw StoreError("PostgreSQL refused the connection: " + reason);
      throw StoreUnavailable("cannot connect to PostgreSQL: " + reason);
    }
    // Fixed per-connection settings: UTC stamps, hex bytea, no notices on stderr, and a bound
    // on how long a statement waits for a row lock (a stuck peer must not hang a request).
    libpq().PQsetNoticeProcessor(connection_, [](void*, const char*) {}, nullptr);
    execute("SET TIME ZONE 'UTC'; SET bytea_output = 'hex'; SET lock_timeout = '30s'; "
            "SET idle_in_transaction_session_timeout = '60s'");
  } catch (...) {
    libpq().PQfinish(connection_);  // the destructor does not run for a constructor that throws
    throw;
  }
}

void Connection::fail(const PGresult* result, const std::string& what) {
  const char* sqlstate = result == nullptr ? nullptr : libpq().PQresultErrorField(result, PG_DIAG_SQLSTATE);
  Failure failure = classify(sqlstate);
  if (libpq().PQstatus(connection_) != CONNECTION_OK) failure = Failure::unavailable;
  const std::string message = first_line(result != nullptr ? libpq().PQresultErrorMessage(result) : libpq().PQerrorMessage(connection_));
  switch (failure) {
    case Failure::disk_full: throw StorageFull("the disk holding the database is full (" + message + ")");
    case Failure::unavailable: throw StoreUnavailable("the PostgreSQL connection was lost: " + message);
    case Failure::retry: throw ConflictRetry(what + ": " + message);
    default: throw StoreError(what + ": " + message);
  }
}

Result Connection::exec(const std::string& sql, const Params& params, bool binary_results) {
  auto found = prepared_.find(sql);
  if (found == prepared_.end()) {
    std::string name = "s" + std::to_string(prepared_.size());
    Result prepared(libpq().PQprepare(connection_, name.c_str(), sql.c_str(), params.size(), nullptr));
    if (libpq().PQresultStatus(prepared.get()) != PGRES_COMMAND_OK) fail(prepared.get(), "a statement could not be prepared");
    found = prepared_.emplace(sql, std::move(name)).first;
  }
  const auto values = params.pointers();
  const auto lengths = params.lengths();
  const auto formats = params.formats();
  Result result(libpq().PQexecPrepared(connection_, found->second.c_str(), params.size(), values.data(), lengths.data(),
                               formats.data(), binary_results ? 1 : 0));
  const PGresult* raw = result.get();
  const auto status = libpq().PQresultStatus(raw);
  if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) fail(raw, "a statement failed");
  changes_ += result.changed();
  return result;
}

void Connection::execute(const std::string& sql) {
  Result result(libpq().PQexec(connection_, sql.c_str()));
  const PGresult* raw = result.get();
  const auto status = libpq().PQresultStatus(raw);
  if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) fail(raw, "a statement failed");
}

void Connection::copy_in(const std::string& sql, const std::string& data) {
  {
    Result start(libpq().PQexec(connection_, sql.c_str()));
    const PGresult* raw = start.get();
    if (libpq().PQresultStatus(raw) != PGRES_COPY_IN) fail(raw, "COPY did not start");
  }
  if (libpq().PQputCopyData(connection_, data.data(), static_cast<int>(data.size())) != 1 ||
      libpq().PQputCopyEnd(connection_, nullptr) != 1) {
    fail(nullptr, "COPY failed");
  }
  for (PGresult* raw; (raw = libpq().PQgetResult(connection_)) != nullptr;) {
    Result end(raw);
    if (libpq().PQresultStatus(raw) != PGRES_COMMAND_OK) fail(raw, "COPY failed");
    changes_ += end.changed();
  }
}

std::vector<std::string> Connection::notifications(std::chrono::milliseconds timeout) {
  pollfd descriptor{libpq().PQsocket(connection_), POLLIN, 0};
  if (descriptor.fd < 0) throw StoreUnavailable("the PostgreSQL connection was lost");
  if (::poll(&descriptor, 1, static_cast<int>(timeout.count())) < 0 && errno != EINTR) {
    throw StoreUnavailable("the PostgreSQL connection was lost");
  }
  if (libpq().PQconsumeInput(connection_) == 0) {
    throw StoreUnavailable("the PostgreSQL connection was lost: " + first_line(libpq().PQerrorMessage(connection_)));
  }
  std::vector<std::string> payloads;
  while (PGnotify* notification = libpq().PQnotifies(connection_)) {
    payloads.emplace_back(notification->extra);
    libpq().PQfreemem(notification);
  }
  return payloads;
}

void Connection::rollback_quietly() noexcept {
  if (libpq().PQstatus(connection_) != CONNECTION_OK) return;
  if (libpq().PQtransactionStatus(connection_) == PQTRANS_IDLE) return;
  libpq().PQclear(libpq().PQexec(connection_, "ROLLBACK"));
}

// ---- ConnectionPool ----

ConnectionPool::ConnectionPool(std::string conninfo, std::size_t size)
    : conninfo_(std::move(conninfo)), size_(std::max<std::size_t>(size, 1)) {}

ConnectionPool::Handle ConnectionPool::checkout() {
  std::unique_lock lock(mutex_);
  returned_.wait(lock, [this] { return !idle_.empty() || open_ < size_; });
  if (!idle_.empty()) {
    auto connection = std::move(idle_.back());
    idle_.pop_back();
    return Handle(*this, std::move(connection));
  }
  ++open_;  // counted before connecting, so no other thread opens past the size meanwhile
  lock.unlock();
  try {
    auto connection = std::make_unique<Connection>(conninfo_);
    connection->attach(&health_);
    return Handle(*this, std::move(connection));
  } catch (...) {
    lock.lock();
    --open_;
    returned_.notify_one();
    throw;
  }
}

void ConnectionPool::give_back(std::unique_ptr<Connection> connection) noexcept {
  std::lock_guard lock(mutex_);
  if (connection->usable()) {
    idle_.push_back(std::move(connection));
  } else {
    --open_;  // a broken connection is dropped; the next checkout opens a new one
  }
  returned_.notify_one();
}

// ---- transactions ----

namespace detail {

void begin(Connection& connection, TransactionKind kind) {
  connection.reset_changes();
  if (kind == TransactionKind::statement) return;
  connection.execute(kind == TransactionKind::read ? "BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY" : "BEGIN");
}

void commit(Connection& connection, TransactionKind kind) {
  if (kind != TransactionKind::statement) connection.execute("COMMIT");
  const bool proves_space = kind == TransactionKind::write || kind == TransactionKind::statement;
  if (proves_space && connection.health() != nullptr && connection.changes() > 0) {
    connection.health()->succeeded();
  }
}

}  // namespace detail

}  // namespace manipid::server::store::postgres
