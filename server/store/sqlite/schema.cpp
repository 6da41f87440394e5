// schema.cpp — the tables of the SQLite store and the migrations between versions.
// A migration is appended, never edited: databases in the field have run the old ones.
#include "store/sqlite/schema.h"

#include <algorithm>
#include <array>
#include <string>

namespace manipid::server::store::sqlite {

namespace {

// kMigrations[i] takes user_version i to i + 1, and sets it.
constexpr std::array<const char*, 7> kMigrations = {
    // 0 → 1: the first schema.
    R"sql(
    -- seq orders datasets newest first for keyset paging; AUTOINCREMENT never hands out a
    -- seq again, even after the newest row is deleted. The blobs come last so that reading
    -- the description (find/list) never touches their overflow pages.
    CREATE TABLE datasets (
      seq           INTEGER PRIMARY KEY AUTOINCREMENT,
      id            TEXT    NOT NULL UNIQUE,
      name          TEXT    NOT NULL,
      created_at    TEXT    NOT NULL,
      source_job    TEXT,
      joints        INTEGER NOT NULL,
      samples       INTEGER NOT NULL,
      dt            REAL    NOT NULL,
      has_torque    INTEGER NOT NULL,
      has_reference INTEGER NOT NULL,
      t   BLOB,   -- samples doubles, little-endian
      q   BLOB,   -- samples x joints, column-major
      tau BLOB,   -- NULL when has_torque = 0
      ref BLOB    -- NULL when has_reference = 0
    );

    -- dataset_id has no foreign key: a job's record outlives the datasets it used or made.
    CREATE TABLE jobs (
      seq              INTEGER PRIMARY KEY AUTOINCREMENT,
      id               TEXT    NOT NULL UNIQUE,
      kind             TEXT    NOT NULL CHECK (kind IN ('simulation', 'identification')),
      state            TEXT    NOT NULL
                       CHECK (state IN ('queued', 'running', 'succeeded', 'failed', 'cancelled')),
      request          TEXT    NOT NULL,
      dataset_id       TEXT,
      created_at       TEXT    NOT NULL,
      started_at       TEXT,
      finished_at      TEXT,
      evaluations      INTEGER NOT NULL DEFAULT 0,
      best_cost        REAL,
      cancel_requested INTEGER NOT NULL DEFAULT 0,
      attempts         INTEGER NOT NULL DEFAULT 0,
      result           TEXT,
      error            TEXT
    );
    CREATE INDEX jobs_by_state ON jobs (state, seq);  -- claim order, listing by state
    CREATE INDEX jobs_by_kind ON jobs (kind, seq);    -- listing by kind

    CREATE TABLE job_history (
      job_id TEXT    NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
      idx    INTEGER NOT NULL,
      cost   REAL,           -- NULL stands for NaN (SQLite stores NaN as NULL)
      theta  BLOB,           -- doubles, little-endian
      PRIMARY KEY (job_id, idx)
    ) WITHOUT ROWID;

    CREATE TABLE estimates (
      job_id    TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
      name      TEXT NOT NULL,
      value     REAL,
      std_error REAL,
      PRIMARY KEY (job_id, name)
    ) WITHOUT ROWID;

    CREATE TABLE idempotency_keys (
      scope       TEXT NOT NULL CHECK (scope IN ('job', 'dataset')),
      key         TEXT NOT NULL,
      fingerprint TEXT NOT NULL,
      resource_id TEXT NOT NULL,
      created_at  TEXT NOT NULL,
      PRIMARY KEY (scope, key)
    ) WITHOUT ROWID;
    CREATE INDEX idempotency_keys_by_resource ON idempotency_keys (resource_id);

    PRAGMA user_version = 1;
    )sql",

    // 1 → 2: how often a job's worker died while running it (start-up recovery counts), so a
    // job that crashes the process is failed after --max-attempts deaths instead of looping.
    R"sql(
    ALTER TABLE jobs ADD COLUMN worker_losses INTEGER NOT NULL DEFAULT 0;
    PRAGMA user_version = 2;
    )sql",

