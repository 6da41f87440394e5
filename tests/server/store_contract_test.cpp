// store_contract_test.cpp — the contract every store backend keeps (store/store.h), one suite run
// against each backend as LevelDB runs env_test on each Env: round trips, idempotency, the job
// life cycle, paging, recovery after a reopen and concurrent callers, each test on a fresh store
// in its own temporary directory. What only one backend does lives beside it (sqlite_store_test).
#include "store/store.h"
#include "store/idempotency.h"

#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <condition_variable>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <ostream>
#include <limits>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace manipid::server::store {
namespace {

namespace fs = std::filesystem;
using api::JobState;

Trajectory make_trajectory(int samples, int joints, bool torque, bool reference) {
  Trajectory data;
  data.t.resize(samples);
  for (int i = 0; i < samples; ++i) data.t[i] = 0.001 * i;
  // Values whose last bits would not survive a trip through decimal text.
  std::mt19937_64 generator(42);
  std::uniform_real_distribution<double> any(-10.0, 10.0);
  auto fill = [&](Eigen::MatrixXd& matrix) {
    matrix.resize(samples, joints);
    for (Eigen::Index i = 0; i < matrix.size(); ++i) matrix.data()[i] = any(generator) / 3.0;
  };
  fill(data.q);
  if (samples > 2) {
    data.q(0, 0) = -0.0;
    data.q(1, 0) = std::numeric_limits<double>::denorm_min();
    data.q(2, 0) = std::nextafter(1.0, 2.0);
  }
  if (torque) fill(data.tau);
  if (reference) fill(data.ref);
  return data;
}

bool same_bits(const Eigen::MatrixXd& left, const Eigen::MatrixXd& right) {
  return left.rows() == right.rows() && left.cols() == right.cols() &&
         (left.size() == 0 || std::memcmp(left.data(), right.data(), sizeof(double) * left.size()) == 0);
}

bool same_bits(const Eigen::VectorXd& left, const Eigen::VectorXd& right) {
  return left.size() == right.size() &&
         (left.size() == 0 || std::memcmp(left.data(), right.data(), sizeof(double) * left.size()) == 0);
}

NewJob identification_job(const std::string& request = R"({"upload_id":"ds_x"})") {
  NewJob job;
  job.kind = api::JobKind::identification;
  job.request = request;
  job.dataset_id = "ds_0123456789abcdef";
  return job;
}

std::vector<api::HistoryEntry> history_batch(long first, long count) {
  std::vector<api::HistoryEntry> batch;
  for (long index = first; index < first + count; ++index) {
    batch.push_back({index, 100.0 / (index + 1) + 1e-17, {1.0 / 3.0 + index, 2.0 / 7.0, -0.0}});
  }
  return batch;
}

/// A job's end without history or progress (JobEnd's other members as finish_job's callers give them).
JobEnd end_as(api::JobState state, std::string result, std::string error, std::vector<EstimateRow> estimates,
              std::string dataset_id) {
  JobEnd end;
  end.state = state;
  end.result = std::move(result);
  end.error = std::move(error);
  end.estimates = std::move(estimates);
  end.dataset_id = std::move(dataset_id);
  return end;
}

template <class Call>
void expect_invalid_field(Call call, const std::string& field) {
  try {
    call();
    ADD_FAILURE() << "expected PageRequestError for " << field;
  } catch (const PageRequestError& error) {
    EXPECT_EQ(error.field(), field);
  }
}

/// A backend under test: its name, how it opens (or reopens) the store kept for `directory`,
/// how it removes that store, and why it cannot run here (empty: it can).
struct Backend {
  std::string name;
  std::function<std::unique_ptr<Store>(const fs::path& directory, const StoreOptions& options)> open;
  std::function<void(const fs::path& directory)> remove = [](const fs::path&) {};
  std::function<std::string()> unavailable = [] { return std::string(); };
};

void PrintTo(const Backend& backend, std::ostream* out) { *out << backend.name; }

/// The private cluster of the ctest fixture "postgres" (tests/server/postgres_cluster.sh): a
/// libpq URI template with "%s" for the database name, or empty when there is none.
std::string postgres_uri_template() {
  const char* file = std::getenv("MANIPID_TEST_POSTGRES_FILE");
  if (file == nullptr) return {};
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  return line;
}

std::string postgres_uri(const std::string& database) {
  std::string uri = postgres_uri_template();
  return uri.replace(uri.find("%s"), 2, database);
}

/// One database per test, named after its temporary directory.
std::string postgres_database(const fs::path& directory) {
  std::string name = "t_";
  for (char c : directory.filename().string()) {
    if (std::isalnum(static_cast<unsigned char>(c))) name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return name;
}

/// Runs statements on one of the cluster's databases (by default the maintenance database, for
/// CREATE and DROP DATABASE).
void postgres_admin(const std::string& sql, const std::string& database = "postgres") {
  PGconn* connection = PQconnectdb(postgres_uri(database).c_str());
  const bool connected = PQstatus(connection) == CONNECTION_OK;
  std::string error = connected ? "" : PQerrorMessage(connection);
  if (connected) {
    PGresult* result = PQexec(connection, sql.c_str());
    if (PQresultStatus(result) != PGRES_COMMAND_OK) error = PQresultErrorMessage(result);
    PQclear(result);
  }
  PQfinish(connection);
  if (!error.empty()) throw std::runtime_error(sql + ": " + error);
}

std::vector<Backend> backends() {
  Backend sqlite{"sqlite", [](const fs::path& directory, const StoreOptions& options) {
                   return open_store("sqlite:" + (directory / "manipid.db").string(), options);
                 }};
  Backend postgres{"postgres", [](const fs::path& directory, const StoreOptions& options) {
                     const std::string database = postgres_database(directory);
                     if (!fs::exists(directory / "database")) {
                       postgres_admin("CREATE DATABASE " + database);
                       std::ofstream(directory / "database") << database << "\n";
                     }
                     return open_store(postgres_uri(database), options);
                   }};
  postgres.remove = [](const fs::path& directory) {
    if (fs::exists(directory / "database")) postgres_admin("DROP DATABASE " + postgres_database(directory) + " WITH (FORCE)");
  };
  postgres.unavailable = [] {
    return postgres_uri_template().empty()
               ? std::string("no PostgreSQL cluster: run through ctest (fixture \"postgres\", "
                             "tests/server/postgres_cluster.sh; needs the Debian package postgresql)")
               : std::string();
  };
  return {sqlite, postgres};
}

class StoreContract : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    if (const std::string why = GetParam().unavailable(); !why.empty()) GTEST_SKIP() << why;
    std::string pattern = (fs::temp_directory_path() / "manipid-store-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    directory_ = pattern;
    store_ = GetParam().open(directory_, {});
  }

  void TearDown() override {
    store_.reset();  // close every connection before the files go
    if (directory_.empty()) return;
    GetParam().remove(directory_);
    fs::remove_all(directory_);
  }

  void reopen(const StoreOptions& options = {}) {
    store_.reset();
    store_ = GetParam().open(directory_, options);
  }

  std::string submit(const NewJob& job = identification_job()) {
    auto outcome = store_->submit_job(job, std::nullopt, 0);
    EXPECT_EQ(outcome.status, SubmitStatus::created);
    return outcome.job.id;
  }

  /// The next queued job, claimed by `owner` for `lease`.
  std::optional<api::JobInfo> claim(const std::string& owner = "host-a:100",
                                    std::chrono::milliseconds lease = std::chrono::seconds(30)) {
    return store_->claim_next_job(owner, lease);
  }

  /// The lease a job is under now (owner and attempt as stored): what its worker would carry.
  Lease held(const std::string& id) {
    const auto job = store_->find_job(api::all_owners, id);
    return job ? Lease{id, job->worker, job->attempts} : Lease{id, "", 0};
  }

  /// Start-up recovery as `manipid serve` does it, with the default of 3 worker deaths.
  RecoveryOutcome recover(int max_attempts = 3, const std::string& alive = "") {
    return store_->recover_interrupted_jobs(
        max_attempts, [](int losses) { return "{\"lost\": " + std::to_string(losses) + "}"; },
        [&](const std::string& worker) { return worker != alive; });
  }

  fs::path directory_;
  std::unique_ptr<Store> store_;
};

INSTANTIATE_TEST_SUITE_P(Backends, StoreContract, ::testing::ValuesIn(backends()),
                         [](const ::testing::TestParamInfo<Backend>& info) { return info.param.name; });

// "2026-11-22T06:40:12.345Z": a digit where the template has 'd', a hex digit for 'x', the
// rest literally. (Hand-written: <regex> trips GCC 12's -Wmaybe-uninitialized here.)
bool matches_template(const std::string& text, const std::string& pattern) {
  if (text.size() != pattern.size()) return false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const bool digit = text[i] >= '0' && text[i] <= '9';
    const bool hex_digit = digit || (text[i] >= 'a' && text[i] <= 'f');
    if (pattern[i] == 'd' ? !digit : pattern[i] == 'x' ? !hex_digit : text[i] != pattern[i]) return false;
  }
  return true;
}

bool is_time(const std::string& text) { return matches_template(text, "dddd-dd-ddTdd:dd:dd.dddZ"); }
bool is_id(const std::string& text, const std::string& prefix) {
  return text.starts_with(prefix) && matches_template(text.substr(prefix.size()), std::string(16, 'x'));
}

// ---- datasets ----

TEST_P(StoreContract, DatasetRoundTripIsBitExact) {
  const auto data = make_trajectory(257, 3, true, true);
  const auto outcome = store_->insert_dataset("", "lab run 7", data, "job_00000000000000aa", std::nullopt);
  ASSERT_EQ(outcome.status, SubmitStatus::created);
  EXPECT_TRUE(is_id(outcome.dataset.id, "ds_"));
  EXPECT_TRUE(is_time(outcome.dataset.created_at)) << outcome.dataset.created_at;

  const auto info = store_->find_dataset(api::all_owners, outcome.dataset.id);
  ASSERT_TRUE(info);
  EXPECT_EQ(info->name, "lab run 7");
  EXPECT_EQ(info->source_job, "job_00000000000000aa");
  EXPECT_EQ(info->joints, 3);
  EXPECT_EQ(info->samples, 257);
  EXPECT_EQ(info->dt, data.dt());
  EXPECT_TRUE(info->has_torque);
  EXPECT_TRUE(info->has_reference);
  EXPECT_EQ(info->created_at, outcome.dataset.created_at);

  const auto loaded = store_->load_dataset(api::all_owners, outcome.dataset.id);
  ASSERT_TRUE(loaded);
  EXPECT_TRUE(same_bits(loaded->t, data.t));
  EXPECT_TRUE(same_bits(loaded->q, data.q));
  EXPECT_TRUE(same_bits(loaded->tau, data.tau));
  EXPECT_TRUE(same_bits(loaded->ref, data.ref));
  EXPECT_TRUE(std::signbit(loaded->q(0, 0)));
  // Read again (a backend may keep recent samples in memory): the same bits; deleted — by this
  // store or by another process's — gone.
  const auto again = store_->load_dataset(api::all_owners, outcome.dataset.id);
  ASSERT_TRUE(again);
  EXPECT_TRUE(same_bits(again->q, data.q));
  auto other = GetParam().open(directory_, {});
  EXPECT_EQ(other->delete_dataset(api::all_owners, outcome.dataset.id), DeleteResult::deleted);
  other.reset();
  EXPECT_FALSE(store_->load_dataset(api::all_owners, outcome.dataset.id));
  EXPECT_FALSE(store_->find_dataset(api::all_owners, outcome.dataset.id));
}

