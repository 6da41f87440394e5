"""memory_test.py — hostile-client suite: memory (item 7 of the hardening issue), against the
real `manipid serve` on port 0.

Large bodies are admitted against --memory-budget before a byte of them is read, 3 bytes per
body byte (api::memory_per_body_byte): beyond it a body gets 503 MEMORY_BUSY with Retry-After
and its connection closes, unread; a dataset of short numbers tops its reservation up to 32
bytes per number before it is parsed (503 when there is no room now, 413 when there never is); the reservation is given back when the answer is made, the
body complete or not. A JSON upload is read without a document of the whole body (SAX), with
the same answers as before for what is wrong in it. How much memory an upload takes is
measured, not asserted: bench/upload_memory.py (VmHWM).

A job is admitted against --job-memory by its estimate from its samples, joints and parameters
(api::job_memory_bytes): one that could never fit is refused at submission with 422 naming the
field that sets its size; one that fits waits in the pool until the running jobs leave room,
and a cancel ends it while it waits. What a job takes is measured by bench/job_memory.py.

Run: MANIPID_BIN=build/debug/server/manipid python3 tests/hostile/memory_test.py -v
"""
import json
import os
import re
import socket
import subprocess
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "service"))
from harness import Server, SharedServerTestCase, binary, temporary_directory  # noqa: E402

MAX_BODY = 1 << 20  # --max-body 1MiB
BUDGET = 3 << 20    # --memory-budget 3MiB: one body of --max-body fits, not two of 600 kB


def upload_body(samples, joints=2):
    """A JSON dataset of about `samples` × joints × 20 bytes."""
    return json.dumps({"dt": 0.001, "q": [[0.123456789012345 + 1e-6 * i for i in range(samples)]
                                          for _ in range(joints)]}).encode()


def head(length):
    return (f"POST /v1/datasets HTTP/1.1\r\nHost: test\r\nContent-Type: application/json\r\n"
            f"Content-Length: {length}\r\n\r\n").encode()


def answer_of(sock):
    """(status, headers, body) of the answer on a raw socket, read until the server closes or the body is complete."""
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = sock.recv(65536)
        if not chunk:
            raise AssertionError(f"closed before an answer: {data!r}")
        data += chunk
    head_text, body = data.split(b"\r\n\r\n", 1)
    lines = head_text.decode().split("\r\n")
    headers = {}
    for line in lines[1:]:
        name, value = line.split(":", 1)
        headers[name.strip().lower()] = value.strip()
    length = int(headers.get("content-length", "0"))
    while len(body) < length:
        chunk = sock.recv(65536)
        if not chunk:
            break
        body += chunk
    return int(lines[0].split()[1]), headers, body


