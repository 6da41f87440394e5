// rows.cpp — shared row reads and writes of the SQLite store (see rows.h).
#include "store/sqlite/rows.h"

#include "store/encoding.h"
#include "store/rules.h"

namespace manipid::server::store::sqlite {

api::JobInfo read_job(const Statement& row) {
  api::JobInfo job;
  job.id = row.text(0);
  const auto kind = kind_from_text(row.text(1));
  const auto state = state_from_text(row.text(2));
  if (!kind || !state) throw StoreError("job " + job.id + " has an unknown kind or state in the database");
  job.kind = *kind;
  job.state = *state;
  job.created_at = row.text(3);
  job.started_at = row.text(4);
  job.finished_at = row.text(5);
  job.request = row.text(6);
  job.dataset_id = row.text(7);
  job.evaluations = static_cast<long>(row.integer(8));
  job.best_cost = row.real_or_null(9);
  job.cancel_requested = row.integer(10) != 0;
  job.attempts = static_cast<int>(row.integer(11));
  job.result = row.text(12);
  job.error = row.text(13);
  job.robot_id = row.text(14);
  job.validation_dataset_id = row.text(15);
  job.worker = row.text(16);
  job.owner = row.text(kJobOwnerColumn);
  return job;
}

api::DatasetInfo read_dataset(const Statement& row) {
  api::DatasetInfo dataset;
  dataset.id = row.text(0);
  dataset.name = row.text(1);
  dataset.created_at = row.text(2);
  dataset.source_job = row.text(3);
  dataset.joints = static_cast<int>(row.integer(4));
  dataset.samples = static_cast<int>(row.integer(5));
  dataset.dt = row.real(6);
  dataset.has_torque = row.integer(7) != 0;
  dataset.has_reference = row.integer(8) != 0;
  dataset.uniform = row.integer(9) != 0;
  dataset.has_rates = row.integer(10) != 0;
  dataset.has_accelerations = row.integer(11) != 0;
  dataset.owner = row.text(kDatasetOwnerColumn);
  return dataset;
}

api::RobotInfo read_robot(const Statement& row) {
  api::RobotInfo robot;
  robot.id = row.text(0);
  robot.name = row.text(1);
  robot.created_at = row.text(2);
  robot.base = row.text(3);
  robot.tip = row.text(4);
  robot.joints = static_cast<int>(row.integer(5));
  robot.summary = row.text(6);
  robot.owner = row.text(kRobotOwnerColumn);
  return robot;
}

std::string owner_condition(const api::OwnerScope& owners, int parameter) {
  return owners ? " AND owner = ?" + std::to_string(parameter) : "";
}

void bind_owner(Statement& statement, const api::OwnerScope& owners, int parameter) {
  if (owners) statement.bind_text(parameter, *owners);
}

std::optional<api::RobotInfo> select_robot(Connection& connection, const api::OwnerScope& owners, const std::string& id) {
  auto statement = connection.prepare("SELECT " + kRobotColumns + " FROM robots WHERE id = ?1" + owner_condition(owners, 2));
  statement.bind_text(1, id);
  bind_owner(statement, owners, 2);
  if (!statement.step()) return std::nullopt;
  return read_robot(statement);
}

std::optional<api::JobInfo> select_job(Connection& connection, const api::OwnerScope& owners, const std::string& id) {
  auto statement = connection.prepare("SELECT " + kJobColumns + " FROM jobs WHERE id = ?1" + owner_condition(owners, 2));
  statement.bind_text(1, id);
  bind_owner(statement, owners, 2);
  if (!statement.step()) return std::nullopt;
  return read_job(statement);
}

std::optional<api::DatasetInfo> select_dataset(Connection& connection, const api::OwnerScope& owners,
                                               const std::string& id) {
  auto statement =
      connection.prepare("SELECT " + kDatasetColumns + " FROM datasets WHERE id = ?1" + owner_condition(owners, 2));
  statement.bind_text(1, id);
  bind_owner(statement, owners, 2);
  if (!statement.step()) return std::nullopt;
  return read_dataset(statement);
}

std::optional<api::JobState> select_state(Connection& connection, const api::OwnerScope& owners, const std::string& id) {
  auto statement = connection.prepare("SELECT state FROM jobs WHERE id = ?1" + owner_condition(owners, 2));
  statement.bind_text(1, id);
  bind_owner(statement, owners, 2);
  if (!statement.step()) return std::nullopt;
  const auto state = state_from_text(statement.text(0));
  if (!state) throw StoreError("job " + id + " has an unknown state in the database");
  return state;
}

// ---- idempotency keys ----

std::optional<KeyRecord> select_key(Connection& connection, const char* scope, const std::string& owner,
                                    const std::string& key, const std::string& not_before) {
  auto statement = connection.prepare(
      "SELECT fingerprint, resource_id FROM idempotency_keys WHERE scope = ?1 AND owner = ?2 AND key = ?3 "
      "AND created_at >= ?4");
  statement.bind_text(1, scope).bind_text(2, owner).bind_text(3, key).bind_text(4, not_before);
  if (!statement.step()) return std::nullopt;
  return KeyRecord{statement.text(0), statement.text(1)};
}

void store_key(Connection& connection, const char* scope, const std::string& owner, const api::IdempotencyKey& key,
               const std::string& id, const std::string& now, const std::string& not_before) {
  auto expired = connection.prepare("DELETE FROM idempotency_keys WHERE created_at < ?1");
  expired.bind_text(1, not_before);
  expired.run();
  auto statement = connection.prepare(
      "INSERT OR REPLACE INTO idempotency_keys (scope, owner, key, fingerprint, resource_id, created_at) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6)");
  statement.bind_text(1, scope).bind_text(2, owner).bind_text(3, key.key).bind_text(4, key.fingerprint);
  statement.bind_text(5, id).bind_text(6, now);
  statement.run();
}

void forget_keys_of(Connection& connection, const char* scope, const std::string& id) {
  auto statement = connection.prepare("DELETE FROM idempotency_keys WHERE scope = ?1 AND resource_id = ?2");
  statement.bind_text(1, scope).bind_text(2, id);
  statement.run();
}

std::string unused_id(Connection& connection, const char* prefix, const std::string& exists_sql) {
  for (;;) {
    std::string id = random_id(prefix);
    auto statement = connection.prepare(exists_sql);
    statement.bind_text(1, id);
    if (!statement.step()) return id;
  }
}

void clear_progress(Connection& connection, const std::string& id) {
  auto history = connection.prepare("DELETE FROM job_history WHERE job_id = ?1");
  history.bind_text(1, id);
  history.run();
  auto estimates = connection.prepare("DELETE FROM estimates WHERE job_id = ?1");
  estimates.bind_text(1, id);
  estimates.run();
}

}  // namespace manipid::server::store::sqlite
