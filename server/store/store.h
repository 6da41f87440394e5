// store.h — where datasets, robots, jobs, cost histories and estimates live: a small storage
// interface, so the SQL dialect stays inside one backend (store/sqlite/ now; PostgreSQL for
// multi-machine deployments next), and open_store(url), which picks the backend.
//
// Contract every backend keeps:
//  - Each state change is one transaction; what a call returned as done survives a crash of
//    the process (nothing acknowledged is lost).
//  - Thread-safe: any thread may call any method at any time (backends keep their own
//    connections per thread or a pool).
//  - Jobs are claimed in submission order, each by exactly one worker, on a lease: the claim
//    names the owner and counts the attempt; every later write of that running job (progress,
//    its end, putting it back) carries the Lease and changes nothing unless the job is still
//    running under that owner and attempt. A worker that lost its lease (paused past it, or its
//    job recovered by another process) learns so from its next write and stops; its writes never
//    show. Times of leases are the database's clock, never a worker's.
//  - Ids are random ("ds_"/"job_" + 16 hex digits), never reused.
//  - Every dataset, robot and job has an owner (the name of the token that made it; "" without
//    named tokens). Reads, lists, cancels and deletes take an api::OwnerScope: a resource outside
//    it is answered exactly as a missing one (not_found, nullopt, absent from lists), filtered in
//    the SQL. An Idempotency-Key belongs to the owner that sent it: another owner's same key is
//    another key. (A Lease's `owner` below is the worker process that holds a running job, not this.)
#pragma once

#include "manipid/api/records.h"
#include "manipid/core/signal/trajectory.h"

#include <chrono>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace manipid::server::store {

/// A storage failure the caller cannot fix (disk full, corrupt file, I/O error). The
/// service answers 500 / marks the job failed; the message is for the log only.
class StoreError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The disk (or quota) holding the database is full: nothing of the write was kept, and the
/// same write may succeed once space is freed. The service answers 507 and retries a job's
/// final write (worker_pool.cpp); /healthz says "degraded" until a write succeeds again.
class StorageFull : public StoreError {
 public:
  using StoreError::StoreError;
};

/// The database cannot be reached now (a PostgreSQL server restarting, a network cut): nothing
/// of the call was done, and the same call may succeed shortly; the connection is opened again
/// on the next call. The service answers 503 with Retry-After.
class StoreUnavailable : public StoreError {
 public:
  using StoreError::StoreError;
};

/// A page request the store cannot serve: a negative page size, a page token it did not issue
/// (or issued for another filter). The caller's mistake: the service answers 422 naming `field`.
class PageRequestError : public std::invalid_argument {
 public:
  PageRequestError(std::string field, const std::string& message)
      : std::invalid_argument(message), field_(std::move(field)) {}
  const std::string& field() const noexcept { return field_; }

 private:
  std::string field_;
};

struct NewJob {
  api::JobKind kind = api::JobKind::identification;
  std::string request;                ///< JSON text
  std::string dataset_id;             ///< input dataset, may be empty
  std::string robot_id;               ///< the URDF robot it works on, may be empty
  std::string validation_dataset_id;  ///< a second dataset it reads, may be empty
  std::string owner;                  ///< who submitted it (api::Caller::owner); its output datasets are theirs too
};

enum class SubmitStatus {
  created,               ///< a new job (or dataset) was stored
  replayed,              ///< same Idempotency-Key and fingerprint: the earlier one is returned
  key_reused,            ///< same key, different fingerprint: nothing stored
  queue_full,            ///< queued jobs ≥ queue_limit: nothing stored
};

struct SubmitOutcome {
  SubmitStatus status = SubmitStatus::created;
  api::JobInfo job;  ///< the new or earlier job (empty unless created/replayed)
};

struct DatasetOutcome {
  SubmitStatus status = SubmitStatus::created;  ///< never queue_full
  api::DatasetInfo dataset;
};

struct NewRobot {
  std::string name;
  std::string urdf;     ///< the document, kept byte for byte
  std::string base, tip;
  int joints = 0;
  std::string summary;  ///< the robot resource's description, JSON text
  std::string owner;    ///< who uploaded it (api::Caller::owner)
};

struct RobotOutcome {
  SubmitStatus status = SubmitStatus::created;  ///< never queue_full
  api::RobotInfo robot;
};

/// What a delete did. `in_use`: a queued or running job will read it, nothing deleted.
enum class DeleteResult { deleted, not_found, in_use };

/// Estimates of a finished identification, one row per parameter (also kept in the result
/// JSON; this table is for queries across jobs).
struct EstimateRow {
  std::string name;
  double value = 0.0;
  std::optional<double> std_error;
};

/// A running job's end, as finish_job writes it in one transaction.
struct JobEnd {
  api::JobState state = api::JobState::failed;  ///< succeeded, failed or cancelled
  std::string result;                            ///< result JSON text (may be empty)
  std::string error;                             ///< problem JSON text (failed)
  std::vector<EstimateRow> estimates;
  std::string dataset_id;                        ///< the dataset it made or used (empty: unchanged)
  /// The evaluations not yet written — the history's last batch — with the progress counters
  /// they bring (evaluations set: the counters are written; unset: they stay as they are).
  std::vector<api::HistoryEntry> history;
  std::optional<long> evaluations;
  std::optional<double> best_cost;
};

