// fake_service.h — an in-memory api::Service for the route tests (routes_test.cpp): datasets,
// jobs and histories in maps, every call and its caller recorded, scriptable answers (replays,
// errors, exceptions, shutting down), and the owner rule the real one keeps (another owner's
// resource is missing), so the routes are tested without SQLite or workers.
#pragma once

#include "manipid/api/problem.h"
#include "manipid/api/robot_cache.h"
#include "manipid/api/service.h"

#include <algorithm>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace manipid::api::testing {

/// What the next calls do instead of their ordinary work (FakeService::script replaces it).
struct Script {
  bool replay = false;                         ///< submit / create_dataset answer "replayed"
  std::optional<ProblemKind> submit_error;     ///< submit throws ApiError of this kind
  std::optional<DeleteOutcome> delete_outcome; ///< delete_dataset / delete_job answer this
  std::string throw_what;                      ///< non-empty: every call throws std::runtime_error(this)
  bool throw_non_standard = false;             ///< every call throws an int (not a std::exception)
  bool throw_bad_alloc = false;                ///< every call throws std::bad_alloc
  std::string next_page_token;                 ///< datasets() / jobs() answer with this token
};

struct Submission {
  JobKind kind = JobKind::identification;
  std::string request_json;
  std::string dataset_id;
  std::optional<IdempotencyKey> key;
  std::string robot_id;
  std::string validation_dataset_id;
};

struct Upload {
  DatasetUpload upload;
  std::optional<IdempotencyKey> key;
};

class FakeService : public Service {
 public:
  // ---- Test side: fill and script (under the lock: handlers run on the server's threads) ----
  void add_dataset(const DatasetInfo& info, std::optional<Trajectory> data = std::nullopt) {
    std::lock_guard lock(mutex_);
    datasets_[info.id] = info;
    if (data) data_[info.id] = *data;
  }
  void add_job(const JobInfo& job, std::vector<HistoryEntry> history = {}) {
    std::lock_guard lock(mutex_);
    jobs_[job.id] = job;
    histories_[job.id] = std::move(history);
  }
  /// Replaces the script with the default one changed by `change`: script([](Script& s) { s.replay = true; }).
  void script(const std::function<void(Script&)>& change) {
    std::lock_guard lock(mutex_);
    script_ = Script{};
    change(script_);
  }
  void set_accepting(bool accepting) {
    std::lock_guard lock(mutex_);
    accepting_ = accepting;
  }
  std::vector<Submission> submissions() const {
    std::lock_guard lock(mutex_);
    return submissions_;
  }
  std::vector<Upload> uploads() const {
    std::lock_guard lock(mutex_);
    return uploads_;
  }
  std::vector<double> waits() const {
    std::lock_guard lock(mutex_);
    return waits_;
  }
  std::vector<PageRequest> page_requests() const {
    std::lock_guard lock(mutex_);
    return page_requests_;
  }
  std::vector<JobFilter> filters() const {
    std::lock_guard lock(mutex_);
    return filters_;
  }
  std::vector<long> overview_requests() const {
    std::lock_guard lock(mutex_);
    return overview_requests_;
  }
  /// Service calls made so far (any method): a refused request must make none.
  int calls() const {
    std::lock_guard lock(mutex_);
    return calls_;
  }
  /// Whom each call was made for, in order (metrics has none).
  std::vector<Caller> callers() const {
    std::lock_guard lock(mutex_);
    return callers_;
  }

