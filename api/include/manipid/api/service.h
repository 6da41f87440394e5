// service.h — what the HTTP routes need from the process behind them. server/ implements it
// over the job store and the worker pool; the routes (routes.h) only map HTTP to these calls,
// so they can be tested against a fake.
//
// Errors a caller can fix come back as ApiError (problem.h): queue full, idempotency-key
// mismatch, wrong state. "Not there" is an empty optional — and so is another owner's resource:
// every call takes the Caller, and what is outside its scope is answered exactly as missing.
#pragma once

#include "manipid/api/records.h"
#include "manipid/api/requests.h"
#include "manipid/api/robot_requests.h"

#include <memory>
#include <optional>
#include <string>

namespace manipid::api {

enum class DeleteOutcome { deleted, not_found, conflict };

/// Who a request acts for: the named token it came with (`manipid serve --token-file`).
struct Caller {
  std::string owner;   ///< what it creates is this owner's ("" for --token or a server without tokens)
  bool admin = true;   ///< sees and acts on every owner's resources (an admin token, --token, no token at all)
  /// What its reads, cancels and deletes reach.
  OwnerScope scope() const { return admin ? all_owners : OwnerScope(owner); }
};

struct SubmitResult {
  JobInfo job;
  bool replayed = false;  ///< the Idempotency-Key matched an earlier submission
};

struct DatasetCreated {
  DatasetInfo dataset;
  bool replayed = false;
};

struct RobotCreated {
  RobotInfo robot;
  bool replayed = false;
};

/// A job to queue, its request validated already.
struct JobSubmission {
  JobKind kind = JobKind::identification;
  std::string request_json;
  std::string dataset_id;             ///< the identification's input dataset (empty for simulations)
  std::string robot_id;               ///< the URDF robot it works on (empty for the preset)
  std::string validation_dataset_id;  ///< a second dataset it reads
};

class Service {
 public:
  virtual ~Service() = default;

  virtual DatasetCreated create_dataset(const Caller& caller, const DatasetUpload& upload,
                                        const std::optional<IdempotencyKey>& key) = 0;
  virtual std::optional<DatasetInfo> dataset(const Caller& caller, const std::string& id) = 0;
  virtual std::optional<Trajectory> dataset_data(const Caller& caller, const std::string& id) = 0;
  virtual Page<DatasetInfo> datasets(const Caller& caller, const PageRequest& page) = 0;
  virtual DeleteOutcome delete_dataset(const Caller& caller, const std::string& id) = 0;

  /// A URDF robot, parsed already (`parsed`: kept for its jobs and views; `description`: robot_json.h's
  /// robot_description as JSON text).
  virtual RobotCreated create_robot(const Caller& caller, const RobotUpload& upload,
                                    std::shared_ptr<const ParsedRobot> parsed, const std::string& description,
                                    const std::optional<IdempotencyKey>& key) = 0;
  virtual std::optional<RobotInfo> robot(const Caller& caller, const std::string& id) = 0;
  /// The URDF document as uploaded.
  virtual std::optional<std::string> robot_urdf(const Caller& caller, const std::string& id) = 0;
  /// The stored robot parsed, once per process (robot_cache.h), or nullptr when the caller has none by that id.
  virtual std::shared_ptr<const ParsedRobot> parsed_robot(const Caller& caller, const std::string& id) = 0;
  virtual Page<RobotInfo> robots(const Caller& caller, const PageRequest& page) = 0;
  /// Conflict while a queued or running job uses it.
  virtual DeleteOutcome delete_robot(const Caller& caller, const std::string& id) = 0;

  /// Queues a job whose request was validated already.
  virtual SubmitResult submit(const Caller& caller, const JobSubmission& submission,
                              const std::optional<IdempotencyKey>& key) = 0;
  /// The job with its live progress.
  virtual std::optional<JobInfo> job(const Caller& caller, const std::string& id) = 0;
  /// As job(), but first waits up to `seconds` for it to reach a terminal state.
  virtual std::optional<JobInfo> wait(const Caller& caller, const std::string& id, double seconds) = 0;
  virtual Page<JobInfo> jobs(const Caller& caller, const JobFilter& filter, const PageRequest& page) = 0;
  /// The cost history in index order, a page at a time; empty optional if no such job.
  virtual std::optional<Page<HistoryEntry>> history(const Caller& caller, const std::string& id,
                                                    const PageRequest& page) = 0;
  /// The history thinned to about `max_points` entries for drawing (see HistoryOverview).
  virtual std::optional<HistoryOverview> history_overview(const Caller& caller, const std::string& id,
                                                          long max_points) = 0;
  /// Best effort and idempotent: a queued job ends cancelled at once, a running one at its
  /// next cost evaluation; a finished job is returned unchanged.
  virtual std::optional<JobInfo> cancel(const Caller& caller, const std::string& id) = 0;
  /// Finished jobs only (conflict while queued or running).
  virtual DeleteOutcome delete_job(const Caller& caller, const std::string& id) = 0;

  /// Prometheus text for the job side (jobs by state, queue depth, job durations), every owner's:
  /// the routes answer it to admin tokens only.
  virtual std::string metrics() = 0;
  /// False once the server is shutting down.
  virtual bool accepting() const = 0;
  /// Why the server works only in part now (e.g. "the disk holding the database is full":
  /// reads answer, writes get 507), or nullopt when all is well. /healthz says "degraded".
  virtual std::optional<std::string> degraded() const = 0;
};

}  // namespace manipid::api