TEST_P(StoreContract, DatasetRoundTripWithoutTorqueOrReference) {
  const auto data = make_trajectory(40, 2, false, false);
  const auto id = store_->insert_dataset("", "q only", data, "", std::nullopt).dataset.id;
  const auto info = store_->find_dataset(api::all_owners, id);
  ASSERT_TRUE(info);
  EXPECT_FALSE(info->has_torque);
  EXPECT_FALSE(info->has_reference);
  EXPECT_EQ(info->source_job, "");
  const auto loaded = store_->load_dataset(api::all_owners, id);
  ASSERT_TRUE(loaded);
  EXPECT_TRUE(same_bits(loaded->t, data.t));
  EXPECT_TRUE(same_bits(loaded->q, data.q));
  EXPECT_EQ(loaded->tau.rows(), 40);
  EXPECT_EQ(loaded->tau.cols(), 0);
  EXPECT_EQ(loaded->ref.cols(), 0);
  EXPECT_FALSE(loaded->has_torque());

  // Torque without reference, the other mix.
  const auto torque_only = make_trajectory(10, 2, true, false);
  const std::string torque_id = store_->insert_dataset("", "tau", torque_only, "", std::nullopt).dataset.id;
  const auto loaded_torque = store_->load_dataset(api::all_owners, torque_id);
  ASSERT_TRUE(loaded_torque);
  EXPECT_TRUE(same_bits(loaded_torque->tau, torque_only.tau));
  EXPECT_EQ(loaded_torque->ref.cols(), 0);
}

TEST_P(StoreContract, UnknownDatasetIsAbsent) {
  EXPECT_FALSE(store_->find_dataset(api::all_owners, "ds_0000000000000000"));
  EXPECT_FALSE(store_->load_dataset(api::all_owners, "ds_0000000000000000"));
  EXPECT_EQ(store_->delete_dataset(api::all_owners, "ds_0000000000000000"), DeleteResult::not_found);
}

TEST_P(StoreContract, DatasetOfAQueuedOrRunningJobIsNotDeleted) {
  const std::string dataset =
      store_->insert_dataset("", "in use", make_trajectory(10, 2, true, false), "", std::nullopt).dataset.id;
  NewJob job = identification_job();
  job.dataset_id = dataset;
  const std::string id = submit(job);
  EXPECT_EQ(store_->delete_dataset(api::all_owners, dataset), DeleteResult::in_use);
  ASSERT_TRUE(claim());
  EXPECT_EQ(store_->delete_dataset(api::all_owners, dataset), DeleteResult::in_use);
  store_->finish_job(held(id), end_as(api::JobState::succeeded, "{}", "", {}, dataset));
  EXPECT_EQ(store_->delete_dataset(api::all_owners, dataset), DeleteResult::deleted);
  EXPECT_FALSE(store_->find_dataset(api::all_owners, dataset));
  EXPECT_EQ(store_->delete_dataset(api::all_owners, dataset), DeleteResult::not_found);
}

TEST_P(StoreContract, AValidationDatasetIsInUseToo) {
  const auto data = make_trajectory(10, 2, true, false);
  const std::string first = store_->insert_dataset("", "a", data, "", std::nullopt).dataset.id;
  const std::string second = store_->insert_dataset("", "b", data, "", std::nullopt).dataset.id;
  NewJob job = identification_job();
  job.dataset_id = first;
  job.validation_dataset_id = second;
  const std::string id = submit(job);
  EXPECT_EQ(store_->find_job(api::all_owners, id)->validation_dataset_id, second);
  EXPECT_EQ(store_->delete_dataset(api::all_owners, second), DeleteResult::in_use);
  ASSERT_TRUE(store_->cancel_job(api::all_owners, id) == CancelOutcome::cancelled_now);
  EXPECT_EQ(store_->delete_dataset(api::all_owners, second), DeleteResult::deleted);
}

TEST_P(StoreContract, JitteryDatasetsWithRatesRoundTripAsMeasured) {
  auto data = make_trajectory(50, 3, true, false);
  data.t[10] += 0.3 * (data.t[11] - data.t[10]);  // a logger's jitter
  data.qd = data.q * 2.0;
  const auto info = store_->insert_dataset("", "jittery", data, "", std::nullopt).dataset;
  EXPECT_FALSE(info.uniform);
  EXPECT_TRUE(info.has_rates);
  EXPECT_EQ(info.dt, data.median_step());
  const auto found = store_->find_dataset(api::all_owners, info.id);
  EXPECT_FALSE(found->uniform);
  EXPECT_TRUE(found->has_rates);
  const auto loaded = store_->load_dataset(api::all_owners, info.id);
  ASSERT_TRUE(loaded);
  EXPECT_TRUE(same_bits(loaded->t, data.t));
  EXPECT_TRUE(same_bits(loaded->qd, data.qd));
  const std::string uniform =
      store_->insert_dataset("", "uniform", make_trajectory(5, 1, false, false), "", std::nullopt).dataset.id;
  EXPECT_TRUE(store_->find_dataset(api::all_owners, uniform)->uniform);
}

// ---- robots ----

NewRobot some_robot(const std::string& name = "arm") {
  NewRobot robot;
  robot.name = name;
  robot.urdf = "<robot name=\"" + name + "\">\r\n  <!-- kept byte for byte: \xc3\xa9 -->\n</robot>";
  robot.tip = "tool0";
  robot.joints = 6;
  robot.summary = R"({"joints": 6})";
  return robot;
}

TEST_P(StoreContract, RobotsRoundTripTheirDocumentByteForByte) {
  const NewRobot robot = some_robot();
  const RobotOutcome created = store_->insert_robot(robot, std::nullopt);
  ASSERT_EQ(created.status, SubmitStatus::created);
  EXPECT_EQ(created.robot.id.rfind("rb_", 0), 0u);
  EXPECT_EQ(created.robot.id.size(), 19u);
  const auto found = store_->find_robot(api::all_owners, created.robot.id);
  ASSERT_TRUE(found);
  EXPECT_EQ(found->name, "arm");
  EXPECT_EQ(found->base, "");
  EXPECT_EQ(found->tip, "tool0");
  EXPECT_EQ(found->joints, 6);
  EXPECT_EQ(found->summary, robot.summary);
  EXPECT_EQ(store_->load_robot_urdf(api::all_owners, created.robot.id), robot.urdf);
  reopen();
  EXPECT_EQ(store_->load_robot_urdf(api::all_owners, created.robot.id), robot.urdf);
  EXPECT_FALSE(store_->find_robot(api::all_owners, "rb_0000000000000000"));
  EXPECT_FALSE(store_->load_robot_urdf(api::all_owners, "rb_0000000000000000"));
}

TEST_P(StoreContract, RobotsAreIdempotentPagedAndNotDeletedWhileInUse) {
  const api::IdempotencyKey key{"upload-1", "f1"};
  const RobotOutcome first = store_->insert_robot(some_robot("a"), key);
  EXPECT_EQ(store_->insert_robot(some_robot("a"), key).status, SubmitStatus::replayed);
  EXPECT_EQ(store_->insert_robot(some_robot("a"), key).robot.id, first.robot.id);
  EXPECT_EQ(store_->insert_robot(some_robot("b"), api::IdempotencyKey{"upload-1", "f2"}).status, SubmitStatus::key_reused);
  for (int i = 0; i < 4; ++i) store_->insert_robot(some_robot("r" + std::to_string(i)), std::nullopt);
  api::PageRequest page;
  page.page_size = 3;
  const auto one = store_->list_robots(api::all_owners, page);
  ASSERT_EQ(one.items.size(), 3u);
  EXPECT_EQ(one.items[0].name, "r3");  // newest first
  page.page_token = one.next_page_token;
  const auto two = store_->list_robots(api::all_owners, page);
  ASSERT_EQ(two.items.size(), 2u);
  EXPECT_EQ(two.items[1].name, "a");
  EXPECT_EQ(two.next_page_token, "");

  NewJob job = identification_job();
  job.robot_id = first.robot.id;
  const std::string id = submit(job);
  EXPECT_EQ(store_->find_job(api::all_owners, id)->robot_id, first.robot.id);
  submit(identification_job());  // a job on no robot: not in the robot's list
  api::JobFilter on_robot;
  on_robot.robot_id = first.robot.id;
  const auto robot_jobs = store_->list_jobs(api::all_owners, on_robot, {});
  ASSERT_EQ(robot_jobs.items.size(), 1u);
  EXPECT_EQ(robot_jobs.items[0].id, id);
  on_robot.robot_id = "rb_none";
  EXPECT_TRUE(store_->list_jobs(api::all_owners, on_robot, {}).items.empty());
  EXPECT_EQ(store_->delete_robot(api::all_owners, first.robot.id), DeleteResult::in_use);
  ASSERT_TRUE(claim());
  EXPECT_EQ(store_->delete_robot(api::all_owners, first.robot.id), DeleteResult::in_use);
  store_->finish_job(held(id), end_as(api::JobState::succeeded, "{}", "", {}, ""));
  EXPECT_EQ(store_->delete_robot(api::all_owners, first.robot.id), DeleteResult::deleted);
  EXPECT_EQ(store_->delete_robot(api::all_owners, first.robot.id), DeleteResult::not_found);
  // Its key went with it: the same key now makes a new robot.
  EXPECT_EQ(store_->insert_robot(some_robot("a"), key).status, SubmitStatus::created);
}

