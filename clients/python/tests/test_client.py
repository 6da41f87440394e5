"""Tests of manipid_client against a real `manipid serve` started by its own local_server().

Run from the repository root (no pytest needed):
    MANIPID_BIN=build/debug/server/manipid python3 -m unittest discover -s clients/python/tests -v
Without MANIPID_BIN, build/debug/server/manipid (ASan) is used if it exists, else build/release.
"""
from __future__ import annotations

import contextlib
import io
import os
import re
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path

PACKAGE_ROOT = Path(__file__).resolve().parent.parent  # clients/python
REPOSITORY = PACKAGE_ROOT.parent.parent
sys.path.insert(0, str(PACKAGE_ROOT))

from manipid_client import (BinaryNotFound, Client, Dataset, Job, JobCancelled, JobFailed,  # noqa: E402
                            ManipidConnectionError, ManipidError, find_binary, local_server)

if not os.environ.get("MANIPID_BIN"):
    for candidate in ("build/debug/server/manipid", "build/release/server/manipid"):
        if os.access(REPOSITORY / candidate, os.X_OK):
            os.environ["MANIPID_BIN"] = str(REPOSITORY / candidate)
            break
BINARY = os.environ.get("MANIPID_BIN", "")
if BINARY:  # absolute: the quick-start test runs in another directory
    BINARY = os.environ["MANIPID_BIN"] = os.path.abspath(BINARY)

try:
    import numpy
except ImportError:
    numpy = None


def simulate_csv(path: str, *arguments: str) -> str:
    subprocess.run([BINARY, "simulate", "--out", path, *arguments], check=True, stderr=subprocess.DEVNULL)
    with open(path) as stream:
        return stream.read()


class TtyBuffer(io.StringIO):
    """A stream that says it is a terminal, to see the live progress line."""

    def isatty(self) -> bool:
        return True


