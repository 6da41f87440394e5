// worker_pool_test.cpp — the worker pool on its own, over a SQLite store in a temporary directory, with a
// stand-in for run_job that the test steers (WorkerPoolOptions::run): claims in submission order, ends
// recorded, a cancel that reaches a running job or one not yet claimed (it never starts), a shutdown that puts running jobs
// back in the queue, and a job that could never fit in --job-memory. Every wait is for a state to be reached
// (with a generous bound that only a hang meets); nothing asserts how long anything took.
#include "jobs/worker_pool.h"
#include "store/sqlite/store.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace manipid::server::jobs {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// Long enough that only a hang reaches it.
constexpr auto kPatience = std::chrono::seconds(60);

/// The stand-in for run_job: records each job it is given, then — while `hold`
/// is on — waits until the test releases the job or its cancel flag is set, and ends the way run_job does:
/// a shutdown's cancel puts the job back in the queue, a user's cancels it, else it succeeded.
class SteeredRunner {
 public:
  JobOutcome run(const api::JobInfo& job, LiveJob& live) {
    std::unique_lock lock(mutex_);
    started_.push_back(job.id);
    changed_.notify_all();
    // The pool sets live.cancel without telling this object: looked at again every few milliseconds.
    while (hold_ && released_.count(job.id) == 0 && !live.cancel.load()) changed_.wait_for(lock, std::chrono::milliseconds(5));
    JobOutcome outcome;
    if (live.cancel.load()) {
      outcome.requeue = live.shutdown.load();
      outcome.state = api::JobState::cancelled;
      shut_down_[job.id] = live.shutdown.load();
      return outcome;
    }
    outcome.state = api::JobState::succeeded;
    outcome.result = R"({"ran":")" + job.id + R"("})";
    return outcome;
  }

  void hold(bool on) {
    std::lock_guard lock(mutex_);
    hold_ = on;
  }
  void release(const std::string& id) {
    std::lock_guard lock(mutex_);
    released_.insert(id);
    changed_.notify_all();
  }
  /// Waits until `count` jobs have started; false only on a hang.
  bool wait_started(std::size_t count) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, kPatience, [&] { return started_.size() >= count; });
  }
  std::vector<std::string> started() const {
    std::lock_guard lock(mutex_);
    return started_;
  }
  bool shut_down(const std::string& id) const {
    std::lock_guard lock(mutex_);
    return shut_down_.count(id) > 0 && shut_down_.at(id);
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool hold_ = false;
  std::set<std::string> released_;
  std::vector<std::string> started_;
  std::map<std::string, bool> shut_down_;
};

class WorkerPoolTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "manipid-pool-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    directory_ = pattern;
    store_ = store::sqlite::open_store((directory_ / "manipid.db").string());
  }
  void TearDown() override {
    pool_.reset();
    store_.reset();
    fs::remove_all(directory_);
  }

  WorkerPoolOptions options(int workers) {
    WorkerPoolOptions options;
    options.workers = workers;
    options.owner = "test-host:1";
    options.idle_poll = std::chrono::milliseconds(20);
    options.run = [this](const api::JobInfo& job, store::Store&, LiveJob& live, const RunnerOptions&) {
      return runner_.run(job, live);
    };
    return options;
  }
  /// A pool not started yet: nothing is claimed until start().
  void make(WorkerPoolOptions options) {
    pool_ = std::make_unique<WorkerPool>(*store_, std::move(options), [this](const std::string& line) {
      std::lock_guard lock(log_mutex_);
      log_.push_back(line);
    });
  }
  void start(WorkerPoolOptions options) {
    make(std::move(options));
    pool_->start();
  }
  std::string submit(const std::string& request = "{}") {
    const store::SubmitOutcome outcome =
        store_->submit_job({api::JobKind::simulation, request, "", "", "", ""}, std::nullopt, 0);
    EXPECT_EQ(outcome.status, store::SubmitStatus::created);
    if (pool_) pool_->notify_submitted();
    return outcome.job.id;
  }
  api::JobInfo job(const std::string& id) { return *store_->find_job(api::all_owners, id); }
  /// Waits until job `id` is in `state` (the pool's change signal, or its idle look at the store).
  bool wait_state(const std::string& id, api::JobState state) {
    const auto deadline = Clock::now() + kPatience;
    while (Clock::now() < deadline) {
      const unsigned long generation = pool_->generation();
      if (job(id).state == state) return true;
      pool_->wait_for_change(generation, std::min(deadline, Clock::now() + std::chrono::milliseconds(50)));
    }
    return job(id).state == state;
  }
  bool logged(const std::string& part) {
    std::lock_guard lock(log_mutex_);
    for (const std::string& line : log_) {
      if (line.find(part) != std::string::npos) return true;
    }
    return false;
  }

  fs::path directory_;
  std::unique_ptr<store::Store> store_;
  SteeredRunner runner_;
  std::unique_ptr<WorkerPool> pool_;
  std::mutex log_mutex_;
  std::vector<std::string> log_;
};

