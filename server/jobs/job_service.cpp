// job_service.cpp — the routes' Service over the store and the worker pool (job_service.h).
#include "jobs/job_service.h"

#include "manipid/api/problem.h"

#include <algorithm>
#include <chrono>
#include <sstream>

namespace manipid::server::jobs {

JobService::JobService(store::Store& store, WorkerPool& pool, JobServiceOptions options)
    : store_(store), pool_(pool), options_(options) {}

namespace {

[[noreturn]] void key_reused() {
  throw api::ApiError(api::ProblemKind::idempotency_mismatch,
                      "this Idempotency-Key was used before with a different request body; use a new key for a new request",
                      "Idempotency-Key");
}

api::DeleteOutcome outcome_of(store::DeleteResult result) {
  switch (result) {
    case store::DeleteResult::deleted: return api::DeleteOutcome::deleted;
    case store::DeleteResult::in_use: return api::DeleteOutcome::conflict;
    default: return api::DeleteOutcome::not_found;
  }
}

/// A store call; a database that cannot be reached now (PostgreSQL restarting, a network cut)
/// is 503 with Retry-After: nothing was done, the same request may succeed shortly.
template <class Call>
auto reached(Call&& call) {
  try {
    return call();
  } catch (const store::StoreUnavailable&) {
    throw api::ApiError(api::ProblemKind::store_unavailable,
                        "the database cannot be reached now: nothing was done; retry shortly");
  }
}

/// A store's write; a full disk is the client's 507 (nothing was stored; retry later), not a 500.
template <class Write>
auto stored(Write&& write) {
  try {
    return reached(write);
  } catch (const store::StorageFull&) {
    throw api::ApiError(api::ProblemKind::insufficient_storage,
                        "the server's disk is full: nothing was stored; retry when space has been freed");
  }
}

/// A store's list call; a page request it refuses is the caller's mistake (422 naming the field).
template <class Read>
auto page_of(Read&& read) {
  try {
    return reached(read);
  } catch (const store::PageRequestError& error) {
    throw api::ApiError(api::ProblemKind::invalid_field, error.what(), error.field());
  }
}

}  // namespace

api::DatasetCreated JobService::create_dataset(const api::Caller& caller, const api::DatasetUpload& upload,
                                               const std::optional<api::IdempotencyKey>& key) {
  if (!accepting()) throw api::ApiError(api::ProblemKind::shutting_down, "the server is shutting down");
  const store::DatasetOutcome outcome =
      stored([&] { return store_.insert_dataset(caller.owner, upload.name, upload.trajectory, "", key); });
  if (outcome.status == store::SubmitStatus::key_reused) key_reused();
  return {outcome.dataset, outcome.status == store::SubmitStatus::replayed};
}

std::optional<api::DatasetInfo> JobService::dataset(const api::Caller& caller, const std::string& id) {
  return reached([&] { return store_.find_dataset(caller.scope(), id); });
}
std::optional<Trajectory> JobService::dataset_data(const api::Caller& caller, const std::string& id) {
  return reached([&] { return store_.load_dataset(caller.scope(), id); });
}
api::Page<api::DatasetInfo> JobService::datasets(const api::Caller& caller, const api::PageRequest& page) {
  return page_of([&] { return store_.list_datasets(caller.scope(), page); });
}

api::DeleteOutcome JobService::delete_dataset(const api::Caller& caller, const std::string& id) {
  return outcome_of(stored([&] { return store_.delete_dataset(caller.scope(), id); }));
}

api::RobotCreated JobService::create_robot(const api::Caller& caller, const api::RobotUpload& upload,
                                           std::shared_ptr<const api::ParsedRobot> parsed, const std::string& description,
                                           const std::optional<api::IdempotencyKey>& key) {
  if (!accepting()) throw api::ApiError(api::ProblemKind::shutting_down, "the server is shutting down");
  const int joints = parsed->model.joint_count();
  const store::RobotOutcome outcome = stored([&] {
    return store_.insert_robot({upload.name, upload.urdf, upload.base, upload.tip, joints, description, caller.owner}, key);
  });
  if (outcome.status == store::SubmitStatus::key_reused) key_reused();
  pool_.robots().keep(outcome.robot.id, std::move(parsed), upload.urdf.size());  // parsed once: its jobs read it here
  return {outcome.robot, outcome.status == store::SubmitStatus::replayed};
}

std::optional<api::RobotInfo> JobService::robot(const api::Caller& caller, const std::string& id) {
  return reached([&] { return store_.find_robot(caller.scope(), id); });
}
std::optional<std::string> JobService::robot_urdf(const api::Caller& caller, const std::string& id) {
  return reached([&] { return store_.load_robot_urdf(caller.scope(), id); });
}
std::shared_ptr<const api::ParsedRobot> JobService::parsed_robot(const api::Caller& caller, const std::string& id) {
  const std::optional<api::RobotInfo> found = robot(caller, id);
  if (!found) return nullptr;
  return pool_.robots().get(*found, [&] { return robot_urdf(caller, id); });
}
api::Page<api::RobotInfo> JobService::robots(const api::Caller& caller, const api::PageRequest& page) {
  return page_of([&] { return store_.list_robots(caller.scope(), page); });
}
api::DeleteOutcome JobService::delete_robot(const api::Caller& caller, const std::string& id) {
  return outcome_of(stored([&] { return store_.delete_robot(caller.scope(), id); }));
}

api::SubmitResult JobService::submit(const api::Caller& caller, const api::JobSubmission& submission,
                                     const std::optional<api::IdempotencyKey>& key) {
  if (!accepting()) throw api::ApiError(api::ProblemKind::shutting_down, "the server is shutting down");
  const api::JobKind kind = submission.kind;
  // A job that could never fit in --job-memory is refused now, naming what sets its size. The
  // routes checked that the caller sees the datasets and robot it names; the sizes are read
  // within the same scope, so nothing of another owner's is measured either.
  api::check_job_memory(job_shape(kind, submission.request_json, store_, caller.scope()), pool_.job_memory_budget());
  const store::SubmitOutcome outcome = stored([&] {
    return store_.submit_job({kind, submission.request_json, submission.dataset_id, submission.robot_id,
                              submission.validation_dataset_id, caller.owner},
                             key, options_.queue_limit);
  });
  switch (outcome.status) {
    case store::SubmitStatus::key_reused: key_reused();
    case store::SubmitStatus::queue_full:
      throw api::ApiError(api::ProblemKind::queue_full, "the job queue is full (" + std::to_string(options_.queue_limit) +
                                                            " queued jobs); retry later");
    case store::SubmitStatus::created:
      if (options_.log) {
        options_.log("job " + outcome.job.id + " " + api::to_string(kind) + ": queued" +
                     (caller.owner.empty() ? "" : " for " + caller.owner));
      }
      pool_.notify_submitted();
      break;
    case store::SubmitStatus::replayed: break;
  }
  return {with_live_progress(outcome.job), outcome.status == store::SubmitStatus::replayed};
}

api::JobInfo JobService::with_live_progress(api::JobInfo job) const {
  if (job.state != api::JobState::running) return job;
  if (const auto live = pool_.progress(job.id)) {
    job.evaluations = std::max(job.evaluations, live->evaluations);
    if (live->best_cost) job.best_cost = live->best_cost;
  }
  return job;
}

std::optional<api::JobInfo> JobService::job(const api::Caller& caller, const std::string& id) {
  auto found = reached([&] { return store_.find_job(caller.scope(), id); });
  if (!found) return std::nullopt;
  return with_live_progress(std::move(*found));
}

namespace {
constexpr std::chrono::seconds kWaitPoll{1};
}  // namespace

std::optional<api::JobInfo> JobService::wait(const api::Caller& caller, const std::string& id, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                                std::chrono::duration<double>(std::max(0.0, seconds)));
  for (;;) {
    const unsigned long generation = pool_.generation();
    auto found = job(caller, id);
    if (!found || api::is_terminal(found->state) || std::chrono::steady_clock::now() >= deadline || !accepting()) {
      return found;
    }
    // This process's workers wake the wait at once; a job another process runs on the same
    // database is looked at again every second.
    pool_.wait_for_change(generation, std::min(deadline, std::chrono::steady_clock::now() + kWaitPoll));
  }
}