@unittest.skipUnless(BINARY, "no manipid binary: set MANIPID_BIN or build build/release")
class AgainstServer(unittest.TestCase):
    """One server and one paper identification for the class (keeps the ASan run short)."""

    @classmethod
    def setUpClass(cls) -> None:
        cls.stack = contextlib.ExitStack()
        cls.directory = cls.stack.enter_context(tempfile.TemporaryDirectory(prefix="manipid-client-test-"))
        cls.csv_path = os.path.join(cls.directory, "run.csv")
        cls.csv = simulate_csv(cls.csv_path)
        cls.url = cls.stack.enter_context(local_server(workers=2))
        cls.client = Client(cls.url)
        cls.dataset = cls.client.upload_dataset(cls.csv_path)
        cls.job = cls.client.identify(cls.dataset, preset="cedro2009")
        cls.result = cls.job.wait(timeout=300)

    @classmethod
    def tearDownClass(cls) -> None:
        cls.stack.close()

    def test_upload_csv_path(self) -> None:
        self.assertIsInstance(self.dataset, Dataset)
        self.assertTrue(self.dataset.id.startswith("ds_"))
        self.assertEqual((self.dataset.joints, self.dataset.samples), (4, 9701))
        self.assertTrue(self.dataset.has_torque and self.dataset.has_reference)
        self.assertEqual(self.client.dataset_csv(self.dataset), self.csv)
        self.assertEqual(self.client.dataset(self.dataset.id).samples, 9701)

    def test_identify_wait_result_is_the_papers(self) -> None:
        self.assertEqual(self.job.state, "succeeded")
        self.assertAlmostEqual(self.result["estimates"]["m2"], 25.0, delta=0.01)
        self.assertEqual(self.job.result(), self.result)
        self.assertEqual(self.job.dataset_id, self.dataset.id)
        self.assertEqual(self.job.progress["evaluations"], self.result["evaluations"])

    def test_history_pages_through_every_evaluation(self) -> None:
        history = self.job.history(page_size=700)  # several pages
        self.assertEqual(len(history), self.result["evaluations"])
        self.assertEqual([entry["index"] for entry in history], list(range(len(history))))
        self.assertEqual(min(entry["cost"] for entry in history), self.result["final_cost"])
        self.assertEqual(sorted(history[0]["parameters"]), sorted(self.result["estimates"]))
        self.assertEqual(len(self.job.history_csv().strip().split("\n")), len(history) + 1)

    def test_plotting_helpers(self) -> None:
        overview = self.job.history_overview(max_points=100)
        self.assertEqual(overview["total"], self.result["evaluations"])
        self.assertLessEqual(len(overview["items"]), 102)
        fit = self.job.fit(max_points=300)
        self.assertEqual(len(fit["joints"]), 4)
        self.assertLessEqual(len(fit["t"]), 301)
        self.assertAlmostEqual(sum(joint["rms_residual"] ** 2 for joint in fit["joints"]), self.result["final_cost"],
                               delta=1e-6 * self.result["final_cost"])
        data = self.client.dataset_data(self.dataset)
        self.assertEqual(len(data["t"]), 9701)
        self.assertEqual(len(self.client.dataset_data(self.dataset, max_points=100)["t"]), 100)
        preset = self.client.preset("cedro2009")
        self.assertEqual(preset["true_parameters"]["m2"], 25)
        # What the data cannot determine alone has no estimate: m1 and l1 are None.
        self.assertIsNone(self.result["estimates"]["m1"])
        self.assertIsNone(self.result["estimates"]["l1"])

    @unittest.skipUnless(numpy, "numpy is not installed")
    def test_history_as_numpy(self) -> None:
        history = self.job.history(as_numpy=True)
        self.assertEqual(history.theta.shape, (self.result["evaluations"], len(history.names)))
        self.assertEqual(list(history.index), list(range(self.result["evaluations"])))
        self.assertEqual(float(history.cost.min()), self.result["final_cost"])

    def test_upload_arrays_per_joint_lists(self) -> None:
        rows = [[float(x) for x in line.split(",")] for line in self.csv.strip().split("\n")[1:400]]
        columns = [list(column) for column in zip(*rows)]
        dataset = self.client.upload_dataset(
            {"t": columns[0], "q": columns[1:5], "tau": columns[5:9], "ref": columns[9:13]}, name="first 399")
        self.assertEqual((dataset.name, dataset.samples, dataset.joints), ("first 399", 399, 4))
        self.assertEqual(dataset.csv().strip().split("\n")[1:], self.csv.strip().split("\n")[1:400])

    @unittest.skipUnless(numpy, "numpy is not installed")
    def test_upload_numpy_samples_by_joints(self) -> None:
        table = numpy.array([[float(x) for x in line.split(",")] for line in self.csv.strip().split("\n")[1:300]])
        dataset = self.client.upload_dataset({"dt": 0.001, "q": table[:, 1:5], "tau": table[:, 5:9]})
        self.assertEqual((dataset.samples, dataset.joints), (299, 4))

    def test_named_csv_upload_is_exact(self) -> None:
        dataset = self.client.upload_dataset(self.csv_path, name="paper run", idempotency_key="named-1")
        self.assertEqual(dataset.name, "paper run")
        self.assertEqual(dataset.csv(), self.csv)
        again = self.client.upload_dataset(self.csv_path, name="paper run", idempotency_key="named-1")
        self.assertEqual(again.id, dataset.id)

    def test_simulate_then_list(self) -> None:
        job = self.client.simulate(duration=0.5)
        self.assertIsInstance(job, Job)
        result = job.wait(timeout=120)
        self.assertEqual(result["samples"], 501)
        self.assertEqual(job.dataset_id, result["dataset_id"])
        ids = [dataset.id for dataset in self.client.datasets(page_size=1)]  # one per page
        self.assertIn(result["dataset_id"], ids)
        self.assertEqual(len(ids), len(set(ids)))
        simulations = list(self.client.jobs(state="succeeded", kind="simulation", page_size=1))
        self.assertIn(job.id, [j.id for j in simulations])
        self.assertTrue(all(j.kind == "simulation" for j in simulations))

    def test_cancel_a_running_output_error_job(self) -> None:
        job = self.client.identify(self.dataset, method="output-error", max_evaluations=100000)
        deadline = time.monotonic() + 60
        while not (job.state == "running" and job.progress.get("evaluations")) and time.monotonic() < deadline:
            time.sleep(0.05)
            job.refresh()
        self.assertEqual(job.state, "running")
        self.assertIs(job.cancel(), job)
        with self.assertRaises(JobCancelled) as caught:
            job.wait(timeout=120)
        self.assertEqual(job.state, "cancelled")
        self.assertEqual(caught.exception.result["stop_reason"], "cancelled")
        self.assertEqual(job.cancel().state, "cancelled")  # idempotent

    def test_errors_carry_the_problem_fields(self) -> None:
        with self.assertRaises(ManipidError) as caught:
            self.client.identify(self.dataset, max_evaluations="many")
        error = caught.exception
        self.assertEqual((error.status, error.code, error.field), (422, "INVALID_FIELD", "max_evaluations"))
        self.assertEqual(error.type, "/problems/invalid-field")
        self.assertTrue(error.title and error.detail)
        self.assertIn("INVALID_FIELD [max_evaluations]", str(error))

        with self.assertRaises(ManipidError) as caught:
            self.client.job("job_does_not_exist")
        self.assertEqual((caught.exception.status, caught.exception.code), (404, "NOT_FOUND"))
        with self.assertRaises(ManipidError) as caught:
            self.client.upload_dataset({"dt": 0.01, "q": [[0, 1, 2], [0, 1]]})
        self.assertEqual(caught.exception.field, "q[1]")

    def test_progress_without_a_terminal(self) -> None:
        job = self.client.identify(self.dataset, free=["m2"], max_evaluations=50)
        stream = io.StringIO()
        with contextlib.redirect_stderr(stream):
            result = job.wait(progress=True, timeout=120)
        self.assertIn("estimates", result)
        lines = stream.getvalue().splitlines()
        self.assertNotIn("\r", stream.getvalue())
        self.assertTrue(lines and lines[-1].startswith(f"{job.id} succeeded"), lines)

    def test_progress_on_a_terminal_rewrites_one_line(self) -> None:
        job = self.client.identify(self.dataset, free=["m2"], max_evaluations=50)
        stream = TtyBuffer()
        job.wait(progress=stream, timeout=120)
        text = stream.getvalue()
        self.assertTrue(text.startswith("\r") and text.endswith("\n"), repr(text))
        self.assertEqual(text.count("\n"), 1)
        self.assertIn("best cost", text)


