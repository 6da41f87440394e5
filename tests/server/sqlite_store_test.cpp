// sqlite_store_test.cpp — what only the SQLite backend does (the contract every backend keeps is
// store_contract_test.cpp): its schema version check, unusable files, waiting for another
// connection's write lock, and open_store() choosing it from a --db value.
#include "store/sqlite/connection.h"
#include "store/sqlite/schema.h"
#include "store/sqlite/store.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>
#include <thread>

namespace manipid::server::store {
namespace {

namespace fs = std::filesystem;

NewJob stored_identification_job() {
  NewJob job;
  job.kind = api::JobKind::identification;
  job.request = R"({"upload_id":"ds_x"})";
  job.dataset_id = "ds_0123456789abcdef";
  return job;
}

/// Breaks the b-tree page header of `table`'s root page (a cell count of 65535 on a 4 KiB page) as a
/// bad disk or a torn copy would, leaving page 1 intact so the file still opens.
void damage_table(const std::string& path, const std::string& table) {
  sqlite3* database = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &database), SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(database, "SELECT rootpage, (SELECT page_size FROM pragma_page_size) FROM sqlite_master "
                                         "WHERE name = ?1",
                               -1, &statement, nullptr),
            SQLITE_OK);
  sqlite3_bind_text(statement, 1, table.c_str(), -1, SQLITE_TRANSIENT);
  ASSERT_EQ(sqlite3_step(statement), SQLITE_ROW);
  const long page = sqlite3_column_int64(statement, 0);
  const long page_size = sqlite3_column_int64(statement, 1);
  sqlite3_finalize(statement);
  sqlite3_close(database);
  ASSERT_GT(page, 1);
  std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
  file.seekp((page - 1) * page_size + 3);  // bytes 3-4 of a b-tree page header: its cell count
  const char cells[2] = {'\xff', '\xff'};
  file.write(cells, 2);
  ASSERT_TRUE(file.good());
}

class SqliteStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "manipid-sqlite-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    directory_ = pattern;
    path_ = (directory_ / "manipid.db").string();
    store_ = sqlite::open_store(path_);
  }

  void TearDown() override {
    store_.reset();  // close every connection before the files go
    fs::remove_all(directory_);
  }

  fs::path directory_;
  std::string path_;
  std::unique_ptr<Store> store_;
};

TEST_F(SqliteStoreTest, DatabaseFromNewerVersionIsRefused) {
  store_.reset();
  sqlite3* database = nullptr;
  ASSERT_EQ(sqlite3_open(path_.c_str(), &database), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(database, "PRAGMA user_version = 99", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(database);
  try {
    sqlite::open_store(path_);
    ADD_FAILURE() << "expected StoreError";
  } catch (const StoreError& error) {
    EXPECT_NE(std::string(error.what()).find("newer"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("99"), std::string::npos) << error.what();
  }
}

TEST_F(SqliteStoreTest, UnusableFilesThrowStoreError) {
  EXPECT_THROW(sqlite::open_store((directory_ / "missing-dir" / "x.db").string()), StoreError);
  const auto garbage = directory_ / "garbage.db";
  {
    std::FILE* file = std::fopen(garbage.c_str(), "wb");
    ASSERT_NE(file, nullptr);
    for (int i = 0; i < 4096; ++i) std::fputc('x', file);
    std::fclose(file);
  }
  EXPECT_THROW(sqlite::open_store(garbage.string()), StoreError);
}

TEST_F(SqliteStoreTest, WriterWaitsForAnotherConnectionsLockInsteadOfFailing) {
  // Another connection (as another process would) holds the write lock for a while.
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open(path_.c_str(), &other), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(other, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr), SQLITE_OK);
  std::thread release([other] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    sqlite3_exec(other, "COMMIT", nullptr, nullptr, nullptr);
  });
  const auto start = std::chrono::steady_clock::now();
  SubmitOutcome outcome;
  EXPECT_NO_THROW(outcome = store_->submit_job(stored_identification_job(), std::nullopt, 0));
  const auto waited = std::chrono::steady_clock::now() - start;
  release.join();
  sqlite3_close(other);
  EXPECT_EQ(outcome.status, SubmitStatus::created);
  EXPECT_GE(waited, std::chrono::milliseconds(250));
  // Readers are not blocked by a writer in WAL mode.
  EXPECT_TRUE(store_->find_job(api::all_owners, outcome.job.id));
}

TEST_F(SqliteStoreTest, ADamagedPageIsFoundAtOpenNotByAFailingReadLater) {
  for (int i = 0; i < 5; ++i) store_->submit_job(stored_identification_job(), std::nullopt, 0);
  store_.reset();  // the last connection checkpoints the WAL into the file
  damage_table(path_, "jobs");
  try {
    sqlite::open_store(path_);
    ADD_FAILURE() << "expected StoreError";
  } catch (const StoreError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("the database file is damaged (PRAGMA quick_check: "), std::string::npos) << message;
    EXPECT_NE(message.find("manipid doctor --db FILE"), std::string::npos) << message;
  }
}