api::Page<api::JobInfo> JobService::jobs(const api::Caller& caller, const api::JobFilter& filter,
                                         const api::PageRequest& page) {
  api::Page<api::JobInfo> result = page_of([&] { return store_.list_jobs(caller.scope(), filter, page); });
  for (api::JobInfo& job : result.items) job = with_live_progress(std::move(job));
  return result;
}

std::optional<api::Page<api::HistoryEntry>> JobService::history(const api::Caller& caller, const std::string& id,
                                                                const api::PageRequest& page) {
  return page_of([&] { return store_.history(caller.scope(), id, page); });
}

std::optional<api::HistoryOverview> JobService::history_overview(const api::Caller& caller, const std::string& id,
                                                                 long max_points) {
  return reached([&] { return store_.history_overview(caller.scope(), id, max_points); });
}

std::optional<api::JobInfo> JobService::cancel(const api::Caller& caller, const std::string& id) {
  switch (stored([&] { return store_.cancel_job(caller.scope(), id); })) {
    case store::CancelOutcome::not_found: return std::nullopt;
    case store::CancelOutcome::cancelled_now:
      if (options_.log) options_.log("job " + id + ": cancelled (was queued)");
      pool_.notify_changed();
      break;
    case store::CancelOutcome::requested:
      if (options_.log) options_.log("job " + id + ": cancel requested");
      pool_.cancel(id);
      break;
    case store::CancelOutcome::already_finished: break;
  }
  return job(caller, id);
}

