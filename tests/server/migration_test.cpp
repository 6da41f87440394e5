// migration_test.cpp — a database written by the last release (manipid 0.1.0, schema version 1) opens
// with today's schema and keeps every job, dataset, history, estimate and idempotency key; its rows
// belong to no owner (the admin's to see, no named token's). And a version 5 database's robot
// identifications (identification jobs that name a robot) read as robot_identification after 5 → 6, and a
// version 6 database keeps its rows through 6 → 7 and takes payload_identification jobs after it.
//
// tests/server/data/manipid-0.1.0.db was made by that release's own binary
// (tests/server/data/make_release_0.1.0_db.sh); this test reads the file's rows with plain SQL first, opens a
// copy with today's store (which migrates it), and compares.
#include "store/sqlite/schema.h"
#include "store/sqlite/store.h"

#include <gtest/gtest.h>

#include <chrono>
#include <sqlite3.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace manipid::server::store {
namespace {

namespace fs = std::filesystem;

/// Rows of a query on a database file, each row's columns as text ("" for NULL).
std::vector<std::vector<std::string>> query(const std::string& path, const std::string& sql) {
  sqlite3* database = nullptr;
  EXPECT_EQ(sqlite3_open_v2(path.c_str(), &database, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(database, sql.c_str(), -1, &statement, nullptr), SQLITE_OK) << sql;
  std::vector<std::vector<std::string>> rows;
  while (sqlite3_step(statement) == SQLITE_ROW) {
    std::vector<std::string> row;
    for (int c = 0; c < sqlite3_column_count(statement); ++c) {
      const auto* text = sqlite3_column_text(statement, c);
      row.emplace_back(text ? reinterpret_cast<const char*>(text) : "");
    }
    rows.push_back(row);
  }
  sqlite3_finalize(statement);
  sqlite3_close(database);
  return rows;
}

class ReleaseDatabase : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "manipid-migration-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    directory_ = pattern;
    path_ = (directory_ / "manipid.db").string();
    fs::copy_file(fs::path(MANIPID_SOURCE_DIR) / "tests/server/data/manipid-0.1.0.db", path_);
  }
  void TearDown() override { fs::remove_all(directory_); }

  fs::path directory_;
  std::string path_;
};

