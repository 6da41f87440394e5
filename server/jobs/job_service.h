// job_service.h — the Service the HTTP routes call (api/service.h), made of the store and the
// worker pool: submissions go to the store as the caller's and wake a worker; reads (within the
// caller's scope) merge the store's row with the pool's live progress; long-polls sleep on the
// pool's change signal.
#pragma once

#include "manipid/api/service.h"
#include "store/store.h"
#include "jobs/worker_pool.h"

#include <atomic>
#include <functional>
#include <string>

namespace manipid::server::jobs {

struct JobServiceOptions {
  int queue_limit = 10000;  ///< queued jobs at most; more → 429 (≤ 0: no limit)
  /// Job transitions made here (queued, cancelled while queued); the pool logs the rest.
  std::function<void(const std::string& line)> log;
};

class JobService : public api::Service {
 public:
  JobService(store::Store& store, WorkerPool& pool, JobServiceOptions options);

  api::DatasetCreated create_dataset(const api::Caller& caller, const api::DatasetUpload& upload,
                                     const std::optional<api::IdempotencyKey>& key) override;
  std::optional<api::DatasetInfo> dataset(const api::Caller& caller, const std::string& id) override;
  std::optional<Trajectory> dataset_data(const api::Caller& caller, const std::string& id) override;
  api::Page<api::DatasetInfo> datasets(const api::Caller& caller, const api::PageRequest& page) override;
  api::DeleteOutcome delete_dataset(const api::Caller& caller, const std::string& id) override;

  api::RobotCreated create_robot(const api::Caller& caller, const api::RobotUpload& upload,
                                 std::shared_ptr<const api::ParsedRobot> parsed, const std::string& description,
                                 const std::optional<api::IdempotencyKey>& key) override;
  std::optional<api::RobotInfo> robot(const api::Caller& caller, const std::string& id) override;
  std::optional<std::string> robot_urdf(const api::Caller& caller, const std::string& id) override;
  std::shared_ptr<const api::ParsedRobot> parsed_robot(const api::Caller& caller, const std::string& id) override;
  api::Page<api::RobotInfo> robots(const api::Caller& caller, const api::PageRequest& page) override;
  api::DeleteOutcome delete_robot(const api::Caller& caller, const std::string& id) override;

  api::SubmitResult submit(const api::Caller& caller, const api::JobSubmission& submission,
                           const std::optional<api::IdempotencyKey>& key) override;
  std::optional<api::JobInfo> job(const api::Caller& caller, const std::string& id) override;
  std::optional<api::JobInfo> wait(const api::Caller& caller, const std::string& id, double seconds) override;
  api::Page<api::JobInfo> jobs(const api::Caller& caller, const api::JobFilter& filter,
                               const api::PageRequest& page) override;
  std::optional<api::Page<api::HistoryEntry>> history(const api::Caller& caller, const std::string& id,
                                                      const api::PageRequest& page) override;
  std::optional<api::HistoryOverview> history_overview(const api::Caller& caller, const std::string& id,
                                                       long max_points) override;
  std::optional<api::JobInfo> cancel(const api::Caller& caller, const std::string& id) override;
  api::DeleteOutcome delete_job(const api::Caller& caller, const std::string& id) override;

  std::string metrics() override;
  bool accepting() const override { return accepting_.load(); }
  /// The store's write trouble (a full disk), in words for /healthz.
  std::optional<std::string> degraded() const override;
  /// Refuse new submissions from now on (shutdown has begun).
  void stop_accepting() { accepting_ = false; }

 private:
  api::JobInfo with_live_progress(api::JobInfo job) const;

  store::Store& store_;
  WorkerPool& pool_;
  JobServiceOptions options_;
  std::atomic<bool> accepting_{true};
};

}  // namespace manipid::server::jobs
