// worker_pool.cpp — the job threads (worker_pool.h).
#include "jobs/worker_pool.h"

#include "manipid/api/problem.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace manipid::server::jobs {

std::string worker_lost_problem(int losses) {
  return api::problem_to_json({api::ProblemKind::worker_lost,
                               "the worker stopped while running this job " + std::to_string(losses) +
                                   " times (the process crashed, was killed or stopped renewing its lease); it will "
                                   "not be run again",
                               ""})
      .dump();
}

WorkerPool::WorkerPool(store::Store& store, WorkerPoolOptions options, Log log)
    : store_(store), options_(std::move(options)), log_(std::move(log)) {
  if (!options_.runner.robots) options_.runner.robots = &robots_;
  statistics_.duration_bucket_bounds = {0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 300, 3600};
  statistics_.duration_buckets.assign(statistics_.duration_bucket_bounds.size(), 0);
}

WorkerPool::~WorkerPool() { stop(); }

void WorkerPool::start() {
  // What other processes on the database do, told at once where the store can (PostgreSQL):
  // a job to claim wakes an idle worker, a cancel reaches the job running here, an end wakes
  // this process's long-polls. Without it (SQLite) the workers and long-polls look every second.
  watching_ = store_.watch_jobs([this](const store::JobEvent& event) { heed_event(event); });
  for (int i = 0; i < options_.workers; ++i) threads_.emplace_back([this] { work(); });
  keeper_ = std::thread([this] { keep_leases(); });
}

void WorkerPool::heed_event(const store::JobEvent& event) {
  switch (event.kind) {
    case store::JobEvent::Kind::queued:
      notify_submitted();
      break;
    case store::JobEvent::Kind::cancel_requested: {
      bool here = false;
      {
        std::lock_guard lock(mutex_);
        if (auto found = live_.find(event.job_id); found != live_.end()) {
          found->second->cancel = true;
          here = true;
        }
      }
      if (here) memory_freed_.notify_all();  // a job waiting for memory ends at once
      break;
    }
    case store::JobEvent::Kind::changed:
      notify_changed();
      break;
  }
}

void WorkerPool::stop() {
  // No more events: replacing the watcher waits for one being heeded to return.
  if (watching_) {
    store_.watch_jobs({});
    watching_ = false;
  }
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && threads_.empty()) return;
    stopping_ = true;
    for (auto& [id, live] : live_) {
      live->shutdown = true;
      live->cancel = true;
    }
  }
  work_available_.notify_all();
  memory_freed_.notify_all();
  keeper_wake_.notify_all();
  for (std::thread& thread : threads_) thread.join();
  threads_.clear();
  // After the workers: their jobs went back to the queue under leases the keeper no longer renews.
  if (keeper_.joinable()) keeper_.join();
  changed_.notify_all();
}

void WorkerPool::notify_submitted() {
  {
    std::lock_guard lock(mutex_);
    ++submissions_;
  }
  work_available_.notify_one();
}

void WorkerPool::cancel(const std::string& id) {
  {
    std::lock_guard lock(mutex_);
    if (auto found = live_.find(id); found != live_.end()) {
      found->second->cancel = true;
    } else {
      pending_cancels_.insert(id);
    }
  }
  memory_freed_.notify_all();  // a job waiting for memory ends at once
}

std::optional<LiveProgress> WorkerPool::progress(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const auto found = live_.find(id);
  if (found == live_.end()) return std::nullopt;
  LiveProgress progress;
  progress.evaluations = found->second->evaluations.load();
  const double best = found->second->best_cost.load();
  if (std::isfinite(best)) progress.best_cost = best;
  return progress;
}

unsigned long WorkerPool::generation() const {
  std::lock_guard lock(mutex_);
  return generation_;
}

void WorkerPool::wait_for_change(unsigned long generation, std::chrono::steady_clock::time_point deadline) const {
  std::unique_lock lock(mutex_);
  changed_.wait_until(lock, deadline, [&] { return generation_ != generation || stopping_; });
}

void WorkerPool::notify_changed() {
  {
    std::lock_guard lock(mutex_);
    ++generation_;
  }
  changed_.notify_all();
}

void WorkerPool::keep_leases() {
  const auto period = std::max(options_.lease / 3, std::chrono::milliseconds(20));
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      if (keeper_wake_.wait_for(lock, period, [&] { return stopping_; })) return;
    }
    // Renew first: after this process was paused past its leases, its own jobs are not
    // recovered from under it when no other process took them meanwhile.
    renew_leases();
    try {
      const store::RecoveryOutcome recovered = store_.recover_expired_leases(options_.max_attempts, options_.lost_error);
      if (recovered.requeued > 0) {
        log_("leases: " + std::to_string(recovered.requeued) + " job(s) whose worker stopped renewing its lease queued again");
        notify_submitted();
      }
      if (recovered.cancelled > 0) {
        log_("leases: " + std::to_string(recovered.cancelled) + " job(s) whose worker stopped renewing its lease cancelled as asked");
      }
      for (const std::string& id : recovered.failed) {
        log_("leases: job " + id + " failed: its worker was lost " + std::to_string(options_.max_attempts) +
             " or more times while running it");
      }
      if (recovered.requeued + recovered.cancelled > 0 || !recovered.failed.empty()) notify_changed();
    } catch (const std::exception& error) {
      log_(std::string("leases: cannot recover expired leases: ") + error.what());
    }
  }
}

