// store.cpp — the Store (store/store.h) over one SQLite file: datasets with their samples,
// jobs and their life cycle, cost histories, estimates and idempotency keys. Every state
// change is one BEGIN IMMEDIATE transaction run through run_transaction (retried on BUSY).
#include "store/sqlite/connection.h"
#include "store/encoding.h"
#include "store/idempotency.h"
#include "store/new_records.h"
#include "store/sqlite/rows.h"
#include "store/sqlite/schema.h"
#include "store/sqlite/store.h"

#include "manipid/api/problem.h"
#include "store/rules.h"

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace manipid::server::store::sqlite {

namespace {

/// One job_history row (idx, cost, theta) of the statement's current step.
api::HistoryEntry history_entry(const Statement& rows, const std::string& id) {
  return decode_history_entry(rows.integer(0), rows.real_or_null(1), rows.blob(2), id);
}

class SqliteStore final : public Store {
 public:
  SqliteStore(const std::string& path, const StoreOptions& options)
      : options_(options), pool_(path, open_and_prepare(path)) {}

  // ---- datasets ----

  DatasetOutcome insert_dataset(const std::string& owner, const std::string& name, const Trajectory& data,
                                const std::string& source_job, const std::optional<api::IdempotencyKey>& key) override {
    api::DatasetInfo dataset = describe_dataset(owner, name, data, source_job);
    // Encoded before the transaction (the write lock is held only for the insert itself); on a
    // little-endian machine the dataset's own memory, bound without a copy.
    std::vector<unsigned char> scratch[6];
    const auto stored = [&](const auto& block, int i) {
      return doubles_as_stored(block.data(), static_cast<std::size_t>(block.size()), scratch[i]);
    };
    const auto t = stored(data.t, 0), q = stored(data.q, 1), tau = stored(data.tau, 2), ref = stored(data.ref, 3),
               qd = stored(data.qd, 4), qdd = stored(data.qdd, 5);

    const std::string keys_not_before = rfc3339_ago(options_.idempotency_ttl);
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&]() -> DatasetOutcome {
      if (key) {
        if (auto answer = answer_from_key<DatasetOutcome>(
                select_key(*connection, "dataset", owner, key->key, keys_not_before), *key,
                [&](const std::string& earlier) { return select_dataset(*connection, owner, earlier); })) {
          return *answer;
        }
      }
      dataset.id = unused_id(*connection, "ds_", "SELECT 1 FROM datasets WHERE id = ?1");
      dataset.created_at = now_rfc3339();

      auto insert = connection->prepare(
          "INSERT INTO datasets (id, name, created_at, source_job, joints, samples, dt, has_torque, "
          "has_reference, t, q, tau, ref, uniform, has_rates, qd, has_accelerations, qdd, owner) "
          "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19)");
      insert.bind_text(1, dataset.id)
          .bind_text(2, dataset.name)
          .bind_text(3, dataset.created_at)
          .bind_text_or_null(4, dataset.source_job)
          .bind_integer(5, dataset.joints)
          .bind_integer(6, dataset.samples)
          .bind_real(7, dataset.dt)
          .bind_integer(8, dataset.has_torque ? 1 : 0)
          .bind_integer(9, dataset.has_reference ? 1 : 0)
          .bind_blob_or_null(10, t)
          .bind_blob_or_null(11, q)
          .bind_blob_or_null(12, tau)
          .bind_blob_or_null(13, ref)
          .bind_integer(14, dataset.uniform ? 1 : 0)
          .bind_integer(15, dataset.has_rates ? 1 : 0)
          .bind_blob_or_null(16, qd)
          .bind_integer(17, dataset.has_accelerations ? 1 : 0)
          .bind_blob_or_null(18, qdd)
          .bind_text(19, owner);
      insert.run();
      if (key) store_key(*connection, "dataset", owner, *key, dataset.id, dataset.created_at, keys_not_before);
      return {SubmitStatus::created, dataset};
    });
  }

  std::optional<api::DatasetInfo> find_dataset(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read,
                                   [&] { return select_dataset(*connection, scope, id); });
  }

  std::optional<Trajectory> load_dataset(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read, [&]() -> std::optional<Trajectory> {
      auto row = connection->prepare(
          "SELECT samples, joints, has_torque, has_reference, t, q, tau, ref, has_rates, qd, has_accelerations, qdd "
          "FROM datasets WHERE id = ?1" + owner_condition(scope, 2));
      row.bind_text(1, id);
      bind_owner(row, scope, 2);
      if (!row.step()) return std::nullopt;
      StoredSamples stored;
      stored.samples = row.integer(0);
      stored.joints = row.integer(1);
      stored.has_torque = row.integer(2) != 0;
      stored.has_reference = row.integer(3) != 0;
      stored.has_rates = row.integer(8) != 0;
      stored.has_accelerations = row.integer(10) != 0;
      stored.t = row.blob(4);
      stored.q = row.blob(5);
      stored.tau = row.blob(6);
      stored.ref = row.blob(7);
      stored.qd = row.blob(9);
      stored.qdd = row.blob(11);
      return decode_samples(id, stored);
    });
  }

  api::Page<api::DatasetInfo> list_datasets(const api::OwnerScope& scope, const api::PageRequest& page) override {
    const int size = effective_page_size(page.page_size);
    const std::string context = list_context(scope);
    const std::int64_t before =
        page.page_token.empty() ? INT64_MAX : decode_page_token(page.page_token, "d1", context);
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read, [&] {
      auto rows = connection->prepare("SELECT " + kDatasetColumns + " FROM datasets WHERE seq < ?1" +
                                      owner_condition(scope, 3) + " ORDER BY seq DESC LIMIT ?2");
      rows.bind_integer(1, before).bind_integer(2, size + 1);  // one more tells whether a next page exists
      bind_owner(rows, scope, 3);
      api::Page<api::DatasetInfo> result;
      std::int64_t last_seq = 0;
      while (rows.step()) {
        if (static_cast<int>(result.items.size()) == size) {
          result.next_page_token = encode_page_token("d1", last_seq, context);
          break;
        }
        result.items.push_back(read_dataset(rows));
        last_seq = rows.integer(kDatasetSeqColumn);
      }
      return result;
    });
  }

  DeleteResult delete_dataset(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&] {
      // Another owner's dataset is not found, whoever's jobs read it.
      if (!select_dataset(*connection, scope, id)) return DeleteResult::not_found;
      auto readers = connection->prepare(
          "SELECT 1 FROM jobs WHERE (dataset_id = ?1 OR validation_dataset_id = ?1) AND state IN ('queued', 'running') "
          "LIMIT 1");
      readers.bind_text(1, id);
      if (readers.step()) return DeleteResult::in_use;
      auto remove = connection->prepare("DELETE FROM datasets WHERE id = ?1");
      remove.bind_text(1, id);
      remove.run();
      if (connection->changes() == 0) return DeleteResult::not_found;
      forget_keys_of(*connection, "dataset", id);
      return DeleteResult::deleted;
    });
  }

  // ---- robots ----

  RobotOutcome insert_robot(const NewRobot& robot, const std::optional<api::IdempotencyKey>& key) override {
    const std::string keys_not_before = rfc3339_ago(options_.idempotency_ttl);
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&]() -> RobotOutcome {
      if (key) {
        if (auto answer = answer_from_key<RobotOutcome>(
                select_key(*connection, "robot", robot.owner, key->key, keys_not_before), *key,
                [&](const std::string& earlier) { return sqlite::select_robot(*connection, robot.owner, earlier); })) {
          return *answer;
        }
      }
      api::RobotInfo created = describe_robot(robot);
      created.id = unused_id(*connection, "rb_", "SELECT 1 FROM robots WHERE id = ?1");
      created.created_at = now_rfc3339();
      auto insert = connection->prepare(
          "INSERT INTO robots (id, name, created_at, base, tip, joints, summary, urdf, owner) "
          "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)");
      insert.bind_text(1, created.id)
          .bind_text(2, created.name)
          .bind_text(3, created.created_at)
          .bind_text_or_null(4, created.base)
          .bind_text_or_null(5, created.tip)
          .bind_integer(6, created.joints)
          .bind_text(7, created.summary)
          .bind_text(8, robot.urdf)
          .bind_text(9, robot.owner);
      insert.run();
      if (key) store_key(*connection, "robot", robot.owner, *key, created.id, created.created_at, keys_not_before);
      return {SubmitStatus::created, created};
    });
  }

  std::optional<api::RobotInfo> find_robot(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read,
                                   [&] { return sqlite::select_robot(*connection, scope, id); });
  }

  std::optional<std::string> load_robot_urdf(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read, [&]() -> std::optional<std::string> {
      auto row = connection->prepare("SELECT urdf FROM robots WHERE id = ?1" + owner_condition(scope, 2));
      row.bind_text(1, id);
      bind_owner(row, scope, 2);
      if (!row.step()) return std::nullopt;
      return row.text(0);
    });
  }

  api::Page<api::RobotInfo> list_robots(const api::OwnerScope& scope, const api::PageRequest& page) override {
    const int size = effective_page_size(page.page_size);
    const std::string context = list_context(scope);
    const std::int64_t before =
        page.page_token.empty() ? INT64_MAX : decode_page_token(page.page_token, "r1", context);
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read, [&] {
      auto rows = connection->prepare("SELECT " + kRobotColumns + " FROM robots WHERE seq < ?1" +
                                      owner_condition(scope, 3) + " ORDER BY seq DESC LIMIT ?2");
      rows.bind_integer(1, before).bind_integer(2, size + 1);
      bind_owner(rows, scope, 3);
      api::Page<api::RobotInfo> result;
      std::int64_t last_seq = 0;
      while (rows.step()) {
        if (static_cast<int>(result.items.size()) == size) {
          result.next_page_token = encode_page_token("r1", last_seq, context);
          break;
        }
        result.items.push_back(sqlite::read_robot(rows));
        last_seq = rows.integer(kRobotSeqColumn);
      }
      return result;
    });
  }

  DeleteResult delete_robot(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&] {
      // Another owner's robot is not found, whoever's jobs use it.
      if (!sqlite::select_robot(*connection, scope, id)) return DeleteResult::not_found;
      auto users = connection->prepare(
          "SELECT 1 FROM jobs WHERE robot_id = ?1 AND state IN ('queued', 'running') LIMIT 1");
      users.bind_text(1, id);
      if (users.step()) return DeleteResult::in_use;
      auto remove = connection->prepare("DELETE FROM robots WHERE id = ?1");
      remove.bind_text(1, id);
      remove.run();
      if (connection->changes() == 0) return DeleteResult::not_found;
      forget_keys_of(*connection, "robot", id);
      return DeleteResult::deleted;
    });
  }

  // ---- jobs ----

  SubmitOutcome submit_job(const NewJob& job, const std::optional<api::IdempotencyKey>& key,
                           int queue_limit) override {
    const std::string keys_not_before = rfc3339_ago(options_.idempotency_ttl);
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&]() -> SubmitOutcome {
      if (key) {
        if (auto answer = answer_from_key<SubmitOutcome>(
                select_key(*connection, "job", job.owner, key->key, keys_not_before), *key,
                [&](const std::string& earlier) { return select_job(*connection, job.owner, earlier); })) {
          return *answer;
        }
      }
      if (queue_limit > 0) {
        auto count = connection->prepare("SELECT count(*) FROM jobs WHERE state = 'queued'");
        if (count.step() && count.integer(0) >= queue_limit) return {SubmitStatus::queue_full, {}};
      }
      api::JobInfo created = describe_job(job);
      created.id = unused_id(*connection, "job_", "SELECT 1 FROM jobs WHERE id = ?1");
      created.created_at = now_rfc3339();

      auto insert = connection->prepare(
          "INSERT INTO jobs (id, kind, state, request, dataset_id, created_at, robot_id, validation_dataset_id, owner) "
          "VALUES (?1, ?2, 'queued', ?3, ?4, ?5, ?6, ?7, ?8)");
      insert.bind_text(1, created.id)
          .bind_text(2, kind_text(job.kind))
          .bind_text(3, job.request)
          .bind_text_or_null(4, job.dataset_id)
          .bind_text(5, created.created_at)
          .bind_text_or_null(6, job.robot_id)
          .bind_text_or_null(7, job.validation_dataset_id)
          .bind_text(8, job.owner);
      insert.run();
      if (key) store_key(*connection, "job", job.owner, *key, created.id, created.created_at, keys_not_before);
      return {SubmitStatus::created, created};
    });
  }

  std::optional<api::JobInfo> find_job(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read, [&] { return select_job(*connection, scope, id); });
  }

  api::Page<api::JobInfo> list_jobs(const api::OwnerScope& scope, const api::JobFilter& filter,
                                    const api::PageRequest& page) override {
    const int size = effective_page_size(page.page_size);
    // The token is bound to the scope and filter: a token from another filter would skip or repeat jobs.
    const std::string context = job_list_context(scope, filter);
    const std::int64_t before =
        page.page_token.empty() ? INT64_MAX : decode_page_token(page.page_token, "j1", context);
    // Fixed SQL fragments per filter combination (no values in the text), so each variant is
    // prepared once and can use its index.
    std::string sql = "SELECT " + kJobColumns + " FROM jobs WHERE seq < ?1";
    if (filter.state) sql += " AND state = ?2";
    if (filter.kind) sql += " AND kind = ?3";
    if (!filter.robot_id.empty()) sql += " AND robot_id = ?5";
    sql += owner_condition(scope, 6);
    sql += " ORDER BY seq DESC LIMIT ?4";

    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read, [&] {
      auto rows = connection->prepare(sql);
      rows.bind_integer(1, before).bind_integer(4, size + 1);
      if (filter.state) rows.bind_text(2, state_text(*filter.state));
      if (filter.kind) rows.bind_text(3, kind_text(*filter.kind));
      if (!filter.robot_id.empty()) rows.bind_text(5, filter.robot_id);
      bind_owner(rows, scope, 6);
      api::Page<api::JobInfo> result;
      std::int64_t last_seq = 0;
      while (rows.step()) {
        if (static_cast<int>(result.items.size()) == size) {
          result.next_page_token = encode_page_token("j1", last_seq, context);
          break;
        }
        result.items.push_back(read_job(rows));
        last_seq = rows.integer(kJobSeqColumn);
      }
      return result;
    });
  }

  std::optional<api::JobInfo> claim_next_job(const std::string& owner, std::chrono::milliseconds lease) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&]() -> std::optional<api::JobInfo> {
      // One statement under the write lock: no other connection can claim the same row.
      auto claim = connection->prepare(
          "UPDATE jobs SET state = 'running', started_at = ?1, attempts = attempts + 1, worker = ?2, "
          "lease_expires_at = " + kNowSeconds + " + ?3 "
          "WHERE seq = (SELECT seq FROM jobs WHERE state = 'queued' ORDER BY seq LIMIT 1) RETURNING " +
          kJobColumns);
      claim.bind_text(1, now_rfc3339()).bind_text(2, owner).bind_real(3, seconds(lease));
      if (!claim.step()) return std::nullopt;
      auto job = read_job(claim);
      claim.run();  // finish the statement before COMMIT
      return job;
    });
  }

  LeaseStatus renew_lease(const Lease& lease, std::chrono::milliseconds duration) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write_in_place,
                                   [&] { return extend(*connection, lease, duration, nullptr); });
  }

  LeaseStatus record_progress(const Lease& lease, long evaluations, std::optional<double> best_cost,
                              const std::vector<api::HistoryEntry>& batch) override {
    const auto thetas = encode_thetas(batch);
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&] {
      // The guarded update first: a batch of an attempt that lost its lease is dropped whole.
      const Progress progress{evaluations, best_cost};
      const LeaseStatus status = extend(*connection, lease, std::nullopt, &progress);
      if (status == LeaseStatus::lost) return status;
      write_history(*connection, lease.job_id, batch, thetas);
      return status;
    });
  }

  bool finish_job(const Lease& lease, const JobEnd& end) override {
    if (!api::is_terminal(end.state)) throw std::invalid_argument("finish_job needs succeeded, failed or cancelled");
    const auto thetas = encode_thetas(end.history);
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&] {
      // Only the attempt that holds the lease ends the job, and only once.
      auto update = connection->prepare(
          "UPDATE jobs SET state = ?4, finished_at = ?5, result = ?6, error = ?7, "
          "dataset_id = coalesce(?8, dataset_id), worker = NULL, lease_expires_at = NULL, "
          "evaluations = coalesce(?9, evaluations), best_cost = CASE WHEN ?9 IS NULL THEN best_cost ELSE ?10 END " +
          kHeldBy);
      bind_lease(update, lease)
          .bind_text(4, state_text(end.state))
          .bind_text(5, now_rfc3339())
          .bind_text_or_null(6, end.result)
          .bind_text_or_null(7, end.error)
          .bind_text_or_null(8, end.dataset_id);
      if (end.evaluations) update.bind_integer(9, *end.evaluations).bind_real_or_null(10, end.best_cost);
      update.run();
      if (connection->changes() == 0) return false;
      write_history(*connection, lease.job_id, end.history, thetas);
      auto clear = connection->prepare("DELETE FROM estimates WHERE job_id = ?1");
      clear.bind_text(1, lease.job_id);
      clear.run();
      for (const auto& estimate : end.estimates) {
        auto insert = connection->prepare(
            "INSERT OR REPLACE INTO estimates (job_id, name, value, std_error) VALUES (?1, ?2, ?3, ?4)");
        insert.bind_text(1, lease.job_id).bind_text(2, estimate.name).bind_real(3, estimate.value).bind_real_or_null(
            4, estimate.std_error);
        insert.run();
      }
      return true;
    });
  }

  void requeue_job(const Lease& lease) override {
    auto connection = pool_.checkout();
    sqlite::run_transaction(*connection, TransactionKind::write, [&] {
      auto running = connection->prepare("SELECT cancel_requested FROM jobs " + kHeldBy);
      bind_lease(running, lease);
      if (!running.step()) return;
      const bool cancel_requested = running.integer(0) != 0;
      running.run();
      const std::string& id = lease.job_id;
      if (cancel_requested) {
        // The client asked to cancel it: running it again would ignore that.
        auto cancel = connection->prepare(
            "UPDATE jobs SET state = 'cancelled', finished_at = ?2, worker = NULL, lease_expires_at = NULL "
            "WHERE id = ?1");
        cancel.bind_text(1, id).bind_text(2, now_rfc3339());
        cancel.run();
        return;
      }
      clear_progress(*connection, id);
      auto requeue = connection->prepare(
          "UPDATE jobs SET state = 'queued', started_at = NULL, cancel_requested = 0, evaluations = 0, "
          "best_cost = NULL, worker = NULL, lease_expires_at = NULL WHERE id = ?1");
      requeue.bind_text(1, id);
      requeue.run();
    });
  }

  CancelOutcome cancel_job(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&] {
      const auto state = select_state(*connection, scope, id);
      if (!state) return CancelOutcome::not_found;
      if (*state == api::JobState::queued) {
        auto cancel = connection->prepare("UPDATE jobs SET state = 'cancelled', finished_at = ?2 WHERE id = ?1");
        cancel.bind_text(1, id).bind_text(2, now_rfc3339());
        cancel.run();
        return CancelOutcome::cancelled_now;
      }
      if (*state == api::JobState::running) {
        auto request = connection->prepare("UPDATE jobs SET cancel_requested = 1 WHERE id = ?1");
        request.bind_text(1, id);
        request.run();
        return CancelOutcome::requested;
      }
      return CancelOutcome::already_finished;
    });
  }

  DeleteResult delete_job(const api::OwnerScope& scope, const std::string& id) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&] {
      const auto state = select_state(*connection, scope, id);
      if (!state) return DeleteResult::not_found;
      if (!api::is_terminal(*state)) return DeleteResult::in_use;
      clear_progress(*connection, id);
      forget_keys_of(*connection, "job", id);
      auto remove = connection->prepare("DELETE FROM jobs WHERE id = ?1");
      remove.bind_text(1, id);
      remove.run();
      return DeleteResult::deleted;
    });
  }

  std::optional<api::Page<api::HistoryEntry>> history(const api::OwnerScope& scope, const std::string& id,
                                                      const api::PageRequest& page) override {
    const int size = effective_page_size(page.page_size);
    const bool first_page = page.page_token.empty();
    const std::int64_t after = first_page ? 0 : decode_page_token(page.page_token, "h1", id);
    auto connection = pool_.checkout();
    return sqlite::run_transaction(
        *connection, TransactionKind::read, [&]() -> std::optional<api::Page<api::HistoryEntry>> {
          if (!select_state(*connection, scope, id)) return std::nullopt;
          auto rows = connection->prepare(
              first_page ? "SELECT idx, cost, theta FROM job_history WHERE job_id = ?1 ORDER BY idx LIMIT ?3"
                         : "SELECT idx, cost, theta FROM job_history WHERE job_id = ?1 AND idx > ?2 "
                           "ORDER BY idx LIMIT ?3");
          rows.bind_text(1, id).bind_integer(3, size + 1);
          if (!first_page) rows.bind_integer(2, after);
          api::Page<api::HistoryEntry> result;
          while (rows.step()) {
            if (static_cast<int>(result.items.size()) == size) {
              result.next_page_token = encode_page_token("h1", result.items.back().index, id);
              break;
            }
            result.items.push_back(history_entry(rows, id));
          }
          return result;
        });
  }

  std::optional<api::HistoryOverview> history_overview(const api::OwnerScope& scope, const std::string& id,
                                                       long max_points) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read, [&]() -> std::optional<api::HistoryOverview> {
      if (!select_state(*connection, scope, id)) return std::nullopt;
      api::HistoryOverview overview;
      auto extent = connection->prepare("SELECT count(*), min(idx), max(idx) FROM job_history WHERE job_id = ?1");
      extent.bind_text(1, id);
      extent.step();
      overview.total = static_cast<long>(extent.integer(0));
      if (overview.total == 0) return overview;
      const std::int64_t first = extent.integer(1), last = extent.integer(2);
      auto best = connection->prepare(
          "SELECT idx FROM job_history WHERE job_id = ?1 AND cost IS NOT NULL ORDER BY cost, idx LIMIT 1");
      best.bind_text(1, id);
      if (best.step()) overview.best_index = static_cast<long>(best.integer(0));
      overview.stride = api::thinning_stride(overview.total, max_points);
      // A scan of the job's part of the primary key; only the chosen rows' blobs are decoded.
      auto rows = connection->prepare(
          "SELECT idx, cost, theta FROM job_history WHERE job_id = ?1 "
          "AND ((idx - ?2) % ?3 = 0 OR idx = ?4 OR idx = ?5) ORDER BY idx");
      rows.bind_text(1, id).bind_integer(2, first).bind_integer(3, overview.stride).bind_integer(4, last);
      rows.bind_integer(5, overview.best_index.value_or(last));
      while (rows.step()) overview.items.push_back(history_entry(rows, id));
      return overview;
    });
  }

  // ---- the process's life ----

  RecoveryOutcome recover_interrupted_jobs(int max_attempts, const std::function<std::string(int losses)>& lost_error,
                                           const std::function<bool(const std::string& worker)>& gone) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write, [&] {
      connection->execute("CREATE TEMP TABLE IF NOT EXISTS lost_jobs (id TEXT PRIMARY KEY) WITHOUT ROWID");
      std::vector<std::string> lost;
      auto running = connection->prepare("SELECT id, worker FROM jobs WHERE state = 'running'");
      while (running.step()) {
        const std::string worker = running.text(1);
        if (worker.empty() || gone(worker)) lost.push_back(running.text(0));
      }
      for (const std::string& id : lost) {
        auto insert = connection->prepare("INSERT INTO temp.lost_jobs (id) VALUES (?1)");
        insert.bind_text(1, id);
        insert.run();
      }
      return recover_lost(*connection, max_attempts, lost_error);
    });
  }

  RecoveryOutcome recover_expired_leases(int max_attempts,
                                         const std::function<std::string(int losses)>& lost_error) override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::write_in_place, [&] {
      connection->execute("CREATE TEMP TABLE IF NOT EXISTS lost_jobs (id TEXT PRIMARY KEY) WITHOUT ROWID");
      connection
          ->prepare("INSERT INTO temp.lost_jobs SELECT id FROM jobs WHERE state = 'running' "
                    "AND (lease_expires_at IS NULL OR lease_expires_at < " + kNowSeconds + ")")
          .run();
      return recover_lost(*connection, max_attempts, lost_error);
    });
  }

  std::map<api::JobState, long> count_jobs_by_state() override {
    auto connection = pool_.checkout();
    return sqlite::run_transaction(*connection, TransactionKind::read, [&] {
      std::map<api::JobState, long> counts;
      for (auto state : {api::JobState::queued, api::JobState::running, api::JobState::succeeded,
                         api::JobState::failed, api::JobState::cancelled}) {
        counts[state] = 0;
      }
      auto rows = connection->prepare("SELECT state, count(*) FROM jobs GROUP BY state");
      while (rows.step()) {
        const auto state = state_from_text(rows.text(0));
        if (!state) throw StoreError("a job has an unknown state in the database");
        counts[*state] = static_cast<long>(rows.integer(1));
      }
      return counts;
    });
  }

  std::optional<std::string> write_trouble() const override { return pool_.health().trouble(); }

 private:
  /// Now on the database's clock, Unix seconds with the fraction (julianday('now') is ms-exact).
  static inline const std::string kNowSeconds = "((julianday('now') - 2440587.5) * 86400.0)";
  /// The guard of every write of a running job: ?1 id, ?2 owner, ?3 attempt.
  static inline const std::string kHeldBy = "WHERE id = ?1 AND state = 'running' AND worker = ?2 AND attempts = ?3";

  struct Progress {
    long evaluations = 0;
    std::optional<double> best_cost;
  };

  static double seconds(std::chrono::milliseconds duration) { return static_cast<double>(duration.count()) / 1000.0; }

  static Statement& bind_lease(Statement& statement, const Lease& lease) {
    return statement.bind_text(1, lease.job_id).bind_text(2, lease.owner).bind_integer(3, lease.attempt);
  }

  /// Each entry's θ as a blob, made before the transaction (no encoding under the write lock).
  static std::vector<std::vector<unsigned char>> encode_thetas(const std::vector<api::HistoryEntry>& batch) {
    std::vector<std::vector<unsigned char>> thetas;
    thetas.reserve(batch.size());
    for (const auto& entry : batch) thetas.push_back(encode_doubles(entry.theta.data(), entry.theta.size()));
    return thetas;
  }

  /// History entries of job `id`; an index written again replaces its row.
  static void write_history(Connection& connection, const std::string& id, const std::vector<api::HistoryEntry>& batch,
                            const std::vector<std::vector<unsigned char>>& thetas) {
    for (std::size_t i = 0; i < batch.size(); ++i) {
      auto insert =
          connection.prepare("INSERT OR REPLACE INTO job_history (job_id, idx, cost, theta) VALUES (?1, ?2, ?3, ?4)");
      insert.bind_text(1, id).bind_integer(2, batch[i].index).bind_real(3, batch[i].cost);
      insert.bind_blob_or_null(4, thetas[i]);  // an empty θ is NULL and reads back empty
      insert.run();
    }
  }

  /// The guarded update of a held lease: progress and/or a new expiry; what it learned.
  static LeaseStatus extend(Connection& connection, const Lease& lease, std::optional<std::chrono::milliseconds> duration,
                            const Progress* progress) {
    std::string sql = "UPDATE jobs SET ";
    sql += duration ? "lease_expires_at = " + kNowSeconds + " + ?4" : "lease_expires_at = lease_expires_at";
    if (progress) sql += ", evaluations = ?5, best_cost = ?6";
    sql += " " + kHeldBy + " RETURNING cancel_requested";
    auto update = connection.prepare(sql);
    bind_lease(update, lease);
    if (duration) update.bind_real(4, seconds(*duration));
    if (progress) update.bind_integer(5, progress->evaluations).bind_real_or_null(6, progress->best_cost);
    if (!update.step()) return LeaseStatus::lost;
    const bool cancel_requested = update.integer(0) != 0;
    update.run();  // finish the statement
    return cancel_requested ? LeaseStatus::cancel_requested : LeaseStatus::held;
  }

  /// Ends or requeues the jobs listed in temp.lost_jobs (their worker is gone), then empties it.
  static RecoveryOutcome recover_lost(Connection& connection, int max_attempts,
                                      const std::function<std::string(int losses)>& lost_error) {
    RecoveryOutcome outcome;
    const std::string now = now_rfc3339();
    const std::string lost = "id IN (SELECT id FROM temp.lost_jobs)";
    // Cancellation was asked for before the worker went: honour it rather than run the job again.
    auto cancel = connection.prepare(
        "UPDATE jobs SET state = 'cancelled', finished_at = ?1, worker = NULL, lease_expires_at = NULL "
        "WHERE " + lost + " AND cancel_requested = 1");
    cancel.bind_text(1, now);
    cancel.run();
    outcome.cancelled = connection.changes();
    connection.prepare("DELETE FROM temp.lost_jobs WHERE id IN (SELECT id FROM jobs WHERE state <> 'running')").run();
    connection.prepare("UPDATE jobs SET worker_losses = worker_losses + 1 WHERE " + lost).run();
    // The attempt that died leaves nothing behind: its history and estimates go.
    connection.prepare("DELETE FROM job_history WHERE job_id IN (SELECT id FROM temp.lost_jobs)").run();
    connection.prepare("DELETE FROM estimates WHERE job_id IN (SELECT id FROM temp.lost_jobs)").run();
    // A job that took its worker down max_attempts times is failed, never run again.
    std::vector<std::pair<std::string, int>> poisoned;
    auto select = connection.prepare("SELECT id, worker_losses FROM jobs WHERE " + lost + " AND worker_losses >= ?1");
    select.bind_integer(1, max_attempts);
    while (select.step()) poisoned.emplace_back(select.text(0), static_cast<int>(select.integer(1)));
    for (const auto& [id, losses] : poisoned) {
      auto fail = connection.prepare(
          "UPDATE jobs SET state = 'failed', finished_at = ?2, error = ?3, worker = NULL, lease_expires_at = NULL "
          "WHERE id = ?1");
      fail.bind_text(1, id).bind_text(2, now).bind_text(3, lost_error(losses));
      fail.run();
      outcome.failed.push_back(id);
    }
    auto requeue = connection.prepare(
        "UPDATE jobs SET state = 'queued', started_at = NULL, evaluations = 0, best_cost = NULL, worker = NULL, "
        "lease_expires_at = NULL WHERE " + lost + " AND state = 'running'");
    requeue.run();
    outcome.requeued = connection.changes();
    connection.prepare("DELETE FROM temp.lost_jobs").run();
    return outcome;
  }

  static std::unique_ptr<Connection> open_and_prepare(const std::string& path) {
    auto connection = std::make_unique<Connection>(path);
    sqlite::prepare_database(*connection);
    return connection;
  }

  StoreOptions options_;
  sqlite::ConnectionPool pool_;
};

}  // namespace