  // ---- Service ----
  DatasetCreated create_dataset(const Caller& caller, const DatasetUpload& upload,
                                const std::optional<IdempotencyKey>& key) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    uploads_.push_back({upload, key});
    DatasetInfo info;
    info.id = "ds_" + std::to_string(uploads_.size());
    info.owner = caller.owner;
    info.name = upload.name;
    info.created_at = "2026-01-01T00:00:00.000Z";
    info.joints = upload.trajectory.joint_count();
    info.samples = upload.trajectory.samples();
    info.dt = upload.trajectory.dt();
    info.has_torque = upload.trajectory.has_torque();
    info.has_reference = upload.trajectory.has_reference();
    datasets_[info.id] = info;
    data_[info.id] = upload.trajectory;
    return {info, script_.replay};
  }
  std::optional<DatasetInfo> dataset(const Caller& caller, const std::string& id) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    const auto found = datasets_.find(id);
    return found == datasets_.end() || !sees(caller, found->second.owner) ? std::nullopt : std::optional(found->second);
  }
  std::optional<Trajectory> dataset_data(const Caller& caller, const std::string& id) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    const auto found = data_.find(id);
    const auto info = datasets_.find(id);
    if (info != datasets_.end() && !sees(caller, info->second.owner)) return std::nullopt;
    return found == data_.end() ? std::nullopt : std::optional(found->second);
  }
  Page<DatasetInfo> datasets(const Caller& caller, const PageRequest& page) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    page_requests_.push_back(page);
    Page<DatasetInfo> answer;
    for (const auto& [id, info] : datasets_) {
      if (sees(caller, info.owner) && static_cast<int>(answer.items.size()) < page.page_size) answer.items.push_back(info);
    }
    answer.next_page_token = script_.next_page_token;
    return answer;
  }
  DeleteOutcome delete_dataset(const Caller& caller, const std::string& id) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    if (script_.delete_outcome) return *script_.delete_outcome;
    if (const auto found = datasets_.find(id); found != datasets_.end() && !sees(caller, found->second.owner)) {
      return DeleteOutcome::not_found;
    }
    return datasets_.erase(id) + data_.erase(id) > 0 ? DeleteOutcome::deleted : DeleteOutcome::not_found;
  }

  RobotCreated create_robot(const Caller& caller, const RobotUpload& upload, std::shared_ptr<const ParsedRobot> parsed,
                            const std::string& description, const std::optional<IdempotencyKey>& key) override {
    const int joints = parsed->model.joint_count();
    std::lock_guard lock(mutex_);
    enter(caller);
    if (script_.submit_error) throw ApiError(*script_.submit_error, "scripted refusal");
    RobotInfo robot;
    robot.id = "rb_" + std::to_string(robots_.size() + 1);
    robot.owner = caller.owner;
    robot.name = upload.name;
    robot.created_at = "2026-01-01T00:00:00.000Z";
    robot.base = upload.base;
    robot.tip = upload.tip;
    robot.joints = joints;
    robot.summary = description;
    robots_[robot.id] = robot;
    urdfs_[robot.id] = upload.urdf;
    robot_keys_.push_back(key);
    return {robot, script_.replay};
  }
  std::optional<RobotInfo> robot(const Caller& caller, const std::string& id) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    const auto found = robots_.find(id);
    return found == robots_.end() || !sees(caller, found->second.owner) ? std::nullopt : std::optional(found->second);
  }
  std::optional<std::string> robot_urdf(const Caller& caller, const std::string& id) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    const auto found = urdfs_.find(id);
    const auto info = robots_.find(id);
    if (info != robots_.end() && !sees(caller, info->second.owner)) return std::nullopt;
    return found == urdfs_.end() ? std::nullopt : std::optional(found->second);
  }
  /// Parsed once per fake (its ids start again at rb_1 in every test), as a server parses once per process.
  std::shared_ptr<const ParsedRobot> parsed_robot(const Caller& caller, const std::string& id) override {
    const std::optional<RobotInfo> found = robot(caller, id);
    if (!found) return nullptr;
    return robot_cache_.get(*found, [&] { return robot_urdf(caller, id); });
  }
  Page<RobotInfo> robots(const Caller& caller, const PageRequest& page) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    page_requests_.push_back(page);
    Page<RobotInfo> answer;
    for (const auto& [id, info] : robots_) {
      if (sees(caller, info.owner) && static_cast<int>(answer.items.size()) < page.page_size) answer.items.push_back(info);
    }
    answer.next_page_token = script_.next_page_token;
    return answer;
  }
  DeleteOutcome delete_robot(const Caller& caller, const std::string& id) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    if (script_.delete_outcome) return *script_.delete_outcome;
    if (const auto found = robots_.find(id); found != robots_.end() && !sees(caller, found->second.owner)) {
      return DeleteOutcome::not_found;
    }
    return robots_.erase(id) + urdfs_.erase(id) > 0 ? DeleteOutcome::deleted : DeleteOutcome::not_found;
  }

  SubmitResult submit(const Caller& caller, const JobSubmission& submission,
                      const std::optional<IdempotencyKey>& key) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    if (script_.submit_error) throw ApiError(*script_.submit_error, "scripted refusal");
    submissions_.push_back({submission.kind, submission.request_json, submission.dataset_id, key, submission.robot_id,
                            submission.validation_dataset_id});
    JobInfo job;
    job.id = "job_" + std::to_string(submissions_.size());
    job.owner = caller.owner;
    job.kind = submission.kind;
    job.state = JobState::queued;
    job.created_at = "2026-01-01T00:00:00.000Z";
    job.request = submission.request_json;
    job.dataset_id = submission.dataset_id;
    job.robot_id = submission.robot_id;
    job.validation_dataset_id = submission.validation_dataset_id;
    jobs_[job.id] = job;
    return {job, script_.replay};
  }
  std::optional<JobInfo> job(const Caller& caller, const std::string& id) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    const auto found = jobs_.find(id);
    return found == jobs_.end() || !sees(caller, found->second.owner) ? std::nullopt : std::optional(found->second);
  }
  std::optional<JobInfo> wait(const Caller& caller, const std::string& id, double seconds) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    waits_.push_back(seconds);  // answers at once: the tests look at what the route asked for
    const auto found = jobs_.find(id);
    return found == jobs_.end() || !sees(caller, found->second.owner) ? std::nullopt : std::optional(found->second);
  }
  Page<JobInfo> jobs(const Caller& caller, const JobFilter& filter, const PageRequest& page) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    filters_.push_back(filter);
    page_requests_.push_back(page);
    Page<JobInfo> answer;
    for (const auto& [id, job] : jobs_) {
      if (sees(caller, job.owner) && (!filter.state || job.state == *filter.state) &&
          (!filter.kind || job.kind == *filter.kind) &&
          (filter.robot_id.empty() || job.robot_id == filter.robot_id) &&
          static_cast<int>(answer.items.size()) < page.page_size) {
        answer.items.push_back(job);
      }
    }
    answer.next_page_token = script_.next_page_token;
    return answer;
  }
  /// Pages of the history; the token is the index of the page's first entry.
  std::optional<Page<HistoryEntry>> history(const Caller& caller, const std::string& id, const PageRequest& page) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    page_requests_.push_back(page);
    const auto found = histories_.find(id);
    if (found == histories_.end() || !owned_job_seen(caller, id)) return std::nullopt;
    const std::vector<HistoryEntry>& entries = found->second;
    const std::size_t first = page.page_token.empty() ? 0 : std::stoul(page.page_token);
    const std::size_t last = std::min(entries.size(), first + static_cast<std::size_t>(page.page_size));
    Page<HistoryEntry> answer;
    for (std::size_t i = first; i < last; ++i) answer.items.push_back(entries[i]);
    if (last < entries.size()) answer.next_page_token = std::to_string(last);
    return answer;
  }
  std::optional<HistoryOverview> history_overview(const Caller& caller, const std::string& id, long max_points) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    overview_requests_.push_back(max_points);
    const auto found = histories_.find(id);
    if (found == histories_.end() || !owned_job_seen(caller, id)) return std::nullopt;
    HistoryOverview overview;
    overview.total = static_cast<long>(found->second.size());
    overview.stride = overview.total > max_points ? (overview.total + max_points - 1) / max_points : 1;
    for (long i = 0; i < overview.total; i += overview.stride) overview.items.push_back(found->second[static_cast<std::size_t>(i)]);
    if (!found->second.empty()) overview.best_index = 0;
    return overview;
  }
  std::optional<JobInfo> cancel(const Caller& caller, const std::string& id) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    const auto found = jobs_.find(id);
    if (found == jobs_.end() || !sees(caller, found->second.owner)) return std::nullopt;
    if (!is_terminal(found->second.state)) found->second.state = JobState::cancelled;
    return found->second;
  }
  DeleteOutcome delete_job(const Caller& caller, const std::string& id) override {
    std::lock_guard lock(mutex_);
    enter(caller);
    if (script_.delete_outcome) return *script_.delete_outcome;
    const auto found = jobs_.find(id);
    if (found == jobs_.end() || !sees(caller, found->second.owner)) return DeleteOutcome::not_found;
    if (!is_terminal(found->second.state)) return DeleteOutcome::conflict;
    jobs_.erase(found);
    return DeleteOutcome::deleted;
  }

  std::string metrics() override {
    std::lock_guard lock(mutex_);
    count();
    return "# TYPE manipid_queue_depth gauge\nmanipid_queue_depth 7\n";
  }
  bool accepting() const override {
    std::lock_guard lock(mutex_);
    return accepting_;
  }
  std::optional<std::string> degraded() const override {
    std::lock_guard lock(mutex_);
    return degraded_;
  }
  void set_degraded(std::optional<std::string> reason) {
    std::lock_guard lock(mutex_);
    degraded_ = std::move(reason);
  }

 private:
  /// Counts the call, notes its caller and throws what the script asks for.
  void enter(const Caller& caller) {
    callers_.push_back(caller);
    count();
  }
  void count() {
    ++calls_;
    if (!script_.throw_what.empty()) throw std::runtime_error(script_.throw_what);
    if (script_.throw_non_standard) throw 42;
    if (script_.throw_bad_alloc) throw std::bad_alloc();
  }

  /// The real service's rule: an admin sees every owner's, anyone else their own only.
  static bool sees(const Caller& caller, const std::string& owner) { return caller.admin || owner == caller.owner; }
  bool owned_job_seen(const Caller& caller, const std::string& id) const {
    const auto job = jobs_.find(id);
    return job == jobs_.end() || sees(caller, job->second.owner);
  }

  mutable std::mutex mutex_;
  Script script_;
  bool accepting_ = true;
  std::optional<std::string> degraded_;
  int calls_ = 0;
  std::vector<Caller> callers_;
  std::map<std::string, DatasetInfo> datasets_;
  std::map<std::string, RobotInfo> robots_;
  std::map<std::string, std::string> urdfs_;
  RobotCache robot_cache_;
  std::vector<std::optional<IdempotencyKey>> robot_keys_;
  std::map<std::string, Trajectory> data_;
  std::map<std::string, JobInfo> jobs_;
  std::map<std::string, std::vector<HistoryEntry>> histories_;
  std::vector<Submission> submissions_;
  std::vector<Upload> uploads_;
  std::vector<double> waits_;
  std::vector<PageRequest> page_requests_;
  std::vector<JobFilter> filters_;
  std::vector<long> overview_requests_;
};

}  // namespace manipid::api::testing
