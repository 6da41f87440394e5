// problem.cpp — the error table behind problem.h: each ProblemKind's HTTP status, stable code
// and title, and the RFC 9457 problem+json object built from them.
#include "manipid/api/problem.h"

#include <cstddef>
#include <string_view>

namespace manipid::api {
namespace {

struct ProblemEntry {
  int status;
  const char* code;
  const char* title;
};

// One row per ProblemKind, in declaration order. The codes are a public contract: scripts
// switch on them, so they never change once released.
ProblemEntry entry_of(ProblemKind kind) {
  switch (kind) {
    case ProblemKind::malformed_body: return {400, "MALFORMED_BODY", "The request body is malformed"};
    case ProblemKind::invalid_field: return {422, "INVALID_FIELD", "A field of the request is invalid"};
    case ProblemKind::unsupported_media: return {415, "UNSUPPORTED_MEDIA", "The media type is not supported"};
    case ProblemKind::length_required: return {411, "LENGTH_REQUIRED", "A Content-Length is required"};
    case ProblemKind::payload_too_large: return {413, "PAYLOAD_TOO_LARGE", "The request body is too large"};
    case ProblemKind::uri_too_long: return {414, "URI_TOO_LONG", "The request target is too long"};
    case ProblemKind::unauthorized: return {401, "UNAUTHORIZED", "Authentication is required"};
    case ProblemKind::not_found: return {404, "NOT_FOUND", "The resource was not found"};
    case ProblemKind::method_not_allowed: return {405, "METHOD_NOT_ALLOWED", "The method is not allowed"};
    case ProblemKind::conflict: return {409, "CONFLICT", "The resource is in the wrong state for the request"};
    case ProblemKind::idempotency_mismatch:
      return {422, "IDEMPOTENCY_MISMATCH", "The Idempotency-Key was used with a different request"};
    case ProblemKind::queue_full: return {429, "QUEUE_FULL", "The job queue is full"};
    case ProblemKind::shutting_down: return {503, "SHUTTING_DOWN", "The server is shutting down"};
    case ProblemKind::insufficient_storage: return {507, "INSUFFICIENT_STORAGE", "The server has no room to store the request"};
    case ProblemKind::memory_busy: return {503, "MEMORY_BUSY", "The server has no memory for this request now"};
    case ProblemKind::store_unavailable: return {503, "STORE_UNAVAILABLE", "The database cannot be reached now"};
    case ProblemKind::uploads_busy: return {503, "UPLOADS_BUSY", "The server is receiving too many request bodies now"};
    case ProblemKind::job_failed: return {500, "JOB_FAILED", "The job could not be completed"};
    case ProblemKind::not_computable: return {422, "NOT_COMPUTABLE", "The identification has no finite cost to minimise"};
    case ProblemKind::worker_lost: return {500, "WORKER_LOST", "The job's worker stopped before it finished, too often"};
    case ProblemKind::forbidden: return {403, "FORBIDDEN", "The token may not do this"};
    case ProblemKind::internal: break;
  }
  // Also the answer for a value outside the enum: never a crash while reporting an error.
  return {500, "INTERNAL", "Internal server error"};
}

/// "INVALID_FIELD" → "invalid-field", for the type URI.
std::string kebab_case(std::string_view code) {
  std::string text(code);
  for (char& c : text) c = c == '_' ? '-' : static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  return text;
}

/// Length of the valid UTF-8 sequence starting at text[i], or 0 when it is not one.
std::size_t utf8_sequence_length(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  if (lead < 0x80) return 1;
  std::size_t length = 0;
  unsigned int low = 0x80, high = 0xBF;  // allowed range of the second byte (no overlongs, no surrogates)
  if (lead >= 0xC2 && lead <= 0xDF) length = 2;
  else if (lead >= 0xE0 && lead <= 0xEF) {
    length = 3;
    if (lead == 0xE0) low = 0xA0;
    if (lead == 0xED) high = 0x9F;
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    length = 4;
    if (lead == 0xF0) low = 0x90;
    if (lead == 0xF4) high = 0x8F;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  if (byte(i + 1) < low || byte(i + 1) > high) return 0;
  for (std::size_t k = 2; k < length; ++k) {
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  }
  return length;
}

/// Details and fields can quote user input (a CSV header, a file name); nlohmann::json::dump
/// throws on invalid UTF-8, which would turn an error answer into a crash. Bad bytes become U+FFFD.
std::string valid_utf8(std::string_view text) {
  std::string result;
  result.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t length = utf8_sequence_length(text, i);
    if (length == 0) {
      result += "\xEF\xBF\xBD";
      ++i;
    } else {
      result.append(text.substr(i, length));
      i += length;
    }
  }
  return result;
}

/// Details are sentences for people, not dumps: past this many bytes the text is cut (at a
/// character boundary) with "...", whatever a message builder quoted.
constexpr std::size_t max_detail_bytes = 400;
constexpr std::size_t max_field_bytes = 120;

std::string capped(std::string text, std::size_t most) {
  if (text.size() <= most) return text;
  std::size_t end = most - 3;
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) --end;
  text.resize(end);
  return text + "...";
}

}  // namespace

int status_of(ProblemKind kind) { return entry_of(kind).status; }
const char* code_of(ProblemKind kind) { return entry_of(kind).code; }
const char* title_of(ProblemKind kind) { return entry_of(kind).title; }

nlohmann::json problem_to_json(const Problem& problem, const std::string& instance) {
  const ProblemEntry entry = entry_of(problem.kind);
  nlohmann::json body;
  body["type"] = "/problems/" + kebab_case(entry.code);
  body["title"] = entry.title;
  body["status"] = entry.status;
  // RFC 9457 makes detail optional, but clients print it: never leave it empty.
  body["detail"] = problem.detail.empty() ? std::string(entry.title) : capped(valid_utf8(problem.detail), max_detail_bytes);
  body["code"] = entry.code;
  if (!problem.field.empty()) body["field"] = capped(valid_utf8(problem.field), max_field_bytes);
  if (!instance.empty()) body["instance"] = valid_utf8(instance);
  return body;
}

Problem problem_from(const InputError& error) {
  return Problem{ProblemKind::invalid_field, error.what(), error.field()};
}

bool is_valid_utf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t length = utf8_sequence_length(text, i);
    if (length == 0) return false;
    i += length;
  }
  return true;
}

}  // namespace manipid::api