@unittest.skipUnless(BINARY, "no manipid binary: set MANIPID_BIN or build build/release")
class LocalServerAndConnection(unittest.TestCase):
    def test_server_stops_and_cleans_up(self) -> None:
        with local_server() as url:
            self.assertRegex(url, r"^http://127\.0\.0\.1:\d+$")
            self.assertEqual(Client(url).health(), {"status": "ok"})
            process, directory = url.process, os.path.dirname(url.db)
        self.assertEqual(process.returncode, 0)  # SIGTERM: clean exit
        self.assertFalse(os.path.exists(directory))
        with self.assertRaises(ManipidConnectionError):
            Client(url, timeout=5).health()

    def test_token(self) -> None:
        with local_server(extra_args=("--token", "s3cret")) as url:
            with self.assertRaises(ManipidError) as caught:
                list(Client(url).jobs())
            self.assertEqual(caught.exception.code, "UNAUTHORIZED")
            self.assertEqual(list(Client(url, token="s3cret").jobs()), [])

    def test_binary_lookup(self) -> None:
        self.assertEqual(find_binary(BINARY), BINARY)
        with self.assertRaises(BinaryNotFound):
            with local_server(binary="/nonexistent/manipid"):
                pass
        saved = os.environ.get("MANIPID_BIN")
        try:
            os.environ["MANIPID_BIN"] = "/nonexistent/manipid"
            with self.assertRaises(BinaryNotFound) as caught:
                find_binary()
            self.assertIn("MANIPID_BIN", str(caught.exception))
        finally:
            os.environ["MANIPID_BIN"] = saved or ""

    def test_readme_quick_start_verbatim(self) -> None:
        readme = (PACKAGE_ROOT / "README.md").read_text()
        code = re.search(r"## Quick start.*?```python\n(.*?)```", readme, re.S).group(1)
        self.assertIn('client.upload_dataset("run.csv")', code)
        with tempfile.TemporaryDirectory(prefix="manipid-quick-start-") as directory:
            simulate_csv(os.path.join(directory, "run.csv"))
            environment = dict(os.environ, PYTHONPATH=str(PACKAGE_ROOT), MANIPID_BIN=BINARY)
            done = subprocess.run([sys.executable, "-c", code], cwd=directory, env=environment,
                                  capture_output=True, text=True, timeout=300)
        self.assertEqual(done.returncode, 0, done.stderr)
        estimates = eval(done.stdout.strip(), {})  # the printed dict
        self.assertAlmostEqual(estimates["m2"], 25.0, delta=0.01)
        self.assertIn("succeeded", done.stderr)  # progress on a non-terminal: a line per state


class WithoutServer(unittest.TestCase):
    def test_connection_refused(self) -> None:
        with self.assertRaises(ManipidConnectionError) as caught:
            Client("http://127.0.0.1:9", timeout=5).health()
        self.assertIsInstance(caught.exception, ConnectionError)

    def test_failed_job_raises_with_its_problem(self) -> None:
        job = Job(Client("http://127.0.0.1:9"), {"id": "job_x", "state": "failed", "error": {
            "type": "/problems/job-failed", "title": "The job failed", "status": 500,
            "code": "JOB_FAILED", "detail": "the integrator diverged"}})
        with self.assertRaises(JobFailed) as caught:
            job.wait()
        self.assertEqual(caught.exception.code, "JOB_FAILED")
        self.assertIn("job_x failed", str(caught.exception))
        self.assertIn("the integrator diverged", str(caught.exception))

    def test_bad_arguments(self) -> None:
        with self.assertRaises(ValueError):
            Client("localhost:8080")
        with self.assertRaises(ValueError):  # NaN is not JSON: refused before sending
            Client("http://127.0.0.1:9").upload_dataset({"dt": 1.0, "q": [[0.0, float("nan")]]})

    def test_version_matches_packaging(self) -> None:
        import manipid_client
        sys.path.insert(0, str(PACKAGE_ROOT / "_build"))
        try:
            import manipid_build
        finally:
            sys.path.pop(0)
        self.assertEqual(manipid_build._names()[2], manipid_client.__version__)


if __name__ == "__main__":
    unittest.main()
