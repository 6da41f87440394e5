"""lease_test.py — running jobs are held on leases: two `manipid serve` processes on one
database file; the one running a job is paused (SIGSTOP) past its lease, the other takes the job
over and finishes it; the paused one wakes up (SIGCONT) and writes nothing more. A cancel sent to
the process that is not running the job stops it within one renewal. `manipid serve --workers 0`
answers the API while `manipid worker` processes run the jobs; a worker that starts later leaves
the running jobs of the live one alone. Each test runs on a SQLite file and again on a PostgreSQL
database of the private cluster ctest starts (fixture "postgres"; skipped without it).

Run: MANIPID_BIN=build/debug/server/manipid python3 -m unittest tests/service/lease_test.py
"""
import os
import signal
import subprocess
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, binary, postgres_database, postgres_template, temporary_directory  # noqa: E402

LEASE = "1"  # s: renewed every 1/3 s, taken over a second after the last renewal


def new_database(directory, backend):
    """A fresh database for one test: a file in `directory`, or a new PostgreSQL database."""
    if backend == "sqlite":
        return os.path.join(directory, "jobs.db")
    return postgres_database(directory, "lease")[1]


def start(db, directory, name):
    server = Server(db, "--lease", LEASE, workers=1)
    server.log_path = os.path.join(directory, f"{name}.log")
    return server.start()


def worker_name(server):
    return f"{os.uname().nodename}:{server.process.pid}"


def wait_for(predicate, server, job_id, timeout=120):
    deadline = time.time() + timeout
    while time.time() < deadline:
        _, _, job = server.request("GET", f"/v1/jobs/{job_id}")
        if predicate(job):
            return job
        time.sleep(0.05)
    raise AssertionError(f"job {job_id} never got there: {job}")


class Leases(unittest.TestCase):
    backend = "sqlite"

    def setUp(self):
        if self.backend == "postgres" and postgres_template() is None:
            self.skipTest("no PostgreSQL cluster (ctest fixture postgres)")
        self.directory = temporary_directory()
        path = self.directory.__enter__()
        self.db = new_database(path, self.backend)
        self.servers = [start(self.db, path, "a"), start(self.db, path, "b")]

    def tearDown(self):
        for server in self.servers:
            if server.process.poll() is None:
                server.process.send_signal(signal.SIGCONT)
                server.stop()
        self.directory.__exit__(None, None, None)

    def holder_and_other(self, job):
        names = [worker_name(server) for server in self.servers]
        self.assertIn(job["worker"], names, job)
        holder = self.servers[names.index(job["worker"])]
        return holder, self.servers[1 - names.index(job["worker"])]

    def test_a_paused_worker_loses_its_job_to_the_other_process_and_writes_nothing_more(self):
        # Output-error simulates the loop at every evaluation: 200 of a 10 s run take about 1.5 s in a release
        # build (40 of 3 s, 0.08 s, ended before the poll could see it running) and ~15 s under the sanitizers.
        body = {"simulation": {"duration": 10.0}, "method": "output-error", "max_evaluations": 200}
        status, _, job = self.servers[0].request("POST", "/v1/identifications", body)
        self.assertEqual(status, 202, job)
        running = wait_for(lambda j: j["state"] == "running" and j["progress"]["evaluations"] > 0,
                           self.servers[0], job["id"])
        self.assertEqual(running["attempts"], 1)
        holder, other = self.holder_and_other(running)

        holder.process.send_signal(signal.SIGSTOP)
        taken = wait_for(lambda j: j["attempts"] == 2 and j["state"] != "queued", other, job["id"], timeout=60)
        if taken["state"] == "running":
            self.assertEqual(taken["worker"], worker_name(other))
        holder.process.send_signal(signal.SIGCONT)

        done = other.wait_job(job["id"])
        self.assertEqual(done["state"], "succeeded", done)
        self.assertEqual(done["attempts"], 2)
        self.assertIsNone(done["worker"])
        # One attempt's history only: indices 0..evaluations-1, once each, none of the paused one's.
        _, _, page = other.request("GET", f"/v1/jobs/{job['id']}/history?page_size=1000")
        indices = [entry["index"] for entry in page["items"]]
        self.assertEqual(indices, list(range(done["result"]["evaluations"])))
        # The paused process learned it had lost the job and stopped it without writing.
        deadline = time.time() + 30
        while "stopped, its lease lost" not in holder.read_log() and time.time() < deadline:
            time.sleep(0.1)
        self.assertIn("stopped, its lease lost", holder.read_log())
        self.assertIn("whose worker stopped renewing its lease queued again", other.read_log())
        _, _, after = holder.request("GET", f"/v1/jobs/{job['id']}")
        self.assertEqual((after["state"], after["attempts"]), ("succeeded", 2))

    def test_a_cancel_through_the_other_process_stops_the_running_job(self):
        # Long enough to be cancelled in a Release build too (each evaluation simulates 12 s; 400 of 3 s took 0.4 s).
        body = {"simulation": {"duration": 12.0}, "method": "output-error", "max_evaluations": 2000}
        status, _, job = self.servers[0].request("POST", "/v1/identifications", body)
        self.assertEqual(status, 202, job)
        running = wait_for(lambda j: j["state"] == "running" and j["progress"]["evaluations"] > 0,
                           self.servers[0], job["id"])
        holder, other = self.holder_and_other(running)
        status, _, answer = other.request("POST", f"/v1/jobs/{job['id']}/cancel")
        self.assertEqual(status, 200, answer)
        asked = time.time()
        done = holder.wait_job(job["id"], timeout=60)
        self.assertEqual(done["state"], "cancelled", done)
        self.assertEqual(done["attempts"], 1)
        # Within a few renewals (1/3 s each), not at the end of its 400 evaluations.
        self.assertLess(done["progress"]["evaluations"], 400)
        print(f"cancel through the other process ended the job {time.time() - asked:.2f} s after it was asked")


