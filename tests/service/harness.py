"""harness.py — starts the real `manipid serve` binary for whole-process tests and talks to it
over HTTP with nothing but the standard library.

Server(binary, db) runs `manipid serve --port 0 --db DB`, reads the port from the first line
on stdout ("listening on http://HOST:PORT"), and keeps stderr (the request and job log) in a
file the tests can read. request() returns (status, headers, body) where body is parsed JSON
for JSON answers and text otherwise.
"""
import http.client
import json
import os
import signal
import subprocess
import tempfile
import time
import unittest


def binary():
    path = os.environ.get("MANIPID_BIN")
    if not path or not os.access(path, os.X_OK):
        raise RuntimeError("set MANIPID_BIN to the manipid executable")
    return path


class Server:
    def __init__(self, db, *extra, workers=2):
        self.db = db
        self.extra = list(extra)
        self.workers = workers
        self.process = None
        self.log_path = db + ".log"

    def start(self, timeout=60):
        self.log = open(self.log_path, "ab")
        command = [binary(), "serve", "--port", "0", "--db", self.db, "--workers", str(self.workers)] + self.extra
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=self.log)
        line = self.process.stdout.readline().decode()
        if not line.startswith("listening on http://"):
            self.process.wait(timeout)
            raise RuntimeError(f"server did not start: {line!r}; log: {self.read_log()}")
        self.url = line.split()[-1]
        self.host, port = self.url[len("http://"):].rsplit(":", 1)
        self.port = int(port)
        return self

    def read_log(self):
        with open(self.log_path, "rb") as stream:
            return stream.read().decode(errors="replace")

    def stop(self, sig=signal.SIGTERM, timeout=60):
        """Sends `sig` and waits; returns the exit status."""
        if self.process is None:
            return None
        self.process.send_signal(sig)
        status = self.process.wait(timeout)
        self.process.stdout.close()
        self.log.close()
        self.process = None
        return status

    def kill(self):
        return self.stop(signal.SIGKILL)

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        if self.process is not None:
            self.stop()

    def request(self, method, path, body=None, headers=None, timeout=120):
        """One request on a fresh connection. `body`: dict/list (sent as JSON), str or bytes."""
        headers = dict(headers or {})
        if isinstance(body, (dict, list)):
            body = json.dumps(body)
            headers.setdefault("Content-Type", "application/json")
        if isinstance(body, str):
            body = body.encode()
        connection = http.client.HTTPConnection(self.host, self.port, timeout=timeout)
        try:
            connection.request(method, path, body=body, headers=headers)
            response = connection.getresponse()
            data = response.read()
            answer_headers = {k.lower(): v for k, v in response.getheaders()}
        finally:
            connection.close()
        kind = answer_headers.get("content-type", "")
        if "json" in kind and data:
            data = json.loads(data)
        else:
            data = data.decode(errors="replace")
        return response.status, answer_headers, data

    def wait_job(self, job_id, timeout=300):
        """Long-polls until the job is terminal; returns its JSON."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            status, headers, job = self.request("GET", f"/v1/jobs/{job_id}?wait=20")
            assert status == 200, (status, job)
            if job["state"] in ("succeeded", "failed", "cancelled"):
                return job
            if headers.get("manipid-wait") == "declined":  # every long-poll slot taken: as Retry-After says
                time.sleep(float(headers.get("retry-after", "1")))
        raise AssertionError(f"job {job_id} did not finish in {timeout} s")


def sanitized():
    """Whether MANIPID_BIN is a sanitizer build (the debug preset): several times slower, so
    timing bounds are looser there."""
    with open(binary(), "rb") as stream:
        return b"__asan_init" in stream.read()


def postgres_template():
    """The libpq URI of the private PostgreSQL cluster the ctest fixture "postgres" runs
    (tests/server/postgres_cluster.sh), with %s where a database name goes; None without one."""
    state = os.environ.get("MANIPID_TEST_POSTGRES_FILE")
    if not state or not os.path.exists(state):
        return None
    with open(state) as stream:
        return stream.readline().strip()


def postgres_sql(database, sql):
    """Runs one statement with psql on `database` of that cluster."""
    subprocess.run(["psql", postgres_template().replace("%s", database), "-qc", sql], check=True,
                   stdout=subprocess.DEVNULL)


def postgres_database(directory, prefix):
    """A new database on the cluster, named after `directory` (a test's temporary directory):
    its name and its URI."""
    name = prefix + "_" + "".join(c for c in os.path.basename(directory).lower() if c.isalnum())
    postgres_sql("postgres", f"CREATE DATABASE {name}")
    return name, postgres_template().replace("%s", name)


def temporary_directory():
    return tempfile.TemporaryDirectory(prefix="manipid-service-test-")


class SharedServerTestCase(unittest.TestCase):
    """A test class whose tests share one `manipid serve` (cls.server) on a database in a temporary
    directory (cls.directory), started before the first test and stopped after the last."""

    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        cls.server = Server(os.path.join(cls.directory.name, "jobs.db")).start()

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()
        cls.directory.cleanup()


def simulate_csv(path, *arguments):
    """Writes a trajectory CSV with `manipid simulate` (the paper's run unless told otherwise)."""
    subprocess.run([binary(), "simulate", "--out", path, *arguments], check=True, stderr=subprocess.DEVNULL)
    with open(path) as stream:
        return stream.read()


def identify_cli(path, *arguments):
    """`manipid identify --json` on a file: the reference the service must agree with."""
    output = subprocess.run([binary(), "identify", path, "--json", *arguments], check=True, capture_output=True)
    return json.loads(output.stdout)
