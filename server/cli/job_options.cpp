// job_options.cpp — the options, store opening and pool settings `serve` and `worker` share.
#include "cli/job_options.h"

#include "cli/common.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <thread>

namespace manipid::server::cli {
namespace {

std::mutex log_mutex;

/// Whether the process named `worker` ("HOST:PID") is known to be gone: on this machine and no
/// longer running, or this very name (this process's earlier self: a container restarted with
/// the same host name and PID). Another machine's process cannot be told from here: its lease will.
bool worker_gone(const std::string& worker, const std::string& self) {
  if (worker == self) return true;
  const std::size_t colon = worker.rfind(':');
  if (colon == std::string::npos) return true;  // not a name this version writes
  if (worker.substr(0, colon) != self.substr(0, self.rfind(':'))) return false;
  const std::string digits = worker.substr(colon + 1);
  if (digits.empty() || digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c); })) {
    return true;
  }
  const pid_t pid = static_cast<pid_t>(std::stol(digits));
  return pid <= 0 || (kill(pid, 0) != 0 && errno == ESRCH);
}

}  // namespace

void add_job_options(CLI::App& command, JobOptions& options, int fewest_workers) {
  command.add_option("--db", options.database,
                     "Store: a SQLite file, PATH or sqlite:PATH (created with its schema if missing), or a PostgreSQL "
                     "database shared with other processes, postgresql://USER@HOST/DB (the password from PGPASSWORD "
                     "or ~/.pgpass)")
      ->capture_default_str();
  command.add_option("--workers", options.workers,
                     fewest_workers == 0 ? "Job threads (default: hardware threads; 0: none, the API only, for a "
                                           "database that `manipid worker` processes serve)"
                                         : "Job threads (default: hardware threads)")
      ->check(integer_between(fewest_workers, 256));
  command.add_option("--job-memory", options.job_memory,
                     "Memory the running jobs may hold together, each by its estimate from its samples, joints and kind of "
                     "work; a job starts when it fits and waits otherwise, one that could never fit is refused (422)")
      ->capture_default_str();
  command.add_option("--job-timeout", options.job_timeout, "Longest a job may run, s (an identification then stops with its best point; any job still running 0.5 s later fails saying so)")
      ->check(positive_number())
      ->capture_default_str();
  command.add_option("--max-attempts", options.max_attempts,
                     "A job whose worker was lost this many times (the process crashed, was killed or stopped "
                     "renewing the job's lease) is failed instead of run again")
      ->check(integer_between(1, 1000))
      ->capture_default_str();
  command.add_option("--lease", options.lease,
                     "Seconds a running job's claim holds without renewal (renewed every third of it): a job whose "
                     "process stopped renewing it runs again elsewhere after this long")
      ->check(CLI::Range(0.1, 86400.0))
      ->capture_default_str();
}

int worker_threads(const JobOptions& options) {
  return options.workers >= 0 ? options.workers : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

std::unique_ptr<store::Store> open_job_store(const JobOptions& options, int other_threads) {
  std::unique_ptr<store::Store> store;
  try {
    store::StoreOptions store_options;
    store_options.idempotency_ttl = std::chrono::seconds(std::llround(options.idempotency_ttl * 3600.0));
    // Every job thread and HTTP thread may hold a connection at once, plus the lease keeper's.
    store_options.connections = static_cast<std::size_t>(worker_threads(options) + std::max(other_threads, 0) + 1);
    store = store::open_store(options.database, store_options);
  } catch (const store::StoreError& error) {
    // Not the value itself: a database URL may carry a password (SQLite's messages name the file).
    if (store::is_postgres_url(options.database)) throw OutputError(std::string("--db: ") + error.what());
    throw UsageError(std::string("--db: ") + error.what());
  }
  const std::string self = process_name();
  const store::RecoveryOutcome recovered = store->recover_interrupted_jobs(
      options.max_attempts, jobs::worker_lost_problem, [&](const std::string& worker) { return worker_gone(worker, self); });
  if (recovered.requeued > 0) log_line("manipid: " + std::to_string(recovered.requeued) + " interrupted job(s) queued again");
  if (recovered.cancelled > 0) log_line("manipid: " + std::to_string(recovered.cancelled) + " interrupted job(s) cancelled as asked");
  for (const std::string& id : recovered.failed) {
    log_line("manipid: job " + id + " failed: its worker died " + std::to_string(options.max_attempts) +
             " or more times while running it");
  }
  return store;
}

jobs::WorkerPoolOptions worker_pool_options(const JobOptions& options) {
  jobs::WorkerPoolOptions pool;
  pool.workers = worker_threads(options);
  pool.runner.job_time_limit_seconds = options.job_timeout;
  pool.job_memory = parse_size(options.job_memory, "--job-memory");
  pool.owner = process_name();
  pool.lease = std::chrono::milliseconds(static_cast<long>(std::lround(options.lease * 1000.0)));
  pool.max_attempts = options.max_attempts;
  return pool;
}

sigset_t block_stop_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  return signals;
}

std::string process_name() {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0 || host[0] == '\0') std::snprintf(host, sizeof host, "localhost");
  return std::string(host) + ":" + std::to_string(getpid());
}

void log_line(const std::string& line) {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto millis = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char stamp[40];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%S", &utc);
  std::lock_guard lock(log_mutex);
  std::fprintf(stderr, "%s.%03dZ %s\n", stamp, static_cast<int>(millis), line.c_str());
}

std::size_t parse_size(const std::string& text, const std::string& option) {
  std::size_t digits = 0;
  while (digits < text.size() && std::isdigit(static_cast<unsigned char>(text[digits]))) ++digits;
  std::string unit = text.substr(digits);
  std::transform(unit.begin(), unit.end(), unit.begin(), [](unsigned char c) { return std::tolower(c); });
  std::size_t scale = 0;
  if (unit.empty() || unit == "b") scale = 1;
  else if (unit == "k" || unit == "kib" || unit == "kb") scale = 1u << 10;
  else if (unit == "m" || unit == "mib" || unit == "mb") scale = 1u << 20;
  else if (unit == "g" || unit == "gib" || unit == "gb") scale = 1u << 30;
  if (digits == 0 || digits > 12 || scale == 0) {
    throw UsageError(option + ": expected a size such as 64MiB, 500k or 1048576, got '" + text + "'");
  }
  const std::size_t size = std::stoull(text.substr(0, digits)) * scale;
  if (size < 1024) throw UsageError(option + ": at least 1k, got '" + text + "'");
  return size;
}

}  // namespace manipid::server::cli
