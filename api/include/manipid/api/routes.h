// routes.h — the HTTP surface of `manipid serve`: registers every route on a cpp-httplib
// server over a Service (service.h), plus the cross-cutting parts every request passes
// through: bearer-token check (and whom the token stands for), upload guards (length required,
// no compressed bodies, size limit), problem+json for every error, one log line per request,
// request counters for /metrics. The table of routes is in api/openapi.yaml (served at GET /openapi.json); the
// code is in api/src/http/ (route table, helpers, guards) and api/src/routes/ (one file per resource).
#pragma once

#include "manipid/api/service.h"

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace httplib {
class Server;
}

namespace manipid::api {

/// Memory a request may take per byte of its body while it is read, parsed and stored (the
/// body itself, its numbers, the store's copy): what each body reserves of the memory budget
/// before it is read. Right for numbers of ten characters or more; a dataset of short numbers
/// ("0,", 25 bytes per body byte once parsed and stored) tops its reservation up from
/// memory_per_dataset_number before it is parsed.
inline constexpr std::size_t memory_per_body_byte = 3;

/// Memory a CSV or JSON dataset upload takes per number of its body at its peak, besides the body:
/// the parser's arrays (8 bytes, 16 while one grows), the dataset (8, and 8 per sample for times
/// made from dt) and the store's copy (SQLite: its row record, 8; PostgreSQL: the encoded bytes
/// and libpq's buffer, 16). Measured: a 40 MB JSON body of 20 million zeros peaked at 1,000 MiB
/// before this bound (and SQLite's copies of the bound blobs) was in place, 560 MiB after.
inline constexpr std::size_t memory_per_dataset_number = 32;

/// A bearer token the server takes and whom it stands for (`manipid serve --token-file`).
struct NamedToken {
  std::string name;    ///< its requests act for this owner (1..64 of A-Z a-z 0-9 . _ -); shown in the log
  std::string token;   ///< the secret; never logged
  bool admin = false;  ///< sees and acts on every owner's datasets, robots and jobs, and reads /metrics
};

struct RouteOptions {
  std::size_t max_body = 64u << 20;  ///< bytes; larger bodies get 413
  /// Bytes the bodies being read and handled at once may take, memory_per_body_byte × each
  /// one's Content-Length; a body beyond it gets 503 with Retry-After (and its connection
  /// closes, unread). At least memory_per_body_byte × max_body, so any body fits alone.
  std::size_t memory_budget = std::size_t{1} << 30;
  /// When set, every /v1 request and /metrics need "Authorization: Bearer <token>": one admin
  /// token (--token, MANIPID_TOKEN), owner "" for what it creates.
  std::string token;
  /// Named tokens (--token-file): every /v1 request and /metrics need one of them; a request acts
  /// for its token's name and sees that owner's datasets, robots and jobs only (an admin token,
  /// every owner's); another owner's resource is answered 404, as a missing one. /metrics is
  /// an admin token's only (403). Neither `token` nor `tokens`: no check, everyone the admin.
  std::vector<NamedToken> tokens;
  double max_wait_seconds = 30.0;    ///< cap of ?wait= long-polls
  /// Long-polls that may wait at once; each holds an HTTP thread while it waits (cpp-httplib
  /// 0.11.4 has no other way), so `manipid serve` gives them half its threads and keeps the
  /// rest for everything else. Beyond it a ?wait= is answered at once with the job as it stands,
  /// `Retry-After: 1` and `Manipid-Wait: declined`. ≤ 0: no long-poll ever waits.
  int max_waiters = 16;
  std::function<void(const std::string& line)> log;  ///< one line per request; empty = silent
};

/// Registers the routes and handlers. `service` must outlive `server`'s listening.
void register_routes(httplib::Server& server, Service& service, RouteOptions options);

/// api/openapi.yaml as JSON text (generated at build time).
const char* openapi_json();

}  // namespace manipid::api
