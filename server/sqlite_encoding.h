// sqlite_encoding.h — how the SQLite store writes values: samples as little-endian double
// blobs, RFC 3339 times, random ids, page tokens, and its own spelling of job states and
// kinds (the database's format, independent of how the HTTP API spells them).
#pragma once

#include "manipid/api/records.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace manipid::server::sqlite {

/// Raw IEEE-754 little-endian doubles, in the given order.
std::vector<unsigned char> encode_doubles(const double* values, std::size_t count);
/// Fills `count` doubles; false when the blob does not hold exactly that many.
bool decode_doubles(std::span<const unsigned char> bytes, double* values, std::size_t count);

/// e.g. "2026-11-22T06:40:12.345Z"
std::string now_rfc3339();

/// `prefix` + 16 lowercase hex digits from a per-thread generator seeded by std::random_device.
std::string random_id(std::string_view prefix);

const char* state_text(api::JobState state);
std::optional<api::JobState> state_from_text(std::string_view text);
const char* kind_text(api::JobKind kind);
std::optional<api::JobKind> kind_from_text(std::string_view text);

/// Page tokens: "<tag>.<position in hex>.<check>", where the check is a hash of the tag, the
/// position and the context (the job id of a history, the filter of a job list). Not secret;
/// it catches hand-edited or truncated tokens and tokens reused with other parameters.
std::string encode_page_token(std::string_view tag, std::int64_t position, std::string_view context);
/// The position; throws api::ApiError(invalid_field, ..., "page_token") when malformed.
std::int64_t decode_page_token(std::string_view token, std::string_view tag, std::string_view context);

/// 0 → 50, above 1000 → 1000; negative → api::ApiError(invalid_field, ..., "page_size").
int effective_page_size(int requested);

}  // namespace manipid::server::sqlite