class MemoryBudget(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        cls.server = Server(os.path.join(cls.directory.name, "jobs.db"), "--max-body", "1MiB",
                            "--memory-budget", "3MiB").start()

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()
        cls.directory.cleanup()

    def reserved(self):
        status, _, text = self.server.request("GET", "/metrics")
        self.assertEqual(status, 200)
        budget = re.search(r"^manipid_memory_budget_bytes (\d+)$", text, re.M)
        self.assertEqual(int(budget.group(1)), BUDGET)
        return int(re.search(r"^manipid_memory_reserved_bytes (\d+)$", text, re.M).group(1))

    def wait_reserved(self, expected, timeout=10):
        deadline = time.time() + timeout
        while time.time() < deadline:
            if self.reserved() == expected:
                return
            time.sleep(0.02)
        self.fail(f"reserved {self.reserved()} bytes, expected {expected}")

    def test_a_second_large_body_beyond_the_budget_gets_503_with_retry_after(self):
        body = upload_body(15000)  # ~600 kB
        self.assertGreater(len(body), BUDGET // 6)
        self.assertLess(len(body), MAX_BODY)
        self.wait_reserved(0)
        # The first upload: its head and half its body, then held open.
        first = socket.create_connection((self.server.host, self.server.port), timeout=30)
        first.sendall(head(len(body)) + body[: len(body) // 2])
        self.wait_reserved(3 * len(body))  # admitted: 3 bytes per body byte, before the body is read
        # The second: refused from its head, the connection closed with its body unread.
        second = socket.create_connection((self.server.host, self.server.port), timeout=30)
        second.sendall(head(len(body)))
        status, headers, answer = answer_of(second)
        self.assertEqual(status, 503, answer)
        self.assertEqual(headers["content-type"], "application/problem+json")
        self.assertEqual(headers["retry-after"], "5")
        self.assertEqual(headers["connection"], "close")
        problem = json.loads(answer)
        self.assertEqual(problem["code"], "MEMORY_BUSY")
        self.assertEqual(problem["status"], 503)
        self.assertIn("--memory-budget 3145728 bytes", problem["detail"])
        self.assertEqual(second.recv(65536), b"")  # closed
        second.close()
        # Small requests go on meanwhile.
        self.assertEqual(self.server.request("GET", "/healthz")[0], 200)
        # The first completes and is stored; its reservation is given back.
        first.sendall(body[len(body) // 2:])
        status, _, answer = answer_of(first)
        self.assertEqual(status, 201, answer)
        self.assertEqual(json.loads(answer)["samples"], 15000)
        first.close()
        self.wait_reserved(0)
        # Now the second fits.
        status, _, created = self.server.request("POST", "/v1/datasets", body)
        self.assertEqual(status, 201, created)
        self.wait_reserved(0)

    def test_a_body_that_never_arrives_gives_its_reservation_back(self):
        body = upload_body(15000)
        self.wait_reserved(0)
        client = socket.create_connection((self.server.host, self.server.port), timeout=30)
        client.sendall(head(len(body)) + body[:1000])
        self.wait_reserved(3 * len(body))
        client.close()  # gone, mid-body
        self.wait_reserved(0)

    def test_bodies_within_the_budget_are_admitted_together(self):
        body = upload_body(5000)  # ~200 kB: 3 × 200 kB × 2 fits 3 MiB
        self.wait_reserved(0)
        first = socket.create_connection((self.server.host, self.server.port), timeout=30)
        first.sendall(head(len(body)) + body[:100])
        self.wait_reserved(3 * len(body))
        status, _, created = self.server.request("POST", "/v1/datasets", body)
        self.assertEqual(status, 201, created)
        first.sendall(body[100:])
        self.assertEqual(answer_of(first)[0], 201)
        first.close()
        self.wait_reserved(0)


    def test_short_numbers_reserve_what_they_take_once_parsed(self):
        # Item 6 of hardening round 3: 3 bytes per body byte undercounts a body of short numbers
        # ("0," is 2 bytes, 8 as a double, 8 more as the store's copy): a 40 MB JSON body of zeros
        # peaked at 1,000 MiB, six at once passed a 1 GiB budget. Such a body now tops its reservation
        # up to api::memory_per_dataset_number (32) per number before it is parsed.
        def zeros(count):
            return ('{"dt": 0.001, "q": [[' + ",".join(["0"] * count) + "]]}").encode()

        # One that no budget of this server could ever hold: 413 naming --memory-budget, at once.
        body = zeros(400000)  # 800 kB: under --max-body, 13 MB once parsed and stored
        self.assertLess(len(body), MAX_BODY)
        status, _, problem = self.server.request("POST", "/v1/datasets", body)
        self.assertEqual(status, 413, problem)
        self.assertEqual(problem["field"], "body")
        self.assertIn("400003 numbers", problem["detail"])  # separators + 1: an upper bound
        self.assertIn("--memory-budget (3 MiB)", problem["detail"])
        self.wait_reserved(0)
        # One that fits alone but not beside another upload in progress: 503, then 201 once alone.
        small = zeros(50000)  # 100 kB: 1.7 MB with its numbers
        large = upload_body(15000)  # ~600 kB, 1.8 MB reserved while it is read
        first = socket.create_connection((self.server.host, self.server.port), timeout=30)
        first.sendall(head(len(large)) + large[:1000])
        self.wait_reserved(3 * len(large))
        status, headers, problem = self.server.request("POST", "/v1/datasets", small)
        self.assertEqual(status, 503, problem)
        self.assertEqual(problem["code"], "MEMORY_BUSY")
        self.assertEqual(headers.get("Retry-After") or headers.get("retry-after"), "5")
        self.assertIn("50003 numbers", problem["detail"])
        first.sendall(large[1000:])
        self.assertEqual(answer_of(first)[0], 201)
        first.close()
        self.wait_reserved(0)
        status, _, created = self.server.request("POST", "/v1/datasets", small)
        self.assertEqual(status, 201, created)
        self.assertEqual(created["samples"], 50000)
        self.wait_reserved(0)


class MemoryBudgetOption(unittest.TestCase):
    def test_a_budget_below_three_bodies_of_max_body_is_refused_at_start(self):
        with temporary_directory() as directory:
            result = subprocess.run([binary(), "serve", "--port", "0", "--db", os.path.join(directory, "jobs.db"),
                                     "--max-body", "1MiB", "--memory-budget", "2MiB"],
                                    capture_output=True, text=True, timeout=60)
        self.assertNotEqual(result.returncode, 0)
        self.assertIn("--memory-budget: at least 3 x --max-body", result.stderr)


STIFF = {"duration": 600, "kd": [1e5, 1e5, 1e5, 1e5]}  # minutes to simulate: a job that runs until cancelled


def estimate_mib(detail):
    """The estimate a 422 states ("would hold about 58 MiB of memory" or "about 5.1 GiB")."""
    found = re.search(r"would hold about ([0-9.]+) (MiB|GiB)", detail)
    assert found, detail
    return float(found.group(1)) * (1024 if found.group(2) == "GiB" else 1)


class JobMemory(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()

    @classmethod
    def tearDownClass(cls):
        cls.directory.cleanup()

    def server(self, name, job_memory, workers=2):
        return Server(os.path.join(self.directory.name, name + ".db"), "--job-memory", job_memory, workers=workers)

    def estimates(self, *requests):
        """The server's own estimate of each simulation request, in MiB, from the 422 a 1 MiB budget gives."""
        with self.server("probe", "1MiB") as probe:
            found = []
            for request in requests:
                status, _, problem = probe.request("POST", "/v1/simulations", request)
                self.assertEqual(status, 422, problem)
                found.append(estimate_mib(problem["detail"]))
            return found

    def test_a_job_that_could_never_fit_is_refused_naming_the_field(self):
        with self.server("small", "64MiB") as server:
            for path, body, field in [("/v1/simulations", {"duration": 3600}, "duration"),
                                      ("/v1/identifications", {"simulation": {"duration": 3600}}, "simulation")]:
                status, _, problem = server.request("POST", path, body)
                self.assertEqual(status, 422, problem)
                self.assertEqual(problem["field"], field)
                self.assertIn("--job-memory", problem["detail"])
                self.assertIn("64 MiB", problem["detail"])
                self.assertGreater(estimate_mib(problem["detail"]), 64)
            status, _, jobs = server.request("GET", "/v1/jobs")
            self.assertEqual(jobs["items"], [])  # nothing queued
            status, _, job = server.request("POST", "/v1/simulations", {"duration": 2})
            self.assertEqual(status, 202, job)
            self.assertEqual(server.wait_job(job["id"])["state"], "succeeded")
            status, _, text = server.request("GET", "/metrics")
            self.assertIn(f"manipid_job_memory_budget_bytes {64 << 20}\n", text)
            self.assertIn("manipid_job_memory_reserved_bytes 0\n", text)

    def test_a_job_waits_for_room_and_a_cancel_ends_it_while_it_waits(self):
        stiff, short = self.estimates(STIFF, {"duration": 2})
        budget = f"{int(stiff + short / 2)}MiB"  # the stiff run fits alone, the short one not beside it
        with self.server("waits", budget) as server:
            status, _, first = server.request("POST", "/v1/simulations", STIFF)
            self.assertEqual(status, 202, first)
            self.wait_for(lambda: server.request("GET", f"/v1/jobs/{first['id']}")[2]["state"] == "running")
            status, _, second = server.request("POST", "/v1/simulations", {"duration": 2})
            self.assertEqual(status, 202, second)
            self.wait_for(lambda: f"job {second['id']}: waits for" in server.read_log())
            status, _, text = server.request("GET", "/metrics")
            reserved = int(re.search(r"^manipid_job_memory_reserved_bytes (\d+)$", text, re.M).group(1))
            self.assertAlmostEqual(reserved / 2**20, stiff, delta=1)  # the stiff run's only
            status, _, cancelled = server.request("POST", f"/v1/jobs/{second['id']}/cancel")
            self.assertEqual(server.wait_job(second["id"], timeout=30)["state"], "cancelled")
            self.assertEqual(server.request("GET", f"/v1/jobs/{first['id']}")[2]["state"], "running")
            # Another short job waits, and runs once the stiff run is cancelled.
            status, _, third = server.request("POST", "/v1/simulations", {"duration": 2})
            self.wait_for(lambda: f"job {third['id']}: waits for" in server.read_log())
            server.request("POST", f"/v1/jobs/{first['id']}/cancel")
            self.assertEqual(server.wait_job(first["id"], timeout=30)["state"], "cancelled")
            finished = server.wait_job(third["id"], timeout=120)
            self.assertEqual(finished["state"], "succeeded")
            self.assertNotIn(f"job {second['id']} simulation: running", server.read_log())

    def test_a_job_queued_before_a_smaller_budget_fails_with_the_reason(self):
        db_name = "restart"
        with self.server(db_name, "4GiB", workers=1) as server:
            status, _, first = server.request("POST", "/v1/simulations", STIFF)
            self.wait_for(lambda: server.request("GET", f"/v1/jobs/{first['id']}")[2]["state"] == "running")
            status, _, queued = server.request("POST", "/v1/simulations", {"duration": 300})
            self.assertEqual(status, 202, queued)
            server.request("POST", f"/v1/jobs/{first['id']}/cancel")
            server.stop()  # the second may be running or queued: either way it is queued again
        with self.server(db_name, "16MiB", workers=1) as server:
            job = server.wait_job(queued["id"], timeout=60)
            self.assertEqual(job["state"], "failed", job)
            self.assertIn("--job-memory", job["error"]["detail"])

    def wait_for(self, condition, timeout=30):
        deadline = time.time() + timeout
        while time.time() < deadline:
            if condition():
                return
            time.sleep(0.05)
        self.fail("timed out")


class SaxUpload(SharedServerTestCase):
    """The upload read without a document answers as before (tests/api checks every message)."""

    def test_wrong_bodies_get_the_same_problems(self):
        cases = [
            (b'{"dt": 0.1, "q": [[1, 2], [3, 1e400]]}', 400, "MALFORMED_BODY", "body", "a number at q[1][1] is out of range"),
            (b'{"dt": 0.1, "q": [[1, 2], [3, 4]], "dt": 0.2}', 422, "INVALID_FIELD", "dt", "appears twice"),
            (b'{"dt": 0.1, "q": [[1, 2], [3, "4"]]}', 422, "INVALID_FIELD", "q[1][1]", 'must be a number, got a string ("4")'),
            (b'{"q": [[1, 2], [3]], "t": [0, 1]}', 422, "INVALID_FIELD", "q[1]", "q[1] has 1 sample, expected 2 (as t)"),
            (b'[[1, 2]]', 400, "MALFORMED_BODY", "body", "expected a JSON object at the top level"),
            (b'{"dt": 0.1, "q": [[1, 2]', 400, "MALFORMED_BODY", "body", "the body is not valid JSON"),
            (b"[" * 100000, 400, "MALFORMED_BODY", "body", "more than 64 deep"),
        ]
        for body, status, code, field, words in cases:
            with self.subTest(body=body[:60]):
                answer_status, headers, problem = self.server.request(
                    "POST", "/v1/datasets", body, {"Content-Type": "application/json"})
                self.assertEqual(answer_status, status, problem)
                self.assertEqual(problem["code"], code)
                self.assertEqual(problem["field"], field)
                self.assertIn(words, problem["detail"])


    def test_a_long_dataset_is_answered_in_pieces_that_read_back_exactly(self):
        # More than 65,536 samples: the JSON and CSV answers are written piece by piece (chunked).
        samples = 70000
        body = {"t": [0.001 * i for i in range(samples)],
                "q": [[0.123456789 * ((i * 7919) % 1000) / 1000 for i in range(samples)]],
                "tau": [[-1.5e-3 * ((i * 104729) % 997) for i in range(samples)]]}
        status, _, created = self.server.request("POST", "/v1/datasets", body)
        self.assertEqual(status, 201, created)
        status, headers, data = self.server.request("GET", f"/v1/datasets/{created['id']}/data")
        self.assertEqual(status, 200)
        self.assertEqual(headers.get("transfer-encoding"), "chunked")
        self.assertEqual(list(data), ["t", "q", "tau"])
        self.assertEqual(data, body)
        status, headers, text = self.server.request("GET", f"/v1/datasets/{created['id']}?format=csv")
        self.assertEqual(status, 200)
        self.assertEqual(headers.get("transfer-encoding"), "chunked")
        lines = text.splitlines()
        self.assertEqual(lines[0], "t,q1,tau1")
        self.assertEqual(len(lines), samples + 1)  # one header, every row once
        status, _, again = self.server.request("POST", "/v1/datasets", text, {"Content-Type": "text/csv"})
        self.assertEqual(status, 201, again)
        status, _, data = self.server.request("GET", f"/v1/datasets/{again['id']}/data?format=json")
        self.assertEqual(data, body)
        # Thinned for drawing: one document, as before.
        status, headers, thinned = self.server.request("GET", f"/v1/datasets/{created['id']}/data?max_points=100")
        self.assertEqual(status, 200)
        self.assertNotIn("transfer-encoding", headers)
        self.assertLessEqual(len(thinned["t"]), 101)


if __name__ == "__main__":
    unittest.main()