TEST_P(StoreContract, MismatchedTrajectoryShapeIsRefused) {
  auto data = make_trajectory(10, 2, true, false);
  data.tau.resize(9, 2);
  EXPECT_THROW(store_->insert_dataset("", "bad", data, "", std::nullopt), std::invalid_argument);
  EXPECT_TRUE(store_->list_datasets(api::all_owners, {}).items.empty());
}

TEST_P(StoreContract, DatasetIdempotencyKey) {
  const auto data = make_trajectory(20, 2, true, false);
  const api::IdempotencyKey key{"upload-1", "fingerprint-a"};
  const auto first = store_->insert_dataset("", "first", data, "", key);
  ASSERT_EQ(first.status, SubmitStatus::created);

  const auto replay = store_->insert_dataset("", "first", data, "", key);
  EXPECT_EQ(replay.status, SubmitStatus::replayed);
  EXPECT_EQ(replay.dataset.id, first.dataset.id);
  EXPECT_EQ(replay.dataset.name, "first");

  const auto conflict = store_->insert_dataset("", "other", data, "", api::IdempotencyKey{"upload-1", "fingerprint-b"});
  EXPECT_EQ(conflict.status, SubmitStatus::key_reused);
  EXPECT_TRUE(conflict.dataset.id.empty());
  EXPECT_EQ(store_->list_datasets(api::all_owners, {}).items.size(), 1u);

  // Deleting the dataset frees its key.
  EXPECT_EQ(store_->delete_dataset(api::all_owners, first.dataset.id), DeleteResult::deleted);
  EXPECT_FALSE(store_->find_dataset(api::all_owners, first.dataset.id));
  const auto again = store_->insert_dataset("", "again", data, "", api::IdempotencyKey{"upload-1", "fingerprint-b"});
  EXPECT_EQ(again.status, SubmitStatus::created);
  EXPECT_NE(again.dataset.id, first.dataset.id);
}

TEST_P(StoreContract, ListDatasetsNewestFirstInPages) {
  std::vector<std::string> ids;
  for (int i = 0; i < 5; ++i) {
    ids.push_back(store_->insert_dataset("", "d" + std::to_string(i), make_trajectory(3, 1, false, false), "",
                                         std::nullopt)
                      .dataset.id);
  }
  std::vector<std::string> seen;
  api::PageRequest request{2, ""};
  std::vector<std::size_t> sizes;
  for (;;) {
    const auto page = store_->list_datasets(api::all_owners, request);
    sizes.push_back(page.items.size());
    for (const auto& dataset : page.items) seen.push_back(dataset.id);
    if (page.next_page_token.empty()) break;
    request.page_token = page.next_page_token;
  }
  EXPECT_EQ(sizes, (std::vector<std::size_t>{2, 2, 1}));
  std::reverse(ids.begin(), ids.end());
  EXPECT_EQ(seen, ids);
  expect_invalid_field([&] { store_->list_datasets(api::all_owners, {2, "not-a-token"}); }, "page_token");
}

// ---- submitting and claiming ----

TEST_P(StoreContract, SubmittedJobIsQueued) {
  const auto outcome = store_->submit_job(identification_job(R"({"a":1})"), std::nullopt, 0);
  ASSERT_EQ(outcome.status, SubmitStatus::created);
  EXPECT_TRUE(is_id(outcome.job.id, "job_"));
  const auto job = store_->find_job(api::all_owners, outcome.job.id);
  ASSERT_TRUE(job);
  EXPECT_EQ(job->state, JobState::queued);
  EXPECT_EQ(job->kind, api::JobKind::identification);
  EXPECT_EQ(job->request, R"({"a":1})");
  EXPECT_EQ(job->dataset_id, "ds_0123456789abcdef");
  EXPECT_TRUE(is_time(job->created_at));
  EXPECT_EQ(job->started_at, "");
  EXPECT_EQ(job->finished_at, "");
  EXPECT_EQ(job->attempts, 0);
  EXPECT_EQ(job->evaluations, 0);
  EXPECT_FALSE(job->best_cost);
  EXPECT_FALSE(job->cancel_requested);
  EXPECT_FALSE(store_->find_job(api::all_owners, "job_0000000000000000"));
}

TEST_P(StoreContract, JobIdempotencyKey) {
  const api::IdempotencyKey key{"client-1:abc", "sha-1"};
  const auto first = store_->submit_job(identification_job(), key, 0);
  ASSERT_EQ(first.status, SubmitStatus::created);
  const auto replay = store_->submit_job(identification_job(), key, 0);
  EXPECT_EQ(replay.status, SubmitStatus::replayed);
  EXPECT_EQ(replay.job.id, first.job.id);

  const auto conflict = store_->submit_job(identification_job(R"({"other":2})"), {{"client-1:abc", "sha-2"}}, 0);
  EXPECT_EQ(conflict.status, SubmitStatus::key_reused);
  EXPECT_TRUE(conflict.job.id.empty());
  EXPECT_EQ(store_->count_jobs_by_state()[JobState::queued], 1);

  // A replay of a job that has since run shows its current state.
  ASSERT_TRUE(claim());
  EXPECT_EQ(store_->submit_job(identification_job(), key, 0).job.state, JobState::running);
}

TEST_P(StoreContract, QueueLimit) {
  const api::IdempotencyKey key{"k", "f"};
  EXPECT_EQ(store_->submit_job(identification_job(), key, 2).status, SubmitStatus::created);
  EXPECT_EQ(store_->submit_job(identification_job(), std::nullopt, 2).status, SubmitStatus::created);
  const auto full = store_->submit_job(identification_job(), api::IdempotencyKey{"k2", "f"}, 2);
  EXPECT_EQ(full.status, SubmitStatus::queue_full);
  EXPECT_TRUE(full.job.id.empty());
  EXPECT_EQ(store_->count_jobs_by_state()[JobState::queued], 2);
  // The refused submission stored no key: it can be sent again later.
  // A replay is answered even when the queue is full.
  EXPECT_EQ(store_->submit_job(identification_job(), key, 2).status, SubmitStatus::replayed);
  // No limit at 0 or below.
  EXPECT_EQ(store_->submit_job(identification_job(), std::nullopt, 0).status, SubmitStatus::created);
  EXPECT_EQ(store_->submit_job(identification_job(), std::nullopt, -1).status, SubmitStatus::created);
  // Running jobs do not count against the queue.
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(claim());
  EXPECT_EQ(store_->submit_job(identification_job(), api::IdempotencyKey{"k2", "f"}, 2).status,
            SubmitStatus::created);
}

TEST_P(StoreContract, ClaimOrderIsSubmissionOrder) {
  std::vector<std::string> submitted;
  for (int i = 0; i < 6; ++i) submitted.push_back(submit());
  for (const auto& expected : submitted) {
    const auto claimed = claim();
    ASSERT_TRUE(claimed);
    EXPECT_EQ(claimed->id, expected);
    EXPECT_EQ(claimed->state, JobState::running);
    EXPECT_EQ(claimed->attempts, 1);
    EXPECT_TRUE(is_time(claimed->started_at));
  }
  EXPECT_FALSE(claim());
  const auto counts = store_->count_jobs_by_state();
  EXPECT_EQ(counts.at(JobState::running), 6);
  EXPECT_EQ(counts.at(JobState::queued), 0);
}

TEST_P(StoreContract, EightThreadsNeverClaimTheSameJob) {
  constexpr int kJobs = 200;
  std::set<std::string> submitted;
  for (int i = 0; i < kJobs; ++i) submitted.insert(submit());

  std::vector<std::vector<std::string>> claimed(8);
  std::atomic<int> failures{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      try {
        while (auto job = claim()) claimed[t].push_back(job->id);
      } catch (...) {
        ++failures;
      }
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(failures.load(), 0);
  std::multiset<std::string> all;
  for (const auto& ids : claimed) all.insert(ids.begin(), ids.end());
  EXPECT_EQ(all.size(), static_cast<std::size_t>(kJobs));
  EXPECT_EQ(std::set<std::string>(all.begin(), all.end()), submitted);
}

// ---- progress and history ----

TEST_P(StoreContract, ProgressAndHistoryPaging) {
  const auto id = submit();
  ASSERT_TRUE(claim());
  store_->record_progress(held(id), 60, 0.5, history_batch(0, 60));
  store_->record_progress(held(id), 120, 0.25, history_batch(60, 60));
  store_->record_progress(held(id), 120, 0.25, history_batch(60, 60));  // a re-sent batch is harmless

  const auto job = store_->find_job(api::all_owners, id);
  ASSERT_TRUE(job);
  EXPECT_EQ(job->evaluations, 120);
  ASSERT_TRUE(job->best_cost);
  EXPECT_EQ(*job->best_cost, 0.25);

  std::vector<api::HistoryEntry> all;
  std::vector<std::size_t> sizes;
  api::PageRequest request{50, ""};
  for (;;) {
    const auto page = store_->history(api::all_owners, id, request);
    ASSERT_TRUE(page);
    sizes.push_back(page->items.size());
    all.insert(all.end(), page->items.begin(), page->items.end());
    if (page->next_page_token.empty()) break;
    request.page_token = page->next_page_token;
  }
  EXPECT_EQ(sizes, (std::vector<std::size_t>{50, 50, 20}));
  const auto expected = history_batch(0, 120);
  ASSERT_EQ(all.size(), expected.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].index, expected[i].index);
    EXPECT_EQ(std::memcmp(&all[i].cost, &expected[i].cost, sizeof(double)), 0);
    ASSERT_EQ(all[i].theta.size(), 3u);
    EXPECT_EQ(std::memcmp(all[i].theta.data(), expected[i].theta.data(), 3 * sizeof(double)), 0);
  }

  EXPECT_EQ(store_->history(api::all_owners, id, {0, ""})->items.size(), 50u);            // 0 → default 50
  const auto everything = store_->history(api::all_owners, id, {5000, ""});                // coerced to 1000
  EXPECT_EQ(everything->items.size(), 120u);
  EXPECT_TRUE(everything->next_page_token.empty());
  const auto exact = store_->history(api::all_owners, id, {120, ""});                      // exactly one full page
  EXPECT_EQ(exact->items.size(), 120u);
  EXPECT_TRUE(exact->next_page_token.empty());

  const auto first = store_->history(api::all_owners, id, {10, ""});
  ASSERT_FALSE(first->next_page_token.empty());
  const auto second = store_->history(api::all_owners, id, {10, first->next_page_token});
  EXPECT_EQ(second->items.front().index, 10);

  std::string edited = first->next_page_token;
  edited[3] = edited[3] == '1' ? '2' : '1';
  expect_invalid_field([&] { store_->history(api::all_owners, id, {10, "garbage"}); }, "page_token");
  expect_invalid_field([&] { store_->history(api::all_owners, id, {10, edited}); }, "page_token");
  expect_invalid_field([&] { store_->history(api::all_owners, id, {10, first->next_page_token + "0"}); }, "page_token");
  expect_invalid_field([&] { store_->history(api::all_owners, id, {-1, ""}); }, "page_size");
  // A token is bound to its job.
  const auto other = submit();
  expect_invalid_field([&] { store_->history(api::all_owners, other, {10, first->next_page_token}); }, "page_token");

  EXPECT_FALSE(store_->history(api::all_owners, "job_0000000000000000", {}));
  const auto empty = store_->history(api::all_owners, other, {});
  ASSERT_TRUE(empty);
  EXPECT_TRUE(empty->items.empty());
  EXPECT_TRUE(empty->next_page_token.empty());
}