    // 2 → 3: robots (URDF documents), excitation jobs, jobs that name a robot and a validation
    // dataset, datasets as measured (jittery time stamps, joint rates). SQLite cannot change a CHECK
    // or insert a column before the blobs, so jobs, datasets and idempotency_keys are rebuilt: create
    // the new table, copy, drop the old, rename (the procedure of sqlite.org/lang_altertable.html §7;
    // prepare_database turns foreign keys off around it, or dropping jobs would delete every
    // history through ON DELETE CASCADE). Rows from before stay as they were: every dataset then
    // was uniform and had no rates.
    R"sql(
    CREATE TABLE robots (
      seq        INTEGER PRIMARY KEY AUTOINCREMENT,
      id         TEXT    NOT NULL UNIQUE,
      name       TEXT    NOT NULL,
      created_at TEXT    NOT NULL,
      base       TEXT,
      tip        TEXT,
      joints     INTEGER NOT NULL,
      summary    TEXT    NOT NULL,  -- the robot resource's description, JSON
      urdf       TEXT    NOT NULL   -- the document as uploaded, byte for byte; last, so lists never read it
    );

    CREATE TABLE jobs_v3 (
      seq                   INTEGER PRIMARY KEY AUTOINCREMENT,
      id                    TEXT    NOT NULL UNIQUE,
      kind                  TEXT    NOT NULL CHECK (kind IN ('simulation', 'identification', 'excitation')),
      state                 TEXT    NOT NULL
                            CHECK (state IN ('queued', 'running', 'succeeded', 'failed', 'cancelled')),
      request               TEXT    NOT NULL,
      dataset_id            TEXT,
      robot_id              TEXT,
      validation_dataset_id TEXT,
      created_at            TEXT    NOT NULL,
      started_at            TEXT,
      finished_at           TEXT,
      evaluations           INTEGER NOT NULL DEFAULT 0,
      best_cost             REAL,
      cancel_requested      INTEGER NOT NULL DEFAULT 0,
      attempts              INTEGER NOT NULL DEFAULT 0,
      worker_losses         INTEGER NOT NULL DEFAULT 0,
      result                TEXT,
      error                 TEXT
    );
    INSERT INTO jobs_v3 (seq, id, kind, state, request, dataset_id, created_at, started_at, finished_at, evaluations,
                         best_cost, cancel_requested, attempts, worker_losses, result, error)
      SELECT seq, id, kind, state, request, dataset_id, created_at, started_at, finished_at, evaluations,
             best_cost, cancel_requested, attempts, worker_losses, result, error FROM jobs;
    DROP TABLE jobs;
    ALTER TABLE jobs_v3 RENAME TO jobs;
    CREATE INDEX jobs_by_state ON jobs (state, seq);
    CREATE INDEX jobs_by_kind ON jobs (kind, seq);
    CREATE INDEX jobs_by_robot ON jobs (robot_id) WHERE robot_id IS NOT NULL;

    CREATE TABLE datasets_v3 (
      seq           INTEGER PRIMARY KEY AUTOINCREMENT,
      id            TEXT    NOT NULL UNIQUE,
      name          TEXT    NOT NULL,
      created_at    TEXT    NOT NULL,
      source_job    TEXT,
      joints        INTEGER NOT NULL,
      samples       INTEGER NOT NULL,
      dt            REAL    NOT NULL,  -- the period (uniform) or the median step (jittery)
      uniform       INTEGER NOT NULL,
      has_torque    INTEGER NOT NULL,
      has_reference INTEGER NOT NULL,
      has_rates     INTEGER NOT NULL,
      has_accelerations INTEGER NOT NULL,
      t   BLOB,   -- samples doubles, little-endian
      q   BLOB,   -- samples x joints, column-major
      tau BLOB,   -- NULL when has_torque = 0
      ref BLOB,   -- NULL when has_reference = 0
      qd  BLOB,   -- NULL when has_rates = 0
      qdd BLOB    -- NULL when has_accelerations = 0
    );
    INSERT INTO datasets_v3 (seq, id, name, created_at, source_job, joints, samples, dt, uniform, has_torque,
                             has_reference, has_rates, has_accelerations, t, q, tau, ref, qd, qdd)
      SELECT seq, id, name, created_at, source_job, joints, samples, dt, 1, has_torque, has_reference, 0, 0, t, q,
             tau, ref, NULL, NULL FROM datasets;
    DROP TABLE datasets;
    ALTER TABLE datasets_v3 RENAME TO datasets;

