// rows.h — reading and writing the PostgreSQL store's rows that several store methods share:
// whole job, dataset and robot records, pages of them, idempotency keys, fresh ids, a job's
// history and estimates. Every function runs on the caller's connection, inside the caller's
// transaction when it has one.
#pragma once

#include "store/columns.h"
#include "store/idempotency.h"
#include "store/postgres/connection.h"
#include "store/rules.h"

#include "manipid/api/records.h"

#include <optional>
#include <string>
#include <vector>

namespace manipid::server::store::postgres {

/// kJobColumns (store/columns.h), each as "jobs.<column>" (for a statement that joins another relation).
std::string qualified_job_columns();

/// Whole records, from a statement that selects store/columns.h's columns.
api::JobInfo read_job(const Result& rows, int row);
api::DatasetInfo read_dataset(const Result& rows, int row);
api::RobotInfo read_robot(const Result& rows, int row);
/// One job_history row (idx, cost, theta) of job `id`.
api::HistoryEntry history_entry(const Result& rows, int row, const std::string& id);

/// Up to `size` items read from `rows` (which hold at most size + 1: one more tells that a next
/// page exists); the next page's token carries the last item's seq.
template <class Item, class Read>
api::Page<Item> page_of(const Result& rows, int size, const char* tag, const std::string& context, int seq_column,
                        Read read) {
  api::Page<Item> result;
  for (int row = 0; row < rows.rows(); ++row) {
    if (static_cast<int>(result.items.size()) == size) {
      result.next_page_token = encode_page_token(tag, rows.integer(row - 1, seq_column), context);
      break;
    }
    result.items.push_back(read(rows, row));
  }
  return result;
}

/// " AND owner = $N" when `owners` names one owner (added to `params` as $N), else "": the
/// fragment a statement's WHERE gets.
std::string owner_condition(const api::OwnerScope& owners, Params& params);

/// The record of `id` if it is within `owners` (a row of another owner is not found, as a missing one).
std::optional<api::JobInfo> select_job(Connection& connection, const api::OwnerScope& owners, const std::string& id);
std::optional<api::DatasetInfo> select_dataset(Connection& connection, const api::OwnerScope& owners,
                                               const std::string& id);
std::optional<api::RobotInfo> select_robot(Connection& connection, const api::OwnerScope& owners, const std::string& id);
/// The job's state, its row locked until the transaction ends (`lock`), or nullopt.
std::optional<api::JobState> select_state(Connection& connection, const api::OwnerScope& owners, const std::string& id,
                                          bool lock);

/// A fresh random id ("ds_"/"job_"/"rb_" + 16 hex) not held by a row of `table` (a 64-bit
/// collision is unlikely, but a UNIQUE failure would be a 500).
std::string unused_id(Connection& connection, const char* prefix, const std::string& table);

// ---- idempotency keys (scope: "job", "dataset" or "robot"; owner: whose key it is) ----

/// Claims `owner`'s Idempotency-Key `key` in `scope` for the new resource `id`: nullopt when the
/// key is now ours (create the resource), else the live record that holds it. Expired keys are
/// forgotten first (by the index on their age). Never a read-then-write: of two processes
/// sending the same key, the second waits for the first's commit and then finds its row.
std::optional<KeyRecord> claim_key(Connection& connection, const char* scope, const std::string& owner,
                                   const api::IdempotencyKey& key, const std::string& id, const std::string& now,
                                   const std::string& not_before);
/// The key now names `id` (its earlier resource is gone).
void retake_key(Connection& connection, const char* scope, const std::string& owner, const api::IdempotencyKey& key,
                const std::string& id, const std::string& now);
void forget_keys_of(Connection& connection, const char* scope, const std::string& id);

/// A keyed insert's first step: claims `owner`'s `key` (when given) for the new resource `id` and
/// answers as the shared rule says (answer_from_key, store/idempotency.h) — the earlier resource
/// (`find`) or a refusal; nullopt: create `id`, the key (if any) now names it.
template <class Outcome, class Find>
std::optional<Outcome> claim_key_for(Connection& connection, const char* scope, const std::string& owner,
                                     const std::optional<api::IdempotencyKey>& key, const std::string& id,
                                     const std::string& now, const std::string& not_before, Find&& find) {
  if (!key) return std::nullopt;
  const auto held = claim_key(connection, scope, owner, *key, id, now, not_before);
  auto answer = answer_from_key<Outcome>(held, *key, find);
  if (!answer && held) retake_key(connection, scope, owner, *key, id, now);
  return answer;
}

// ---- a running job's progress ----

/// Deletes the cost history and estimates of the jobs `ids`.
void clear_progress(Connection& connection, const std::vector<std::string>& ids);
/// The per-session staging table write_history copies into: made once per connection, outside
/// any transaction (a rollback would take it along).
void prepare_staging(Connection& connection);
/// COPY `rows` (history_rows, store/postgres/literals.h) into the per-session staging table
/// (prepare_staging), then one upsert: an index written again replaces its row, as in the
/// SQLite store. Nothing when `rows` is empty.
void write_history(Connection& connection, const std::string& rows);

}  // namespace manipid::server::store::postgres