TEST_F(ReleaseDatabase, OpensMigratedWithEveryRowKept) {
  ASSERT_EQ(query(path_, "PRAGMA user_version")[0][0], "1");
  const auto jobs_before = query(path_, "SELECT id, kind, state, request, dataset_id, result, evaluations, attempts FROM jobs ORDER BY seq");
  const auto history_before = query(path_, "SELECT job_id, idx, cost, hex(theta) FROM job_history ORDER BY job_id, idx");
  const auto estimates_before = query(path_, "SELECT job_id, name, value, std_error FROM estimates ORDER BY job_id, name");
  const auto datasets_before = query(path_, "SELECT id, name, samples, joints, dt, hex(t), hex(q), hex(tau) FROM datasets ORDER BY seq");
  ASSERT_EQ(jobs_before.size(), 4u);
  ASSERT_EQ(datasets_before.size(), 2u);
  ASSERT_GT(history_before.size(), 200u);

  {
    // The release's rows are days old: keys live long enough here for its key to be checked.
    const auto store = sqlite::open_store(path_, {.idempotency_ttl = std::chrono::hours(24 * 365 * 20)});
    for (const auto& row : jobs_before) {
      const auto job = store->find_job(api::all_owners, row[0]);
      ASSERT_TRUE(job) << row[0];
      EXPECT_EQ(api::to_string(job->kind), row[1]);
      EXPECT_EQ(api::to_string(job->state), row[2]);
      EXPECT_EQ(job->request, row[3]);
      EXPECT_EQ(job->dataset_id, row[4]);
      EXPECT_EQ(job->result, row[5]);
      EXPECT_EQ(job->evaluations, std::stol(row[6]));
      EXPECT_EQ(job->attempts, std::stoi(row[7]));
      EXPECT_EQ(job->robot_id, "");
    }
    for (const auto& row : datasets_before) {
      const auto dataset = store->find_dataset(api::all_owners, row[0]);
      ASSERT_TRUE(dataset) << row[0];
      EXPECT_EQ(dataset->name, row[1]);
      EXPECT_EQ(dataset->samples, std::stoi(row[2]));
      EXPECT_TRUE(dataset->uniform);
      EXPECT_FALSE(dataset->has_rates);
      const auto data = store->load_dataset(api::all_owners, row[0]);
      ASSERT_TRUE(data);
      EXPECT_EQ(data->joint_count(), std::stoi(row[3]));
      EXPECT_EQ(data->qd.cols(), 0);
    }
    // The succeeded identification's history is whole, in order, as stored.
    const std::string identified = jobs_before[0][0];
    const auto page = store->history(api::all_owners, identified, {1000, ""});
    ASSERT_TRUE(page);
    EXPECT_EQ(static_cast<long>(page->items.size()), store->find_job(api::all_owners, identified)->evaluations);
    // The release's idempotency key still replays its job (within the key lifetime).
    const auto key_rows = query(path_, "SELECT key, fingerprint, resource_id FROM idempotency_keys WHERE scope = 'job'");
    ASSERT_EQ(key_rows.size(), 1u);
    const SubmitOutcome replay = store->submit_job({api::JobKind::identification, "{}", "", "", "", ""},
                                                  api::IdempotencyKey{key_rows[0][0], key_rows[0][1]}, 0);
    EXPECT_EQ(replay.status, SubmitStatus::replayed);
    EXPECT_EQ(replay.job.id, key_rows[0][2]);
    // The release's rows belong to no one: the admin's (all owners) to see, no named owner's.
    EXPECT_EQ(store->find_job(api::all_owners, jobs_before[0][0])->owner, "");
    EXPECT_EQ(store->find_dataset(api::all_owners, datasets_before[0][0])->owner, "");
    EXPECT_EQ(store->list_jobs(api::all_owners, {}, {}).items.size(), jobs_before.size());
    EXPECT_EQ(store->list_datasets(api::all_owners, {}).items.size(), datasets_before.size());
    EXPECT_FALSE(store->find_job(api::OwnerScope("alice"), jobs_before[0][0]));
    EXPECT_TRUE(store->list_jobs(api::OwnerScope("alice"), {}, {}).items.empty());
    EXPECT_TRUE(store->list_datasets(api::OwnerScope("alice"), {}).items.empty());
    NewJob alices{api::JobKind::identification, "{}", "", "", "", "alice"};
    EXPECT_EQ(store->submit_job(alices, api::IdempotencyKey{key_rows[0][0], key_rows[0][1]}, 0).status,
              SubmitStatus::created);  // the release's key is no one's: alice's same key is hers
    // And today's rows go in beside them.
    const RobotOutcome robot = store->insert_robot({"arm", "<robot name=\"arm\"/>", "", "", 2, "{}", ""}, std::nullopt);
    EXPECT_EQ(robot.status, SubmitStatus::created);
    NewJob job{api::JobKind::excitation, "{}", "", robot.robot.id, "", ""};
    EXPECT_EQ(store->submit_job(job, std::nullopt, 0).job.kind, api::JobKind::excitation);
  }

  EXPECT_EQ(query(path_, "PRAGMA user_version")[0][0], std::to_string(sqlite::current_schema_version()));
  EXPECT_EQ(query(path_, "PRAGMA integrity_check")[0][0], "ok");
  EXPECT_TRUE(query(path_, "PRAGMA foreign_key_check").empty());
  EXPECT_EQ(query(path_, "SELECT job_id, idx, cost, hex(theta) FROM job_history ORDER BY job_id, idx"), history_before);
  EXPECT_EQ(query(path_, "SELECT job_id, name, value, std_error FROM estimates ORDER BY job_id, name"), estimates_before);
  EXPECT_EQ(query(path_, "SELECT id, name, samples, joints, dt, hex(t), hex(q), hex(tau) FROM datasets ORDER BY seq LIMIT 2"),
            datasets_before);
}