    CREATE TABLE idempotency_keys_v3 (
      scope       TEXT NOT NULL CHECK (scope IN ('job', 'dataset', 'robot')),
      key         TEXT NOT NULL,
      fingerprint TEXT NOT NULL,
      resource_id TEXT NOT NULL,
      created_at  TEXT NOT NULL,
      PRIMARY KEY (scope, key)
    ) WITHOUT ROWID;
    INSERT INTO idempotency_keys_v3 SELECT scope, key, fingerprint, resource_id, created_at FROM idempotency_keys;
    DROP TABLE idempotency_keys;
    ALTER TABLE idempotency_keys_v3 RENAME TO idempotency_keys;
    CREATE INDEX idempotency_keys_by_resource ON idempotency_keys (resource_id);

    PRAGMA user_version = 3;
    )sql",

    // 3 → 4: leases, and keys that expire. A claim names its owner ("HOST:PID") and when the lease ends (Unix seconds,
    // the database's clock); every write of a running job checks owner and attempt, and any
    // process recovers the running jobs whose lease has ended. Jobs running in the old file have no
    // lease: start-up recovery (the only way they could be running) puts them back in the queue.
    R"sql(
    ALTER TABLE jobs ADD COLUMN worker TEXT;
    ALTER TABLE jobs ADD COLUMN lease_expires_at REAL;
    CREATE INDEX jobs_by_lease ON jobs (lease_expires_at) WHERE state = 'running';
    -- Keys expire (StoreOptions::idempotency_ttl): the old ones are found, and forgotten, by age.
    CREATE INDEX idempotency_keys_by_age ON idempotency_keys (created_at);
    PRAGMA user_version = 4;
    )sql",

    // 4 → 5: owners (`manipid serve --token-file`). Every dataset, robot and job belongs to the name
    // of the token that made it; the rows from before belong to no one (''), which admin tokens and
    // servers without named tokens see. datasets and robots are rebuilt so that owner comes before
    // their blobs and documents (a column after them is read through their overflow pages, on every
    // list); their AUTOINCREMENT counter is carried over, so a seq is still never handed out twice.
    // jobs has no such column: owner is appended. An Idempotency-Key is its owner's: the primary key
    // takes the owner in (SQLite cannot change a primary key: rebuilt too).
    R"sql(
    CREATE TABLE datasets_v5 (
      seq           INTEGER PRIMARY KEY AUTOINCREMENT,
      id            TEXT    NOT NULL UNIQUE,
      name          TEXT    NOT NULL,
      created_at    TEXT    NOT NULL,
      source_job    TEXT,
      joints        INTEGER NOT NULL,
      samples       INTEGER NOT NULL,
      dt            REAL    NOT NULL,  -- the period (uniform) or the median step (jittery)
      uniform       INTEGER NOT NULL,
      has_torque    INTEGER NOT NULL,
      has_reference INTEGER NOT NULL,
      has_rates     INTEGER NOT NULL,
      has_accelerations INTEGER NOT NULL,
      owner         TEXT    NOT NULL DEFAULT '',
      t   BLOB,   -- samples doubles, little-endian
      q   BLOB,   -- samples x joints, column-major
      tau BLOB,   -- NULL when has_torque = 0
      ref BLOB,   -- NULL when has_reference = 0
      qd  BLOB,   -- NULL when has_rates = 0
      qdd BLOB    -- NULL when has_accelerations = 0
    );
    INSERT INTO datasets_v5 (seq, id, name, created_at, source_job, joints, samples, dt, uniform, has_torque,
                             has_reference, has_rates, has_accelerations, owner, t, q, tau, ref, qd, qdd)
      SELECT seq, id, name, created_at, source_job, joints, samples, dt, uniform, has_torque, has_reference,
             has_rates, has_accelerations, '', t, q, tau, ref, qd, qdd FROM datasets;
    DELETE FROM sqlite_sequence WHERE name = 'datasets_v5';
    INSERT INTO sqlite_sequence (name, seq) SELECT 'datasets_v5', seq FROM sqlite_sequence WHERE name = 'datasets';
    DROP TABLE datasets;
    ALTER TABLE datasets_v5 RENAME TO datasets;
    CREATE INDEX datasets_by_owner ON datasets (owner, seq);

    CREATE TABLE robots_v5 (
      seq        INTEGER PRIMARY KEY AUTOINCREMENT,
      id         TEXT    NOT NULL UNIQUE,
      name       TEXT    NOT NULL,
      created_at TEXT    NOT NULL,
      base       TEXT,
      tip        TEXT,
      joints     INTEGER NOT NULL,
      summary    TEXT    NOT NULL,  -- the robot resource's description, JSON
      owner      TEXT    NOT NULL DEFAULT '',
      urdf       TEXT    NOT NULL   -- the document as uploaded, byte for byte; last, so lists never read it
    );
    INSERT INTO robots_v5 (seq, id, name, created_at, base, tip, joints, summary, owner, urdf)
      SELECT seq, id, name, created_at, base, tip, joints, summary, '', urdf FROM robots;
    DELETE FROM sqlite_sequence WHERE name = 'robots_v5';
    INSERT INTO sqlite_sequence (name, seq) SELECT 'robots_v5', seq FROM sqlite_sequence WHERE name = 'robots';
    DROP TABLE robots;
    ALTER TABLE robots_v5 RENAME TO robots;
    CREATE INDEX robots_by_owner ON robots (owner, seq);

    ALTER TABLE jobs ADD COLUMN owner TEXT NOT NULL DEFAULT '';
    CREATE INDEX jobs_by_owner ON jobs (owner, seq);

    CREATE TABLE idempotency_keys_v5 (
      scope       TEXT NOT NULL CHECK (scope IN ('job', 'dataset', 'robot')),
      owner       TEXT NOT NULL DEFAULT '',
      key         TEXT NOT NULL,
      fingerprint TEXT NOT NULL,
      resource_id TEXT NOT NULL,
      created_at  TEXT NOT NULL,
      PRIMARY KEY (scope, owner, key)
    ) WITHOUT ROWID;
    INSERT INTO idempotency_keys_v5 (scope, owner, key, fingerprint, resource_id, created_at)
      SELECT scope, '', key, fingerprint, resource_id, created_at FROM idempotency_keys;
    DROP TABLE idempotency_keys;
    ALTER TABLE idempotency_keys_v5 RENAME TO idempotency_keys;
    CREATE INDEX idempotency_keys_by_resource ON idempotency_keys (resource_id);
    CREATE INDEX idempotency_keys_by_age ON idempotency_keys (created_at);

    PRAGMA user_version = 5;
    )sql",

    // 5 → 6: a URDF robot's identification is a kind of its own, robot_identification (it was an
    // identification with a robot_id). The CHECK on kind changes, which SQLite cannot alter: jobs is rebuilt
    // as in 2 → 3 (foreign keys off around it), its rows copied with the old robot identifications renamed,
    // its AUTOINCREMENT counter carried over (as in 4 → 5), and its indexes made again.
    R"sql(
    CREATE TABLE jobs_v6 (
      seq                   INTEGER PRIMARY KEY AUTOINCREMENT,
      id                    TEXT    NOT NULL UNIQUE,
      kind                  TEXT    NOT NULL
                            CHECK (kind IN ('simulation', 'identification', 'excitation', 'robot_identification')),
      state                 TEXT    NOT NULL
                            CHECK (state IN ('queued', 'running', 'succeeded', 'failed', 'cancelled')),
      request               TEXT    NOT NULL,
      dataset_id            TEXT,
      robot_id              TEXT,
      validation_dataset_id TEXT,
      created_at            TEXT    NOT NULL,
      started_at            TEXT,
      finished_at           TEXT,
      evaluations           INTEGER NOT NULL DEFAULT 0,
      best_cost             REAL,
      cancel_requested      INTEGER NOT NULL DEFAULT 0,
      attempts              INTEGER NOT NULL DEFAULT 0,
      worker_losses         INTEGER NOT NULL DEFAULT 0,
      result                TEXT,
      error                 TEXT,
      worker                TEXT,
      lease_expires_at      REAL,
      owner                 TEXT    NOT NULL DEFAULT ''
    );
    INSERT INTO jobs_v6 (seq, id, kind, state, request, dataset_id, robot_id, validation_dataset_id, created_at,
                         started_at, finished_at, evaluations, best_cost, cancel_requested, attempts, worker_losses,
                         result, error, worker, lease_expires_at, owner)
      SELECT seq, id,
             CASE WHEN kind = 'identification' AND robot_id IS NOT NULL AND robot_id <> '' THEN 'robot_identification'
                  ELSE kind END,
             state, request, dataset_id, robot_id, validation_dataset_id, created_at, started_at, finished_at,
             evaluations, best_cost, cancel_requested, attempts, worker_losses, result, error, worker,
             lease_expires_at, owner FROM jobs;
    DELETE FROM sqlite_sequence WHERE name = 'jobs_v6';
    INSERT INTO sqlite_sequence (name, seq) SELECT 'jobs_v6', seq FROM sqlite_sequence WHERE name = 'jobs';
    DROP TABLE jobs;
    ALTER TABLE jobs_v6 RENAME TO jobs;
    CREATE INDEX jobs_by_state ON jobs (state, seq);
    CREATE INDEX jobs_by_kind ON jobs (kind, seq);
    CREATE INDEX jobs_by_robot ON jobs (robot_id) WHERE robot_id IS NOT NULL;
    CREATE INDEX jobs_by_lease ON jobs (lease_expires_at) WHERE state = 'running';
    CREATE INDEX jobs_by_owner ON jobs (owner, seq);

    PRAGMA user_version = 6;
    )sql",

    // 6 → 7: a payload on a robot's tip link is a kind of its own, payload_identification (new: no rows to
    // rename). The CHECK on kind changes: jobs is rebuilt as in 5 → 6 (foreign keys off around it), its rows
    // copied as they are, its AUTOINCREMENT counter carried over, and its indexes made again.
    R"sql(
    CREATE TABLE jobs_v7 (
      seq                   INTEGER PRIMARY KEY AUTOINCREMENT,
      id                    TEXT    NOT NULL UNIQUE,
      kind                  TEXT    NOT NULL
                            CHECK (kind IN ('simulation', 'identification', 'excitation', 'robot_identification',
                                            'payload_identification')),
      state                 TEXT    NOT NULL
                            CHECK (state IN ('queued', 'running', 'succeeded', 'failed', 'cancelled')),
      request               TEXT    NOT NULL,
      dataset_id            TEXT,
      robot_id              TEXT,
      validation_dataset_id TEXT,
      created_at            TEXT    NOT NULL,
      started_at            TEXT,
      finished_at           TEXT,
      evaluations           INTEGER NOT NULL DEFAULT 0,
      best_cost             REAL,
      cancel_requested      INTEGER NOT NULL DEFAULT 0,
      attempts              INTEGER NOT NULL DEFAULT 0,
      worker_losses         INTEGER NOT NULL DEFAULT 0,
      result                TEXT,
      error                 TEXT,
      worker                TEXT,
      lease_expires_at      REAL,
      owner                 TEXT    NOT NULL DEFAULT ''
    );
    INSERT INTO jobs_v7 (seq, id, kind, state, request, dataset_id, robot_id, validation_dataset_id, created_at,
                         started_at, finished_at, evaluations, best_cost, cancel_requested, attempts, worker_losses,
                         result, error, worker, lease_expires_at, owner)
      SELECT seq, id, kind, state, request, dataset_id, robot_id, validation_dataset_id, created_at, started_at,
             finished_at, evaluations, best_cost, cancel_requested, attempts, worker_losses, result, error, worker,
             lease_expires_at, owner FROM jobs;
    DELETE FROM sqlite_sequence WHERE name = 'jobs_v7';
    INSERT INTO sqlite_sequence (name, seq) SELECT 'jobs_v7', seq FROM sqlite_sequence WHERE name = 'jobs';
    DROP TABLE jobs;
    ALTER TABLE jobs_v7 RENAME TO jobs;
    CREATE INDEX jobs_by_state ON jobs (state, seq);
    CREATE INDEX jobs_by_kind ON jobs (kind, seq);
    CREATE INDEX jobs_by_robot ON jobs (robot_id) WHERE robot_id IS NOT NULL;
    CREATE INDEX jobs_by_lease ON jobs (lease_expires_at) WHERE state = 'running';
    CREATE INDEX jobs_by_owner ON jobs (owner, seq);

    PRAGMA user_version = 7;
    )sql",
};