TEST_P(StoreContract, ProgressOnlyForRunningJobs) {
  const auto id = submit();
  EXPECT_EQ(store_->record_progress(held(id), 5, 1.0, history_batch(0, 5)), LeaseStatus::lost);  // still queued
  EXPECT_EQ(store_->find_job(api::all_owners, id)->evaluations, 0);
  EXPECT_TRUE(store_->history(api::all_owners, id, {})->items.empty());
}

// ---- finishing, cancelling, deleting ----

TEST_P(StoreContract, FinishJobKeepsOutcome) {
  const auto id = submit();
  ASSERT_TRUE(claim());
  store_->record_progress(held(id), 10, 0.1, history_batch(0, 10));
  store_->finish_job(held(id), end_as(JobState::succeeded, R"({"theta":[1,2]})", "",
                     {{"m1", 1.5, 0.01}, {"l1", 0.3, std::nullopt}}, "ds_aaaaaaaaaaaaaaaa"));
  auto job = store_->find_job(api::all_owners, id);
  ASSERT_TRUE(job);
  EXPECT_EQ(job->state, JobState::succeeded);
  EXPECT_EQ(job->result, R"({"theta":[1,2]})");
  EXPECT_EQ(job->error, "");
  EXPECT_EQ(job->dataset_id, "ds_aaaaaaaaaaaaaaaa");
  EXPECT_TRUE(is_time(job->finished_at));
  EXPECT_EQ(store_->history(api::all_owners, id, {})->items.size(), 10u);  // the history stays with the result

  // A second end does not overwrite the first; an empty dataset id keeps the input's.
  store_->finish_job(held(id), end_as(JobState::failed, "", R"({"code":"INTERNAL"})", {}, ""));
  job = store_->find_job(api::all_owners, id);
  EXPECT_EQ(job->state, JobState::succeeded);
  EXPECT_EQ(job->error, "");

  const auto failed = submit();
  ASSERT_TRUE(claim());
  store_->finish_job(held(failed), end_as(JobState::failed, "", R"({"code":"INTERNAL"})", {}, ""));
  job = store_->find_job(api::all_owners, failed);
  EXPECT_EQ(job->state, JobState::failed);
  EXPECT_EQ(job->error, R"({"code":"INTERNAL"})");
  EXPECT_EQ(job->dataset_id, "ds_0123456789abcdef");

  EXPECT_THROW(store_->finish_job(held(failed), end_as(JobState::running, "", "", {}, "")), std::invalid_argument);
}

TEST_P(StoreContract, TheEndBringsTheLastHistoryBatchAndItsProgressInOneWrite) {
  const auto id = submit();
  ASSERT_TRUE(claim());
  store_->record_progress(held(id), 10, 0.5, history_batch(0, 10));
  JobEnd end = end_as(JobState::succeeded, "{}", "", {{"m1", 1.5, 0.01}}, "");
  end.history = history_batch(10, 5);
  end.evaluations = 15;
  end.best_cost = 0.125;
  ASSERT_TRUE(store_->finish_job(held(id), end));
  auto job = store_->find_job(api::all_owners, id);
  EXPECT_EQ(job->state, JobState::succeeded);
  EXPECT_EQ(job->evaluations, 15);
  EXPECT_EQ(job->best_cost, 0.125);
  const auto items = store_->history(api::all_owners, id, {})->items;
  ASSERT_EQ(items.size(), 15u);
  const auto expected = history_batch(0, 15);
  for (std::size_t i = 0; i < items.size(); ++i) {
    EXPECT_EQ(items[i].index, expected[i].index);
    EXPECT_EQ(items[i].cost, expected[i].cost);  // bit for bit
    EXPECT_EQ(items[i].theta, expected[i].theta);
  }

  // An end without progress leaves the counters as the last progress write left them.
  const auto quiet = submit();
  ASSERT_TRUE(claim());
  store_->record_progress(held(quiet), 7, 0.25, history_batch(0, 7));
  ASSERT_TRUE(store_->finish_job(held(quiet), end_as(JobState::cancelled, "", "", {}, "")));
  job = store_->find_job(api::all_owners, quiet);
  EXPECT_EQ(job->evaluations, 7);
  EXPECT_EQ(job->best_cost, 0.25);

  // An attempt that lost its lease writes none of it: neither the end nor the batch.
  const auto lost = submit();
  ASSERT_TRUE(claim());
  JobEnd stale = end;
  stale.history = history_batch(0, 3);
  stale.evaluations = 3;
  EXPECT_FALSE(store_->finish_job(Lease{lost, "someone-else:1", 1}, stale));
  job = store_->find_job(api::all_owners, lost);
  EXPECT_EQ(job->state, JobState::running);
  EXPECT_EQ(job->evaluations, 0);
  EXPECT_TRUE(store_->history(api::all_owners, lost, {})->items.empty());
}

TEST_P(StoreContract, CancelRules) {
  const auto queued = submit();
  const auto running = submit();
  EXPECT_EQ(store_->cancel_job(api::all_owners, queued), CancelOutcome::cancelled_now);
  auto job = store_->find_job(api::all_owners, queued);
  EXPECT_EQ(job->state, JobState::cancelled);
  EXPECT_TRUE(is_time(job->finished_at));
  EXPECT_EQ(store_->cancel_job(api::all_owners, queued), CancelOutcome::already_finished);

  ASSERT_EQ(claim()->id, running);  // the cancelled one is skipped
  EXPECT_EQ(store_->cancel_job(api::all_owners, running), CancelOutcome::requested);
  EXPECT_EQ(store_->cancel_job(api::all_owners, running), CancelOutcome::requested);
  job = store_->find_job(api::all_owners, running);
  EXPECT_EQ(job->state, JobState::running);
  EXPECT_TRUE(job->cancel_requested);
  store_->finish_job(held(running), end_as(JobState::cancelled, "", "", {}, ""));
  EXPECT_EQ(store_->cancel_job(api::all_owners, running), CancelOutcome::already_finished);
  EXPECT_EQ(store_->cancel_job(api::all_owners, "job_0000000000000000"), CancelOutcome::not_found);
}

TEST_P(StoreContract, DeleteRules) {
  const api::IdempotencyKey key{"delete-me", "f"};
  const auto queued = store_->submit_job(identification_job(), key, 0).job.id;
  EXPECT_EQ(store_->delete_job(api::all_owners, queued), DeleteResult::in_use);

  ASSERT_TRUE(claim());
  EXPECT_EQ(store_->delete_job(api::all_owners, queued), DeleteResult::in_use);

  store_->record_progress(held(queued), 3, 1.0, history_batch(0, 3));
  store_->finish_job(held(queued), end_as(JobState::succeeded, "{}", "", {{"m1", 1.0, std::nullopt}}, ""));
  EXPECT_EQ(store_->delete_job(api::all_owners, queued), DeleteResult::deleted);
  EXPECT_FALSE(store_->find_job(api::all_owners, queued));
  EXPECT_FALSE(store_->history(api::all_owners, queued, {}));

  EXPECT_EQ(store_->delete_job(api::all_owners, queued), DeleteResult::not_found);

  // The deleted job's key no longer replays.
  const auto again = store_->submit_job(identification_job(), key, 0);
  EXPECT_EQ(again.status, SubmitStatus::created);
  EXPECT_NE(again.job.id, queued);
}

TEST_P(StoreContract, RequeueClearsProgressAndKeepsAttempts) {
  const auto id = submit();
  ASSERT_TRUE(claim());
  store_->record_progress(held(id), 7, 0.7, history_batch(0, 7));
  store_->requeue_job(held(id));
  auto job = store_->find_job(api::all_owners, id);
  EXPECT_EQ(job->state, JobState::queued);
  EXPECT_EQ(job->started_at, "");
  EXPECT_EQ(job->evaluations, 0);
  EXPECT_FALSE(job->best_cost);
  EXPECT_EQ(job->attempts, 1);
  EXPECT_TRUE(store_->history(api::all_owners, id, {})->items.empty());
  const auto again = claim();
  ASSERT_TRUE(again);
  EXPECT_EQ(again->id, id);
  EXPECT_EQ(again->attempts, 2);

  // A job whose cancellation was asked for is not run again.
  EXPECT_EQ(store_->cancel_job(api::all_owners, id), CancelOutcome::requested);
  store_->requeue_job(held(id));
  EXPECT_EQ(store_->find_job(api::all_owners, id)->state, JobState::cancelled);
  EXPECT_FALSE(claim());
}

// ---- restarts ----

TEST_P(StoreContract, RecoverInterruptedJobsAfterReopen) {
  const auto interrupted = submit();
  const auto cancelling = submit();
  const auto waiting = submit();
  ASSERT_EQ(claim()->id, interrupted);
  ASSERT_EQ(claim()->id, cancelling);
  store_->record_progress(held(interrupted), 30, 0.3, history_batch(0, 30));
  ASSERT_EQ(store_->cancel_job(api::all_owners, cancelling), CancelOutcome::requested);

  reopen();  // as if the process had died with the jobs running
  const RecoveryOutcome recovered = recover();
  EXPECT_EQ(recovered.requeued, 1);
  EXPECT_EQ(recovered.cancelled, 1);
  EXPECT_TRUE(recovered.failed.empty());
  auto job = store_->find_job(api::all_owners, interrupted);
  EXPECT_EQ(job->state, JobState::queued);
  EXPECT_EQ(job->attempts, 1);
  EXPECT_EQ(job->started_at, "");
  EXPECT_EQ(job->evaluations, 0);
  EXPECT_TRUE(store_->history(api::all_owners, interrupted, {})->items.empty());
  EXPECT_EQ(store_->find_job(api::all_owners, cancelling)->state, JobState::cancelled);
  EXPECT_EQ(store_->find_job(api::all_owners, waiting)->state, JobState::queued);
  EXPECT_EQ(recover().requeued, 0);

  // Back in submission order; the interrupted job starts its second attempt.
  const auto first = claim();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->id, interrupted);
  EXPECT_EQ(first->attempts, 2);
  EXPECT_EQ(claim()->id, waiting);
}

