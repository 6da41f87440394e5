// problem.h — every error the service answers with, as RFC 9457 problem details.
//
// One table (problem.cpp) maps each failure kind to its HTTP status, a stable `code`
// (UPPER_SNAKE, the contract scripts can switch on), a fixed `title` and a `type` URI
// "/problems/<code in kebab case>". `detail` is free text for people; `field` names the
// offending input ("q3", "initial.m2", "half_length", "body") whenever there is one.
#pragma once

#include "manipid/core/errors.h"

#include <nlohmann/json.hpp>

#include <stdexcept>
#include <string>
#include <string_view>

namespace manipid::api {

enum class ProblemKind {
  malformed_body,        ///< 400 the body is not JSON / CSV at all (syntax)
  invalid_field,         ///< 422 a field's value is wrong (unknown name, NaN, ragged, bounds, ...)
  unsupported_media,     ///< 415 Content-Type or Content-Encoding the route does not take
  length_required,       ///< 411 chunked or length-less upload
  payload_too_large,     ///< 413 body over --max-body
  uri_too_long,          ///< 414 the request target is longer than the server reads
  unauthorized,          ///< 401 missing or wrong bearer token
  not_found,             ///< 404 unknown dataset, job or route
  method_not_allowed,    ///< 405
  conflict,              ///< 409 the resource is in the wrong state for the request
  idempotency_mismatch,  ///< 422 an Idempotency-Key reused with a different request
  queue_full,            ///< 429 the job queue is at --queue-limit (with Retry-After)
  shutting_down,         ///< 503 the server is stopping
  insufficient_storage,  ///< 507 the server's disk is full: nothing was stored (with Retry-After)
  memory_busy,           ///< 503 no memory for this request now: over --memory-budget, or it ran out (with Retry-After)
  store_unavailable,     ///< 503 the database cannot be reached now: nothing was done (with Retry-After)
  uploads_busy,          ///< 503 too many bodies being received now, from this address or in all (with Retry-After)
  internal,              ///< 500 a bug; the detail never carries internals
  // A job's `error` (the request was accepted; the run could not finish):
  job_failed,            ///< 500 the computation could not finish (a diverging simulation, a store failure)
  not_computable,        ///< 422 the data and starting values give no finite cost to minimise
  worker_lost,           ///< 500 the process running the job died --max-attempts times: never run again
  // Appended (the codes are a contract; the table in problem.cpp is by name, not position):
  forbidden,             ///< 403 a known token that may not do this (/metrics with a token that is not an admin's)
};

struct Problem {
  ProblemKind kind = ProblemKind::internal;
  std::string detail;
  std::string field;  ///< empty when no single input is at fault
};

int status_of(ProblemKind kind);
const char* code_of(ProblemKind kind);   ///< e.g. "INVALID_FIELD"
const char* title_of(ProblemKind kind);  ///< e.g. "A field of the request is invalid"

/// {"type", "title", "status", "detail", "code"[, "field"][, "instance"]}
nlohmann::json problem_to_json(const Problem& problem, const std::string& instance = "");

/// Whether `text` is well-formed UTF-8 (no overlong forms, no surrogates): what JSON text may hold.
bool is_valid_utf8(std::string_view text);

/// Thrown by api/ and server/ code that wants a specific answer; routes turn it into the
/// response. InputError from the core becomes invalid_field with the same field.
class ApiError : public std::runtime_error {
 public:
  ApiError(ProblemKind kind, std::string detail, std::string field = "")
      : std::runtime_error(detail), problem_{kind, std::move(detail), std::move(field)} {}
  const Problem& problem() const { return problem_; }

 private:
  Problem problem_;
};

/// InputError("q3", "...") → Problem{invalid_field, "...", "q3"}.
Problem problem_from(const InputError& error);

}  // namespace manipid::api
