// job_runner_test.cpp — run_job's failures as a client sees them: a store that fails (SQLite's
// own text, "string or blob too big") ends the job with a sentence for people, the text in the log only.
#include "jobs/job_runner.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>

namespace manipid::server::jobs {
namespace {

using namespace manipid::server::store;  // the Store interface this fake implements

/// A store whose every call fails as SQLite does when a value is over its limit.
class FailingStore : public Store {
 public:
  [[noreturn]] static void fail() { throw StoreError("string or blob too big"); }
  DatasetOutcome insert_dataset(const std::string&, const std::string&, const Trajectory&, const std::string&,
                                const std::optional<api::IdempotencyKey>&) override { fail(); }
  std::optional<api::DatasetInfo> find_dataset(const api::OwnerScope&, const std::string&) override { fail(); }
  std::optional<Trajectory> load_dataset(const api::OwnerScope&, const std::string&) override { fail(); }
  api::Page<api::DatasetInfo> list_datasets(const api::OwnerScope&, const api::PageRequest&) override { fail(); }
  DeleteResult delete_dataset(const api::OwnerScope&, const std::string&) override { fail(); }
  RobotOutcome insert_robot(const NewRobot&, const std::optional<api::IdempotencyKey>&) override { fail(); }
  std::optional<api::RobotInfo> find_robot(const api::OwnerScope&, const std::string&) override { fail(); }
  std::optional<std::string> load_robot_urdf(const api::OwnerScope&, const std::string&) override { fail(); }
  api::Page<api::RobotInfo> list_robots(const api::OwnerScope&, const api::PageRequest&) override { fail(); }
  DeleteResult delete_robot(const api::OwnerScope&, const std::string&) override { fail(); }
  SubmitOutcome submit_job(const NewJob&, const std::optional<api::IdempotencyKey>&, int) override { fail(); }
  std::optional<api::JobInfo> find_job(const api::OwnerScope&, const std::string&) override { fail(); }
  api::Page<api::JobInfo> list_jobs(const api::OwnerScope&, const api::JobFilter&, const api::PageRequest&) override {
    fail();
  }
  std::optional<api::JobInfo> claim_next_job(const std::string&, std::chrono::milliseconds) override { fail(); }
  LeaseStatus renew_lease(const Lease&, std::chrono::milliseconds) override { fail(); }
  LeaseStatus record_progress(const Lease&, long, std::optional<double>, const std::vector<api::HistoryEntry>&) override { fail(); }
  bool finish_job(const Lease&, const JobEnd&) override { fail(); }
  void requeue_job(const Lease&) override { fail(); }
  CancelOutcome cancel_job(const api::OwnerScope&, const std::string&) override { fail(); }
  DeleteResult delete_job(const api::OwnerScope&, const std::string&) override { fail(); }
  std::optional<api::Page<api::HistoryEntry>> history(const api::OwnerScope&, const std::string&,
                                                      const api::PageRequest&) override {
    fail();
  }
  std::optional<api::HistoryOverview> history_overview(const api::OwnerScope&, const std::string&, long) override {
    fail();
  }
  RecoveryOutcome recover_interrupted_jobs(int, const std::function<std::string(int)>&,
                                           const std::function<bool(const std::string&)>&) override { fail(); }
  RecoveryOutcome recover_expired_leases(int, const std::function<std::string(int)>&) override { fail(); }
  std::map<api::JobState, long> count_jobs_by_state() override { fail(); }
  std::optional<std::string> write_trouble() const override { return "string or blob too big"; }
};

TEST(RunJob, AStorageErrorIsASentenceForTheClientAndSqlitesTextForTheLog) {
  FailingStore store;
  LiveJob live;
  api::JobInfo job;
  job.id = "job_0123456789abcdef";
  job.kind = api::JobKind::identification;
  job.state = api::JobState::running;
  job.request = R"({"dataset_id": "ds_0123456789abcdef"})";
  const JobOutcome outcome = run_job(job, store, live, RunnerOptions{});
  EXPECT_EQ(outcome.state, api::JobState::failed);
  const nlohmann::json problem = nlohmann::json::parse(outcome.error);
  EXPECT_EQ(problem.at("code"), "JOB_FAILED");
  EXPECT_EQ(problem.at("detail"), "the job's data could not be read or written (a storage error; see the server log)");
  EXPECT_EQ(outcome.error.find("blob"), std::string::npos) << outcome.error;
  EXPECT_EQ(outcome.log, "storage error: string or blob too big");
}

}  // namespace
}  // namespace manipid::server::jobs
