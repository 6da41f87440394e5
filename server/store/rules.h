// rules.h — the rules every store backend shares, so each is defined once: random ids, RFC 3339
// time stamps, page sizes, and the page tokens that carry a list's position and filter.
#pragma once

#include "store/store.h"

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

namespace manipid::server::store {

/// e.g. "2026-11-22T06:40:12.345Z" (UTC, milliseconds). Stamps of this one format compare as
/// text in time order, so stores can compare them in SQL.
std::string now_rfc3339();
/// The stamp `age` before now, in the same format (for "older than" in SQL).
std::string rfc3339_ago(std::chrono::seconds age);

/// `prefix` + 16 lowercase hex digits from a per-thread generator seeded by std::random_device
/// ("ds_", "job_", "rb_"): unguessable enough that ids are never reused, not a secret.
std::string random_id(std::string_view prefix);

/// Page tokens: "<tag>.<position in hex>.<check>", where the check is a hash of the tag, the
/// position and the context (the job id of a history, the filter of a job list). Not secret;
/// it catches hand-edited or truncated tokens and tokens reused with other parameters.
std::string encode_page_token(std::string_view tag, std::int64_t position, std::string_view context);
/// The position; throws PageRequestError (field "page_token") when malformed.
std::int64_t decode_page_token(std::string_view token, std::string_view tag, std::string_view context);

/// What a dataset or robot list's page tokens are bound to: its owner scope (a token is refused in
/// another owner's list).
std::string list_context(const api::OwnerScope& scope);
/// What a job list's page tokens are bound to: its scope and filter (a token from another filter
/// would skip or repeat jobs).
std::string job_list_context(const api::OwnerScope& scope, const api::JobFilter& filter);

/// Page sizes: 0 → 50, above 1000 → 1000; negative → PageRequestError (field "page_size").
int effective_page_size(int requested);

}  // namespace manipid::server::store