int read_user_version(Connection& connection) {
  auto statement = connection.prepare("PRAGMA user_version");
  return statement.step() ? static_cast<int>(statement.integer(0)) : 0;
}

}  // namespace

int current_schema_version() { return static_cast<int>(kMigrations.size()); }

void prepare_database(Connection& connection, int target) {
  // journal_mode is kept in the file, so only this first connection sets it.
  std::string mode;
  for (int attempt = 1;; ++attempt) {
    try {
      auto statement = connection.prepare("PRAGMA journal_mode = WAL");
      mode = statement.step() ? statement.text(0) : "";
      break;
    } catch (const BusyError&) {
      if (attempt >= kMaxAttempts) throw;
      sleep_before_retry(attempt);
    }
  }
  if (mode != "wal") {
    throw StoreError("the database cannot use WAL journaling (journal_mode is '" + mode +
                     "'); it must be a file on a local file system");
  }

  // A damaged page is found here, once, rather than by a 500 on whichever read reaches it.
  if (const auto findings = integrity_findings(connection, false, 3); !findings.empty()) {
    throw StoreError("the database file is damaged (PRAGMA quick_check: " + findings.front() +
                     (findings.size() > 1 ? "; and more" : "") +
                     "); manipid will not serve from it: restore it from a backup (`manipid doctor --db FILE` lists "
                     "what is wrong)");
  }

  const int newest = std::min(target, current_schema_version());
  // Migrations rebuild tables that others reference (lang_altertable.html §7): foreign keys off for
  // the transaction (the pragma is a no-op inside one), checked before the commit, on again after.
  connection.execute("PRAGMA foreign_keys = OFF");
  try {
    run_transaction(connection, TransactionKind::write, [&] {
      const int version = read_user_version(connection);
      if (version > current_schema_version()) {
        throw StoreError("the database has schema version " + std::to_string(version) + ", newer than version " +
                         std::to_string(current_schema_version()) + " this manipid understands; use a newer manipid");
      }
      for (int step = version; step < newest; ++step) connection.execute(kMigrations[static_cast<std::size_t>(step)]);
      auto violations = connection.prepare("PRAGMA foreign_key_check");
      if (violations.step()) throw StoreError("the database's rows do not match after the schema migration");
    });
  } catch (...) {
    connection.execute("PRAGMA foreign_keys = ON");
    throw;
  }
  connection.execute("PRAGMA foreign_keys = ON");
}