TEST_F(WorkerPoolTest, RunsQueuedJobsInSubmissionOrderAndRecordsTheirEnds) {
  const std::vector<std::string> ids = {submit(), submit(), submit()};
  start(options(1));
  for (const std::string& id : ids) ASSERT_TRUE(wait_state(id, api::JobState::succeeded)) << id;
  EXPECT_EQ(runner_.started(), ids);  // one worker: claimed oldest first, each once
  for (const std::string& id : ids) {
    const api::JobInfo ended = job(id);
    EXPECT_EQ(ended.result, R"({"ran":")" + id + R"("})");
    EXPECT_EQ(ended.attempts, 1);
    EXPECT_FALSE(pool_->progress(id));  // no live progress once it ended
  }
  EXPECT_EQ(pool_->statistics().finished.at("simulation,succeeded"), 3);
  EXPECT_EQ(pool_->statistics().running, 0);
}

TEST_F(WorkerPoolTest, ACancelReachesARunningJob) {
  runner_.hold(true);
  start(options(1));
  const std::string id = submit();
  ASSERT_TRUE(runner_.wait_started(1));
  EXPECT_TRUE(pool_->progress(id));  // running here: its live progress is the pool's
  EXPECT_EQ(job(id).state, api::JobState::running);
  pool_->cancel(id);
  ASSERT_TRUE(wait_state(id, api::JobState::cancelled));
  EXPECT_FALSE(runner_.shut_down(id));
  // The worker is free again: the next job runs.
  const std::string next = submit();
  ASSERT_TRUE(runner_.wait_started(2));
  runner_.release(next);
  ASSERT_TRUE(wait_state(next, api::JobState::succeeded));
  EXPECT_EQ(pool_->statistics().finished.at("simulation,cancelled"), 1);
}

TEST_F(WorkerPoolTest, ACancelBeforeTheClaimEndsTheJobWhenItIsClaimed) {
  make(options(1));  // nothing claims until start()
  const std::string id = submit();
  pool_->cancel(id);  // not running here yet: kept until this pool claims it
  pool_->start();
  ASSERT_TRUE(wait_state(id, api::JobState::cancelled));
  EXPECT_TRUE(runner_.started().empty());  // ended cancelled before its work began
  EXPECT_EQ(pool_->statistics().finished.at("simulation,cancelled"), 1);
}

TEST_F(WorkerPoolTest, StopPutsRunningJobsBackInTheQueueForTheNextStart) {
  runner_.hold(true);
  start(options(2));
  const std::string first = submit(), second = submit();
  ASSERT_TRUE(runner_.wait_started(2));
  pool_->stop();  // returns once both workers have ended their jobs
  for (const std::string& id : {first, second}) {
    EXPECT_TRUE(runner_.shut_down(id)) << id;
    EXPECT_EQ(job(id).state, api::JobState::queued) << id;
    EXPECT_EQ(job(id).attempts, 1) << id;
  }
  EXPECT_TRUE(pool_->statistics().finished.empty());  // a requeue is no end
  pool_->stop();  // stopping twice is harmless

  // The next pool on the same database runs them again.
  runner_.hold(false);
  pool_.reset();
  start(options(1));
  for (const std::string& id : {first, second}) {
    ASSERT_TRUE(wait_state(id, api::JobState::succeeded)) << id;
    EXPECT_EQ(job(id).attempts, 2) << id;
  }
}

TEST_F(WorkerPoolTest, AJobThatCouldNeverFitInItsMemoryFailsWithoutRunning) {
  WorkerPoolOptions small = options(1);
  small.job_memory = 1024;  // below any job's fixed part
  start(small);
  const std::string id = submit(R"({"preset": "cedro2009"})");
  ASSERT_TRUE(wait_state(id, api::JobState::failed));
  EXPECT_TRUE(runner_.started().empty());
  EXPECT_NE(job(id).error.find("--job-memory"), std::string::npos) << job(id).error;
}

TEST_F(WorkerPoolTest, AJobWaitsForMemoryUntilTheRunningOneGivesItBack) {
  const std::string request = R"({"preset": "cedro2009"})";
  const std::size_t need = api::job_memory_bytes(job_shape(api::JobKind::simulation, request, *store_, api::all_owners));
  runner_.hold(true);
  WorkerPoolOptions one_at_a_time = options(2);
  one_at_a_time.job_memory = need + need / 2;  // room for one job, not two
  start(one_at_a_time);
  const std::string first = submit(request);
  ASSERT_TRUE(runner_.wait_started(1));
  const std::string second = submit(request);
  // The second worker claims it and waits for memory: running in the store, not started here.
  const auto deadline = Clock::now() + kPatience;
  while (!logged("job " + second + ": waits for") && Clock::now() < deadline) {
    pool_->wait_for_change(pool_->generation(), Clock::now() + std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(logged("job " + second + ": waits for"));
  EXPECT_EQ(runner_.started(), std::vector<std::string>{first});
  EXPECT_EQ(pool_->statistics().job_memory_reserved, need);
  runner_.release(first);
  ASSERT_TRUE(runner_.wait_started(2));
  EXPECT_EQ(runner_.started(), (std::vector<std::string>{first, second}));
  runner_.release(second);
  ASSERT_TRUE(wait_state(second, api::JobState::succeeded));
  // The first's memory comes back before its end is written, so the second may finish first.
  EXPECT_TRUE(wait_state(first, api::JobState::succeeded));
}

}  // namespace
}  // namespace manipid::server::jobs