void WorkerPool::renew_leases() {
  std::vector<std::shared_ptr<LiveJob>> running;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [id, live] : live_) {
      if (!live->lost.load()) running.push_back(live);
    }
  }
  for (const auto& live : running) {
    try {
      heed(store_.renew_lease(live->lease, options_.lease), *live);
      if (live->lost.load()) {
        log_("job " + live->lease.job_id + ": lease lost (attempt " + std::to_string(live->lease.attempt) +
             " expired and the job was taken over); stopping it without writing anything more");
      }
    } catch (const std::exception& error) {
      log_("job " + live->lease.job_id + ": cannot renew its lease: " + error.what());
    }
  }
  memory_freed_.notify_all();  // a job cancelled while it waits for memory ends at once
}

bool WorkerPool::pause_unless_stopping(std::chrono::milliseconds delay) {
  std::unique_lock lock(mutex_);
  return !work_available_.wait_for(lock, delay, [&] { return stopping_; });
}

bool WorkerPool::record_end(const api::JobInfo& job, LiveJob& live, JobOutcome& outcome) {
  const store::Lease& lease = live.lease;
  // A full disk (StorageFull) or an unreachable database (StoreUnavailable) keeps the end as
  // computed: once space is freed or the database is back it is written, and an hour's
  // identification keeps its result. Any other storage failure may be the result
  // itself (over a limit of the store): after two tries the job is recorded failed with a short
  // error and no estimates — a far smaller write — tried until it sticks. Either way a job never
  // stays `running` for good: it ends when the store takes a write again (a cancel cannot end it
  // sooner: a cancel is a write too, answered 507 while the disk is full).
  constexpr int kTriesAsComputed = 2;
  bool as_computed = true;
  std::chrono::milliseconds delay{250};
  for (int attempt = 1;; ++attempt) {
    try {
      if (!store_.finish_job(lease, outcome)) {
        log_("job " + job.id + ": its end was not recorded: attempt " + std::to_string(lease.attempt) +
             " no longer holds the job's lease (it was recovered, or it had ended)");
        live.lost = true;
        return true;
      }
      if (attempt > 1) log_("job " + job.id + ": its end was recorded at attempt " + std::to_string(attempt));
      return true;
    } catch (const std::exception& error) {
      // A full disk or a database away for a moment: the end as computed is written once it can be.
      const bool passing = dynamic_cast<const store::StorageFull*>(&error) != nullptr ||
                           dynamic_cast<const store::StoreUnavailable*>(&error) != nullptr;
      log_("job " + job.id + ": cannot record its end (attempt " + std::to_string(attempt) + "): " + error.what());
      if (as_computed && !passing && attempt >= kTriesAsComputed) {
        as_computed = false;
        const std::string dataset_id = outcome.dataset_id;  // made or read: it is stored already
        outcome = JobOutcome{};
        outcome.state = api::JobState::failed;
        outcome.dataset_id = dataset_id;
        outcome.error = api::problem_to_json({api::ProblemKind::job_failed,
                                              "the job ran, but its result could not be stored (a storage error; see the server log)", ""})
                            .dump();
      }
    }
    if (!pause_unless_stopping(delay)) return false;
    delay = std::min(delay * 2, options_.final_write_max_backoff);
  }
}

bool WorkerPool::set_memory_aside(std::size_t bytes, const LiveJob& live) {
  std::unique_lock lock(mutex_);
  memory_freed_.wait(lock, [&] { return stopping_ || live.cancel.load() || memory_set_aside_ + bytes <= options_.job_memory; });
  if (stopping_ || live.cancel.load()) return false;
  memory_set_aside_ += bytes;
  return true;
}

void WorkerPool::give_memory_back(std::size_t bytes) {
  {
    std::lock_guard lock(mutex_);
    memory_set_aside_ -= bytes;
  }
  memory_freed_.notify_all();
}

PoolStatistics WorkerPool::statistics() const {
  std::lock_guard lock(mutex_);
  PoolStatistics copy = statistics_;
  copy.running = static_cast<long>(live_.size());
  copy.job_memory_reserved = memory_set_aside_;
  copy.job_memory_budget = options_.job_memory;
  return copy;
}