enum class CancelOutcome { not_found, cancelled_now, requested, already_finished };

/// Who runs a claimed job: its owner, the worker ("HOST:PID:THREAD"; not the job's api owner), and
/// the attempt the claim counted.
struct Lease {
  std::string job_id;
  std::string owner;
  int attempt = 0;
};

/// What a guarded write of a running job learned.
enum class LeaseStatus {
  held,              ///< written; the job is still this worker's
  cancel_requested,  ///< written; a client asked to cancel it (stop, then end it cancelled)
  lost,              ///< nothing written: the job is no longer this attempt's (stop, write nothing more)
};

/// What start-up recovery did with the jobs a dead process left running.
struct RecoveryOutcome {
  int requeued = 0;                  ///< back in the queue, to run again
  int cancelled = 0;                 ///< their cancellation had been asked for: cancelled
  std::vector<std::string> failed;   ///< ids of jobs whose worker died too often: failed for good
};

/// A change to a job that a process committed, as a backend that can tell every process at once
/// reports it (PostgreSQL: LISTEN/NOTIFY).
struct JobEvent {
  enum class Kind {
    queued,            ///< a job can be claimed (submitted, or put back)
    cancel_requested,  ///< a client asked to cancel a running job
    changed,           ///< a job's state changed otherwise (its end, a queued job cancelled)
  };
  Kind kind = Kind::changed;
  std::string job_id;
};

class Store {
 public:
  virtual ~Store() = default;

  /// Calls `on_event`, from a thread of the store's own, for every job change any process on
  /// the database commits (this one's too), until replaced by another call (an empty function:
  /// none). Returns false when this backend cannot tell (SQLite: callers look at the store
  /// again from time to time instead). Once it returns true, every change committed after that
  /// is heard while the database can be reached; events may be missed while it is away, so
  /// callers poll as well, only less often. Replacing waits for a call in progress to return.
  virtual bool watch_jobs(std::function<void(const JobEvent&)> on_event) {
    (void)on_event;
    return false;
  }

  // ---- datasets ----
  /// Stores the samples (as binary blobs, not text) as `owner`'s. `key`, when given, makes it
  /// idempotent among that owner's datasets.
  virtual DatasetOutcome insert_dataset(const std::string& owner, const std::string& name, const Trajectory& data,
                                        const std::string& source_job, const std::optional<api::IdempotencyKey>& key) = 0;
  virtual std::optional<api::DatasetInfo> find_dataset(const api::OwnerScope& scope, const std::string& id) = 0;
  virtual std::optional<Trajectory> load_dataset(const api::OwnerScope& scope, const std::string& id) = 0;
  /// Newest first; a page token holds for the scope it was issued in only.
  virtual api::Page<api::DatasetInfo> list_datasets(const api::OwnerScope& scope, const api::PageRequest& page) = 0;
  /// Not while a queued or running job will read it (as its data or its validation data).
  virtual DeleteResult delete_dataset(const api::OwnerScope& scope, const std::string& id) = 0;

  // ---- robots ----
  /// Stores a URDF robot (document and parsed summary) as robot.owner's. `key`, when given, makes
  /// it idempotent among that owner's robots.
  virtual RobotOutcome insert_robot(const NewRobot& robot, const std::optional<api::IdempotencyKey>& key) = 0;
  virtual std::optional<api::RobotInfo> find_robot(const api::OwnerScope& scope, const std::string& id) = 0;
  /// The URDF document as uploaded.
  virtual std::optional<std::string> load_robot_urdf(const api::OwnerScope& scope, const std::string& id) = 0;
  /// Newest first; a page token holds for the scope it was issued in only.
  virtual api::Page<api::RobotInfo> list_robots(const api::OwnerScope& scope, const api::PageRequest& page) = 0;
  /// Not while a queued or running job uses it.
  virtual DeleteResult delete_robot(const api::OwnerScope& scope, const std::string& id) = 0;

