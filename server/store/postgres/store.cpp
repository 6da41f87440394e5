// store.cpp — the Store (store/store.h) over a PostgreSQL database that many processes share:
// its methods, each one transaction (or one statement) on a pooled connection. The rows several
// methods share are rows.cpp's, the announcements and the listener events.cpp's, the array and
// COPY literals literals.cpp's, the cache of recent samples recent_datasets.cpp's.
// How each guarantee of the contract is kept when other processes write at the same time:
//  - a claim takes the oldest queued job with FOR UPDATE SKIP LOCKED, so concurrent claimers
//    never wait on each other and never get the same job;
//  - every write of a running job is one UPDATE guarded by id, state, owner and attempt that
//    returns cancel_requested: the row lock orders it against recovery and cancel, and a lost
//    attempt's write (progress, history, end) changes nothing and is rolled back whole;
//  - an Idempotency-Key is claimed by inserting it (ON CONFLICT DO NOTHING on its primary key):
//    of two processes sending the same key, the second waits for the first's commit and then
//    finds its row — never a read-then-write (rows.cpp's claim_key); what the row it finds
//    means (replay, refuse, or take the key over) is the rule both backends share
//    (store/idempotency.h);
//  - the queue limit's count and insert run under a transaction-scoped advisory lock, so
//    concurrent submissions cannot overshoot it;
//  - recovery locks the expired jobs it takes back (SKIP LOCKED: a job another process is
//    recovering or writing is left to it);
//  - every job change is announced on the channel manipid_jobs within its transaction (NOTIFY
//    is sent at commit, never for a rollback); a listener thread per store hands them to the
//    watcher (watch_jobs).
// Single-statement reads run outside a transaction (each statement is its own snapshot).
#include "store/postgres/store.h"

#include "store/encoding.h"
#include "store/new_records.h"
#include "store/postgres/connection.h"
#include "store/postgres/events.h"
#include "store/postgres/literals.h"
#include "store/postgres/recent_datasets.h"
#include "store/postgres/rows.h"
#include "store/postgres/schema.h"
#include "store/rules.h"

#include <cstdint>
#include <stdexcept>

namespace manipid::server::store::postgres {

namespace {

/// Any fixed number: the advisory lock that orders submissions checked against the queue limit.
constexpr const char* kQueueLock = "1835101802";

/// The guard of every write of a running job: $1 id, $2 owner, $3 attempt.
const std::string kHeldBy = "WHERE id = $1 AND state = 'running' AND worker = $2 AND attempts = $3";

Params lease_params(const Lease& lease) {
  Params params;
  params.text(lease.job_id).text(lease.owner).integer(lease.attempt);
  return params;
}

std::string milliseconds_text(std::chrono::milliseconds duration) { return std::to_string(duration.count()); }

std::vector<unsigned char> encode(const double* values, Eigen::Index count) {
  return encode_doubles(values, static_cast<std::size_t>(count));
}

class PostgresStore final : public Store {
 public:
  PostgresStore(const std::string& uri, const StoreOptions& options, std::size_t connections)
      : options_(options), pool_(uri, connections), listener_(pool_.conninfo()) {
    auto connection = pool_.checkout();
    prepare_database(*connection);
  }

  PostgresStore(const PostgresStore&) = delete;
  PostgresStore& operator=(const PostgresStore&) = delete;

  bool watch_jobs(std::function<void(const JobEvent&)> on_event) override {
    listener_.watch(std::move(on_event));
    return true;
  }

  // ---- datasets ----