std::vector<std::string> integrity_findings(Connection& connection, bool full, int limit) {
  std::vector<std::string> findings;
  try {
    // The limit is a number this code writes, not a value from outside: spliced, as PRAGMA
    // arguments cannot be bound.
    auto check = connection.prepare(std::string(full ? "PRAGMA integrity_check(" : "PRAGMA quick_check(") +
                                    std::to_string(limit) + ")");
    while (check.step()) {
      // A row may hold several lines under a "*** in database main ***" heading: one finding each.
      const std::string text = check.text(0);
      for (std::size_t start = 0; start < text.size();) {
        const std::size_t end = std::min(text.find('\n', start), text.size());
        const std::string line = text.substr(start, end - start);
        if (!line.empty() && line != "ok" && !line.starts_with("*** in database")) findings.push_back(line);
        start = end + 1;
      }
    }
    if (full && findings.empty()) {
      auto orphans = connection.prepare("PRAGMA foreign_key_check");
      while (orphans.step() && static_cast<int>(findings.size()) < limit) {
        findings.push_back("a row of " + orphans.text(0) + " refers to a missing row of " + orphans.text(2));
      }
    }
  } catch (const StoreError& error) {
    findings.push_back(error.what());
  }
  return findings;
}

}  // namespace manipid::server::store::sqlite