api::DeleteOutcome JobService::delete_job(const api::Caller& caller, const std::string& id) {
  return outcome_of(stored([&] { return store_.delete_job(caller.scope(), id); }));
}

std::optional<std::string> JobService::degraded() const {
  if (!store_.write_trouble()) return std::nullopt;
  return "the disk holding the database is full: reads answer, writes are refused (507) until space is freed";
}

std::string JobService::metrics() {
  std::ostringstream out;
  const auto counts = reached([&] { return store_.count_jobs_by_state(); });
  out << "# HELP manipid_jobs Jobs in the store by state.\n# TYPE manipid_jobs gauge\n";
  for (const auto& [state, count] : counts) out << "manipid_jobs{state=\"" << api::to_string(state) << "\"} " << count << "\n";
  const auto queued = counts.find(api::JobState::queued);
  out << "# HELP manipid_queue_depth Jobs waiting for a worker.\n# TYPE manipid_queue_depth gauge\n"
      << "manipid_queue_depth " << (queued == counts.end() ? 0 : queued->second) << "\n";
  const PoolStatistics statistics = pool_.statistics();
  out << "# HELP manipid_jobs_running Jobs this process is running now.\n# TYPE manipid_jobs_running gauge\n"
      << "manipid_jobs_running " << statistics.running << "\n";
  out << "# HELP manipid_job_memory_reserved_bytes Memory the running jobs hold by their estimates.\n"
         "# TYPE manipid_job_memory_reserved_bytes gauge\n"
      << "manipid_job_memory_reserved_bytes " << statistics.job_memory_reserved << "\n"
      << "# HELP manipid_job_memory_budget_bytes What they may hold together (--job-memory).\n"
         "# TYPE manipid_job_memory_budget_bytes gauge\n"
      << "manipid_job_memory_budget_bytes " << statistics.job_memory_budget << "\n";
  out << "# HELP manipid_jobs_finished_total Jobs this process finished, by kind and end state.\n"
         "# TYPE manipid_jobs_finished_total counter\n";
  for (const auto& [key, count] : statistics.finished) {
    const auto comma = key.find(',');
    out << "manipid_jobs_finished_total{kind=\"" << key.substr(0, comma) << "\",state=\"" << key.substr(comma + 1)
        << "\"} " << count << "\n";
  }
  out << "# HELP manipid_job_duration_seconds Wall time of finished jobs.\n"
         "# TYPE manipid_job_duration_seconds histogram\n";
  for (std::size_t b = 0; b < statistics.duration_bucket_bounds.size(); ++b) {
    out << "manipid_job_duration_seconds_bucket{le=\"" << statistics.duration_bucket_bounds[b] << "\"} "
        << statistics.duration_buckets[b] << "\n";
  }
  out << "manipid_job_duration_seconds_bucket{le=\"+Inf\"} " << statistics.duration_count << "\n"
      << "manipid_job_duration_seconds_sum " << statistics.duration_sum << "\n"
      << "manipid_job_duration_seconds_count " << statistics.duration_count << "\n";
  return out.str();
}

}  // namespace manipid::server::jobs