/// Runs SQL on a database file (the rows a test puts in a database of an older schema).
void execute_sql(const std::string& path, const std::string& sql) {
  sqlite3* database = nullptr;
  ASSERT_EQ(sqlite3_open_v2(path.c_str(), &database, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
  char* message = nullptr;
  EXPECT_EQ(sqlite3_exec(database, sql.c_str(), nullptr, nullptr, &message), SQLITE_OK) << (message ? message : "");
  sqlite3_free(message);
  sqlite3_close(database);
}

std::set<std::string> job_ids(const api::Page<api::JobInfo>& page) {
  std::set<std::string> ids;
  for (const api::JobInfo& job : page.items) ids.insert(job.id);
  return ids;
}

TEST_F(ReleaseDatabase, VersionFiveRobotIdentificationsBecomeTheirOwnKind) {
  const std::string path = (directory_ / "version5.db").string();
  {
    sqlite::Connection connection(path);
    sqlite::prepare_database(connection, 5);
  }
  ASSERT_EQ(query(path, "PRAGMA user_version")[0][0], "5");
  const std::string at = "2026-01-01T00:00:00.000Z";
  execute_sql(path,
              "INSERT INTO robots (id, name, created_at, joints, summary, urdf) VALUES ('rb_1', 'arm', '" + at +
                  "', 2, '{}', '<robot name=\"arm\"/>');"
                  "INSERT INTO jobs (id, kind, state, request, dataset_id, robot_id, validation_dataset_id, created_at, "
                  "result, owner) VALUES "
                  "('job_paper', 'identification', 'succeeded', '{\"dataset_id\": \"ds_1\"}', 'ds_1', NULL, NULL, '" +
                  at + "', '{\"point\": {}}', ''),"
                  "('job_robot', 'identification', 'succeeded', '{\"robot_id\": \"rb_1\"}', 'ds_1', 'rb_1', 'ds_2', '" +
                  at + "', '{\"base_parameters\": []}', 'alice'),"
                  "('job_waiting', 'identification', 'queued', '{\"robot_id\": \"rb_1\"}', 'ds_1', 'rb_1', NULL, '" + at +
                  "', NULL, ''),"
                  "('job_design', 'excitation', 'succeeded', '{\"robot_id\": \"rb_1\"}', 'ds_3', 'rb_1', NULL, '" + at +
                  "', '{}', ''),"
                  "('job_gone', 'simulation', 'succeeded', '{}', NULL, NULL, NULL, '" + at + "', NULL, '');"
                  "INSERT INTO estimates (job_id, name, value, std_error) VALUES ('job_robot', 'm1', 1.5, 0.1);"
                  "DELETE FROM jobs WHERE id = 'job_gone';");
  const auto jobs_before = query(path, "SELECT seq, id, state, request, dataset_id, robot_id, validation_dataset_id, "
                                       "created_at, result, owner FROM jobs ORDER BY seq");
  const auto estimates_before = query(path, "SELECT job_id, name, value, std_error FROM estimates ORDER BY job_id, name");
  const long highest_seq = std::stol(query(path, "SELECT seq FROM sqlite_sequence WHERE name = 'jobs'")[0][0]);

  {
    const auto store = sqlite::open_store(path);
    const std::map<std::string, api::JobKind> kinds = {{"job_paper", api::JobKind::identification},
                                                       {"job_robot", api::JobKind::robot_identification},
                                                       {"job_waiting", api::JobKind::robot_identification},
                                                       {"job_design", api::JobKind::excitation}};
    for (const auto& [id, kind] : kinds) {
      const auto job = store->find_job(api::all_owners, id);
      ASSERT_TRUE(job) << id;
      EXPECT_EQ(job->kind, kind) << id;
    }
    api::JobFilter robots;
    robots.kind = api::JobKind::robot_identification;
    EXPECT_EQ(job_ids(store->list_jobs(api::all_owners, robots, {})), (std::set<std::string>{"job_robot", "job_waiting"}));
    api::JobFilter papers;
    papers.kind = api::JobKind::identification;
    EXPECT_EQ(job_ids(store->list_jobs(api::all_owners, papers, {})), std::set<std::string>{"job_paper"});
    EXPECT_EQ(job_ids(store->list_jobs(api::OwnerScope("alice"), robots, {})), std::set<std::string>{"job_robot"});
    // The queued one runs as its kind: a worker claims it as robot_identification.
    const auto claimed = store->claim_next_job("test:1", std::chrono::seconds(30));
    ASSERT_TRUE(claimed);
    EXPECT_EQ(claimed->id, "job_waiting");
    EXPECT_EQ(claimed->kind, api::JobKind::robot_identification);
    // The AUTOINCREMENT counter came along: a new job never takes the deleted one's seq.
    const std::string added = store->submit_job({api::JobKind::robot_identification, "{}", "", "rb_1", "", ""}, std::nullopt, 0).job.id;
    EXPECT_GT(std::stol(query(path, "SELECT seq FROM jobs WHERE id = '" + added + "'")[0][0]), highest_seq);
  }

  EXPECT_EQ(query(path, "PRAGMA user_version")[0][0], std::to_string(sqlite::current_schema_version()));
  EXPECT_EQ(query(path, "PRAGMA integrity_check")[0][0], "ok");
  EXPECT_TRUE(query(path, "PRAGMA foreign_key_check").empty());
  auto jobs_after = query(path, "SELECT seq, id, state, request, dataset_id, robot_id, validation_dataset_id, created_at, "
                                "result, owner FROM jobs ORDER BY seq");
  jobs_after.pop_back();  // the job added above
  for (auto& row : jobs_after) {
    if (row[1] == "job_waiting") row[2] = "queued";  // claimed above
  }
  EXPECT_EQ(jobs_after, jobs_before);
  EXPECT_EQ(query(path, "SELECT job_id, name, value, std_error FROM estimates ORDER BY job_id, name"), estimates_before);
  EXPECT_EQ(query(path, "SELECT name FROM sqlite_master WHERE type = 'index' AND tbl_name = 'jobs' AND sql IS NOT NULL "
                        "ORDER BY name"),
            (std::vector<std::vector<std::string>>{
                {"jobs_by_kind"}, {"jobs_by_lease"}, {"jobs_by_owner"}, {"jobs_by_robot"}, {"jobs_by_state"}}));
  // The two migrated and the one added.
  EXPECT_EQ(query(path, "SELECT count(*) FROM jobs WHERE kind = 'robot_identification'")[0][0], "3");
}

TEST_F(ReleaseDatabase, VersionSixKeepsItsRowsAndTakesPayloadIdentifications) {
  const std::string path = (directory_ / "version6.db").string();
  {
    sqlite::Connection connection(path);
    sqlite::prepare_database(connection, 6);
  }
  ASSERT_EQ(query(path, "PRAGMA user_version")[0][0], "6");
  const std::string at = "2026-01-01T00:00:00.000Z";
  execute_sql(path,
              "INSERT INTO robots (id, name, created_at, joints, summary, urdf) VALUES ('rb_1', 'arm', '" + at +
                  "', 2, '{}', '<robot name=\"arm\"/>');"
                  "INSERT INTO jobs (id, kind, state, request, dataset_id, robot_id, validation_dataset_id, created_at, "
                  "result, owner) VALUES "
                  "('job_arm', 'robot_identification', 'succeeded', '{\"robot_id\": \"rb_1\"}', 'ds_1', 'rb_1', 'ds_2', '" +
                  at + "', '{\"point\": {}}', 'alice'),"
                  "('job_waiting', 'robot_identification', 'queued', '{\"robot_id\": \"rb_1\"}', 'ds_1', 'rb_1', NULL, '" +
                  at + "', NULL, ''),"
                  "('job_gone', 'simulation', 'succeeded', '{}', NULL, NULL, NULL, '" + at + "', NULL, '');"
                  "INSERT INTO estimates (job_id, name, value, std_error) VALUES ('job_arm', 'm1', 1.5, 0.1);"
                  "DELETE FROM jobs WHERE id = 'job_gone';");
  // Before the migration the CHECK refuses the new kind.
  {
    sqlite3* database = nullptr;
    ASSERT_EQ(sqlite3_open_v2(path.c_str(), &database, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
    EXPECT_NE(sqlite3_exec(database,
                           ("INSERT INTO jobs (id, kind, state, request, created_at) VALUES ('job_early', "
                            "'payload_identification', 'queued', '{}', '" + at + "')").c_str(),
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(database);
  }
  const std::string columns = "SELECT seq, id, kind, state, request, dataset_id, robot_id, validation_dataset_id, created_at, "
                              "result, owner FROM jobs ORDER BY seq";
  const auto jobs_before = query(path, columns);
  const auto estimates_before = query(path, "SELECT job_id, name, value, std_error FROM estimates ORDER BY job_id, name");
  const long highest_seq = std::stol(query(path, "SELECT seq FROM sqlite_sequence WHERE name = 'jobs'")[0][0]);

  std::string added;
  {
    const auto store = sqlite::open_store(path);
    EXPECT_EQ(store->find_job(api::all_owners, "job_arm")->kind, api::JobKind::robot_identification);
    added = store->submit_job({api::JobKind::payload_identification, "{\"payload\": true}", "ds_3", "rb_1", "", "alice"},
                              std::nullopt, 0)
                .job.id;
    const auto job = store->find_job(api::all_owners, added);
    ASSERT_TRUE(job);
    EXPECT_EQ(job->kind, api::JobKind::payload_identification);
    api::JobFilter payloads;
    payloads.kind = api::JobKind::payload_identification;
    payloads.robot_id = "rb_1";
    EXPECT_EQ(job_ids(store->list_jobs(api::OwnerScope("alice"), payloads, {})), std::set<std::string>{added});
    // The queued job from before is claimed first, as its kind; then the payload identification.
    const auto first = store->claim_next_job("test:1", std::chrono::seconds(30));
    ASSERT_TRUE(first);
    EXPECT_EQ(first->id, "job_waiting");
    const auto second = store->claim_next_job("test:1", std::chrono::seconds(30));
    ASSERT_TRUE(second);
    EXPECT_EQ(second->id, added);
    EXPECT_EQ(second->kind, api::JobKind::payload_identification);
  }

  EXPECT_EQ(query(path, "PRAGMA user_version")[0][0], std::to_string(sqlite::current_schema_version()));
  EXPECT_EQ(query(path, "PRAGMA integrity_check")[0][0], "ok");
  EXPECT_TRUE(query(path, "PRAGMA foreign_key_check").empty());
  auto jobs_after = query(path, columns);
  ASSERT_EQ(jobs_after.size(), jobs_before.size() + 1);
  EXPECT_GT(std::stol(jobs_after.back()[0]), highest_seq);  // the AUTOINCREMENT counter came along
  jobs_after.pop_back();
  for (auto& row : jobs_after) {
    if (row[1] == "job_waiting") row[3] = "queued";  // claimed above
  }
  EXPECT_EQ(jobs_after, jobs_before);
  EXPECT_EQ(query(path, "SELECT job_id, name, value, std_error FROM estimates ORDER BY job_id, name"), estimates_before);
  EXPECT_EQ(query(path, "SELECT name FROM sqlite_master WHERE type = 'index' AND tbl_name = 'jobs' AND sql IS NOT NULL "
                        "ORDER BY name"),
            (std::vector<std::vector<std::string>>{
                {"jobs_by_kind"}, {"jobs_by_lease"}, {"jobs_by_owner"}, {"jobs_by_robot"}, {"jobs_by_state"}}));
}

}  // namespace
}  // namespace manipid::server::store