TEST_F(SqliteStoreTest, CheckFileSaysWhatIsWrongAndChangesNothing) {
  store_->submit_job(stored_identification_job(), std::nullopt, 0);
  store_.reset();
  const sqlite::FileCheck sound = sqlite::check_file(path_);
  EXPECT_TRUE(sound.findings.empty());
  EXPECT_EQ(sound.schema_version, sqlite::current_schema_version());

  damage_table(path_, "jobs");
  const auto size = fs::file_size(path_);
  const sqlite::FileCheck damaged = sqlite::check_file(path_);
  ASSERT_FALSE(damaged.findings.empty());
  EXPECT_EQ(damaged.findings.front().rfind("Page ", 0), 0u) << damaged.findings.front();
  EXPECT_EQ(fs::file_size(path_), size);
  EXPECT_FALSE(fs::exists(path_ + "-wal") && fs::file_size(path_ + "-wal") > 0);

  EXPECT_THROW(sqlite::check_file((directory_ / "missing.db").string()), StoreError);
  EXPECT_FALSE(fs::exists(directory_ / "missing.db"));  // not created by looking
}

TEST_F(SqliteStoreTest, OpenStoreReadsTheDbValue) {
  // A plain path and sqlite:PATH name the same file: a job stored through one is seen by the other.
  const auto id = store_->submit_job(stored_identification_job(), std::nullopt, 0).job.id;
  EXPECT_TRUE(open_store(path_)->find_job(api::all_owners, id));
  EXPECT_TRUE(open_store("sqlite:" + path_)->find_job(api::all_owners, id));
  try {
    open_store("postgresql://lab@db.example/manipid");
    ADD_FAILURE() << "expected StoreError";
  } catch (const StoreError& error) {
    EXPECT_NE(std::string(error.what()).find("PostgreSQL"), std::string::npos) << error.what();
  }
  EXPECT_THROW(open_store("sqlite:"), StoreError);
  EXPECT_THROW(open_store(""), StoreError);
}

TEST(StoreUrl, DisplayNameShowsNoPassword) {
  EXPECT_EQ(display_name("/var/lib/manipid/jobs.db"), "/var/lib/manipid/jobs.db");
  EXPECT_EQ(display_name("sqlite:jobs.db"), "sqlite:jobs.db");
  EXPECT_EQ(display_name("postgresql://lab@db.example/manipid"), "postgresql://lab@db.example/manipid");
  EXPECT_EQ(display_name("postgresql://lab:s3cret@db.example:5433/manipid"), "postgresql://lab@db.example:5433/manipid");
  EXPECT_EQ(display_name("postgres://lab:s3cret@db.example"), "postgres://lab@db.example");
  EXPECT_EQ(display_name("postgresql:///manipid?host=/tmp/pg&user=lab&password=s3cret"),
            "postgresql:///manipid?host=/tmp/pg&user=lab");
  EXPECT_EQ(display_name("postgresql:///manipid?password=s3cret&host=/tmp/pg"), "postgresql:///manipid?host=/tmp/pg");
  EXPECT_EQ(display_name("postgresql://lab:a@db/manipid?password=b"), "postgresql://lab@db/manipid");
  // A ':' after the '@' is a port, not a password.
  EXPECT_EQ(display_name("postgresql://db.example:5432/manipid"), "postgresql://db.example:5432/manipid");
}

