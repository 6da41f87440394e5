// rows.cpp — shared row reads and writes of the PostgreSQL store (see rows.h).
#include "store/postgres/rows.h"

#include "store/encoding.h"
#include "store/postgres/literals.h"
#include "store/rules.h"

namespace manipid::server::store::postgres {

std::string qualified_job_columns() {
  std::string out;
  std::size_t start = 0;
  while (start < kJobColumns.size()) {
    std::size_t end = kJobColumns.find(", ", start);
    if (end == std::string::npos) end = kJobColumns.size();
    if (!out.empty()) out += ", ";
    out += "jobs." + kJobColumns.substr(start, end - start);
    start = end + 2;
  }
  return out;
}

api::JobInfo read_job(const Result& rows, int row) {
  api::JobInfo job;
  job.id = rows.text(row, 0);
  const auto kind = kind_from_text(rows.text(row, 1));
  const auto state = state_from_text(rows.text(row, 2));
  if (!kind || !state) throw StoreError("job " + job.id + " has an unknown kind or state in the database");
  job.kind = *kind;
  job.state = *state;
  job.created_at = rows.text(row, 3);
  job.started_at = rows.text(row, 4);
  job.finished_at = rows.text(row, 5);
  job.request = rows.text(row, 6);
  job.dataset_id = rows.text(row, 7);
  job.evaluations = static_cast<long>(rows.integer(row, 8));
  job.best_cost = rows.real_or_null(row, 9);
  job.cancel_requested = rows.boolean(row, 10);
  job.attempts = static_cast<int>(rows.integer(row, 11));
  job.result = rows.text(row, 12);
  job.error = rows.text(row, 13);
  job.robot_id = rows.text(row, 14);
  job.validation_dataset_id = rows.text(row, 15);
  job.worker = rows.text(row, 16);
  job.owner = rows.text(row, kJobOwnerColumn);
  return job;
}

api::DatasetInfo read_dataset(const Result& rows, int row) {
  api::DatasetInfo dataset;
  dataset.id = rows.text(row, 0);
  dataset.name = rows.text(row, 1);
  dataset.created_at = rows.text(row, 2);
  dataset.source_job = rows.text(row, 3);
  dataset.joints = static_cast<int>(rows.integer(row, 4));
  dataset.samples = static_cast<int>(rows.integer(row, 5));
  dataset.dt = rows.real(row, 6);
  dataset.has_torque = rows.boolean(row, 7);
  dataset.has_reference = rows.boolean(row, 8);
  dataset.uniform = rows.boolean(row, 9);
  dataset.has_rates = rows.boolean(row, 10);
  dataset.has_accelerations = rows.boolean(row, 11);
  dataset.owner = rows.text(row, kDatasetOwnerColumn);
  return dataset;
}

api::RobotInfo read_robot(const Result& rows, int row) {
  api::RobotInfo robot;
  robot.id = rows.text(row, 0);
  robot.name = rows.text(row, 1);
  robot.created_at = rows.text(row, 2);
  robot.base = rows.text(row, 3);
  robot.tip = rows.text(row, 4);
  robot.joints = static_cast<int>(rows.integer(row, 5));
  robot.summary = rows.text(row, 6);
  robot.owner = rows.text(row, kRobotOwnerColumn);
  return robot;
}

api::HistoryEntry history_entry(const Result& rows, int row, const std::string& id) {
  return decode_history_entry(rows.integer(row, 0), rows.real_or_null(row, 1), rows.bytes(row, 2), id);
}

std::string owner_condition(const api::OwnerScope& owners, Params& params) {
  if (!owners) return "";
  params.text(*owners);
  return " AND owner = $" + std::to_string(params.size());
}

std::optional<api::JobInfo> select_job(Connection& connection, const api::OwnerScope& owners, const std::string& id) {
  Params params;
  params.text(id);
  const std::string sql = "SELECT " + kJobColumns + " FROM jobs WHERE id = $1" + owner_condition(owners, params);
  auto rows = connection.exec(sql, params);
  if (rows.rows() == 0) return std::nullopt;
  return read_job(rows, 0);
}

std::optional<api::DatasetInfo> select_dataset(Connection& connection, const api::OwnerScope& owners,
                                               const std::string& id) {
  Params params;
  params.text(id);
  const std::string sql = "SELECT " + kDatasetColumns + " FROM datasets WHERE id = $1" + owner_condition(owners, params);
  auto rows = connection.exec(sql, params);
  if (rows.rows() == 0) return std::nullopt;
  return read_dataset(rows, 0);
}

std::optional<api::RobotInfo> select_robot(Connection& connection, const api::OwnerScope& owners, const std::string& id) {
  Params params;
  params.text(id);
  const std::string sql = "SELECT " + kRobotColumns + " FROM robots WHERE id = $1" + owner_condition(owners, params);
  auto rows = connection.exec(sql, params);
  if (rows.rows() == 0) return std::nullopt;
  return read_robot(rows, 0);
}

std::optional<api::JobState> select_state(Connection& connection, const api::OwnerScope& owners, const std::string& id,
                                          bool lock) {
  Params params;
  params.text(id);
  const std::string sql = "SELECT state FROM jobs WHERE id = $1" + owner_condition(owners, params) + (lock ? " FOR UPDATE" : "");
  auto rows = connection.exec(sql, params);
  if (rows.rows() == 0) return std::nullopt;
  const auto state = state_from_text(rows.text(0, 0));
  if (!state) throw StoreError("job " + id + " has an unknown state in the database");
  return state;
}

std::string unused_id(Connection& connection, const char* prefix, const std::string& table) {
  for (;;) {
    std::string id = random_id(prefix);
    if (connection.exec("SELECT 1 FROM " + table + " WHERE id = $1", Params().text(id)).rows() == 0) return id;
  }
}

// ---- idempotency keys ----

std::optional<KeyRecord> claim_key(Connection& connection, const char* scope, const std::string& owner,
                                   const api::IdempotencyKey& key, const std::string& id, const std::string& now,
                                   const std::string& not_before) {
  connection.exec("DELETE FROM idempotency_keys WHERE created_at < $1", Params().text(not_before));
  auto inserted = connection.exec(
      "INSERT INTO idempotency_keys (scope, owner, key, fingerprint, resource_id, created_at) "
      "VALUES ($1, $2, $3, $4, $5, $6) ON CONFLICT (scope, owner, key) DO NOTHING",
      Params().text(scope).text(owner).text(key.key).text(key.fingerprint).text(id).text(now));
  if (inserted.changed() == 1) return std::nullopt;
  auto held = connection.exec(
      "SELECT fingerprint, resource_id FROM idempotency_keys WHERE scope = $1 AND owner = $2 AND key = $3",
      Params().text(scope).text(owner).text(key.key));
  if (held.rows() == 0) throw ConflictRetry("an Idempotency-Key was removed while it was being claimed");
  return KeyRecord{held.text(0, 0), held.text(0, 1)};
}

void retake_key(Connection& connection, const char* scope, const std::string& owner, const api::IdempotencyKey& key,
                const std::string& id, const std::string& now) {
  connection.exec(
      "UPDATE idempotency_keys SET resource_id = $4, created_at = $5 WHERE scope = $1 AND owner = $2 AND key = $3",
      Params().text(scope).text(owner).text(key.key).text(id).text(now));
}

void forget_keys_of(Connection& connection, const char* scope, const std::string& id) {
  connection.exec("DELETE FROM idempotency_keys WHERE scope = $1 AND resource_id = $2", Params().text(scope).text(id));
}

// ---- a running job's progress ----

void clear_progress(Connection& connection, const std::vector<std::string>& ids) {
  const std::string array = id_array(ids);
  connection.exec("DELETE FROM job_history WHERE job_id = ANY($1::text[])", Params().text(array));
  connection.exec("DELETE FROM estimates WHERE job_id = ANY($1::text[])", Params().text(array));
}

void prepare_staging(Connection& connection) {
  if (connection.staging_ready) return;
  connection.execute(
      "CREATE TEMP TABLE IF NOT EXISTS history_in (job_id text, idx bigint, cost double precision, theta bytea) "
      "ON COMMIT DELETE ROWS");
  connection.staging_ready = true;
}

void write_history(Connection& connection, const std::string& rows) {
  if (rows.empty()) return;
  connection.copy_in("COPY history_in (job_id, idx, cost, theta) FROM STDIN", rows);
  connection.exec(
      "INSERT INTO job_history (job_id, idx, cost, theta) SELECT job_id, idx, cost, theta FROM history_in "
      "ON CONFLICT (job_id, idx) DO UPDATE SET cost = excluded.cost, theta = excluded.theta");
}

}  // namespace manipid::server::store::postgres
