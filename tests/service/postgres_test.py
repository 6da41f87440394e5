"""postgres_test.py — `manipid serve` and `manipid worker` on PostgreSQL, whole processes: a
database that cannot be reached, that does not exist, that a newer manipid wrote or that refuses
the password is one line on stderr and exit 1 (no stack text, no password); the right password
(in the URI or PGPASSWORD) serves; a cancel sent to one process stops the job a third runs; a
long-poll (`GET /v1/jobs/{id}?wait=`) on one
process wakes when a job another process runs ends; two processes given the same
Idempotency-Key at once make one job; connections the database drops (a restart, an
administrator) are 503 STORE_UNAVAILABLE with Retry-After for the requests that meet them, never
a 500, and are opened again.

Needs the private cluster of the ctest fixture "postgres" (MANIPID_TEST_POSTGRES_FILE); skipped
without it.

Run: MANIPID_BIN=build/debug/server/manipid MANIPID_TEST_POSTGRES_FILE=... python3 tests/service/postgres_test.py -v
"""
import os
import subprocess
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, binary, postgres_database, postgres_sql, postgres_template, temporary_directory  # noqa: E402


class OnPostgres(unittest.TestCase):
    def setUp(self):
        self.template = postgres_template()
        if self.template is None:
            self.skipTest("no PostgreSQL cluster (ctest fixture postgres; Debian package postgresql)")
        self.directory = temporary_directory()
        path = self.directory.__enter__()
        self.name, self.db = postgres_database(path, "svc")
        self.path = path

    def tearDown(self):
        if self.template is None:
            return
        postgres_sql("postgres", f"DROP DATABASE {self.name} WITH (FORCE)")
        self.directory.__exit__(None, None, None)

    def server(self, name, *extra, workers=1):
        server = Server(self.db, *extra, workers=workers)
        server.log_path = os.path.join(self.path, f"{name}.log")
        return server

    def refused(self, db, environment=None):
        """Runs `serve` on `db`; returns (exit status, stderr) once it gives up."""
        process = subprocess.run([binary(), "serve", "--port", "0", "--db", db], capture_output=True, timeout=60,
                                 env={**os.environ, **(environment or {})})
        return process.returncode, process.stderr.decode()

    def password_uri(self, database, password=None):
        """The cluster's role that signs in with a password (tests/server/postgres_cluster.sh)."""
        uri = self.template.replace("%s", database).replace("user=postgres", "user=manipid_password")
        return uri + (f"&password={password}" if password else "")

    def test_bad_configuration_is_one_line_and_exit_1(self):
        cases = {
            "unreachable": ("postgresql:///x?host=/nonexistent-manipid-socket-dir&user=postgres",
                            "--db: cannot connect to PostgreSQL"),
            "no such database": (self.template.replace("%s", "no_such_database"),
                                 "--db: PostgreSQL refused the connection"),
        }
        # A database a newer manipid wrote: its schema version above this build's.
        with self.server("first"):
            pass
        postgres_sql(self.name, "INSERT INTO manipid_schema (version) VALUES (999)")
        cases["newer schema"] = (self.db, "written by a newer manipid (schema version 999")
        for case, (db, expected) in cases.items():
            with self.subTest(case):
                status, stderr = self.refused(db)
                self.assertEqual(status, 1, stderr)
                self.assertIn(expected, stderr)
                lines = [line for line in stderr.splitlines() if line.strip()]
                self.assertEqual(len(lines), 1, stderr)  # one line: no stack, no log noise
                self.assertNotIn("password=", stderr)

    def test_a_wrong_password_is_one_line_and_exit_1_and_the_right_one_serves(self):
        database = self.name + "_pw"
        postgres_sql("postgres", f"CREATE DATABASE {database} OWNER manipid_password")
        try:
            for case, db, environment in (
                    ("in the URI", self.password_uri(database, "not-the-secret-1"), None),
                    ("in PGPASSWORD", self.password_uri(database), {"PGPASSWORD": "not-the-secret-2"})):
                with self.subTest(case):
                    status, stderr = self.refused(db, environment)
                    self.assertEqual(status, 1, stderr)
                    self.assertIn("--db: PostgreSQL refused the connection", stderr)
                    self.assertIn("password", stderr)  # libpq's reason, in words
                    self.assertEqual(len([line for line in stderr.splitlines() if line.strip()]), 1, stderr)
                    self.assertNotIn("not-the-secret", stderr)
            # The right password: the service starts, answers, and never prints the password.
            server = Server(self.password_uri(database, "manipid-test-secret"), workers=0)
            server.log_path = os.path.join(self.path, "password.log")
            with server:
                status, _, health = server.request("GET", "/healthz")
                self.assertEqual(status, 200, health)
                status, _, job = server.request("POST", "/v1/simulations", {"duration": 1.0})
                self.assertEqual(status, 202, job)
            self.assertIn("listening on", server.read_log())
            self.assertNotIn("manipid-test-secret", server.read_log())
        finally:
            postgres_sql("postgres", f"DROP DATABASE {database} WITH (FORCE)")

    def test_cancel_sent_to_one_process_stops_the_job_another_runs(self):
        # Submit on A, cancel on B, the runner on C stops: three processes, one database.
        with self.server("a", workers=0) as a, self.server("b", workers=0) as b, \
                self.server("c", workers=1) as c:
            # Far longer to simulate than this test waits (tests/hostile/long_simulation_test.py).
            status, _, job = a.request("POST", "/v1/simulations", {"duration": 600, "kd": [1e5, 1e5, 1e5, 1e5]})
            self.assertEqual(status, 202, job)
            for _ in range(600):
                status, _, seen = b.request("GET", f"/v1/jobs/{job['id']}")
                if seen["state"] != "queued":
                    break
                time.sleep(0.05)
            self.assertEqual(seen["state"], "running", seen)
            self.assertTrue(seen["worker"].split(":")[1] == str(c.process.pid), seen)
            status, _, cancelled = b.request("POST", f"/v1/jobs/{job['id']}/cancel")
            self.assertIn(status, (200, 202), cancelled)
            status, _, ended = a.request("GET", f"/v1/jobs/{job['id']}?wait=60", timeout=120)
            self.assertEqual(status, 200, ended)
            self.assertEqual(ended["state"], "cancelled", ended)
            # C writes its log line after the end is committed, which is what woke the wait above.
            deadline = time.time() + 10
            while "cancelled" not in c.read_log() and time.time() < deadline:
                time.sleep(0.05)
            self.assertIn("cancelled", c.read_log())

    def test_a_long_poll_on_one_process_wakes_when_another_ends_the_job(self):
        with self.server("api", workers=0) as api, self.server("runner", workers=1) as runner:
            body = {"simulation": {"duration": 3.0}, "method": "output-error", "max_evaluations": 20}
            status, _, job = api.request("POST", "/v1/identifications", body)
            self.assertEqual(status, 202, job)
            started = time.time()
            status, _, waited = api.request("GET", f"/v1/jobs/{job['id']}?wait=60", timeout=120)
            elapsed = time.time() - started
            self.assertEqual(status, 200, waited)
            self.assertEqual(waited["state"], "succeeded", waited)
            self.assertLess(elapsed, 55, "the long-poll ran to its end instead of waking on the change")
            self.assertNotIn("running (attempt", api.read_log())
            self.assertIn("running (attempt 1", runner.read_log())

    def test_dropped_connections_are_503_and_opened_again(self):
        with self.server("api", workers=0) as api:
            for round_ in range(3):
                status, _, before = api.request("GET", "/v1/jobs")
                self.assertEqual(status, 200, before)
                postgres_sql("postgres", "SELECT pg_terminate_backend(pid) FROM pg_stat_activity "
                                         f"WHERE datname = '{self.name}' AND pid <> pg_backend_pid()")
                answers = []
                for _ in range(40):
                    status, headers, body = api.request("GET", "/v1/jobs")
                    answers.append(status)
                    if status == 200:
                        break
                    self.assertEqual(status, 503, body)
                    self.assertEqual(body["code"], "STORE_UNAVAILABLE", body)
                    self.assertIn("retry-after", headers)
                self.assertEqual(answers[-1], 200, answers)
                print(f"after the drop: {answers}", flush=True)
            status, _, job = api.request("POST", "/v1/identifications", {"simulation": {"duration": 1.0}})
            self.assertEqual(status, 202, job)

    def test_two_processes_given_one_key_at_once_make_one_job(self):
        with self.server("a", workers=0) as a, self.server("b", workers=0) as b:
            body = {"simulation": {"duration": 1.0}, "half_length": 100, "band": 0.2, "free": ["m2"]}
            for round_ in range(20):
                answers = [None, None]

                def send(index, server):
                    answers[index] = server.request("POST", "/v1/identifications", body,
                                                    headers={"Idempotency-Key": f"race-{round_}"})

                threads = [threading.Thread(target=send, args=(i, s)) for i, s in enumerate((a, b))]
                for thread in threads:
                    thread.start()
                for thread in threads:
                    thread.join()
                statuses = sorted(answer[0] for answer in answers)
                self.assertEqual(answers[0][2]["id"], answers[1][2]["id"], answers)
                self.assertIn(202, statuses, answers)
            status, _, page = a.request("GET", "/v1/jobs?page_size=100")
            self.assertEqual(len(page["items"]), 20, page)


if __name__ == "__main__":
    if postgres_template() is None:
        print("no PostgreSQL cluster (ctest fixture postgres; Debian package postgresql): skipped")
        sys.exit(77)
    unittest.main()