/// SQLite out of memory (its hard heap limit reached) is std::bad_alloc, which the routes answer 503
/// MEMORY_BUSY and the job runner "out of memory" — not a storage fault answered 500 — and nothing of the
/// write is left behind: the store takes the same write once memory is back.
TEST_F(SqliteStoreTest, OutOfMemoryIsBadAllocAndLeavesNothingHalfWritten) {
  Trajectory data;
  data.t = Eigen::VectorXd::LinSpaced(200000, 0.0, 199.999);
  data.q = Eigen::MatrixXd::Random(200000, 4);
  data.tau = Eigen::MatrixXd::Random(200000, 4);
  struct Unlimited {
    ~Unlimited() { sqlite3_hard_heap_limit64(0); }
  } restore;
  sqlite3_hard_heap_limit64(sqlite3_memory_used() + (256 << 10));
  EXPECT_THROW(store_->insert_dataset("", "too large for the heap", data, "", std::nullopt), std::bad_alloc);
  sqlite3_hard_heap_limit64(0);
  EXPECT_EQ(store_->list_datasets(api::all_owners, {}).items.size(), 0u);
  const DatasetOutcome stored = store_->insert_dataset("", "once memory is back", data, "", std::nullopt);
  EXPECT_EQ(stored.dataset.samples, 200000);
  EXPECT_EQ(store_->list_datasets(api::all_owners, {}).items.size(), 1u);
}

TEST_F(SqliteStoreTest, OnlyAWriteThatChangedRowsClearsAFullDisk) {
  // A file capped at its current size (PRAGMA max_page_count) fails as a full disk does
  // (SQLITE_FULL). An idle worker's claim that finds nothing commits an empty write
  // transaction, a lease's heartbeat a few bytes in place: neither proves anything about the
  // space, and both must leave /healthz degraded.
  WriteHealth health;
  sqlite::Connection connection(path_);
  connection.attach(&health);
  connection.execute("CREATE TABLE filler (bytes BLOB)");
  const std::int64_t pages = [&] {
    sqlite3_stmt* statement = nullptr;
    sqlite3_prepare_v2(connection.handle(), "PRAGMA page_count", -1, &statement, nullptr);
    sqlite3_step(statement);
    const auto count = sqlite3_column_int64(statement, 0);
    sqlite3_finalize(statement);
    return count;
  }();
  connection.execute(("PRAGMA max_page_count = " + std::to_string(pages)).c_str());
  const auto insert_blob = [&](int bytes) { connection.execute(("INSERT INTO filler VALUES (zeroblob(" + std::to_string(bytes) + "))").c_str()); };
  EXPECT_THROW(sqlite::run_transaction(connection, sqlite::TransactionKind::write, [&] { insert_blob(1 << 20); }),
               StorageFull);
  ASSERT_TRUE(health.trouble().has_value());
  sqlite::run_transaction(connection, sqlite::TransactionKind::write, [&] {
    connection.execute("UPDATE filler SET bytes = NULL WHERE 0");
  });
  EXPECT_TRUE(health.trouble().has_value()) << "a commit that changed nothing cleared the trouble";
  // A lease's heartbeat changes a few bytes in place: it fits, and proves nothing about room.
  sqlite::run_transaction(connection, sqlite::TransactionKind::write_in_place,
                          [&] { connection.execute("INSERT INTO filler VALUES (x'00')"); });
  EXPECT_TRUE(health.trouble().has_value()) << "an in-place write cleared the trouble";
  sqlite::run_transaction(connection, sqlite::TransactionKind::read, [&] {});
  EXPECT_TRUE(health.trouble().has_value());
  connection.execute("PRAGMA max_page_count = 1000000");
  sqlite::run_transaction(connection, sqlite::TransactionKind::write, [&] { insert_blob(1 << 20); });
  EXPECT_FALSE(health.trouble().has_value());
}

}  // namespace
}  // namespace manipid::server::store