std::unique_ptr<Store> open_store(const std::string& path, const StoreOptions& options) {
  return std::make_unique<SqliteStore>(path, options);
}

FileCheck check_file(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) throw StoreError("no database file '" + path + "'");
  Connection connection(path);
  FileCheck check;
  check.findings = integrity_findings(connection, true, 100);
  if (!check.findings.empty()) return check;
  auto version = connection.prepare("PRAGMA user_version");
  if (version.step()) check.schema_version = static_cast<int>(version.integer(0));
  // Text that is not UTF-8, stored before the service refused it at the door (a ?name=%FF): the
  // service shows it with U+FFFD; the user should rename or delete the row.
  const auto has_table = [&connection](const char* table) {
    auto statement = connection.prepare("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?1");
    statement.bind_text(1, table);
    return statement.step();
  };
  const auto scan = [&](const char* table, const char* noun, std::initializer_list<const char*> columns) {
    if (!has_table(table)) return;
    std::string sql = "SELECT id";
    for (const char* column : columns) sql += std::string(", ") + column;
    auto rows = connection.prepare(sql + " FROM " + table + " ORDER BY id");
    while (rows.step() && check.text_findings.size() < 100) {
      int index = 1;
      for (const char* column : columns) {
        if (!api::is_valid_utf8(rows.text(index++))) {
          check.text_findings.push_back(std::string(noun) + " " + rows.text(0) + ": its " + column + " is not UTF-8");
        }
      }
    }
  };
  scan("datasets", "dataset", {"name"});
  scan("robots", "robot", {"name", "base", "tip", "urdf"});
  return check;
}

}  // namespace manipid::server::store::sqlite
