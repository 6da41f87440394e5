// schema.cpp — the PostgreSQL store's tables and its migrations (see schema.h). The schema
// mirrors the SQLite store's (store/sqlite/schema.cpp) in PostgreSQL's types: bigserial keys
// that order lists, bytea samples, boolean flags, and lease expiry as timestamptz on the
// database's clock. Times shown to users stay RFC 3339 text (store/rules.h), as in SQLite.
#include "store/postgres/schema.h"

#include <array>
#include <string>

namespace manipid::server::store::postgres {

namespace {

/// Any fixed number: the key of the advisory lock migrations hold ("mani" in ASCII).
constexpr const char* kMigrationLock = "1835101801";

// kMigrations[i] takes version i to i + 1. A migration is appended, never edited: databases in the
// field have run the old ones.
constexpr std::array<const char*, 4> kMigrations = {
    R"sql(
    -- seq orders rows newest first for keyset paging; a sequence never hands a value out twice.
    -- The samples come last: reading a description (find, list) never fetches them (TOAST).
    CREATE TABLE datasets (
      seq               bigserial PRIMARY KEY,
      id                text    NOT NULL UNIQUE,
      name              text    NOT NULL,
      created_at        text    NOT NULL,
      source_job        text,
      joints            integer NOT NULL,
      samples           integer NOT NULL,
      dt                double precision NOT NULL,  -- the period (uniform) or the median step (jittery)
      uniform           boolean NOT NULL,
      has_torque        boolean NOT NULL,
      has_reference     boolean NOT NULL,
      has_rates         boolean NOT NULL,
      has_accelerations boolean NOT NULL,
      t   bytea,  -- samples doubles, little-endian (store/encoding.h)
      q   bytea,  -- samples x joints, column-major
      tau bytea,  -- NULL when has_torque is false
      ref bytea,
      qd  bytea,
      qdd bytea
    );
    -- Samples are doubles, which do not compress: stored out of line as they are (EXTERNAL),
    -- without pglz's attempt on every insert and read.
    ALTER TABLE datasets ALTER COLUMN t SET STORAGE EXTERNAL, ALTER COLUMN q SET STORAGE EXTERNAL,
      ALTER COLUMN tau SET STORAGE EXTERNAL, ALTER COLUMN ref SET STORAGE EXTERNAL,
      ALTER COLUMN qd SET STORAGE EXTERNAL, ALTER COLUMN qdd SET STORAGE EXTERNAL;

    CREATE TABLE robots (
      seq        bigserial PRIMARY KEY,
      id         text    NOT NULL UNIQUE,
      name       text    NOT NULL,
      created_at text    NOT NULL,
      base       text,
      tip        text,
      joints     integer NOT NULL,
      summary    text    NOT NULL,  -- the robot resource's description, JSON
      urdf       text    NOT NULL   -- the document as uploaded, byte for byte
    );

    -- dataset_id and robot_id have no foreign key: a job's record outlives what it used or made.
    CREATE TABLE jobs (
      seq                   bigserial PRIMARY KEY,
      id                    text    NOT NULL UNIQUE,
      kind                  text    NOT NULL CHECK (kind IN ('simulation', 'identification', 'excitation')),
      state                 text    NOT NULL
                            CHECK (state IN ('queued', 'running', 'succeeded', 'failed', 'cancelled')),
      request               text    NOT NULL,
      dataset_id            text,
      robot_id              text,
      validation_dataset_id text,
      created_at            text    NOT NULL,
      started_at            text,
      finished_at           text,
      evaluations           bigint  NOT NULL DEFAULT 0,
      best_cost             double precision,
      cancel_requested      boolean NOT NULL DEFAULT false,
      attempts              integer NOT NULL DEFAULT 0,
      worker_losses         integer NOT NULL DEFAULT 0,
      worker                text,          -- HOST:PID:THREAD of the lease holder while running
      lease_expires_at      timestamptz,   -- the database's clock
      result                text,
      error                 text
    );
    CREATE INDEX jobs_by_state ON jobs (state, seq);
    CREATE INDEX jobs_by_kind ON jobs (kind, seq);
    CREATE INDEX jobs_by_robot ON jobs (robot_id) WHERE robot_id IS NOT NULL;
    CREATE INDEX jobs_queued ON jobs (seq) WHERE state = 'queued';                -- the claim
    CREATE INDEX jobs_by_lease ON jobs (lease_expires_at) WHERE state = 'running';  -- recovery

    CREATE TABLE job_history (
      job_id text   NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
      idx    bigint NOT NULL,
      cost   double precision,  -- NULL stands for NaN, as in the SQLite store
      theta  bytea,             -- doubles, little-endian; NULL when empty
      PRIMARY KEY (job_id, idx)
    );

    CREATE TABLE estimates (
      job_id    text NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
      name      text NOT NULL,
      value     double precision,
      std_error double precision,
      PRIMARY KEY (job_id, name)
    );

    -- The primary key is what makes a key unique across processes: two processes that insert
    -- the same key at once are ordered by it, and the second finds the first's row.
    CREATE TABLE idempotency_keys (
      scope       text NOT NULL CHECK (scope IN ('job', 'dataset', 'robot')),
      key         text NOT NULL,
      fingerprint text NOT NULL,
      resource_id text NOT NULL,
      created_at  text NOT NULL,
      PRIMARY KEY (scope, key)
    );
    CREATE INDEX idempotency_keys_by_resource ON idempotency_keys (resource_id);
    CREATE INDEX idempotency_keys_by_age ON idempotency_keys (created_at);
    )sql",

