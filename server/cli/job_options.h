// job_options.h — what `manipid serve` and `manipid worker` share: the store they open (and the
// jobs a dead process left running there), the jobs they run (threads, time and memory limits,
// leases), the process's name on its leases and the log line format.
#pragma once

#include "jobs/worker_pool.h"
#include "store/store.h"

#include <CLI/CLI.hpp>

#include <signal.h>

#include <cstddef>
#include <memory>
#include <string>

namespace manipid::server::cli {

struct JobOptions {
  std::string database = "./manipid.db";
  int workers = -1;                ///< job threads; -1: the hardware threads (serve: 0 runs none, API only)
  std::string job_memory = "4GiB"; ///< running jobs at once, by their estimates (jobs::WorkerPoolOptions)
  double job_timeout = 3600.0;     ///< s, any job
  int max_attempts = 3;            ///< worker losses a job may cause before it is failed for good
  double lease = 30.0;             ///< s a running job's claim holds without renewal
  double idempotency_ttl = 24.0;   ///< h an Idempotency-Key is remembered (serve's --idempotency-ttl)
};

/// --db, --workers (at least `fewest_workers`), --job-memory, --job-timeout, --max-attempts, --lease.
void add_job_options(CLI::App& command, JobOptions& options, int fewest_workers);

/// Job threads to start: --workers, or the hardware threads when it was not given.
int worker_threads(const JobOptions& options);

/// Opens --db (UsageError naming --db when it cannot) and takes back the jobs that a process of
/// this machine which no longer runs (or this process's earlier self, same HOST:PID in a restarted
/// container) left running: queued again, cancelled as asked, or failed after --max-attempts.
/// Jobs other live processes run keep their leases. Logs what it did. `other_threads`: the
/// threads besides the job threads that use the store (serve's HTTP threads), for the size of a
/// PostgreSQL connection pool. A database that cannot be opened is a UsageError (exit 2) for a
/// SQLite file, an OutputError (exit 1: the program could not run) for PostgreSQL.
std::unique_ptr<store::Store> open_job_store(const JobOptions& options, int other_threads = 0);

/// The worker pool's settings from these options (its owner is process_name()).
jobs::WorkerPoolOptions worker_pool_options(const JobOptions& options);

/// Blocks SIGINT and SIGTERM in the calling thread and every thread started from it after (so no
/// job thread is interrupted mid-transaction); returns them, for one thread to sigwait on.
sigset_t block_stop_signals();

/// "HOST:PID": who holds this process's leases (a running job's `worker`).
std::string process_name();

/// One line on stderr, "2026-11-22T06:40:12.345Z text"; safe from any thread.
void log_line(const std::string& line);

/// "64MiB", "1M", "500k", "1048576" → bytes; `option` names it in messages (UsageError).
std::size_t parse_size(const std::string& text, const std::string& option);

}  // namespace manipid::server::cli
