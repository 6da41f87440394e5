"""api_test.py — the service's main flows against the real binary on port 0 with a real SQLite
file: the paper's experiment by upload + identify and by one simulate+identify request (the
estimates must equal `manipid identify`'s on the same data), job life cycle (wait, history,
cancel, delete), datasets, idempotency, auth, health, metrics and the OpenAPI document.

Run: MANIPID_BIN=build/debug/server/manipid python3 -m unittest tests/service/api_test.py
"""
import json
import math
import os
import subprocess
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, identify_cli, simulate_csv, temporary_directory  # noqa: E402


class PaperExperiment(unittest.TestCase):
    """One server for the whole class: the paper's case, uploaded and simulated."""

    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        cls.csv_path = os.path.join(cls.directory.name, "paper.csv")
        cls.csv = simulate_csv(cls.csv_path)
        cls.server = Server(os.path.join(cls.directory.name, "jobs.db")).start()

    @classmethod
    def tearDownClass(cls):
        status = cls.server.stop()
        cls.directory.cleanup()
        assert status == 0, f"SIGTERM should exit 0, got {status}"

    def upload(self, body=None, headers=None):
        status, answer, dataset = self.server.request(
            "POST", "/v1/datasets", body if body is not None else self.csv,
            {"Content-Type": "text/csv", **(headers or {})})
        self.assertEqual(status, 201, dataset)
        return answer, dataset

    def test_upload_then_identify_equals_the_command_line(self):
        answer, dataset = self.upload()
        self.assertEqual(answer["location"], f"/v1/datasets/{dataset['id']}")
        self.assertEqual((dataset["joints"], dataset["samples"]), (4, 9701))
        self.assertAlmostEqual(dataset["dt"], 0.001, places=12)
        self.assertTrue(dataset["has_torque"] and dataset["has_reference"])

        status, answer, job = self.server.request(
            "POST", "/v1/identifications", {"dataset_id": dataset["id"], "preset": "cedro2009"})
        self.assertEqual(status, 202, job)
        self.assertEqual(answer["location"], f"/v1/jobs/{job['id']}")
        self.assertIn(job["state"], ("queued", "running", "succeeded"))
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "succeeded", job)

        reference = identify_cli(self.csv_path)
        result = job["result"]
        for name, value in reference["estimates"].items():
            if value is None:
                self.assertIsNone(result["estimates"][name], msg=name)
            else:
                self.assertAlmostEqual(result["estimates"][name], value, delta=1e-9 * abs(value), msg=name)
        self.assertEqual(result["final_cost"], reference["final_cost"])
        # m1 and l1 have no estimate of their own: null, and only their product is given.
        self.assertIsNone(result["estimates"]["m1"])
        self.assertIsNone(result["estimates"]["l1"])
        self.assertAlmostEqual(result["point"]["m1"] * result["point"]["l1"] ** 2,
                               result["identifiability"]["combinations"][0]["value"], delta=1e-9)
        # The paper's m2 = 25 kg from noise-free data; m1 and l1 are named as unidentifiable.
        self.assertAlmostEqual(result["estimates"]["m2"], 25.0, delta=0.01)
        self.assertEqual(sorted(result["identifiability"]["unidentifiable"]), ["l1", "m1"])
        self.assertEqual(result["identifiability"]["combinations"][0]["name"], "m1*l1^2")
        self.assertIsNone(result["std_errors"]["m1"])
        self.assertEqual(job["progress"]["evaluations"], result["evaluations"])
        # An uploaded file says nothing of the robot that made it: no true values (not the preset's).
        self.assertIsNone(result["truth"])

        # The whole history is stored and pages through to the same count.
        entries, token = [], None
        while True:
            path = f"/v1/jobs/{job['id']}/history?page_size=400" + (f"&page_token={token}" if token else "")
            status, _, page = self.server.request("GET", path)
            self.assertEqual(status, 200, page)
            entries += page["items"]
            token = page.get("next_page_token")
            if not token:
                break
        self.assertEqual(len(entries), result["evaluations"])
        self.assertEqual([entry["index"] for entry in entries], list(range(len(entries))))
        self.assertEqual(min(entry["cost"] for entry in entries), result["final_cost"])
        status, answer, text = self.server.request("GET", f"/v1/jobs/{job['id']}/history", headers={"Accept": "text/csv"})
        self.assertEqual(status, 200)
        lines = text.strip().split("\n")
        self.assertEqual(lines[0], "index,cost,m1,m2,m3,m4,l1,l2,l3,l4")
        self.assertEqual(len(lines) - 1, result["evaluations"])

    def test_one_request_runs_the_whole_paper_experiment(self):
        status, _, job = self.server.request(
            "POST", "/v1/identifications", {"simulation": {"preset": "cedro2009"}, "preset": "cedro2009"})
        self.assertEqual(status, 202, job)
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "succeeded", job)
        self.assertTrue(job["dataset_id"].startswith("ds_"))
        # The simulated dataset is the paper's run, bit for bit what `manipid simulate` writes.
        status, _, text = self.server.request("GET", f"/v1/datasets/{job['dataset_id']}?format=csv")
        self.assertEqual(status, 200)
        self.assertEqual(text, self.csv)
        reference = identify_cli(self.csv_path)
        for name, value in reference["point"].items():
            self.assertAlmostEqual(job["result"]["point"][name], value, delta=1e-9 * abs(value), msg=name)
        # The data were simulated here: the simulation's own parameters are the truth.
        self.assertEqual(job["result"]["truth"], {"m1": 50, "m2": 25, "m3": 15, "m4": 5,
                                                  "l1": 0.4, "l2": 0.8, "l3": 0.6, "l4": 0.2})

    def test_truth_is_what_is_known(self):
        # Values the user gives are shown as given; names are checked like the other parameter maps.
        _, dataset = self.upload()
        request = {"dataset_id": dataset["id"], "half_length": 100, "band": 0.2, "truth": {"m2": 25, "l2": 0.8}}
        status, _, job = self.server.request("POST", "/v1/identifications", request)
        self.assertEqual(status, 202, job)
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "succeeded", job)
        self.assertEqual(job["result"]["truth"], {"m2": 25, "l2": 0.8})
        status, _, problem = self.server.request("POST", "/v1/identifications", {**request, "truth": {"m9": 1}})
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["field"], "truth.m9", problem)
        # A dataset a simulation job made: that simulation's parameters.
        status, _, simulation = self.server.request(
            "POST", "/v1/simulations", {"preset": "cedro2009", "duration": 1.0, "parameters": {"m2": 21}})
        simulation = self.server.wait_job(simulation["id"])
        self.assertEqual(simulation["state"], "succeeded", simulation)
        status, _, job = self.server.request(
            "POST", "/v1/identifications", {"dataset_id": simulation["dataset_id"], "half_length": 100, "band": 0.2})
        self.assertEqual(status, 202, job)
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "succeeded", job)
        self.assertEqual(job["result"]["truth"]["m2"], 21)
        self.assertEqual(job["result"]["truth"]["m3"], 15)

    def test_simulation_job_creates_a_dataset(self):
        status, _, job = self.server.request("POST", "/v1/simulations", {"preset": "cedro2009", "duration": 1.0})
        self.assertEqual(status, 202, job)
        self.assertEqual(job["kind"], "simulation")
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "succeeded", job)
        dataset_id = job["result"]["dataset_id"]
        status, _, dataset = self.server.request("GET", f"/v1/datasets/{dataset_id}")
        self.assertEqual(status, 200)
        self.assertEqual(dataset["samples"], 1001)
        self.assertEqual(dataset["source_job"], job["id"])

    def test_json_dataset_equals_csv_dataset(self):
        rows = [line.split(",") for line in self.csv.strip().split("\n")[1:400]]
        columns = list(zip(*[[float(x) for x in row] for row in rows]))
        body = {"name": "first 399 samples", "t": columns[0], "q": columns[1:5], "tau": columns[5:9], "ref": columns[9:13]}
        _, dataset = self.upload(body, {"Content-Type": "application/json"})
        self.assertEqual(dataset["name"], "first 399 samples")
        self.assertEqual(dataset["samples"], 399)
        status, _, text = self.server.request("GET", f"/v1/datasets/{dataset['id']}", headers={"Accept": "text/csv"})
        self.assertEqual(status, 200)
        self.assertEqual(text.strip().split("\n")[1:], self.csv.strip().split("\n")[1:400])

    def test_idempotency_key_returns_the_first_job(self):
        _, dataset = self.upload()
        request = {"dataset_id": dataset["id"], "half_length": 100, "band": 0.2, "free": ["m2"]}
        headers = {"Idempotency-Key": "lab-run-42"}
        _, _, first = self.server.request("POST", "/v1/identifications", request, headers)
        status, answer, again = self.server.request("POST", "/v1/identifications", request, headers)
        self.assertEqual(status, 202)
        self.assertEqual(again["id"], first["id"])
        self.assertEqual(answer.get("idempotent-replayed"), "true")
        status, _, problem = self.server.request("POST", "/v1/identifications", {**request, "free": ["m3"]}, headers)
        self.assertEqual(status, 422, problem)
        self.assertEqual(problem["code"], "IDEMPOTENCY_MISMATCH")
        # Datasets too: the same upload under the same key is the same dataset.
        _, again_dataset = self.upload(headers={"Idempotency-Key": "upload-1"})
        _, replay = self.upload(headers={"Idempotency-Key": "upload-1"})
        self.assertEqual(replay["id"], again_dataset["id"])
        self.server.wait_job(first["id"])

    def test_cancel_a_running_job_and_delete_rules(self):
        _, dataset = self.upload()
        # Output-error simulates the closed loop per evaluation: slow enough to catch running.
        status, _, job = self.server.request("POST", "/v1/identifications", {
            "dataset_id": dataset["id"], "method": "output-error", "max_evaluations": 100000, "max_seconds": 600})
        self.assertEqual(status, 202, job)
        deadline = time.time() + 60
        while time.time() < deadline:
            _, _, job = self.server.request("GET", f"/v1/jobs/{job['id']}")
            if job["state"] == "running" and job["progress"]["evaluations"] > 0:
                break
            time.sleep(0.05)
        self.assertEqual(job["state"], "running", job)
        self.assertGreater(job["progress"]["evaluations"], 0)
        status, _, problem = self.server.request("DELETE", f"/v1/jobs/{job['id']}")
        self.assertEqual(status, 409, problem)
        self.assertEqual(problem["code"], "CONFLICT")
        status, _, cancelled = self.server.request("POST", f"/v1/jobs/{job['id']}/cancel")
        self.assertEqual(status, 200, cancelled)
        job = self.server.wait_job(job["id"], timeout=120)
        self.assertEqual(job["state"], "cancelled", job)
        self.assertEqual(job["result"]["stop_reason"], "cancelled")
        # Cancelling again changes nothing; deleting a finished job works once.
        status, _, again = self.server.request("POST", f"/v1/jobs/{job['id']}:cancel")
        self.assertEqual((status, again["state"]), (200, "cancelled"))
        self.assertEqual(self.server.request("DELETE", f"/v1/jobs/{job['id']}")[0], 204)
        self.assertEqual(self.server.request("DELETE", f"/v1/jobs/{job['id']}")[0], 404)
        self.assertEqual(self.server.request("GET", f"/v1/jobs/{job['id']}")[0], 404)

    def test_lists_page_and_filter(self):
        for _ in range(3):
            self.upload()
        status, _, page = self.server.request("GET", "/v1/datasets?page_size=2")
        self.assertEqual(status, 200)
        self.assertEqual(len(page["items"]), 2)
        status, _, rest = self.server.request("GET", f"/v1/datasets?page_size=1000&page_token={page['next_page_token']}")
        self.assertEqual(status, 200)
        ids = [d["id"] for d in page["items"] + rest["items"]]
        self.assertEqual(len(ids), len(set(ids)))
        self.assertNotIn("next_page_token", rest)
        status, _, jobs = self.server.request("GET", "/v1/jobs?kind=simulation&state=succeeded")
        self.assertEqual(status, 200)
        self.assertTrue(all(j["kind"] == "simulation" and j["state"] == "succeeded" for j in jobs["items"]))
        status, _, problem = self.server.request("GET", "/v1/jobs?state=done")
        self.assertEqual((status, problem["field"]), (422, "state"))

    def test_delete_dataset(self):
        _, dataset = self.upload()
        self.assertEqual(self.server.request("DELETE", f"/v1/datasets/{dataset['id']}")[0], 204)
        self.assertEqual(self.server.request("GET", f"/v1/datasets/{dataset['id']}")[0], 404)

    def test_health_metrics_openapi_and_etag(self):
        status, _, health = self.server.request("GET", "/healthz")
        self.assertEqual((status, health["status"]), (200, "ok"))
        status, answer, spec = self.server.request("GET", "/openapi.json")
        self.assertEqual(status, 200)
        self.assertTrue(spec["openapi"].startswith("3."))
        for path in ("/v1/datasets", "/v1/identifications", "/v1/simulations", "/v1/jobs/{id}", "/v1/jobs/{id}/history",
                     "/v1/jobs/{id}/fit", "/v1/datasets/{id}/data"):
            self.assertIn(path, spec["paths"])
        status, _, job = self.server.request("POST", "/v1/simulations", {"duration": 0.2})
        job = self.server.wait_job(job["id"])
        status, answer, _ = self.server.request("GET", f"/v1/jobs/{job['id']}")
        status, _, _ = self.server.request("GET", f"/v1/jobs/{job['id']}", headers={"If-None-Match": answer["etag"]})
        self.assertEqual(status, 304)
        status, _, text = self.server.request("GET", "/metrics")
        self.assertEqual(status, 200)
        self.assertIn('manipid_jobs{state="succeeded"}', text)
        self.assertIn("manipid_queue_depth 0", text)
        self.assertIn("manipid_job_duration_seconds_count", text)
        self.assertIn('manipid_http_requests_total{method="GET",status="200"}', text)


