"""numerics_test.py — hostile-client suite, part 1: requests that used to crash the process
(again on every restart) or "succeed" with no cost, against the real `manipid serve` on port 0.

Items 1 and 2 of the hardening issue: starting values at the edge of floating point
(1e-100, 1e-320, 0, 1e300) are refused at the door with the field named; a sample period of
1e-320 is refused at upload; a cost that is not finite fails the job with a reason; a job
whose worker dies --max-attempts times is failed at start-up instead of run again.

Run: MANIPID_BIN=build/debug/server/manipid python3 tests/hostile/numerics_test.py -v
"""
import os
import subprocess
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "service"))
from harness import Server, SharedServerTestCase, binary, simulate_csv, temporary_directory  # noqa: E402

NAMES = ["m1", "m2", "m3", "m4", "l1", "l2", "l3", "l4"]


def every_parameter(value):
    return {name: value for name in NAMES}


class StartingValues(SharedServerTestCase):
    def assert_refused(self, body, field, words):
        status, headers, problem = self.server.request("POST", "/v1/identifications", body)
        self.assertEqual(status, 422, problem)
        self.assertEqual(headers["content-type"], "application/problem+json")
        self.assertEqual(problem["code"], "INVALID_FIELD")
        self.assertEqual(problem["field"], field)
        self.assertIn(words, problem["detail"])
        self.assertLess(len(problem["detail"]), 200)

    def test_the_150_byte_request_is_refused_not_run(self):
        # The request that crashed the server in assess_uncertainty, and again on every restart.
        _, _, before = self.server.request("GET", "/v1/jobs?page_size=1000")
        for value in (1e-100, 1e-320, 0.0):
            with self.subTest(value=value):
                self.assert_refused({"simulation": {}, "initial": every_parameter(value)}, "initial.m1",
                                    "is not a sensible link mass")
        for algorithm in ("LD_SLSQP", "LN_SBPLX", "LN_NELDERMEAD", "LD_LBFGS"):
            with self.subTest(algorithm=algorithm):
                self.assert_refused({"simulation": {}, "algorithm": algorithm, "initial": every_parameter(1e-100)},
                                    "initial.m1", "give a value from 0.001 to 100000 kg")
        _, _, after = self.server.request("GET", "/v1/jobs?page_size=1000")
        self.assertEqual(len(after["items"]), len(before["items"]))  # nothing was queued
        self.assertEqual(self.server.request("GET", "/healthz")[0], 200)

    def test_huge_starting_values_and_lengths_are_refused(self):
        self.assert_refused({"simulation": {}, "initial": {"m2": 1e300}}, "initial.m2", "1e+300 kg")
        self.assert_refused({"simulation": {}, "initial": {"l3": 1e-100}}, "initial.l3", "is not a sensible link length")

    def test_a_simulated_robot_must_be_sensible_too(self):
        status, _, problem = self.server.request("POST", "/v1/simulations", {"parameters": {"m4": 1e-100}})
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["field"], "parameters.m4")

    def test_a_sample_period_of_1e_320_is_refused_at_upload(self):
        body = {"dt": 1e-320, "q": [[0.0, 0.1, 0.2, 0.3]], "tau": [[1.0, 1.0, 1.0, 1.0]]}
        status, _, problem = self.server.request("POST", "/v1/datasets", body)
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["field"], "dt")
        self.assertIn("sample period", problem["detail"])
        csv = "t,q1,tau1\n0,0,1\n1e-320,0.1,1\n2e-320,0.2,1\n"
        status, _, problem = self.server.request("POST", "/v1/datasets", csv, {"Content-Type": "text/csv"})
        self.assertEqual(status, 422, problem)
        self.assertIn("sample period", problem["detail"])

    def test_a_cost_that_is_not_finite_fails_the_job_with_the_reason(self):
        # Torques of 1e200 N·m: every squared residual overflows, so there is no cost to minimise.
        with temporary_directory() as directory:
            text = simulate_csv(os.path.join(directory, "run.csv"), "--duration", "1")
        lines = text.strip().split("\n")
        header = lines[0].split(",")
        rows = []
        for line in lines[1:]:
            values = line.split(",")
            rows.append(",".join(v if not header[i].startswith("tau") else "1e200" for i, v in enumerate(values)))
        status, _, dataset = self.server.request("POST", "/v1/datasets", "\n".join([lines[0]] + rows) + "\n",
                                                 {"Content-Type": "text/csv"})
        self.assertEqual(status, 201, dataset)
        status, _, job = self.server.request("POST", "/v1/identifications",
                                             {"dataset_id": dataset["id"], "half_length": 100, "band": 0.2})
        self.assertEqual(status, 202, job)
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "failed", job)
        self.assertEqual(job["error"]["code"], "NOT_COMPUTABLE")
        self.assertIn("the cost at the starting values is infinite", job["error"]["detail"])
        self.assertNotIn("field", job["error"])  # the data or the start: no single field is at fault
        self.assertNotIn("result", job)