  DatasetOutcome insert_dataset(const std::string& owner, const std::string& name, const Trajectory& data,
                                const std::string& source_job, const std::optional<api::IdempotencyKey>& key) override {
    api::DatasetInfo dataset = describe_dataset(owner, name, data, source_job);
    const std::string keys_not_before = rfc3339_ago(options_.idempotency_ttl);

    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::write, [&]() -> DatasetOutcome {
      dataset.id = unused_id(*connection, "ds_", "datasets");
      dataset.created_at = now_rfc3339();
      if (auto answer = claim_key_for<DatasetOutcome>(
              *connection, "dataset", owner, key, dataset.id, dataset.created_at, keys_not_before,
              [&](const std::string& earlier) { return select_dataset(*connection, owner, earlier); })) {
        return *answer;
      }
      Params params;
      params.text(dataset.id)
          .text(dataset.name)
          .text(dataset.created_at)
          .text_or_null(dataset.source_job)
          .integer(dataset.joints)
          .integer(dataset.samples)
          .real(dataset.dt)
          .boolean(dataset.uniform)
          .boolean(dataset.has_torque)
          .boolean(dataset.has_reference)
          .boolean(dataset.has_rates)
          .boolean(dataset.has_accelerations)
          .bytes_or_null(encode(data.t.data(), data.t.size()))
          .bytes_or_null(encode(data.q.data(), data.q.size()))
          .bytes_or_null(encode(data.tau.data(), data.tau.size()))
          .bytes_or_null(encode(data.ref.data(), data.ref.size()))
          .bytes_or_null(encode(data.qd.data(), data.qd.size()))
          .bytes_or_null(encode(data.qdd.data(), data.qdd.size()))
          .text(owner);
      connection->exec(
          "INSERT INTO datasets (id, name, created_at, source_job, joints, samples, dt, uniform, has_torque, "
          "has_reference, has_rates, has_accelerations, t, q, tau, ref, qd, qdd, owner) "
          "VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17, $18, $19)",
          params);
      return {SubmitStatus::created, dataset};
    });
  }

  std::optional<api::DatasetInfo> find_dataset(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return select_dataset(*connection, scope, id);
  }

  std::optional<Trajectory> load_dataset(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    Params params;
    params.text(id);
    const std::string owned = owner_condition(scope, params);
    // Datasets never change once stored (ids are never reused): the samples of a recent one are
    // kept in memory, and only its existence (within the scope) is asked again (it may have been
    // deleted since).
    if (auto cached = recent_datasets_.find(id)) {
      if (connection->exec("SELECT 1 FROM datasets WHERE id = $1" + owned, params).rows() == 0) {
        if (!scope) recent_datasets_.erase(id);  // gone for everyone; another owner's is only out of sight
        return std::nullopt;
      }
      return *cached;
    }
    // Binary results: the samples arrive as the bytes stored, not as hex text.
    auto row = connection->exec(
        "SELECT samples, joints, has_torque, has_reference, has_rates, has_accelerations, t, q, tau, ref, qd, qdd "
        "FROM datasets WHERE id = $1" + owned,
        params, true);
    if (row.rows() == 0) return std::nullopt;
    StoredSamples stored;
    stored.samples = row.binary_integer(0, 0);
    stored.joints = row.binary_integer(0, 1);
    stored.has_torque = row.binary_boolean(0, 2);
    stored.has_reference = row.binary_boolean(0, 3);
    stored.has_rates = row.binary_boolean(0, 4);
    stored.has_accelerations = row.binary_boolean(0, 5);
    stored.t = row.binary_bytes(0, 6);
    stored.q = row.binary_bytes(0, 7);
    stored.tau = row.binary_bytes(0, 8);
    stored.ref = row.binary_bytes(0, 9);
    stored.qd = row.binary_bytes(0, 10);
    stored.qdd = row.binary_bytes(0, 11);
    Trajectory data = decode_samples(id, stored);
    recent_datasets_.insert(id, data);
    return data;
  }

  api::Page<api::DatasetInfo> list_datasets(const api::OwnerScope& scope, const api::PageRequest& page) override {
    const int size = effective_page_size(page.page_size);
    const std::string context = list_context(scope);
    const std::int64_t before = page.page_token.empty() ? INT64_MAX : decode_page_token(page.page_token, "d1", context);
    Params params;
    params.integer(before).integer(size + 1);
    const std::string sql = "SELECT " + kDatasetColumns + " FROM datasets WHERE seq < $1" +
                            owner_condition(scope, params) + " ORDER BY seq DESC LIMIT $2";
    auto connection = pool_.checkout();
    auto rows = connection->exec(sql, params);
    return page_of<api::DatasetInfo>(rows, size, "d1", context, kDatasetSeqColumn, read_dataset);
  }