TEST_P(StoreContract, StartUpRecoveryLeavesTheJobsOfLiveWorkers) {
  const auto dead = submit();
  const auto alive = submit();
  ASSERT_EQ(claim("host-a:100")->id, dead);
  ASSERT_EQ(claim("host-a:200")->id, alive);
  reopen();
  const RecoveryOutcome recovered = recover(3, "host-a:200");
  EXPECT_EQ(recovered.requeued, 1);
  EXPECT_EQ(store_->find_job(api::all_owners, dead)->state, JobState::queued);
  const auto job = store_->find_job(api::all_owners, alive);
  EXPECT_EQ(job->state, JobState::running);
  EXPECT_EQ(job->worker, "host-a:200");
  EXPECT_EQ(store_->renew_lease(held(alive), std::chrono::seconds(30)), LeaseStatus::held);
}

TEST_P(StoreContract, AJobThatKillsItsWorkerThreeTimesIsFailedNotRunAgain) {
  const auto poison = submit();
  const auto innocent = submit();
  for (int death = 1; death <= 3; ++death) {
    SCOPED_TRACE(death);
    const auto claimed = claim();
    ASSERT_TRUE(claimed);
    ASSERT_EQ(claimed->id, poison);  // oldest first: the poison job always comes back first
    reopen();                        // the process died while running it
    const RecoveryOutcome recovered = recover();
    if (death < 3) {
      EXPECT_EQ(recovered.requeued, 1);
      EXPECT_TRUE(recovered.failed.empty());
      EXPECT_EQ(store_->find_job(api::all_owners, poison)->state, JobState::queued);
    } else {
      EXPECT_EQ(recovered.requeued, 0);
      EXPECT_EQ(recovered.failed, std::vector<std::string>{poison});
      const auto job = store_->find_job(api::all_owners, poison);
      EXPECT_EQ(job->state, JobState::failed);
      EXPECT_EQ(job->error, "{\"lost\": 3}");
      EXPECT_NE(job->finished_at, "");
    }
  }
  // The queue moves on: the next claim is the innocent job, and nothing else is left.
  const auto next = claim();
  ASSERT_TRUE(next);
  EXPECT_EQ(next->id, innocent);
  EXPECT_FALSE(claim());
}

TEST_P(StoreContract, AGracefulRequeueIsNotAWorkerDeath) {
  const auto id = submit();
  for (int shutdown = 0; shutdown < 5; ++shutdown) {
    ASSERT_EQ(claim()->id, id);
    store_->requeue_job(held(id));  // SIGTERM: the job was handed back, not lost
  }
  ASSERT_EQ(claim()->id, id);
  reopen();
  const RecoveryOutcome recovered = recover();
  EXPECT_EQ(recovered.requeued, 1);  // one death so far, not six
  EXPECT_TRUE(recovered.failed.empty());
}

TEST_P(StoreContract, IdempotencyKeysExpire) {
  const api::IdempotencyKey key{"k-expiring", "f1"};
  const auto first = store_->submit_job(identification_job(), key, 0);
  const auto robot = store_->insert_robot({"arm", "<robot/>", "", "", 1, "{}", ""}, key);
  EXPECT_EQ(store_->submit_job(identification_job(), key, 0).status, SubmitStatus::replayed);
  reopen({.idempotency_ttl = std::chrono::seconds(0)});
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // past the stamps' millisecond
  // Expired: the same key (even with another body) makes a new job; a robot's key of the same name is its own.
  const auto again = store_->submit_job(identification_job(), {{"k-expiring", "f2"}}, 0);
  EXPECT_EQ(again.status, SubmitStatus::created);
  EXPECT_NE(again.job.id, first.job.id);
  reopen();
  EXPECT_EQ(store_->submit_job(identification_job(), {{"k-expiring", "f2"}}, 0).job.id, again.job.id);
  EXPECT_EQ(store_->submit_job(identification_job(), key, 0).status, SubmitStatus::key_reused);
  // The robot's key was stored before the expired job key was replaced: forgotten with it.
  const auto second_robot = store_->insert_robot({"arm", "<robot/>", "", "", 1, "{}", ""}, key);
  EXPECT_EQ(second_robot.status, SubmitStatus::created);
  EXPECT_NE(second_robot.robot.id, robot.robot.id);
}

// ---- leases ----

TEST_P(StoreContract, AClaimNamesItsOwnerAndOnlyThatAttemptWrites) {
  const auto id = submit();
  const auto claimed = claim("host-a:100");
  ASSERT_TRUE(claimed);
  EXPECT_EQ(claimed->worker, "host-a:100");
  EXPECT_EQ(claimed->attempts, 1);
  EXPECT_EQ(store_->find_job(api::all_owners, id)->worker, "host-a:100");
  const Lease lease{id, "host-a:100", 1};
  EXPECT_EQ(store_->renew_lease(lease, std::chrono::seconds(30)), LeaseStatus::held);
  EXPECT_EQ(store_->record_progress(lease, 4, 0.4, history_batch(0, 4)), LeaseStatus::held);

  // Another owner, or an earlier attempt of the same owner, writes nothing.
  for (const Lease& stranger : {Lease{id, "host-b:200", 1}, Lease{id, "host-a:100", 0}}) {
    EXPECT_EQ(store_->renew_lease(stranger, std::chrono::seconds(30)), LeaseStatus::lost);
    EXPECT_EQ(store_->record_progress(stranger, 9, 0.1, history_batch(4, 5)), LeaseStatus::lost);
    EXPECT_FALSE(store_->finish_job(stranger, end_as(JobState::succeeded, "{}", "", {{"m1", 1.0, std::nullopt}}, "")));
    store_->requeue_job(stranger);
  }
  auto job = store_->find_job(api::all_owners, id);
  EXPECT_EQ(job->state, JobState::running);
  EXPECT_EQ(job->evaluations, 4);
  EXPECT_EQ(store_->history(api::all_owners, id, {})->items.size(), 4u);

  // A cancel asked for through any process reaches the holder on its next write.
  EXPECT_EQ(store_->cancel_job(api::all_owners, id), CancelOutcome::requested);
  EXPECT_EQ(store_->renew_lease(lease, std::chrono::seconds(30)), LeaseStatus::cancel_requested);
  EXPECT_EQ(store_->record_progress(lease, 5, 0.3, history_batch(4, 1)), LeaseStatus::cancel_requested);
  EXPECT_TRUE(store_->finish_job(lease, end_as(JobState::cancelled, "", "", {}, "")));
  job = store_->find_job(api::all_owners, id);
  EXPECT_EQ(job->state, JobState::cancelled);
  EXPECT_EQ(job->worker, "");  // only a running job has a worker
  EXPECT_EQ(store_->renew_lease(lease, std::chrono::seconds(30)), LeaseStatus::lost);
}

TEST_P(StoreContract, ExpiredLeasesAreRecoveredAndTheOldAttemptIsShutOut) {
  const auto expiring = submit();
  const auto renewed = submit();
  const auto held_long = submit();
  ASSERT_EQ(claim("host-a:100", std::chrono::milliseconds(150))->id, expiring);
  ASSERT_EQ(claim("host-a:100", std::chrono::milliseconds(150))->id, renewed);
  ASSERT_EQ(claim("host-b:200", std::chrono::seconds(30))->id, held_long);
  const Lease old_attempt = held(expiring);
  ASSERT_EQ(store_->record_progress(old_attempt, 3, 0.3, history_batch(0, 3)), LeaseStatus::held);
  const auto lost_error = [](int losses) { return "{\"lost\": " + std::to_string(losses) + "}"; };
  EXPECT_EQ(store_->recover_expired_leases(3, lost_error).requeued, 0);  // nothing has expired yet

  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ASSERT_EQ(store_->renew_lease(held(renewed), std::chrono::seconds(30)), LeaseStatus::held);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const RecoveryOutcome recovered = store_->recover_expired_leases(3, lost_error);
  EXPECT_EQ(recovered.requeued, 1);
  EXPECT_EQ(recovered.cancelled, 0);
  EXPECT_TRUE(recovered.failed.empty());
  auto job = store_->find_job(api::all_owners, expiring);
  EXPECT_EQ(job->state, JobState::queued);
  EXPECT_EQ(job->worker, "");
  EXPECT_EQ(job->evaluations, 0);
  EXPECT_TRUE(store_->history(api::all_owners, expiring, {})->items.empty());
  EXPECT_EQ(store_->find_job(api::all_owners, renewed)->state, JobState::running);
  EXPECT_EQ(store_->find_job(api::all_owners, held_long)->state, JobState::running);

  // The paused worker wakes up: none of its writes show, before or after the next claim.
  EXPECT_EQ(store_->record_progress(old_attempt, 6, 0.2, history_batch(3, 3)), LeaseStatus::lost);
  const auto again = claim("host-c:300");
  ASSERT_TRUE(again);
  EXPECT_EQ(again->id, expiring);
  EXPECT_EQ(again->attempts, 2);
  EXPECT_EQ(store_->record_progress(old_attempt, 6, 0.2, history_batch(3, 3)), LeaseStatus::lost);
  EXPECT_FALSE(store_->finish_job(old_attempt, end_as(JobState::succeeded, "{\"old\": true}", "", {}, "")));
  EXPECT_TRUE(store_->finish_job(held(expiring), end_as(JobState::succeeded, "{\"new\": true}", "", {}, "")));
  job = store_->find_job(api::all_owners, expiring);
  EXPECT_EQ(job->result, "{\"new\": true}");
  EXPECT_TRUE(store_->history(api::all_owners, expiring, {})->items.empty());
}

