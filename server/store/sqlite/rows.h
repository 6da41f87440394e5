// rows.h — reading and writing the SQLite store's rows that several store methods
// share: whole job, dataset and robot records, idempotency keys, fresh ids, a job's progress rows.
// Every function runs inside the caller's transaction on the caller's connection.
#pragma once

#include "store/columns.h"
#include "store/idempotency.h"
#include "store/sqlite/connection.h"

#include "manipid/api/records.h"

#include <optional>
#include <string>

namespace manipid::server::store::sqlite {

/// Whole records, from a statement that selects store/columns.h's columns.
api::JobInfo read_job(const Statement& row);
api::DatasetInfo read_dataset(const Statement& row);
api::RobotInfo read_robot(const Statement& row);
/// The record of `id` if it is within `owners` (a row of another owner is not found, as a missing one).
std::optional<api::RobotInfo> select_robot(Connection& connection, const api::OwnerScope& owners, const std::string& id);
std::optional<api::JobInfo> select_job(Connection& connection, const api::OwnerScope& owners, const std::string& id);
std::optional<api::DatasetInfo> select_dataset(Connection& connection, const api::OwnerScope& owners,
                                               const std::string& id);
std::optional<api::JobState> select_state(Connection& connection, const api::OwnerScope& owners, const std::string& id);
/// " AND owner = ?N" when `owners` names one owner, else "": the fragment a statement's WHERE
/// gets (bind_owner binds it).
std::string owner_condition(const api::OwnerScope& owners, int parameter);
void bind_owner(Statement& statement, const api::OwnerScope& owners, int parameter);

/// scope: "job", "dataset" or "robot"; `owner`: whose key it is (another owner's same key is another key).
/// The key's record if it was stored at `not_before` or later (older keys have expired); what
/// it means for the request is the rule both backends share (answer_from_key, store/idempotency.h).
std::optional<KeyRecord> select_key(Connection& connection, const char* scope, const std::string& owner,
                                    const std::string& key, const std::string& not_before);
/// Stores `owner`'s key for `id` (INSERT OR REPLACE: a key whose resource has gone, or that expired,
/// is taken over by the new one), forgetting every key stored before `not_before` (expired).
void store_key(Connection& connection, const char* scope, const std::string& owner, const api::IdempotencyKey& key,
               const std::string& id, const std::string& now, const std::string& not_before);
void forget_keys_of(Connection& connection, const char* scope, const std::string& id);

/// A fresh random id ("ds_"/"job_" + 16 hex) not held by a live row; `exists_sql` selects a
/// row by id (?1). A 64-bit collision is unlikely, but a UNIQUE failure would be a 500.
std::string unused_id(Connection& connection, const char* prefix, const std::string& exists_sql);

/// Deletes a job's cost history and estimates.
void clear_progress(Connection& connection, const std::string& id);

}  // namespace manipid::server::store::sqlite
