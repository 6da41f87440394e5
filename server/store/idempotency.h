// idempotency.h — what a request sent with an Idempotency-Key does, given the record the key
// already holds: replay the earlier resource, refuse (the key came with another body), or go on
// and create. The one rule every store backend follows; how a backend finds and claims the
// record (its SQL, its locking) stays in the backend.
#pragma once

#include "store/store.h"

#include "manipid/api/records.h"

#include <optional>
#include <string>
#include <utility>

namespace manipid::server::store {

/// A live (unexpired) Idempotency-Key's stored record, within its scope ("job", "dataset" or
/// "robot").
struct KeyRecord {
  std::string fingerprint;  ///< of the body first sent with the key
  std::string resource_id;  ///< the job, dataset or robot that body made
};

/// The answer to a request sent with `key` whose key holds `held` (nullopt: no live record):
///  - {key_reused, {}} when the fingerprints differ, whether or not the earlier resource exists;
///  - {replayed, earlier} when they match and `find(held->resource_id)` finds the earlier one;
///  - nullopt otherwise: go on and create (the key is free, or its resource is gone and the new
///    one takes the key over).
/// `Outcome` is SubmitOutcome, DatasetOutcome or RobotOutcome; `find(id)` returns the resource
/// as an optional and is asked only when the fingerprints match.
template <class Outcome, class Find>
std::optional<Outcome> answer_from_key(const std::optional<KeyRecord>& held, const api::IdempotencyKey& key,
                                       Find&& find) {
  if (!held) return std::nullopt;
  if (held->fingerprint != key.fingerprint) return Outcome{SubmitStatus::key_reused, {}};
  if (auto earlier = find(held->resource_id)) return Outcome{SubmitStatus::replayed, std::move(*earlier)};
  return std::nullopt;
}

}  // namespace manipid::server::store