  DeleteResult delete_dataset(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::write, [&] {
      // Another owner's dataset is not found, whoever's jobs read it.
      if (!select_dataset(*connection, scope, id)) return DeleteResult::not_found;
      auto readers = connection->exec(
          "SELECT 1 FROM jobs WHERE (dataset_id = $1 OR validation_dataset_id = $1) AND state IN ('queued', 'running') "
          "LIMIT 1",
          Params().text(id));
      if (readers.rows() > 0) return DeleteResult::in_use;
      if (connection->exec("DELETE FROM datasets WHERE id = $1", Params().text(id)).changed() == 0) {
        return DeleteResult::not_found;
      }
      recent_datasets_.erase(id);
      forget_keys_of(*connection, "dataset", id);
      return DeleteResult::deleted;
    });
  }

  // ---- robots ----

  RobotOutcome insert_robot(const NewRobot& robot, const std::optional<api::IdempotencyKey>& key) override {
    const std::string keys_not_before = rfc3339_ago(options_.idempotency_ttl);
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::write, [&]() -> RobotOutcome {
      api::RobotInfo created = describe_robot(robot);
      created.id = unused_id(*connection, "rb_", "robots");
      created.created_at = now_rfc3339();
      if (auto answer = claim_key_for<RobotOutcome>(
              *connection, "robot", robot.owner, key, created.id, created.created_at, keys_not_before,
              [&](const std::string& earlier) { return select_robot(*connection, robot.owner, earlier); })) {
        return *answer;
      }
      connection->exec(
          "INSERT INTO robots (id, name, created_at, base, tip, joints, summary, urdf, owner) "
          "VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9)",
          Params()
              .text(created.id)
              .text(created.name)
              .text(created.created_at)
              .text_or_null(created.base)
              .text_or_null(created.tip)
              .integer(created.joints)
              .text(created.summary)
              .text(robot.urdf)
              .text(robot.owner));
      return {SubmitStatus::created, created};
    });
  }

  std::optional<api::RobotInfo> find_robot(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return select_robot(*connection, scope, id);
  }

  std::optional<std::string> load_robot_urdf(const api::OwnerScope& scope, const std::string& id) override {
    Params params;
    params.text(id);
    const std::string sql = "SELECT urdf FROM robots WHERE id = $1" + owner_condition(scope, params);
    auto connection = pool_.checkout();
    auto row = connection->exec(sql, params);
    if (row.rows() == 0) return std::nullopt;
    return row.text(0, 0);
  }

  api::Page<api::RobotInfo> list_robots(const api::OwnerScope& scope, const api::PageRequest& page) override {
    const int size = effective_page_size(page.page_size);
    const std::string context = list_context(scope);
    const std::int64_t before = page.page_token.empty() ? INT64_MAX : decode_page_token(page.page_token, "r1", context);
    Params params;
    params.integer(before).integer(size + 1);
    const std::string sql = "SELECT " + kRobotColumns + " FROM robots WHERE seq < $1" + owner_condition(scope, params) +
                            " ORDER BY seq DESC LIMIT $2";
    auto connection = pool_.checkout();
    auto rows = connection->exec(sql, params);
    return page_of<api::RobotInfo>(rows, size, "r1", context, kRobotSeqColumn, read_robot);
  }

  DeleteResult delete_robot(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::write, [&] {
      // Another owner's robot is not found, whoever's jobs use it.
      if (!select_robot(*connection, scope, id)) return DeleteResult::not_found;
      auto users = connection->exec("SELECT 1 FROM jobs WHERE robot_id = $1 AND state IN ('queued', 'running') LIMIT 1",
                                    Params().text(id));
      if (users.rows() > 0) return DeleteResult::in_use;
      if (connection->exec("DELETE FROM robots WHERE id = $1", Params().text(id)).changed() == 0) {
        return DeleteResult::not_found;
      }
      forget_keys_of(*connection, "robot", id);
      return DeleteResult::deleted;
    });
  }

  // ---- jobs ----

  SubmitOutcome submit_job(const NewJob& job, const std::optional<api::IdempotencyKey>& key, int queue_limit) override {
    const std::string keys_not_before = rfc3339_ago(options_.idempotency_ttl);
    auto connection = pool_.checkout();
    try {
      return submit(*connection, job, key, queue_limit, keys_not_before);
    } catch (const QueueFull&) {
      return {SubmitStatus::queue_full, {}};
    }
  }

  std::optional<api::JobInfo> find_job(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return select_job(*connection, scope, id);
  }

  api::Page<api::JobInfo> list_jobs(const api::OwnerScope& scope, const api::JobFilter& filter,
                                    const api::PageRequest& page) override {
    const int size = effective_page_size(page.page_size);
    // The token is bound to the scope and filter: a token from another filter would skip or repeat jobs.
    const std::string context = job_list_context(scope, filter);
    const std::int64_t before = page.page_token.empty() ? INT64_MAX : decode_page_token(page.page_token, "j1", context);
    // Fixed SQL fragments per filter combination (values bound, never in the text).
    Params params;
    params.integer(before).integer(size + 1);
    std::string sql = "SELECT " + kJobColumns + " FROM jobs WHERE seq < $1";
    if (filter.state) {
      params.text(state_text(*filter.state));
      sql += " AND state = $" + std::to_string(params.size());
    }
    if (filter.kind) {
      params.text(kind_text(*filter.kind));
      sql += " AND kind = $" + std::to_string(params.size());
    }
    if (!filter.robot_id.empty()) {
      params.text(filter.robot_id);
      sql += " AND robot_id = $" + std::to_string(params.size());
    }
    sql += owner_condition(scope, params);
    sql += " ORDER BY seq DESC LIMIT $2";
    auto connection = pool_.checkout();
    auto rows = connection->exec(sql, params);
    return page_of<api::JobInfo>(rows, size, "j1", context, kJobSeqColumn, read_job);
  }

  std::optional<api::JobInfo> claim_next_job(const std::string& owner, std::chrono::milliseconds lease) override {
    auto connection = pool_.checkout();
    // One statement, atomic on its own: no BEGIN/COMMIT (two round trips of every claim, and
    // idle workers claim every second).
    return run_transaction(*connection, TransactionKind::statement, [&]() -> std::optional<api::JobInfo> {
      auto claimed = connection->exec(
          "WITH next AS (SELECT seq FROM jobs WHERE state = 'queued' ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED) "
          "UPDATE jobs SET state = 'running', started_at = $1, attempts = attempts + 1, worker = $2, "
          "lease_expires_at = now() + $3::double precision * interval '1 millisecond' "
          "FROM next WHERE jobs.seq = next.seq RETURNING " + qualified_job_columns(),
          Params().text(now_rfc3339()).text(owner).text(milliseconds_text(lease)));
      if (claimed.rows() == 0) return std::nullopt;
      return read_job(claimed, 0);
    });
  }

  LeaseStatus renew_lease(const Lease& lease, std::chrono::milliseconds duration) override {
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::write_in_place,
                           [&] { return extend(*connection, lease, duration, nullptr); });
  }

  LeaseStatus record_progress(const Lease& lease, long evaluations, std::optional<double> best_cost,
                              const std::vector<api::HistoryEntry>& batch) override {
    const std::string rows = history_rows(lease.job_id, batch);
    auto connection = pool_.checkout();
    if (!rows.empty()) prepare_staging(*connection);
    return run_transaction(*connection, TransactionKind::write, [&] {
      // The guarded update first: a batch of an attempt that lost its lease is dropped whole.
      const Progress progress{evaluations, best_cost};
      const LeaseStatus status = extend(*connection, lease, std::nullopt, &progress);
      if (status != LeaseStatus::lost) write_history(*connection, rows);
      return status;
    });
  }

  bool finish_job(const Lease& lease, const JobEnd& end) override {
    if (!api::is_terminal(end.state)) throw std::invalid_argument("finish_job needs succeeded, failed or cancelled");
    const std::string rows = history_rows(lease.job_id, end.history);
    auto connection = pool_.checkout();
    if (!rows.empty()) prepare_staging(*connection);
    return run_transaction(*connection, TransactionKind::write, [&] {
      // Only the attempt that holds the lease ends the job, and only once. One round trip: the
      // guarded end with its progress, an earlier attempt's estimates gone, the announcement.
      Params params = lease_params(lease);
      params.text(state_text(end.state)).text(now_rfc3339()).text_or_null(end.result).text_or_null(end.error);
      params.text_or_null(end.dataset_id);
      if (end.evaluations) {
        params.integer(*end.evaluations).real_or_null(end.best_cost);
      } else {
        params.null().null();
      }
      auto ended = connection->exec(
          "WITH ended AS (UPDATE jobs SET state = $4, finished_at = $5, result = $6, error = $7, "
          "dataset_id = coalesce($8, dataset_id), worker = NULL, lease_expires_at = NULL, "
          "evaluations = coalesce($9::bigint, evaluations), "
          "best_cost = CASE WHEN $9::bigint IS NULL THEN best_cost ELSE $10::double precision END " +
              kHeldBy + " RETURNING id), "
          "gone AS (DELETE FROM estimates WHERE job_id IN (SELECT id FROM ended)) " +
              announcement("changed", "ended"),
          params);
      if (ended.rows() == 0) return false;
      write_history(*connection, rows);
      if (!end.estimates.empty()) {
        // One statement for all rows (arrays unnested side by side); a name given twice keeps its last row.
        std::vector<std::string> names;
        std::vector<std::optional<double>> values, errors;
        for (const auto& estimate : end.estimates) {
          names.push_back(estimate.name);
          values.emplace_back(estimate.value);
          errors.push_back(estimate.std_error);
        }
        connection->exec(
            "INSERT INTO estimates (job_id, name, value, std_error) "
            "SELECT DISTINCT ON (name) $1, name, value, std_error FROM unnest($2::text[], $3::float8[], $4::float8[]) "
            "WITH ORDINALITY AS row (name, value, std_error, position) ORDER BY name, position DESC",
            Params().text(lease.job_id).text(array_literal(names)).text(array_literal(values)).text(array_literal(errors)));
      }
      return true;
    });
  }

  void requeue_job(const Lease& lease) override {
    auto connection = pool_.checkout();
    run_transaction(*connection, TransactionKind::write, [&] {
      auto running = connection->exec("SELECT cancel_requested FROM jobs " + kHeldBy + " FOR UPDATE", lease_params(lease));
      if (running.rows() == 0) return;
      const std::string& id = lease.job_id;
      if (running.boolean(0, 0)) {
        // The client asked to cancel it: running it again would ignore that.
        connection->exec(
            "UPDATE jobs SET state = 'cancelled', finished_at = $2, worker = NULL, lease_expires_at = NULL WHERE id = $1",
            Params().text(id).text(now_rfc3339()));
        announce(*connection, "changed", id);
        return;
      }
      clear_progress(*connection, {id});
      connection->exec(
          "UPDATE jobs SET state = 'queued', started_at = NULL, cancel_requested = false, evaluations = 0, "
          "best_cost = NULL, worker = NULL, lease_expires_at = NULL WHERE id = $1",
          Params().text(id));
      announce(*connection, "queued", id);
    });
  }

  CancelOutcome cancel_job(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::write, [&] {
      const auto state = select_state(*connection, scope, id, true);
      if (!state) return CancelOutcome::not_found;
      if (*state == api::JobState::queued) {
        connection->exec("UPDATE jobs SET state = 'cancelled', finished_at = $2 WHERE id = $1",
                         Params().text(id).text(now_rfc3339()));
        announce(*connection, "changed", id);
        return CancelOutcome::cancelled_now;
      }
      if (*state == api::JobState::running) {
        connection->exec("UPDATE jobs SET cancel_requested = true WHERE id = $1", Params().text(id));
        announce(*connection, "cancel", id);
        return CancelOutcome::requested;
      }
      return CancelOutcome::already_finished;
    });
  }

  DeleteResult delete_job(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::write, [&] {
      const auto state = select_state(*connection, scope, id, true);
      if (!state) return DeleteResult::not_found;
      if (!api::is_terminal(*state)) return DeleteResult::in_use;
      clear_progress(*connection, {id});
      forget_keys_of(*connection, "job", id);
      connection->exec("DELETE FROM jobs WHERE id = $1", Params().text(id));
      return DeleteResult::deleted;
    });
  }

  std::optional<api::Page<api::HistoryEntry>> history(const api::OwnerScope& scope, const std::string& id,
                                                      const api::PageRequest& page) override {
    const int size = effective_page_size(page.page_size);
    const bool first_page = page.page_token.empty();
    const std::int64_t after = first_page ? -1 : decode_page_token(page.page_token, "h1", id);
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::read, [&]() -> std::optional<api::Page<api::HistoryEntry>> {
      if (!select_state(*connection, scope, id, false)) return std::nullopt;
      auto rows = connection->exec(
          "SELECT idx, cost, theta FROM job_history WHERE job_id = $1 AND idx > $2 ORDER BY idx LIMIT $3",
          Params().text(id).integer(after).integer(size + 1));
      api::Page<api::HistoryEntry> result;
      for (int row = 0; row < rows.rows(); ++row) {
        if (static_cast<int>(result.items.size()) == size) {
          result.next_page_token = encode_page_token("h1", result.items.back().index, id);
          break;
        }
        result.items.push_back(history_entry(rows, row, id));
      }
      return result;
    });
  }

  std::optional<api::HistoryOverview> history_overview(const api::OwnerScope& scope, const std::string& id,
                                                       long max_points) override {
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::read, [&]() -> std::optional<api::HistoryOverview> {
      if (!select_state(*connection, scope, id, false)) return std::nullopt;
      api::HistoryOverview overview;
      auto extent = connection->exec("SELECT count(*), min(idx), max(idx) FROM job_history WHERE job_id = $1",
                                     Params().text(id));
      overview.total = static_cast<long>(extent.integer(0, 0));
      if (overview.total == 0) return overview;
      const std::int64_t first = extent.integer(0, 1), last = extent.integer(0, 2);
      auto best = connection->exec(
          "SELECT idx FROM job_history WHERE job_id = $1 AND cost IS NOT NULL ORDER BY cost, idx LIMIT 1",
          Params().text(id));
      if (best.rows() > 0) overview.best_index = static_cast<long>(best.integer(0, 0));
      overview.stride = api::thinning_stride(overview.total, max_points);
      auto rows = connection->exec(
          "SELECT idx, cost, theta FROM job_history WHERE job_id = $1 "
          "AND ((idx - $2) % $3 = 0 OR idx = $4 OR idx = $5) ORDER BY idx",
          Params().text(id).integer(first).integer(overview.stride).integer(last).integer(overview.best_index.value_or(last)));
      for (int row = 0; row < rows.rows(); ++row) overview.items.push_back(history_entry(rows, row, id));
      return overview;
    });
  }

  // ---- the process's life ----

  RecoveryOutcome recover_interrupted_jobs(int max_attempts, const std::function<std::string(int losses)>& lost_error,
                                           const std::function<bool(const std::string& worker)>& gone) override {
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::write, [&] {
      auto running = connection->exec("SELECT id, worker FROM jobs WHERE state = 'running' FOR UPDATE SKIP LOCKED");
      std::vector<std::string> lost;
      for (int row = 0; row < running.rows(); ++row) {
        const std::string worker = running.text(row, 1);
        if (worker.empty() || gone(worker)) lost.push_back(running.text(row, 0));
      }
      return recover_lost(*connection, lost, max_attempts, lost_error);
    });
  }

  RecoveryOutcome recover_expired_leases(int max_attempts,
                                         const std::function<std::string(int losses)>& lost_error) override {
    auto connection = pool_.checkout();
    return run_transaction(*connection, TransactionKind::write_in_place, [&] {
      auto expired = connection->exec(
          "SELECT id FROM jobs WHERE state = 'running' AND (lease_expires_at IS NULL OR lease_expires_at < now()) "
          "FOR UPDATE SKIP LOCKED");
      std::vector<std::string> lost;
      for (int row = 0; row < expired.rows(); ++row) lost.push_back(expired.text(row, 0));
      return recover_lost(*connection, lost, max_attempts, lost_error);
    });
  }

  std::map<api::JobState, long> count_jobs_by_state() override {
    std::map<api::JobState, long> counts;
    for (auto state : {api::JobState::queued, api::JobState::running, api::JobState::succeeded, api::JobState::failed,
                       api::JobState::cancelled}) {
      counts[state] = 0;
    }
    auto connection = pool_.checkout();
    auto rows = connection->exec("SELECT state, count(*) FROM jobs GROUP BY state");
    for (int row = 0; row < rows.rows(); ++row) {
      const auto state = state_from_text(rows.text(row, 0));
      if (!state) throw StoreError("a job has an unknown state in the database");
      counts[*state] = static_cast<long>(rows.integer(row, 1));
    }
    return counts;
  }

  std::optional<std::string> write_trouble() const override { return pool_.health().trouble(); }

 private:
  /// Thrown inside submit_job's transaction to roll it back whole; never leaves the store.
  struct QueueFull {};

  struct Progress {
    long evaluations = 0;
    std::optional<double> best_cost;
  };

  /// submit_job's transaction; QueueFull rolls it back whole (the key claimed in it too).
  static SubmitOutcome submit(Connection& connection, const NewJob& job, const std::optional<api::IdempotencyKey>& key,
                              int queue_limit, const std::string& keys_not_before) {
    return run_transaction(connection, TransactionKind::write, [&]() -> SubmitOutcome {
      api::JobInfo created = describe_job(job);
      created.id = random_id("job_");
      created.created_at = now_rfc3339();
      // The key first: a replay or a reused key is answered whatever the queue's length.
      if (auto answer = claim_key_for<SubmitOutcome>(
              connection, "job", job.owner, key, created.id, created.created_at, keys_not_before,
              [&](const std::string& earlier) { return select_job(connection, job.owner, earlier); })) {
        return *answer;
      }
      if (queue_limit > 0) {
        connection.exec(std::string("SELECT pg_advisory_xact_lock(") + kQueueLock + ")");
        auto count = connection.exec("SELECT count(*) FROM jobs WHERE state = 'queued'");
        if (count.integer(0, 0) >= queue_limit) {
          // Nothing of this submission may stay (the key above is rolled back with it).
          throw QueueFull();
        }
      }
      // One round trip: the row and its announcement. An id drawn twice (2^-64) is a conflict:
      // the transaction runs again with a new one.
      auto added = connection.exec(
          "WITH added AS (INSERT INTO jobs (id, kind, state, request, dataset_id, created_at, robot_id, "
          "validation_dataset_id, owner) VALUES ($1, $2, 'queued', $3, $4, $5, $6, $7, $8) ON CONFLICT (id) DO NOTHING "
          "RETURNING id) " + announcement("queued", "added"),
          Params()
              .text(created.id)
              .text(kind_text(job.kind))
              .text(job.request)
              .text_or_null(job.dataset_id)
              .text(created.created_at)
              .text_or_null(job.robot_id)
              .text_or_null(job.validation_dataset_id)
              .text(job.owner));
      if (added.rows() == 0) throw ConflictRetry("job id " + created.id + " drawn twice");
      return {SubmitStatus::created, created};
    });
  }

  /// The guarded update of a held lease: progress and/or a new expiry; what it learned.
  static LeaseStatus extend(Connection& connection, const Lease& lease, std::optional<std::chrono::milliseconds> duration,
                            const Progress* progress) {
    Params params = lease_params(lease);
    std::string sql = "UPDATE jobs SET lease_expires_at = ";
    if (duration) {
      params.text(milliseconds_text(*duration));
      sql += "now() + $4::double precision * interval '1 millisecond'";
    } else {
      sql += "lease_expires_at";
    }
    if (progress) {
      params.integer(progress->evaluations).real_or_null(progress->best_cost);
      const int at = params.size() - 1;
      sql += ", evaluations = $" + std::to_string(at) + ", best_cost = $" + std::to_string(at + 1);
    }
    sql += " " + kHeldBy + " RETURNING cancel_requested";
    auto updated = connection.exec(sql, params);
    if (updated.rows() == 0) return LeaseStatus::lost;
    return updated.boolean(0, 0) ? LeaseStatus::cancel_requested : LeaseStatus::held;
  }

  /// Ends or requeues the running jobs `lost` (their worker is gone; their rows are locked).
  static RecoveryOutcome recover_lost(Connection& connection, const std::vector<std::string>& lost, int max_attempts,
                                      const std::function<std::string(int losses)>& lost_error) {
    RecoveryOutcome outcome;
    if (lost.empty()) return outcome;
    const std::string now = now_rfc3339();
    // Cancellation was asked for before the worker went: honour it rather than run the job again.
    auto cancelled = connection.exec(
        "UPDATE jobs SET state = 'cancelled', finished_at = $1, worker = NULL, lease_expires_at = NULL "
        "WHERE id = ANY($2::text[]) AND state = 'running' AND cancel_requested RETURNING id",
        Params().text(now).text(id_array(lost)));
    outcome.cancelled = cancelled.rows();
    for (int row = 0; row < cancelled.rows(); ++row) announce(connection, "changed", cancelled.text(row, 0));
    auto counted = connection.exec(
        "UPDATE jobs SET worker_losses = worker_losses + 1 WHERE id = ANY($1::text[]) AND state = 'running' "
        "RETURNING id, worker_losses",
        Params().text(id_array(lost)));
    std::vector<std::string> requeue;
    std::vector<std::pair<std::string, int>> poisoned;
    for (int row = 0; row < counted.rows(); ++row) {
      const int losses = static_cast<int>(counted.integer(row, 1));
      if (losses >= max_attempts) poisoned.emplace_back(counted.text(row, 0), losses);
      else requeue.push_back(counted.text(row, 0));
    }
    // The attempt that died leaves nothing behind: its history and estimates go.
    std::vector<std::string> ended;
    for (const auto& [id, losses] : poisoned) ended.push_back(id);
    ended.insert(ended.end(), requeue.begin(), requeue.end());
    clear_progress(connection, ended);
    // A job that took its worker down max_attempts times is failed, never run again.
    for (const auto& [id, losses] : poisoned) {
      connection.exec(
          "UPDATE jobs SET state = 'failed', finished_at = $2, error = $3, worker = NULL, lease_expires_at = NULL "
          "WHERE id = $1",
          Params().text(id).text(now).text(lost_error(losses)));
      outcome.failed.push_back(id);
      announce(connection, "changed", id);
    }
    if (!requeue.empty()) {
      auto requeued = connection.exec(
          "UPDATE jobs SET state = 'queued', started_at = NULL, evaluations = 0, best_cost = NULL, worker = NULL, "
          "lease_expires_at = NULL WHERE id = ANY($1::text[])",
          Params().text(id_array(requeue)));
      outcome.requeued = static_cast<int>(requeued.changed());
      for (const std::string& id : requeue) announce(connection, "queued", id);
    }
    return outcome;
  }

  StoreOptions options_;
  ConnectionPool pool_;
  RecentDatasets recent_datasets_{64u << 20};  ///< 64 MiB of samples
  JobListener listener_;  ///< last: its thread stops before the members above go
};

}  // namespace

std::unique_ptr<Store> open_store(const std::string& uri, const StoreOptions& options, std::size_t connections) {
  return std::make_unique<PostgresStore>(uri, options, connections);
}

}  // namespace manipid::server::store::postgres