void WorkerPool::work() {
  unsigned long seen = 0;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      if (stopping_) return;
      seen = submissions_;
    }
    std::optional<api::JobInfo> job;
    try {
      job = store_.claim_next_job(options_.owner, options_.lease);
    } catch (const std::exception& error) {
      log_(std::string("worker: cannot claim a job: ") + error.what());
    }
    if (job) {
      run_one(*job);
      continue;
    }
    std::unique_lock lock(mutex_);
    work_available_.wait_for(lock, options_.idle_poll, [&] { return stopping_ || submissions_ != seen; });
  }
}

JobOutcome WorkerPool::run_within_memory(const api::JobInfo& job, LiveJob& live) {
  std::size_t need = 0;
  try {
    need = api::job_memory_bytes(job_shape(job.kind, job.request, store_, api::all_owners));
  } catch (const std::exception&) {
    // A request that no longer parses: run_job fails it with the parser's reason.
  }
  const std::string attempt = "attempt " + std::to_string(job.attempts);
  if (need > options_.job_memory) {
    // Queued before a restart with a smaller --job-memory: it could never start.
    JobOutcome outcome;
    outcome.error = api::problem_to_json({api::ProblemKind::job_failed,
                                          "this job would hold about " + api::describe_bytes(need) +
                                              " of memory while it runs; this server runs jobs within " +
                                              api::describe_bytes(options_.job_memory) + " (--job-memory)",
                                          ""})
                        .dump();
    return outcome;
  }
  bool waited = false;
  {
    std::lock_guard lock(mutex_);
    waited = memory_set_aside_ + need > options_.job_memory;
  }
  if (waited) log_("job " + job.id + ": waits for " + api::describe_bytes(need) + " of --job-memory");
  if (!set_memory_aside(need, live)) {
    JobOutcome outcome;
    outcome.requeue = live.shutdown.load();  // a shutdown puts it back; a user's cancel ends it
    outcome.state = api::JobState::cancelled;
    return outcome;
  }
  log_("job " + job.id + " " + api::to_string(job.kind) + ": running (" + attempt + "; holds about " +
       api::describe_bytes(need) + " of --job-memory " + api::describe_bytes(options_.job_memory) + ")");
  JobOutcome outcome = options_.run(job, store_, live, options_.runner);
  give_memory_back(need);
  return outcome;
}

void WorkerPool::run_one(const api::JobInfo& job) {
  auto live = std::make_shared<LiveJob>();
  live->lease = {job.id, job.worker, job.attempts};
  bool registered = false;
  {
    std::lock_guard lock(mutex_);
    if (pending_cancels_.erase(job.id) > 0 || job.cancel_requested) live->cancel = true;
    if (!stopping_) {
      live_[job.id] = live;
      registered = true;
    }
  }
  if (!registered) {
    // Claimed while the pool was stopping: back to the queue untouched, for the next start.
    try {
      store_.requeue_job(live->lease);
    } catch (const std::exception& error) {
      log_("job " + job.id + ": cannot requeue: " + error.what());
    }
    return;
  }
  const auto started = std::chrono::steady_clock::now();
  JobOutcome outcome = run_within_memory(job, *live);
  if (!outcome.log.empty()) log_("job " + job.id + ": " + outcome.log);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (live->lost.load()) {
    // Another process recovered the job: its attempt is the one that counts; this one wrote nothing.
    outcome.requeue = true;
  } else if (outcome.requeue) {
    try {
      store_.requeue_job(live->lease);
    } catch (const std::exception& error) {
      // The row stays running; the next start-up puts it back in the queue.
      log_("job " + job.id + ": cannot put it back in the queue: " + error.what());
    }
  } else if (!record_end(job, *live, outcome)) {
    outcome.requeue = true;  // stopped while its end could not be written: recovery requeues it
  }
  char duration[32];
  std::snprintf(duration, sizeof duration, "%.3f", seconds);
  const std::string end = live->lost.load() ? "stopped, its lease lost"
                          : outcome.requeue   ? "queued again (shutdown)"
                                              : api::to_string(outcome.state);
  log_("job " + job.id + " " + api::to_string(job.kind) + ": " + end + " after " + duration + " s");
  {
    std::lock_guard lock(mutex_);
    live_.erase(job.id);
    ++generation_;
    if (!outcome.requeue && !live->lost.load()) {
      ++statistics_.finished[std::string(api::to_string(job.kind)) + "," + api::to_string(outcome.state)];
      ++statistics_.duration_count;
      statistics_.duration_sum += seconds;
      for (std::size_t b = 0; b < statistics_.duration_bucket_bounds.size(); ++b) {
        if (seconds <= statistics_.duration_bucket_bounds[b]) ++statistics_.duration_buckets[b];
      }
    }
  }
  changed_.notify_all();
}

}  // namespace manipid::server::jobs