TEST_P(StoreContract, AJobWhoseLeaseExpiresMaxAttemptsTimesIsFailed) {
  const auto poison = submit();
  const auto lost_error = [](int losses) { return "{\"lost\": " + std::to_string(losses) + "}"; };
  for (int loss = 1; loss <= 2; ++loss) {
    ASSERT_EQ(claim("host-a:100", std::chrono::milliseconds(1))->id, poison);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    EXPECT_EQ(store_->recover_expired_leases(2, lost_error).requeued, loss == 1 ? 1 : 0);
  }
  const auto job = store_->find_job(api::all_owners, poison);
  EXPECT_EQ(job->state, JobState::failed);
  EXPECT_EQ(job->error, "{\"lost\": 2}");
  EXPECT_EQ(job->attempts, 2);
  EXPECT_FALSE(claim());

  // A running job whose cancellation was asked for ends cancelled, not queued again.
  const auto cancelling = submit();
  ASSERT_EQ(claim("host-a:100", std::chrono::milliseconds(1))->id, cancelling);
  ASSERT_EQ(store_->cancel_job(api::all_owners, cancelling), CancelOutcome::requested);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(store_->recover_expired_leases(2, lost_error).cancelled, 1);
  EXPECT_EQ(store_->find_job(api::all_owners, cancelling)->state, JobState::cancelled);
}

TEST_P(StoreContract, EverythingSurvivesReopen) {
  const auto data = make_trajectory(50, 2, true, true);
  const auto dataset = store_->insert_dataset("", "kept", data, "", api::IdempotencyKey{"d", "f"}).dataset.id;
  const auto job = store_->submit_job(identification_job(), api::IdempotencyKey{"j", "f"}, 0).job.id;
  ASSERT_TRUE(claim());
  store_->record_progress(held(job), 12, 0.12, history_batch(0, 12));

  reopen();
  const auto loaded = store_->load_dataset(api::all_owners, dataset);
  ASSERT_TRUE(loaded);
  EXPECT_TRUE(same_bits(loaded->q, data.q));
  EXPECT_TRUE(same_bits(loaded->ref, data.ref));
  const auto info = store_->find_job(api::all_owners, job);
  ASSERT_TRUE(info);
  EXPECT_EQ(info->state, JobState::running);
  EXPECT_EQ(info->evaluations, 12);
  EXPECT_EQ(store_->history(api::all_owners, job, {})->items.size(), 12u);
  EXPECT_EQ(store_->submit_job(identification_job(), api::IdempotencyKey{"j", "f"}, 0).job.id, job);
  EXPECT_EQ(store_->insert_dataset("", "kept", data, "", api::IdempotencyKey{"d", "f"}).status, SubmitStatus::replayed);
  // New rows after the reopen list above the old ones.
  const auto newer = submit();
  const auto page = store_->list_jobs(api::all_owners, {}, {});
  ASSERT_EQ(page.items.size(), 2u);
  EXPECT_EQ(page.items[0].id, newer);
}

// ---- listing and counting ----

TEST_P(StoreContract, ListJobsNewestFirstWithFilters) {
  NewJob simulation = identification_job();
  simulation.kind = api::JobKind::simulation;
  std::vector<std::string> ids;
  for (int i = 0; i < 7; ++i) ids.push_back(submit(i % 2 == 0 ? simulation : identification_job()));
  ASSERT_EQ(claim()->id, ids[0]);  // a running simulation

  std::vector<std::string> seen;
  api::PageRequest request{3, ""};
  for (;;) {
    const auto page = store_->list_jobs(api::all_owners, {}, request);
    for (const auto& job : page.items) seen.push_back(job.id);
    if (page.next_page_token.empty()) break;
    EXPECT_EQ(page.items.size(), 3u);
    request.page_token = page.next_page_token;
  }
  EXPECT_EQ(seen, std::vector<std::string>(ids.rbegin(), ids.rend()));

  const auto simulations =
      store_->list_jobs(api::all_owners, {.state = {}, .kind = api::JobKind::simulation, .robot_id = {}}, {});
  ASSERT_EQ(simulations.items.size(), 4u);
  EXPECT_EQ(simulations.items[0].id, ids[6]);
  const auto queued_simulations = store_->list_jobs(
      api::all_owners, {.state = JobState::queued, .kind = api::JobKind::simulation, .robot_id = {}}, {});
  EXPECT_EQ(queued_simulations.items.size(), 3u);
  const auto running = store_->list_jobs(api::all_owners, {.state = JobState::running, .kind = {}, .robot_id = {}}, {});
  ASSERT_EQ(running.items.size(), 1u);
  EXPECT_EQ(running.items[0].id, ids[0]);

  const auto first = store_->list_jobs(api::all_owners, {.state = JobState::queued, .kind = {}, .robot_id = {}}, {2, ""});
  ASSERT_FALSE(first.next_page_token.empty());
  EXPECT_EQ(store_->list_jobs(api::all_owners, {.state = JobState::queued, .kind = {}, .robot_id = {}},
                              {2, first.next_page_token})
                .items.size(),
            2u);
  // The token belongs to its filter.
  expect_invalid_field([&] { store_->list_jobs(api::all_owners, {}, {2, first.next_page_token}); }, "page_token");
  expect_invalid_field([&] { store_->list_jobs(api::all_owners, {}, {2, "j1.zz.00000000"}); }, "page_token");
  expect_invalid_field([&] { store_->list_jobs(api::all_owners, {}, {2, "%%%"}); }, "page_token");
}

TEST_P(StoreContract, CountJobsByStateHasAllStates) {
  auto counts = store_->count_jobs_by_state();
  ASSERT_EQ(counts.size(), 5u);
  for (const auto& [state, count] : counts) EXPECT_EQ(count, 0);
  const auto cancelled = submit();
  submit();
  submit();
  store_->cancel_job(api::all_owners, cancelled);
  claim();
  counts = store_->count_jobs_by_state();
  EXPECT_EQ(counts.at(JobState::queued), 1);
  EXPECT_EQ(counts.at(JobState::running), 1);
  EXPECT_EQ(counts.at(JobState::cancelled), 1);
  EXPECT_EQ(counts.at(JobState::succeeded), 0);
  EXPECT_EQ(counts.at(JobState::failed), 0);
}

// ---- many callers at once ----