    // 1 → 2: owners (`manipid serve --token-file`), as in the SQLite store's 4 → 5. Every dataset,
    // robot and job belongs to the name of the token that made it; the rows from before belong to
    // no one (''), which admin tokens and servers without named tokens see. A column with a
    // constant default is added without rewriting the table (PostgreSQL 11 and later). An
    // Idempotency-Key is its owner's: the primary key takes the owner in.
    R"sql(
    ALTER TABLE datasets ADD COLUMN owner text NOT NULL DEFAULT '';
    ALTER TABLE robots ADD COLUMN owner text NOT NULL DEFAULT '';
    ALTER TABLE jobs ADD COLUMN owner text NOT NULL DEFAULT '';
    CREATE INDEX datasets_by_owner ON datasets (owner, seq);
    CREATE INDEX robots_by_owner ON robots (owner, seq);
    CREATE INDEX jobs_by_owner ON jobs (owner, seq);
    ALTER TABLE idempotency_keys ADD COLUMN owner text NOT NULL DEFAULT '';
    ALTER TABLE idempotency_keys DROP CONSTRAINT idempotency_keys_pkey, ADD PRIMARY KEY (scope, owner, key);
    )sql",

    // 2 → 3: a URDF robot's identification is a kind of its own, robot_identification (it was an
    // identification with a robot_id), as in the SQLite store's 5 → 6: the CHECK on kind takes it in and the
    // old robot identifications are renamed.
    R"sql(
    ALTER TABLE jobs DROP CONSTRAINT jobs_kind_check;
    ALTER TABLE jobs ADD CONSTRAINT jobs_kind_check
      CHECK (kind IN ('simulation', 'identification', 'excitation', 'robot_identification'));
    UPDATE jobs SET kind = 'robot_identification' WHERE kind = 'identification' AND robot_id IS NOT NULL AND robot_id <> '';
    )sql",

    // 3 → 4: a payload on a robot's tip link is a kind of its own, payload_identification (new: no rows to
    // rename), as in the SQLite store's 6 → 7: the CHECK on kind takes it in.
    R"sql(
    ALTER TABLE jobs DROP CONSTRAINT jobs_kind_check;
    ALTER TABLE jobs ADD CONSTRAINT jobs_kind_check
      CHECK (kind IN ('simulation', 'identification', 'excitation', 'robot_identification', 'payload_identification'));
    )sql",
};

}  // namespace

int current_schema_version() { return static_cast<int>(kMigrations.size()); }

void prepare_database(Connection& connection) {
  // Session-level advisory lock: held across the migrations' transactions, released below (or
  // with the connection if this process dies meanwhile).
  connection.exec(std::string("SELECT pg_advisory_lock(") + kMigrationLock + ")");
  try {
    connection.execute("CREATE TABLE IF NOT EXISTS manipid_schema (version integer NOT NULL)");
    auto row = connection.exec("SELECT max(version) FROM manipid_schema");
    const int version = row.null(0, 0) ? 0 : static_cast<int>(row.integer(0, 0));
    if (version > current_schema_version()) {
      throw StoreError("the database was written by a newer manipid (schema version " + std::to_string(version) +
                       "; this build knows up to " + std::to_string(current_schema_version()) +
                       "): upgrade manipid, or give another database");
    }
    for (int next = version + 1; next <= current_schema_version(); ++next) {
      run_transaction(connection, TransactionKind::write, [&] {
        connection.execute(kMigrations[static_cast<std::size_t>(next - 1)]);
        connection.exec("INSERT INTO manipid_schema (version) VALUES ($1)", Params().integer(next));
      });
    }
  } catch (...) {
    if (connection.usable()) connection.exec(std::string("SELECT pg_advisory_unlock(") + kMigrationLock + ")");
    throw;
  }
  connection.exec(std::string("SELECT pg_advisory_unlock(") + kMigrationLock + ")");
}

}  // namespace manipid::server::store::postgres
