// job_runner.h — runs one claimed job to its end: parses the stored request (validated at
// submission, parsed again here so a job survives a restart with nothing but its row), runs
// the simulation or identification on the core, streams progress and cost history to the
// store in batches, and says how the job ended. The worker pool owns the threads; this file
// owns what happens on one of them.
#pragma once

#include "manipid/api/records.h"
#include "manipid/api/job_memory.h"
#include "manipid/api/robot_cache.h"
#include "store/store.h"

#include <atomic>
#include <limits>
#include <string>
#include <vector>

namespace manipid::server::jobs {

/// What other threads may see of, or do to, a running job.
struct LiveJob {
  store::Lease lease;                 ///< set before the job runs; every write of it carries this
  std::atomic<bool> cancel{false};    ///< checked at every cost evaluation and simulation step, and inside long steps
  std::atomic<bool> shutdown{false};  ///< the cancel came from a shutdown: requeue, don't cancel
  std::atomic<bool> timed_out{false};  ///< the cancel came from --job-timeout: the job fails saying so
  std::atomic<bool> lost{false};      ///< the lease is gone (another process took the job over): write nothing more
  std::atomic<long> evaluations{0};
  std::atomic<double> best_cost{std::numeric_limits<double>::infinity()};
};

struct RunnerOptions {
  /// Longest a job may run, s: caps an identification's max_seconds (less what a simulation before it
  /// took) and an excitation's (four fifths of it: the rest is for the design's final figures); a job
  /// still running kTimeLimitGrace after it is stopped like a cancel, and fails naming the limit.
  double job_time_limit_seconds = 3600.0;
  int history_batch = 512;                  ///< entries per store write
  /// The process's parsed robots (the worker pool's); null: a robot is parsed for each job that reads it.
  api::RobotCache* robots = nullptr;
  double history_flush_seconds = 0.5;       ///< or sooner than a full batch, while running
};

/// The end to write (store::JobEnd: state, result or problem, estimates, dataset, the history's
/// last batch), and what the worker pool does besides.
struct JobOutcome : store::JobEnd {
  bool requeue = false;  ///< interrupted by shutdown: run again later
  std::string log;       ///< what only the server log may say (SQLite's text)
};

/// Runs `job` (state running, claimed by this thread under `live.lease`). Never throws: every
/// failure becomes a failed outcome with a problem JSON that says what went wrong. A progress
/// write that finds the lease lost sets `live.lost` and stops the job; one that finds a cancel
/// asked for (by any process) stops it as cancelled.
JobOutcome run_job(const api::JobInfo& job, store::Store& store, LiveJob& live, const RunnerOptions& options);

/// Applies what a guarded write learned to a running job: a lost lease sets `lost` and stops it
/// (nothing more is written); a cancel asked for through any process stops it as cancelled.
void heed(store::LeaseStatus status, LiveJob& live);

/// What a job's work is made of (api::job_shape over this store's datasets and robots within
/// `scope`: a submission's caller's, or all_owners for a worker): the measure its memory is
/// estimated by. Throws what the request parsers throw.
api::JobShape job_shape(api::JobKind kind, const std::string& request_json, store::Store& store,
                        const api::OwnerScope& scope);

}  // namespace manipid::server::jobs