class AbsurdButWellFormed(SharedServerTestCase):
    """Round 3, item 8: values that parse but mean nothing are refused at the door, naming themselves."""

    def test_a_band_the_filters_cannot_hold_is_refused_naming_band(self):
        # band 1e-300 underflowed every filter coefficient; the job then failed naming m1.
        for body in ({"simulation": {}, "band": 1e-300, "half_length": 50}, {"simulation": {}, "band": 1e-300},
                     {"simulation": {"reference": {"band": 1e-300}}}):
            with self.subTest(body=body):
                status, _, problem = self.server.request("POST", "/v1/identifications", body)
                self.assertEqual(status, 422, problem)
                self.assertTrue(problem["field"].endswith("band"), problem)
                self.assertIn("underflow", problem["detail"])

    def test_an_overlong_idempotency_key_is_named(self):
        # 10,000 characters were "the request could not be read".
        status, _, problem = self.server.request("POST", "/v1/datasets", {"dt": 0.01, "q": [[0, 1, 2]]},
                                                 headers={"Idempotency-Key": "k" * 10000})
        self.assertEqual(status, 400, problem)
        self.assertIn("Idempotency-Key", problem["detail"])
        self.assertIn("8192", problem["detail"])
        self.assertEqual(self.server.request("GET", "/healthz")[0], 200)


class CommandLine(unittest.TestCase):
    def test_identify_refuses_the_same_values_with_exit_status_2(self):
        with temporary_directory() as directory:
            run = os.path.join(directory, "run.csv")
            simulate_csv(run, "--duration", "1")
            for value in ("1e-100", "1e-320", "0"):
                for algorithm in ("LN_BOBYQA", "LD_SLSQP"):
                    with self.subTest(value=value, algorithm=algorithm):
                        init = ",".join(f"{name}={value}" for name in NAMES)
                        done = subprocess.run([binary(), "identify", run, "--init", init, "--algorithm", algorithm],
                                              capture_output=True, text=True, timeout=120)
                        self.assertEqual(done.returncode, 2, done.stderr)
                        self.assertIn("--init: m1 = ", done.stderr)
                        self.assertIn("is not a sensible link mass", done.stderr)
                        self.assertEqual(done.stderr.count("\n"), 1)


class PoisonJob(unittest.TestCase):
    def test_a_job_whose_worker_dies_three_times_is_failed_and_never_run_again(self):
        with temporary_directory() as directory:
            db = os.path.join(directory, "jobs.db")
            slow = {"simulation": {"duration": 3.0}, "method": "output-error", "max_evaluations": 100000}
            server = Server(db, workers=1).start()
            status, _, poison = server.request("POST", "/v1/identifications", slow)
            self.assertEqual(status, 202, poison)
            status, _, after = server.request("POST", "/v1/simulations", {"duration": 0.5})
            self.assertEqual(status, 202, after)
            for death in range(1, 4):
                deadline = time.time() + 120
                while time.time() < deadline:
                    _, _, job = server.request("GET", f"/v1/jobs/{poison['id']}")
                    if job["state"] == "running":
                        break
                    time.sleep(0.05)
                self.assertEqual(job["state"], "running", job)
                server.kill()  # as if the job had crashed the process
                server = Server(db, workers=1).start()
                if death < 3:
                    self.assertIn("interrupted job(s) queued again", server.read_log())
            try:
                _, _, job = server.request("GET", f"/v1/jobs/{poison['id']}")
                self.assertEqual(job["state"], "failed", job)
                self.assertEqual(job["error"]["code"], "WORKER_LOST")
                self.assertIn("the worker stopped while running this job 3 times", job["error"]["detail"])
                self.assertIn(f"job {poison['id']} failed: its worker died 3 or more times", server.read_log())
                # The server goes on with the rest of the queue.
                self.assertEqual(server.wait_job(after["id"])["state"], "succeeded")
                self.assertEqual(server.request("GET", "/healthz")[0], 200)
            finally:
                server.stop()


if __name__ == "__main__":
    unittest.main()