TEST_P(StoreContract, ConcurrentSubmissionsWithSharedKeys) {
  constexpr int kThreads = 8;
  constexpr int kPerThread = 25;
  // Every fifth submission of each thread uses a key shared by all threads: 5 keys, 40 sends.
  std::atomic<int> failures{0}, created{0}, replayed{0};
  std::vector<std::vector<std::pair<int, std::string>>> shared_ids(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      try {
        for (int i = 0; i < kPerThread; ++i) {
          std::optional<api::IdempotencyKey> key;
          if (i % 5 == 0) {
            key = api::IdempotencyKey{"shared-" + std::to_string(i), "same"};
          } else if (i % 2 == 0) {
            key = api::IdempotencyKey{"own-" + std::to_string(t) + "-" + std::to_string(i), "same"};
          }
          const auto outcome = store_->submit_job(identification_job(), key, 0);
          if (outcome.status == SubmitStatus::created) ++created;
          if (outcome.status == SubmitStatus::replayed) ++replayed;
          if (i % 5 == 0) shared_ids[t].emplace_back(i, outcome.job.id);
          // Readers interleaved with the writers.
          if (!store_->find_job(api::all_owners, outcome.job.id)) ++failures;
        }
      } catch (const std::exception& error) {
        ADD_FAILURE() << error.what();
        ++failures;
      }
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(failures.load(), 0);
  EXPECT_EQ(created.load(), kThreads * kPerThread - 40 + 5);
  EXPECT_EQ(replayed.load(), 35);
  EXPECT_EQ(store_->count_jobs_by_state()[JobState::queued], kThreads * kPerThread - 40 + 5);
  // Every thread got the same job for the same shared key.
  for (int t = 1; t < kThreads; ++t) EXPECT_EQ(shared_ids[t], shared_ids[0]);
}

// ---- what other processes did ----

TEST_P(StoreContract, AWatcherHearsWhatAnotherProcessDid) {
  std::mutex mutex;
  std::condition_variable arrived;
  std::vector<std::pair<JobEvent::Kind, std::string>> events;
  const bool watching = store_->watch_jobs([&](const JobEvent& event) {
    std::lock_guard lock(mutex);
    events.emplace_back(event.kind, event.job_id);
    arrived.notify_all();
  });
  if (!watching) {
    EXPECT_EQ(GetParam().name, "sqlite") << "only SQLite leaves its watchers to poll";
    return;
  }
  // Another process's store on the same database: a job queued, claimed, its cancel asked, ended.
  auto other = GetParam().open(directory_, {});
  const std::string id = other->submit_job(identification_job(), std::nullopt, 0).job.id;
  const auto job = other->claim_next_job("host-b:200", std::chrono::seconds(30));
  ASSERT_TRUE(job);
  EXPECT_EQ(other->cancel_job(api::all_owners, id), CancelOutcome::requested);
  ASSERT_TRUE(other->finish_job({id, job->worker, job->attempts}, end_as(JobState::cancelled, "", "", {}, "")));
  const std::vector<std::pair<JobEvent::Kind, std::string>> expected = {
      {JobEvent::Kind::queued, id}, {JobEvent::Kind::cancel_requested, id}, {JobEvent::Kind::changed, id}};
  {
    std::unique_lock lock(mutex);
    arrived.wait_for(lock, std::chrono::seconds(20), [&] { return events.size() >= expected.size(); });
    EXPECT_EQ(events, expected);
  }
  store_->watch_jobs({});
  other.reset();
}

// The rule both backends apply to a key's live record (store/idempotency.h), without a database:
// the paths the suite above cannot reach directly (a record whose resource is gone).
// ---- owners (manipid serve --token-file) ----

/// What owner `owner` stores: a dataset, a robot, and a job on both.
struct Owned {
  std::string dataset, robot, job;
};

Owned store_as(Store& store, const std::string& owner) {
  Owned owned;
  const DatasetOutcome dataset =
      store.insert_dataset(owner, owner + "'s run", make_trajectory(5, 2, true, false), "", std::nullopt);
  EXPECT_EQ(dataset.dataset.owner, owner);
  owned.dataset = dataset.dataset.id;
  NewRobot robot = some_robot(owner + "-arm");
  robot.owner = owner;
  const RobotOutcome created = store.insert_robot(robot, std::nullopt);
  EXPECT_EQ(created.robot.owner, owner);
  owned.robot = created.robot.id;
  NewJob job = identification_job();
  job.dataset_id = owned.dataset;
  job.robot_id = owned.robot;
  job.owner = owner;
  const SubmitOutcome submitted = store.submit_job(job, std::nullopt, 0);
  EXPECT_EQ(submitted.job.owner, owner);
  owned.job = submitted.job.id;
  return owned;
}

template <class Item>
std::set<std::string> ids_of(const api::Page<Item>& page) {
  std::set<std::string> ids;
  for (const Item& item : page.items) ids.insert(item.id);
  return ids;
}

TEST_P(StoreContract, AnOwnersResourcesAreAnotherOwnersMissingOnesAndAnAdminSeesAll) {
  const Owned alice = store_as(*store_, "alice");
  const Owned bob = store_as(*store_, "bob");
  const api::OwnerScope as_alice = "alice", as_bob = "bob";

  // Her own: found, whole.
  ASSERT_TRUE(store_->find_dataset(as_alice, alice.dataset));
  EXPECT_EQ(store_->find_dataset(as_alice, alice.dataset)->owner, "alice");
  EXPECT_TRUE(store_->load_dataset(as_alice, alice.dataset));
  EXPECT_TRUE(store_->find_robot(as_alice, alice.robot));
  EXPECT_TRUE(store_->load_robot_urdf(as_alice, alice.robot));
  EXPECT_TRUE(store_->find_job(as_alice, alice.job));
  EXPECT_TRUE(store_->history(as_alice, alice.job, {}));
  EXPECT_TRUE(store_->history_overview(as_alice, alice.job, 10));

  // Hers to bob: exactly as missing.
  EXPECT_FALSE(store_->find_dataset(as_bob, alice.dataset));
  EXPECT_FALSE(store_->load_dataset(as_bob, alice.dataset));
  EXPECT_FALSE(store_->find_robot(as_bob, alice.robot));
  EXPECT_FALSE(store_->load_robot_urdf(as_bob, alice.robot));
  EXPECT_FALSE(store_->find_job(as_bob, alice.job));
  EXPECT_FALSE(store_->history(as_bob, alice.job, {}));
  EXPECT_FALSE(store_->history_overview(as_bob, alice.job, 10));
  EXPECT_EQ(store_->cancel_job(as_bob, alice.job), CancelOutcome::not_found);
  EXPECT_EQ(store_->delete_job(as_bob, alice.job), DeleteResult::not_found);  // not in_use: not there at all
  EXPECT_EQ(store_->delete_dataset(as_bob, alice.dataset), DeleteResult::not_found);
  EXPECT_EQ(store_->delete_robot(as_bob, alice.robot), DeleteResult::not_found);
  EXPECT_EQ(store_->find_job(api::all_owners, alice.job)->state, JobState::queued);  // untouched

  // Lists: each owner's alone, every one's to the admin.
  EXPECT_EQ(ids_of(store_->list_datasets(as_bob, {})), std::set<std::string>{bob.dataset});
  EXPECT_EQ(ids_of(store_->list_robots(as_bob, {})), std::set<std::string>{bob.robot});
  EXPECT_EQ(ids_of(store_->list_jobs(as_bob, {}, {})), std::set<std::string>{bob.job});
  api::JobFilter on_alices_robot;
  on_alices_robot.robot_id = alice.robot;
  EXPECT_TRUE(store_->list_jobs(as_bob, on_alices_robot, {}).items.empty());
  EXPECT_EQ(ids_of(store_->list_jobs(as_alice, on_alices_robot, {})), std::set<std::string>{alice.job});
  EXPECT_EQ(ids_of(store_->list_datasets(api::all_owners, {})), (std::set<std::string>{alice.dataset, bob.dataset}));
  EXPECT_EQ(ids_of(store_->list_robots(api::all_owners, {})), (std::set<std::string>{alice.robot, bob.robot}));
  EXPECT_EQ(ids_of(store_->list_jobs(api::all_owners, {}, {})), (std::set<std::string>{alice.job, bob.job}));
  EXPECT_EQ(store_->find_job(api::all_owners, bob.job)->owner, "bob");
  EXPECT_EQ(store_->find_robot(api::all_owners, alice.robot)->owner, "alice");

  // Her own cancel and delete work; the admin's work on anyone's.
  EXPECT_EQ(store_->cancel_job(as_alice, alice.job), CancelOutcome::cancelled_now);
  EXPECT_EQ(store_->delete_job(as_bob, alice.job), DeleteResult::not_found);
  EXPECT_EQ(store_->delete_job(as_alice, alice.job), DeleteResult::deleted);
  EXPECT_EQ(store_->delete_dataset(as_alice, alice.dataset), DeleteResult::deleted);
  EXPECT_EQ(store_->cancel_job(api::all_owners, bob.job), CancelOutcome::cancelled_now);
  EXPECT_EQ(store_->delete_job(api::all_owners, bob.job), DeleteResult::deleted);
  EXPECT_EQ(store_->delete_robot(api::all_owners, bob.robot), DeleteResult::deleted);

  // A worker's output is its job's owner's.
  NewJob simulation;
  simulation.kind = api::JobKind::simulation;
  simulation.request = "{}";
  simulation.owner = "bob";
  const std::string id = submit(simulation);
  const auto claimed = claim();
  ASSERT_TRUE(claimed);
  const DatasetOutcome made = store_->insert_dataset(claimed->owner, "simulated", make_trajectory(4, 1, false, false), id,
                                                     api::IdempotencyKey{"job-output:" + id, id});
  EXPECT_TRUE(store_->find_dataset(as_bob, made.dataset.id));
  EXPECT_FALSE(store_->find_dataset(as_alice, made.dataset.id));
  // Everything is as it was after a reopen.
  reopen();
  EXPECT_EQ(store_->find_dataset(api::all_owners, made.dataset.id)->owner, "bob");
  EXPECT_FALSE(store_->find_robot(as_bob, alice.robot));
  EXPECT_EQ(ids_of(store_->list_robots(as_alice, {})), std::set<std::string>{alice.robot});
}

TEST_P(StoreContract, AnOwnersPagesHoldTheirsAloneAndTheirTokensServeNoOtherList) {
  std::vector<std::string> alices_datasets, alices_jobs;
  for (int i = 0; i < 5; ++i) {
    for (const std::string owner : {"alice", "bob"}) {
      const auto dataset = store_->insert_dataset(owner, owner + std::to_string(i), make_trajectory(3, 1, false, false),
                                                  "", std::nullopt);
      NewJob job = identification_job();
      job.owner = owner;
      const std::string id = submit(job);
      if (owner == "alice") {
        alices_datasets.insert(alices_datasets.begin(), dataset.dataset.id);  // newest first
        alices_jobs.insert(alices_jobs.begin(), id);
      }
    }
  }
  const api::OwnerScope as_alice = "alice";
  std::vector<std::string> seen;
  api::PageRequest request{2, ""};
  std::string alices_token;
  for (;;) {
    const auto page = store_->list_datasets(as_alice, request);
    for (const auto& dataset : page.items) seen.push_back(dataset.id);
    if (page.next_page_token.empty()) break;
    request.page_token = alices_token = page.next_page_token;
  }
  EXPECT_EQ(seen, alices_datasets);
  seen.clear();
  api::JobFilter queued;
  queued.state = JobState::queued;
  request = {2, ""};
  std::string alices_job_token;
  for (;;) {
    const auto page = store_->list_jobs(as_alice, queued, request);
    for (const auto& job : page.items) seen.push_back(job.id);
    if (page.next_page_token.empty()) break;
    request.page_token = alices_job_token = page.next_page_token;
  }
  EXPECT_EQ(seen, alices_jobs);
  // A token is its list's: not bob's, not the admin's (and theirs not hers).
  expect_invalid_field([&] { store_->list_datasets(api::OwnerScope("bob"), {2, alices_token}); }, "page_token");
  expect_invalid_field([&] { store_->list_datasets(api::all_owners, {2, alices_token}); }, "page_token");
  expect_invalid_field([&] { store_->list_jobs(api::OwnerScope("bob"), queued, {2, alices_job_token}); }, "page_token");
  const std::string admins_token = store_->list_datasets(api::all_owners, {2, ""}).next_page_token;
  ASSERT_FALSE(admins_token.empty());
  expect_invalid_field([&] { store_->list_datasets(as_alice, {2, admins_token}); }, "page_token");
  for (int i = 0; i < 3; ++i) {
    NewRobot robot = some_robot("r" + std::to_string(i));
    robot.owner = i == 1 ? "bob" : "alice";
    store_->insert_robot(robot, std::nullopt);
  }
  const auto first = store_->list_robots(as_alice, {1, ""});
  ASSERT_EQ(first.items.size(), 1u);
  EXPECT_EQ(first.items[0].name, "r2");
  const auto second = store_->list_robots(as_alice, {1, first.next_page_token});
  ASSERT_EQ(second.items.size(), 1u);
  EXPECT_EQ(second.items[0].name, "r0");  // bob's r1 between them is skipped, not shown
  EXPECT_EQ(second.next_page_token, "");
  expect_invalid_field([&] { store_->list_robots(api::OwnerScope("bob"), {1, first.next_page_token}); }, "page_token");
}

TEST_P(StoreContract, AnIdempotencyKeyIsItsOwners) {
  const api::IdempotencyKey key{"run-42", "fingerprint-a"};
  NewJob alices = identification_job(), bobs = identification_job();
  alices.owner = "alice";
  bobs.owner = "bob";
  const SubmitOutcome first = store_->submit_job(alices, key, 0);
  ASSERT_EQ(first.status, SubmitStatus::created);
  // Bob's same key, same body: his own new job, never alice's.
  const SubmitOutcome his = store_->submit_job(bobs, key, 0);
  ASSERT_EQ(his.status, SubmitStatus::created);
  EXPECT_NE(his.job.id, first.job.id);
  EXPECT_EQ(his.job.owner, "bob");
  // And each replays their own.
  EXPECT_EQ(store_->submit_job(alices, key, 0).job.id, first.job.id);
  EXPECT_EQ(store_->submit_job(bobs, key, 0).job.id, his.job.id);
  // Another body under the key is refused for its owner alone; a third owner's is a new key.
  NewJob carols = identification_job(R"({"other":1})");
  carols.owner = "carol";
  alices.request = R"({"other":1})";
  EXPECT_EQ(store_->submit_job(alices, api::IdempotencyKey{"run-42", "fingerprint-b"}, 0).status, SubmitStatus::key_reused);
  EXPECT_EQ(store_->submit_job(carols, api::IdempotencyKey{"run-42", "fingerprint-b"}, 0).status, SubmitStatus::created);
  // Deleting bob's job frees his key only.
  ASSERT_EQ(store_->cancel_job(api::OwnerScope("bob"), his.job.id), CancelOutcome::cancelled_now);
  ASSERT_EQ(store_->delete_job(api::OwnerScope("bob"), his.job.id), DeleteResult::deleted);
  EXPECT_EQ(store_->submit_job(bobs, key, 0).status, SubmitStatus::created);
  EXPECT_EQ(store_->submit_job(identification_job(), key, 0).status, SubmitStatus::created);  // owner "": a fourth

  // Datasets and robots alike.
  const auto data = make_trajectory(6, 1, false, false);
  const api::IdempotencyKey upload{"upload-1", "fingerprint-d"};
  const DatasetOutcome her_data = store_->insert_dataset("alice", "run", data, "", upload);
  const DatasetOutcome his_data = store_->insert_dataset("bob", "run", data, "", upload);
  EXPECT_EQ(his_data.status, SubmitStatus::created);
  EXPECT_NE(his_data.dataset.id, her_data.dataset.id);
  EXPECT_EQ(store_->insert_dataset("alice", "run", data, "", upload).dataset.id, her_data.dataset.id);
  EXPECT_EQ(store_->insert_dataset("bob", "run", data, "", upload).dataset.id, his_data.dataset.id);
  NewRobot her_robot = some_robot("arm"), his_robot = some_robot("arm");
  her_robot.owner = "alice";
  his_robot.owner = "bob";
  const RobotOutcome hers = store_->insert_robot(her_robot, upload);
  const RobotOutcome theirs = store_->insert_robot(his_robot, upload);
  EXPECT_EQ(theirs.status, SubmitStatus::created);
  EXPECT_NE(theirs.robot.id, hers.robot.id);
  EXPECT_EQ(store_->insert_robot(his_robot, upload).robot.id, theirs.robot.id);
  EXPECT_EQ(store_->insert_robot(her_robot, upload).robot.id, hers.robot.id);
}

// A PostgreSQL database from before owners (schema version 1: made here by taking today's owner
// columns away again) opens migrated: its rows are no one's, the admin's to see, and its keys still
// replay. (SQLite's migration from a release's file: migration_test.cpp.)
TEST_P(StoreContract, APostgresDatabaseFromBeforeOwnersOpensWithItsRowsTheAdmins) {
  if (GetParam().name != "postgres") GTEST_SKIP() << "SQLite's migrations: migration_test.cpp";
  const std::string dataset =
      store_->insert_dataset("", "old run", make_trajectory(5, 1, false, false), "", std::nullopt).dataset.id;
  const std::string robot = store_->insert_robot(some_robot(), std::nullopt).robot.id;
  const api::IdempotencyKey key{"old-key", "old-fingerprint"};
  const std::string job = store_->submit_job(identification_job(), key, 0).job.id;
  store_.reset();
  postgres_admin(
      "ALTER TABLE idempotency_keys DROP CONSTRAINT idempotency_keys_pkey; "
      "ALTER TABLE idempotency_keys DROP COLUMN owner; ALTER TABLE idempotency_keys ADD PRIMARY KEY (scope, key); "
      "ALTER TABLE datasets DROP COLUMN owner; ALTER TABLE robots DROP COLUMN owner; ALTER TABLE jobs DROP COLUMN owner; "
      "DELETE FROM manipid_schema WHERE version > 1",
      postgres_database(directory_));
  reopen();
  ASSERT_TRUE(store_->find_dataset(api::all_owners, dataset));
  EXPECT_EQ(store_->find_dataset(api::all_owners, dataset)->owner, "");
  EXPECT_EQ(store_->find_robot(api::all_owners, robot)->owner, "");
  EXPECT_EQ(store_->find_job(api::all_owners, job)->owner, "");
  EXPECT_EQ(ids_of(store_->list_jobs(api::all_owners, {}, {})), std::set<std::string>{job});
  EXPECT_FALSE(store_->find_job(api::OwnerScope("alice"), job));
  EXPECT_TRUE(store_->list_datasets(api::OwnerScope("alice"), {}).items.empty());
  EXPECT_EQ(store_->submit_job(identification_job(), key, 0).job.id, job);  // the old key replays
  NewJob alices = identification_job();
  alices.owner = "alice";
  EXPECT_EQ(store_->submit_job(alices, key, 0).status, SubmitStatus::created);  // hers is another key
}

// Every kind is stored and read back as itself, and listed by it.
TEST_P(StoreContract, EveryKindIsStoredAndFilteredAsItself) {
  const std::string robot = store_->insert_robot(some_robot(), std::nullopt).robot.id;
  std::map<api::JobKind, std::string> ids;
  for (const api::JobKind kind : api::kJobKinds) {
    NewJob job = identification_job();
    job.kind = kind;
    if (kind == api::JobKind::excitation || kind == api::JobKind::robot_identification ||
        kind == api::JobKind::payload_identification) {
      job.robot_id = robot;
    }
    ids[kind] = submit(job);
    EXPECT_EQ(store_->find_job(api::all_owners, ids[kind])->kind, kind) << api::to_string(kind);
  }
  for (const api::JobKind kind : api::kJobKinds) {
    const auto page = store_->list_jobs(api::all_owners, {.state = {}, .kind = kind, .robot_id = {}}, {});
    EXPECT_EQ(ids_of(page), std::set<std::string>{ids[kind]}) << api::to_string(kind);
  }
  const auto on_robot = store_->list_jobs(
      api::all_owners, {.state = {}, .kind = api::JobKind::robot_identification, .robot_id = robot}, {});
  EXPECT_EQ(ids_of(on_robot), std::set<std::string>{ids[api::JobKind::robot_identification]});
}

// A PostgreSQL database of schema version 2 (made here by putting back its kinds) opens migrated: its
// identifications that name a robot are robot_identification, the others stay identification.
TEST_P(StoreContract, APostgresVersionTwoRobotIdentificationBecomesItsOwnKind) {
  if (GetParam().name != "postgres") GTEST_SKIP() << "SQLite's migrations: migration_test.cpp";
  const std::string robot = store_->insert_robot(some_robot(), std::nullopt).robot.id;
  NewJob on_robot = identification_job(R"({"robot_id": "rb"})");
  on_robot.kind = api::JobKind::robot_identification;
  on_robot.robot_id = robot;
  const std::string robot_job = submit(on_robot);
  const std::string paper_job = submit(identification_job());
  NewJob design = identification_job();
  design.kind = api::JobKind::excitation;
  design.robot_id = robot;
  const std::string design_job = submit(design);
  store_.reset();
  postgres_admin(
      "UPDATE jobs SET kind = 'identification' WHERE kind = 'robot_identification'; "
      "ALTER TABLE jobs DROP CONSTRAINT jobs_kind_check; "
      "ALTER TABLE jobs ADD CONSTRAINT jobs_kind_check CHECK (kind IN ('simulation', 'identification', 'excitation')); "
      "DELETE FROM manipid_schema WHERE version > 2",
      postgres_database(directory_));
  reopen();
  EXPECT_EQ(store_->find_job(api::all_owners, robot_job)->kind, api::JobKind::robot_identification);
  EXPECT_EQ(store_->find_job(api::all_owners, paper_job)->kind, api::JobKind::identification);
  EXPECT_EQ(store_->find_job(api::all_owners, design_job)->kind, api::JobKind::excitation);
  EXPECT_EQ(ids_of(store_->list_jobs(api::all_owners, {.state = {}, .kind = api::JobKind::robot_identification, .robot_id = {}}, {})),
            std::set<std::string>{robot_job});
  EXPECT_FALSE(submit(on_robot).empty());  // the new CHECK takes the kind in
}

// A PostgreSQL database of schema version 3 (made here by putting back its CHECK) opens migrated: its rows kept,
// and the CHECK on kind takes payload_identification in.
TEST_P(StoreContract, APostgresVersionThreeTakesPayloadIdentifications) {
  if (GetParam().name != "postgres") GTEST_SKIP() << "SQLite's migrations: migration_test.cpp";
  const std::string robot = store_->insert_robot(some_robot(), std::nullopt).robot.id;
  NewJob on_robot = identification_job(R"({"robot_id": "rb"})");
  on_robot.kind = api::JobKind::robot_identification;
  on_robot.robot_id = robot;
  const std::string robot_job = submit(on_robot);
  store_.reset();
  postgres_admin(
      "ALTER TABLE jobs DROP CONSTRAINT jobs_kind_check; "
      "ALTER TABLE jobs ADD CONSTRAINT jobs_kind_check "
      "CHECK (kind IN ('simulation', 'identification', 'excitation', 'robot_identification')); "
      "DELETE FROM manipid_schema WHERE version > 3",
      postgres_database(directory_));
  reopen();
  EXPECT_EQ(store_->find_job(api::all_owners, robot_job)->kind, api::JobKind::robot_identification);
  NewJob payload = identification_job(R"({"payload": true, "robot_id": "rb"})");
  payload.kind = api::JobKind::payload_identification;
  payload.robot_id = robot;
  const std::string payload_job = submit(payload);
  EXPECT_EQ(store_->find_job(api::all_owners, payload_job)->kind, api::JobKind::payload_identification);
  EXPECT_EQ(ids_of(store_->list_jobs(api::all_owners, {.state = {}, .kind = api::JobKind::payload_identification, .robot_id = robot}, {})),
            std::set<std::string>{payload_job});
}

TEST(IdempotencyRule, ReplaysRefusesOrGoesOn) {
  const api::IdempotencyKey key{"k", "f1"};
  int asked = 0;
  const auto find = [&](const std::string& id) -> std::optional<api::JobInfo> {
    ++asked;
    if (id != "job_1") return std::nullopt;
    api::JobInfo job;
    job.id = id;
    return job;
  };
  // No live record: go on and create.
  EXPECT_FALSE(answer_from_key<SubmitOutcome>(std::nullopt, key, find));
  // Another body: refused, whether or not the earlier job exists, and it is not looked for.
  for (const char* earlier : {"job_1", "job_gone"}) {
    const auto refused = answer_from_key<SubmitOutcome>(KeyRecord{"f2", earlier}, key, find);
    ASSERT_TRUE(refused);
    EXPECT_EQ(refused->status, SubmitStatus::key_reused);
    EXPECT_TRUE(refused->job.id.empty());
  }
  EXPECT_EQ(asked, 0);
  // The same body: the earlier job again.
  const auto replayed = answer_from_key<SubmitOutcome>(KeyRecord{"f1", "job_1"}, key, find);
  ASSERT_TRUE(replayed);
  EXPECT_EQ(replayed->status, SubmitStatus::replayed);
  EXPECT_EQ(replayed->job.id, "job_1");
  // The same body, its job gone: go on (the new job takes the key over).
  EXPECT_FALSE(answer_from_key<SubmitOutcome>(KeyRecord{"f1", "job_gone"}, key, find));
  EXPECT_EQ(asked, 2);
}

}  // namespace
}  // namespace manipid::server::store