  // ---- jobs ----
  /// Inserts a queued job of job.owner's unless the key (among that owner's) replays or conflicts
  /// or the queue is full (queue_limit ≤ 0: no limit; every owner's queued jobs count). The key
  /// check, the count and the insert are one transaction.
  virtual SubmitOutcome submit_job(const NewJob& job, const std::optional<api::IdempotencyKey>& key, int queue_limit) = 0;
  virtual std::optional<api::JobInfo> find_job(const api::OwnerScope& scope, const std::string& id) = 0;
  /// Newest first; a page token holds for the filter and the scope it was issued in only.
  virtual api::Page<api::JobInfo> list_jobs(const api::OwnerScope& scope, const api::JobFilter& filter,
                                            const api::PageRequest& page) = 0;
  /// The oldest queued job, now running under a lease of `lease` for `owner`: started_at set,
  /// attempts + 1 (the lease's attempt), `worker` the owner. nullopt when none is queued.
  virtual std::optional<api::JobInfo> claim_next_job(const std::string& owner, std::chrono::milliseconds lease) = 0;
  /// Extends a held lease to now + `lease` (the heartbeat, every lease / 3).
  virtual LeaseStatus renew_lease(const Lease& lease, std::chrono::milliseconds duration) = 0;
  /// Progress of a running job plus a batch of new history entries, in one transaction.
  virtual LeaseStatus record_progress(const Lease& lease, long evaluations, std::optional<double> best_cost,
                                      const std::vector<api::HistoryEntry>& batch) = 0;
  /// A running job's end (JobEnd: state, result or problem, estimates, the dataset it made or
  /// used, the history's last batch and the progress with it) — one transaction, written only
  /// while the lease holds (false: lost, nothing written).
  virtual bool finish_job(const Lease& lease, const JobEnd& end) = 0;
  /// A running job back to queued with its history cleared (shutdown before it finished), if
  /// the lease still holds; cancelled instead when its cancellation was asked for.
  virtual void requeue_job(const Lease& lease) = 0;
  /// Queued → cancelled at once; running → cancel_requested set; finished → unchanged.
  virtual CancelOutcome cancel_job(const api::OwnerScope& scope, const std::string& id) = 0;
  /// Finished jobs only (in_use while queued or running); removes its history and estimates too.
  virtual DeleteResult delete_job(const api::OwnerScope& scope, const std::string& id) = 0;
  /// History entries in index order; the page token is opaque (keyset on index).
  virtual std::optional<api::Page<api::HistoryEntry>> history(const api::OwnerScope& scope, const std::string& id,
                                                              const api::PageRequest& page) = 0;
  /// Every stride-th entry with the first, last and best, stride = ceil(total / max_points),
  /// read in one transaction (a running job's history grows meanwhile).
  virtual std::optional<api::HistoryOverview> history_overview(const api::OwnerScope& scope, const std::string& id,
                                                               long max_points) = 0;

  // ---- the process's life ----
  /// At start-up: every running job whose worker is `gone` (a process known dead; an empty
  /// worker, from before leases, always is) counts one more worker loss and goes back to queued
  /// (history cleared) — unless its cancellation had been asked for (cancelled), or it has now lost
  /// its worker `max_attempts` times: then it is failed with the error `lost_error(losses)` and
  /// never runs again, so a job that kills the process cannot kill it on every restart. Jobs of
  /// workers not known dead wait for their lease to expire. One transaction.
  virtual RecoveryOutcome recover_interrupted_jobs(int max_attempts,
                                                   const std::function<std::string(int losses)>& lost_error,
                                                   const std::function<bool(const std::string& worker)>& gone) = 0;
  /// The same for the running jobs whose lease has expired (their worker died, hung or was
  /// paused past it): what every process does every few seconds.
  virtual RecoveryOutcome recover_expired_leases(int max_attempts,
                                                 const std::function<std::string(int losses)>& lost_error) = 0;
  /// Every owner's jobs (what /metrics shows, to admin tokens only).
  virtual std::map<api::JobState, long> count_jobs_by_state() = 0;
  /// Why writes fail now ("the disk holding the database is full"), or nullopt when the last
  /// write transaction succeeded (or none failed): set by a StorageFull, cleared by the next
  /// write that commits a change (an empty commit proves nothing about the space). What /healthz reports as "degraded".
  virtual std::optional<std::string> write_trouble() const = 0;
};

/// How a store is opened; the defaults are `manipid serve`'s.
struct StoreOptions {
  /// How long an Idempotency-Key is remembered (--idempotency-ttl): the same key sent again after
  /// this makes a new job, dataset or robot; older keys are forgotten as new ones are stored.
  std::chrono::seconds idempotency_ttl = std::chrono::hours(24);
  /// PostgreSQL: the most connections open at once (the threads that use the store: HTTP threads
  /// plus workers plus the lease keeper). SQLite opens one per thread as needed.
  std::size_t connections = 16;
};

/// The store a `--db` value names: "sqlite:PATH" or a plain PATH is a SQLite file (created if
/// missing, migrated if older); "postgresql://…" or "postgres://…" (a libpq connection URI) a
/// PostgreSQL database shared with other processes (schema created or migrated). Throws
/// StoreError when it cannot be opened (StoreUnavailable when the server cannot be reached).
std::unique_ptr<Store> open_store(const std::string& url, const StoreOptions& options = {});
/// Whether a `--db` value names a PostgreSQL database.
bool is_postgres_url(const std::string& url);
/// A `--db` value as logs and stdout may show it: a PostgreSQL URI without its password.
std::string display_name(const std::string& url);
/// The SQLite file a `--db` value names (PATH or sqlite:PATH); StoreError for any other backend
/// or an empty path. open_store and `manipid doctor` both read `--db` through it.
std::string sqlite_path(const std::string& url);

}  // namespace manipid::server::store
