"""errors_test.py — every bad input gets a clear 4xx with an application/problem+json body
naming the field, the server keeps serving, and the store is unchanged.

Run: MANIPID_BIN=build/debug/server/manipid python3 -m unittest tests/service/errors_test.py
"""
import json
import os
import socket
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, temporary_directory  # noqa: E402

HEADER = "t,q1,q2,tau1,tau2"


def csv_rows(count, dt=0.001):
    return "\n".join(f"{i * dt},{0.1 * i},{0.2},{1},{2}" for i in range(count))


class BadInputs(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        cls.server = Server(os.path.join(cls.directory.name, "jobs.db"), "--max-body", "256k").start()
        cls.small = cls.upload_ok(cls, "small", {"dt": 0.001, "q": [[0.0] * 50] * 4, "tau": [[0.0] * 50] * 4})
        cls.no_ref = cls.upload_ok(cls, "no ref", {"dt": 0.001, "q": [[0.0] * 500] * 4, "tau": [[0.0] * 500] * 4})

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()
        cls.directory.cleanup()

    def upload_ok(self, name, body):
        status, _, dataset = self.server.request("POST", "/v1/datasets", {"name": name, **body})
        assert status == 201, dataset
        return dataset["id"]

    def counts(self):
        _, _, jobs = self.server.request("GET", "/v1/jobs?page_size=1000")
        _, _, datasets = self.server.request("GET", "/v1/datasets?page_size=1000")
        return len(jobs["items"]), len(datasets["items"])

    def expect_problem(self, status, code, field, method, path, body=None, headers=None):
        before = self.counts()
        actual, answer, problem = self.server.request(method, path, body, headers)
        self.assertEqual(actual, status, problem)
        self.assertEqual(answer.get("content-type"), "application/problem+json", problem)
        self.assertEqual(problem["status"], status)
        self.assertEqual(problem["code"], code, problem)
        self.assertTrue(problem["type"].startswith("/problems/"))
        self.assertTrue(problem["title"])
        self.assertTrue(problem["detail"])
        if field is not None:
            self.assertEqual(problem.get("field"), field, problem)
        self.assertEqual(self.server.request("GET", "/healthz")[0], 200)
        self.assertEqual(self.counts(), before, "the store changed")
        return problem

    # ---- datasets ----
    def test_malformed_json(self):
        self.expect_problem(400, "MALFORMED_BODY", "body", "POST", "/v1/datasets", '{"dt": 0.001, "q": [[1,2]',
                            {"Content-Type": "application/json"})

    def test_malformed_csv(self):
        self.expect_problem(422, "INVALID_FIELD", None, "POST", "/v1/datasets", f"{HEADER}\n0,1,2,3\n",
                            {"Content-Type": "text/csv"})

    def test_ragged_joint_arrays(self):
        problem = self.expect_problem(422, "INVALID_FIELD", "q[1]", "POST", "/v1/datasets",
                                      {"dt": 0.001, "q": [[0, 1, 2], [0, 1]]})
        self.assertIn("2", problem["detail"])

    def test_torque_joint_count_mismatch(self):
        self.expect_problem(422, "INVALID_FIELD", "tau", "POST", "/v1/datasets",
                            {"dt": 0.001, "q": [[0, 1, 2], [0, 1, 2]], "tau": [[0, 1, 2]]})

    def test_nan_and_infinity(self):
        self.expect_problem(422, "INVALID_FIELD", None, "POST", "/v1/datasets", f"{HEADER}\n0,nan,0,0,0\n0.001,0,0,0,0\n",
                            {"Content-Type": "text/csv"})
        self.expect_problem(400, "MALFORMED_BODY", "body", "POST", "/v1/datasets", '{"dt": 0.001, "q": [[NaN, 1]]}',
                            {"Content-Type": "application/json"})
        self.expect_problem(400, "MALFORMED_BODY", "body", "POST", "/v1/datasets", '{"dt": 0.001, "q": [[1e400, 1]]}',
                            {"Content-Type": "application/json"})

    def test_time_not_increasing_or_a_sample_period_out_of_range(self):
        self.expect_problem(422, "INVALID_FIELD", "t", "POST", "/v1/datasets", {"t": [0, 0.002, 0.001], "q": [[0, 1, 2]]})
        self.expect_problem(422, "INVALID_FIELD", "t", "POST", "/v1/datasets", {"t": [0, 20, 40], "q": [[0, 1, 2]]})

    def test_wrong_media_type_and_compressed_or_chunked_bodies(self):
        self.expect_problem(415, "UNSUPPORTED_MEDIA", "Content-Type", "POST", "/v1/datasets", "<xml/>",
                            {"Content-Type": "application/xml"})
        self.expect_problem(415, "UNSUPPORTED_MEDIA", "Content-Encoding", "POST", "/v1/datasets", "{}",
                            {"Content-Type": "application/json", "Content-Encoding": "gzip"})
        # A chunked body is refused before it is read (cpp-httplib 0.11.4 would not bound it).
        before = self.counts()
        with socket.create_connection((self.server.host, self.server.port), timeout=30) as connection:
            connection.sendall(b"POST /v1/datasets HTTP/1.1\r\nHost: x\r\nContent-Type: text/csv\r\n"
                               b"Transfer-Encoding: chunked\r\n\r\n5\r\nt,q1\n\r\n0\r\n\r\n")
            answer = connection.recv(65536).decode()
        self.assertTrue(answer.startswith("HTTP/1.1 411"), answer)
        self.assertIn("application/problem+json", answer)
        self.assertEqual(self.counts(), before)

    def test_oversize_body(self):
        big = HEADER + "\n" + csv_rows(20000)
        self.assertGreater(len(big), 256 * 1024)
        self.expect_problem(413, "PAYLOAD_TOO_LARGE", "body", "POST", "/v1/datasets", big, {"Content-Type": "text/csv"})

    # ---- jobs ----
    def test_too_few_samples_for_the_filter(self):
        problem = self.expect_problem(422, "INVALID_FIELD", "half_length", "POST", "/v1/identifications",
                                      {"dataset_id": self.small, "half_length": 100, "band": 0.2})
        self.assertIn("202", problem["detail"])

    def test_unknown_names(self):
        self.expect_problem(422, "INVALID_FIELD", "preset", "POST", "/v1/identifications",
                            {"dataset_id": self.no_ref, "preset": "puma560"})
        self.expect_problem(422, "INVALID_FIELD", "free[0]", "POST", "/v1/identifications",
                            {"dataset_id": self.no_ref, "free": ["m9"]})
        self.expect_problem(422, "INVALID_FIELD", "algorithm", "POST", "/v1/identifications",
                            {"dataset_id": self.no_ref, "algorithm": "GN_DIRECT"})
        self.expect_problem(422, "INVALID_FIELD", "max_evaluation", "POST", "/v1/identifications",
                            {"dataset_id": self.no_ref, "max_evaluation": 10})
        self.expect_problem(422, "INVALID_FIELD", "dataset_id", "POST", "/v1/identifications",
                            {"dataset_id": "ds_0000000000000000"})
        self.expect_problem(422, "INVALID_FIELD", "preset", "POST", "/v1/simulations", {"preset": "nope"})

    def test_bounds_that_exclude_the_start(self):
        self.expect_problem(422, "INVALID_FIELD", "lower.m2", "POST", "/v1/identifications",
                            {"dataset_id": self.no_ref, "initial": {"m2": 20}, "lower": {"m2": 30}})

    def test_output_error_needs_reference(self):
        self.expect_problem(422, "INVALID_FIELD", None, "POST", "/v1/identifications",
                            {"dataset_id": self.no_ref, "method": "output-error", "half_length": 100})

    def test_unknown_job_route_and_wrong_state(self):
        self.expect_problem(404, "NOT_FOUND", None, "GET", "/v1/jobs/job_0000000000000000")
        self.expect_problem(404, "NOT_FOUND", None, "GET", "/v1/jobs/job_0000000000000000/history")
        self.expect_problem(404, "NOT_FOUND", None, "POST", "/v1/jobs/job_0000000000000000/cancel")
        self.expect_problem(404, "NOT_FOUND", None, "GET", "/v1/datasets/ds_0000000000000000")
        self.expect_problem(404, "NOT_FOUND", None, "GET", "/v1/nothing-here")
        self.expect_problem(422, "INVALID_FIELD", "wait", "GET", f"/v1/jobs/job_0000000000000000?wait=soon")
        self.expect_problem(422, "INVALID_FIELD", "page_token", "GET", "/v1/jobs?page_token=%%%")
        self.expect_problem(422, "INVALID_FIELD", "page_size", "GET", "/v1/jobs?page_size=-1")

    def test_idempotency_key_format(self):
        self.expect_problem(422, "INVALID_FIELD", "Idempotency-Key", "POST", "/v1/simulations", {"duration": 0.1},
                            {"Idempotency-Key": "x" * 300})


class QueueLimit(unittest.TestCase):
    def test_full_queue_answers_429_with_retry_after(self):
        with temporary_directory() as directory:
            with Server(os.path.join(directory, "jobs.db"), "--queue-limit", "2", workers=1) as server:
                slow = {"simulation": {"duration": 5.0}, "method": "output-error", "max_evaluations": 100000}
                statuses = []
                for _ in range(6):
                    status, answer, body = server.request("POST", "/v1/identifications", slow)
                    statuses.append(status)
                    if status == 429:
                        self.assertEqual(answer["content-type"], "application/problem+json")
                        self.assertEqual(body["code"], "QUEUE_FULL")
                        self.assertIn("retry-after", answer)
                self.assertIn(429, statuses)
                self.assertLessEqual(statuses.count(202), 3)  # one running, two queued
                _, _, jobs = server.request("GET", "/v1/jobs")
                for job in jobs["items"]:
                    server.request("POST", f"/v1/jobs/{job['id']}/cancel")


if __name__ == "__main__":
    unittest.main()