class Authentication(unittest.TestCase):
    def test_token_guards_v1_and_metrics(self):
        with temporary_directory() as directory:
            with Server(os.path.join(directory, "jobs.db"), "--token", "s3cret") as server:
                status, answer, problem = server.request("GET", "/v1/jobs")
                self.assertEqual(status, 401)
                self.assertEqual(answer["content-type"], "application/problem+json")
                self.assertEqual(problem["code"], "UNAUTHORIZED")
                self.assertEqual(server.request("GET", "/v1/jobs", headers={"Authorization": "Bearer wrong"})[0], 401)
                self.assertEqual(server.request("GET", "/v1/jobs", headers={"Authorization": "Bearer s3cret"})[0], 200)
                self.assertEqual(server.request("GET", "/healthz")[0], 200)
                # /metrics tells job counts and memory: the token's too (it was open).
                self.assertEqual(server.request("GET", "/metrics")[0], 401)
                self.assertEqual(server.request("GET", "/metrics", headers={"Authorization": "Bearer s3cret"})[0], 200)


class Shutdown(unittest.TestCase):
    def test_sigterm_requeues_a_running_job_and_a_restart_finishes_it(self):
        with temporary_directory() as directory:
            db = os.path.join(directory, "jobs.db")
            server = Server(db).start()
            # Long enough that the signal finds it running in a Release build too (each evaluation simulates
            # 12 s: about 6 ms there, 60 ms under the sanitizers).
            status, _, job = server.request("POST", "/v1/identifications", {
                "simulation": {"duration": 12.0}, "method": "output-error", "max_evaluations": 60})
            self.assertEqual(status, 202, job)
            deadline = time.time() + 60
            while time.time() < deadline:
                _, _, seen = server.request("GET", f"/v1/jobs/{job['id']}")
                if seen["progress"]["evaluations"] > 0:
                    break
                time.sleep(0.05)
            self.assertEqual(server.stop(), 0)
            self.assertIn("queued again (shutdown)", server.read_log())
            with Server(db) as again:
                finished = again.wait_job(job["id"])
                self.assertEqual(finished["state"], "succeeded", finished)
                self.assertEqual(finished["attempts"], 2)


if __name__ == "__main__":
    unittest.main()