class Worker:
    """`manipid worker` on `db`: started, its first stdout line checked, stopped with SIGTERM."""

    def __init__(self, db, directory, name):
        self.log_path = os.path.join(directory, f"{name}.log")
        self.log = open(self.log_path, "ab")
        self.process = subprocess.Popen([binary(), "worker", "--db", db, "--workers", "1", "--lease", LEASE],
                                        stdout=subprocess.PIPE, stderr=self.log)
        line = self.process.stdout.readline().decode()
        if line != f"working on {db}\n":
            self.process.kill()
            raise RuntimeError(f"worker did not start: {line!r}; log: {self.read_log()}")

    def read_log(self):
        with open(self.log_path, "rb") as stream:
            return stream.read().decode(errors="replace")

    def stop(self):
        self.process.send_signal(signal.SIGTERM)
        status = self.process.wait(60)
        self.process.stdout.close()
        self.log.close()
        return status


class ApiAndWorkers(unittest.TestCase):
    backend = "sqlite"

    def test_the_api_process_runs_nothing_and_the_workers_run_everything(self):
        if self.backend == "postgres" and postgres_template() is None:
            self.skipTest("no PostgreSQL cluster (ctest fixture postgres)")
        with temporary_directory() as directory:
            db = new_database(directory, self.backend)
            api_server = Server(db, workers=0)
            api_server.log_path = os.path.join(directory, "api.log")
            with api_server as api:
                deadline = time.time() + 10  # the log line follows the "listening on" line on stdout
                while "no job threads (API only)" not in api.read_log() and time.time() < deadline:
                    time.sleep(0.05)
                self.assertIn("no job threads (API only)", api.read_log())
                first = Worker(db, directory, "first")
                try:
                    body = {"simulation": {"duration": 3.0}, "method": "output-error", "max_evaluations": 40}
                    status, _, slow = api.request("POST", "/v1/identifications", body)
                    self.assertEqual(status, 202, slow)
                    running = wait_for(lambda j: j["state"] == "running", api, slow["id"])
                    self.assertEqual(running["worker"], worker_name(first))
                    # A second worker starting now takes back no job from the live first one.
                    second = Worker(db, directory, "second")
                    try:
                        self.assertNotIn("interrupted job(s) queued again", second.read_log())
                        quick = {"simulation": {"duration": 1.0}, "half_length": 100, "band": 0.2, "free": ["m2"]}
                        ids = [api.request("POST", "/v1/identifications", quick)[2]["id"] for _ in range(3)]
                        for job_id in ids + [slow["id"]]:
                            done = api.wait_job(job_id)
                            self.assertEqual((done["state"], done["attempts"]), ("succeeded", 1), done)
                        self.assertEqual(second.stop(), 0)
                    finally:
                        if second.process.poll() is None:
                            second.process.kill()
                    self.assertEqual(first.stop(), 0)
                finally:
                    if first.process.poll() is None:
                        first.process.kill()
                self.assertIn("stopped", first.read_log())
                self.assertNotIn("running (attempt", api.read_log())


class LeasesOnPostgres(Leases):
    backend = "postgres"


class ApiAndWorkersOnPostgres(ApiAndWorkers):
    backend = "postgres"


if __name__ == "__main__":
    unittest.main()
