// worker_pool.h — N threads that take queued jobs from the store in submission order and run
// them (job_runner.h). The pool also keeps what only memory can hold: each running job's live
// progress and cancel flag, and a signal that wakes long-polls when any job ends.
//
// Jobs run on leases (store.h): a claim names this process as the owner for `lease`; a keeper
// thread renews the leases of the running jobs every lease / 3 (learning a cancel asked through
// any process), and recovers the jobs whose lease expired — their worker died, hung or was paused —
// in the queue again or, after --max-attempts losses, failed. A job whose lease was lost stops and
// writes nothing more: the attempt that holds the lease is the only one whose writes count.
//
// Shutdown (stop()) tells running jobs to stop at their next cost evaluation or simulation step and
// puts them back in the queue, so a restart runs them again: nothing acknowledged is lost.
#pragma once

#include "jobs/job_runner.h"
#include "manipid/api/robot_cache.h"
#include "store/store.h"

#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace manipid::server::jobs {

/// WORKER_LOST problem JSON: the job's worker died (or stopped renewing its lease) `losses`
/// times; it is not run again.
std::string worker_lost_problem(int losses);

struct WorkerPoolOptions {
  int workers = 1;
  RunnerOptions runner;
  /// Who claims: this process, "HOST:PID" (what a running job's `worker` shows).
  std::string owner = "localhost:0";
  /// How long a claim holds without renewal (--lease); renewed every lease / 3.
  std::chrono::milliseconds lease{30000};
  /// Worker losses (an expired lease) after which a job is failed instead of run again.
  int max_attempts = 3;
  /// The problem JSON of a job failed for losing its worker `losses` times.
  std::function<std::string(int losses)> lost_error = worker_lost_problem;
  /// How often an idle worker looks at the store even without a submit notification (jobs
  /// recovered at start-up, or submitted by another process on the same database).
  std::chrono::milliseconds idle_poll{1000};
  /// A job's end that cannot be written (a full disk) is written again after 250 ms, the wait
  /// doubling up to this; see WorkerPool::record_end.
  std::chrono::milliseconds final_write_max_backoff{10000};
  /// Bytes the running jobs may hold together (--job-memory), each job counted at its estimate
  /// (api::job_memory_bytes): a job starts when it fits beside those running and waits in the
  /// pool otherwise; one that could never fit is refused at submission (JobService) and, if it was
  /// queued before a restart with a smaller budget, fails with the reason instead of running.
  std::size_t job_memory = std::size_t{4} << 30;
  /// What runs a claimed job: run_job (job_runner.h), or a test's stand-in that the test steers.
  std::function<JobOutcome(const api::JobInfo& job, store::Store& store, LiveJob& live, const RunnerOptions& options)> run =
      run_job;
};

struct LiveProgress {
  long evaluations = 0;
  std::optional<double> best_cost;
};

/// Counts and durations of the jobs this process finished, for /metrics.
struct PoolStatistics {
  long running = 0;
  std::size_t job_memory_reserved = 0;  ///< bytes the running jobs hold by their estimates
  std::size_t job_memory_budget = 0;    ///< --job-memory
  std::map<std::string, long> finished;      ///< by "kind,state"
  std::vector<double> duration_bucket_bounds;  ///< s, upper bounds (Prometheus "le")
  std::vector<long> duration_buckets;          ///< cumulative counts, one per bound
  long duration_count = 0;
  double duration_sum = 0.0;
};

class WorkerPool {
 public:
  using Log = std::function<void(const std::string& line)>;
  WorkerPool(store::Store& store, WorkerPoolOptions options, Log log);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  void start();
  /// Stops taking jobs, interrupts running jobs (they are requeued), joins.
  void stop();

  /// A job was queued: wake an idle worker.
  void notify_submitted();
  /// Asks a running job to stop at its next evaluation (also when it is about to start).
  void cancel(const std::string& id);
  std::optional<LiveProgress> progress(const std::string& id) const;

  /// Blocks until some job changes to a terminal state or `deadline` passes; returns at once
  /// if `generation` is already behind. Use: g = generation(); check; wait_for_change(g, t).
  unsigned long generation() const;
  void wait_for_change(unsigned long generation, std::chrono::steady_clock::time_point deadline) const;
  /// Wakes long-polls (a queued job was cancelled by the routes, not by a worker).
  void notify_changed();

  PoolStatistics statistics() const;
  /// --job-memory: what a submission's estimate must fit in (JobService refuses it otherwise).
  std::size_t job_memory_budget() const { return options_.job_memory; }
  /// The process's parsed robots: the jobs' (RunnerOptions::robots) and the routes' (JobService::parsed_robot).
  api::RobotCache& robots() { return robots_; }

 private:
  void work();
  /// The keeper thread: renews this process's leases and recovers expired ones, every lease / 3.
  void keep_leases();
  /// What another process did (store::Store::watch_jobs), from the store's thread.
  void heed_event(const store::JobEvent& event);
  void renew_leases();
  void run_one(const api::JobInfo& job);
  /// run_job once the job's memory estimate is set aside (waiting for room); the estimate is given
  /// back when it ends. A job that could never fit fails; a stop or cancel while waiting ends it.
  JobOutcome run_within_memory(const api::JobInfo& job, LiveJob& live);
  /// Writes a job's end until it sticks; false when the pool stopped first (the row stays
  /// running; start-up recovery puts it back in the queue).
  /// Written under `live.lease`; a lease found lost sets `live.lost` (nothing written, nothing to retry).
  bool record_end(const api::JobInfo& job, LiveJob& live, JobOutcome& outcome);
  /// Waits `delay` unless the pool stops first; false when it stopped.
  bool pause_unless_stopping(std::chrono::milliseconds delay);
  /// Sets `bytes` of --job-memory aside for a job, waiting until they fit beside the jobs running;
  /// false when the pool stops or the job is cancelled first (nothing set aside then).
  bool set_memory_aside(std::size_t bytes, const LiveJob& live);
  void give_memory_back(std::size_t bytes);

  store::Store& store_;
  api::RobotCache robots_;  ///< before options_, whose runner options point at it
  WorkerPoolOptions options_;
  Log log_;
  std::vector<std::thread> threads_;
  std::thread keeper_;
  bool watching_ = false;  ///< the store reports other processes' job changes to heed_event

  mutable std::mutex mutex_;
  std::condition_variable work_available_;
  std::condition_variable memory_freed_;
  std::condition_variable keeper_wake_;  ///< stop() ends the keeper's wait
  std::size_t memory_set_aside_ = 0;  ///< the running jobs' estimates (set_memory_aside)
  mutable std::condition_variable changed_;
  bool stopping_ = false;
  unsigned long submissions_ = 0;
  unsigned long generation_ = 0;
  std::map<std::string, std::shared_ptr<LiveJob>> live_;
  std::set<std::string> pending_cancels_;  ///< cancelled between claim and registration
  PoolStatistics statistics_;
};

}  // namespace manipid::server::jobs
