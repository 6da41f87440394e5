"""plots_test.py — the drawing endpoints against the real binary on port 0 with a real SQLite
file: a dataset's data as JSON (full, which uploads back unchanged, and thinned), a cost
history thinned for drawing (first, best and last always there), and the torque fit at an
identification's estimate (its mean square residual is the reported cost), the presets the
dashboard's form starts from, with their errors.

Run: MANIPID_BIN=build/debug/server/manipid python3 -m unittest tests/service/plots_test.py
"""
import gzip
import http.client
import json
import math
import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, simulate_csv, temporary_directory  # noqa: E402


class DrawingEndpoints(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        cls.csv = simulate_csv(os.path.join(cls.directory.name, "paper.csv"))
        cls.server = Server(os.path.join(cls.directory.name, "jobs.db")).start()
        status, _, cls.dataset = cls.server.request("POST", "/v1/datasets", cls.csv, {"Content-Type": "text/csv"})
        assert status == 201, cls.dataset
        # The paper's filter and torque from the reference, as in its experiment.
        status, _, job = cls.server.request("POST", "/v1/identifications", {
            "dataset_id": cls.dataset["id"], "half_length": 100, "band": 0.2, "torque_source": "reference"})
        assert status == 202, job
        cls.job = cls.server.wait_job(job["id"])
        assert cls.job["state"] == "succeeded", cls.job

    @classmethod
    def tearDownClass(cls):
        status = cls.server.stop()
        cls.directory.cleanup()
        assert status == 0, f"SIGTERM should exit 0, got {status}"

    def get(self, path, expected=200, headers=None):
        status, _, body = self.server.request("GET", path, headers=headers)
        self.assertEqual(status, expected, body)
        return body

    def test_dataset_data_as_json_uploads_back_unchanged(self):
        data = self.get(f"/v1/datasets/{self.dataset['id']}/data")
        self.assertEqual(len(data["t"]), 9701)
        self.assertEqual([len(joint) for joint in data["q"]], [9701] * 4)
        self.assertEqual(len(data["tau"]), 4)
        self.assertEqual(len(data["ref"]), 4)
        status, _, copy = self.server.request("POST", "/v1/datasets", data)
        self.assertEqual(status, 201, copy)
        original = self.get(f"/v1/datasets/{self.dataset['id']}?format=csv")
        self.assertEqual(self.get(f"/v1/datasets/{copy['id']}?format=csv"), original)

    def test_dataset_data_thinned_keeps_both_ends(self):
        data = self.get(f"/v1/datasets/{self.dataset['id']}/data?max_points=100")
        # ceil(9701 / 100) = 98: samples 0, 98, ..., 9604, and the last, 9700.
        self.assertEqual(len(data["t"]), 100)
        self.assertEqual(data["t"][0], 0.0)
        self.assertAlmostEqual(data["t"][1], 0.098, places=12)
        self.assertAlmostEqual(data["t"][-1], 9.7, places=12)
        text = self.get(f"/v1/datasets/{self.dataset['id']}/data?max_points=100", headers={"Accept": "text/csv"})
        lines = text.strip().split("\n")
        self.assertEqual(lines[0], self.csv.split("\n")[0])
        self.assertEqual(len(lines), 101)
        self.assertEqual(lines[-1], self.csv.strip().split("\n")[-1])

    def test_history_thinned_for_drawing(self):
        job_id = self.job["id"]
        evaluations = self.job["result"]["evaluations"]
        full = self.get(f"/v1/jobs/{job_id}/history", headers={"Accept": "text/csv"}).strip().split("\n")[1:]
        costs = [float(line.split(",")[1]) for line in full]
        self.assertEqual(len(costs), evaluations)

        overview = self.get(f"/v1/jobs/{job_id}/history?max_points=50")
        self.assertEqual(overview["total"], evaluations)
        self.assertEqual(overview["stride"], math.ceil(evaluations / 50))
        indices = [item["index"] for item in overview["items"]]
        self.assertEqual(indices, sorted(indices))
        self.assertLessEqual(len(indices), 52)
        self.assertEqual(indices[0], 0)
        self.assertEqual(indices[-1], evaluations - 1)
        best = min(range(len(costs)), key=lambda i: (costs[i], i))
        self.assertEqual(overview["best_index"], best)
        self.assertIn(best, indices)
        for item in overview["items"]:
            self.assertEqual(item["cost"], costs[item["index"]])
            self.assertEqual(sorted(item["parameters"]), ["l1", "l2", "l3", "l4", "m1", "m2", "m3", "m4"])
        # Fewer entries than max_points: all of them.
        everything = self.get(f"/v1/jobs/{job_id}/history?max_points={evaluations + 10}")
        self.assertEqual(everything["stride"], 1)
        self.assertEqual(len(everything["items"]), evaluations)

    def test_fit_at_the_estimate(self):
        result = self.job["result"]
        fit = self.get(f"/v1/jobs/{self.job['id']}/fit?max_points=500")
        self.assertEqual(fit["filter"], {"half_length": 100, "band": 0.2, "dt": result["filter"]["dt"]})
        self.assertEqual(fit["torque_source"], "reference")
        self.assertEqual(fit["samples"], 9701 - 201)
        self.assertEqual(fit["parameters"], result["point"])
        self.assertLessEqual(len(fit["t"]), 501)
        self.assertAlmostEqual(fit["t"][0], 0.1, places=12)  # output j belongs to input sample M + j
        self.assertEqual(len(fit["joints"]), 4)
        for joint in fit["joints"]:
            self.assertEqual(len(joint["measured"]), len(fit["t"]))
            for measured, model, residual in zip(joint["measured"], joint["model"], joint["residual"]):
                self.assertAlmostEqual(residual, model - measured, delta=1e-9 * (1 + abs(measured)))
        # Σ_joints mean square residual is the input-error cost at the estimate.
        cost = sum(joint["rms_residual"] ** 2 for joint in fit["joints"])
        self.assertAlmostEqual(cost, result["final_cost"], delta=1e-6 * result["final_cost"])
        for joint in fit["joints"]:
            self.assertLess(joint["rms_residual"], 0.05 * joint["rms_measured"])

    def test_fit_of_an_output_error_job(self):
        # Output-error filters nothing: the fit shows its estimate through the default filter,
        # at the data's own sample period, with the measured torque.
        status, _, job = self.server.request("POST", "/v1/identifications", {
            "simulation": {"duration": 1.0, "dt": 0.002}, "method": "output-error", "max_evaluations": 3})
        self.assertEqual(status, 202, job)
        job = self.server.wait_job(job["id"])
        self.assertEqual(job["state"], "succeeded", job)
        fit = self.get(f"/v1/jobs/{job['id']}/fit")
        self.assertEqual(fit["filter"]["dt"], 0.002)
        self.assertEqual(fit["torque_source"], "measured")
        self.assertEqual(fit["samples"], 501 - 2 * fit["filter"]["half_length"] - 1)

    def test_presets_give_the_papers_values(self):
        presets = self.get("/v1/presets")["items"]
        self.assertIn("cedro2009", [preset["name"] for preset in presets])
        paper = self.get("/v1/presets/cedro2009?kinetic_energy=paper")
        self.assertEqual(paper["kinetic_energy"], "paper")
        self.assertEqual(paper["joints"], 4)
        self.assertEqual(paper["true_parameters"],
                         {"m1": 50, "m2": 25, "m3": 15, "m4": 5, "l1": 0.4, "l2": 0.8, "l3": 0.6, "l4": 0.2})
        self.assertEqual(paper["initial_parameters"]["m2"], 25.1)
        self.assertEqual(paper["kp"], [3800, 40000, 10000, 500])
        self.assertEqual(paper["kd"], [159.5, 120, 50, 2])
        self.assertEqual(paper["reference"]["step_times"], [1, 3, 5, 7])
        self.assertEqual(paper["simulation"], {"duration": 9.7, "dt": 0.001})
        _, _, problem = self.server.request("GET", "/v1/presets/puma560")
        self.assertEqual((problem["status"], problem["field"]), (404, "name"))
        self.assertIn("cedro2009", problem["detail"])
        _, _, problem = self.server.request("GET", "/v1/presets/cedro2009?kinetic_energy=full")
        self.assertEqual((problem["status"], problem["field"]), (422, "kinetic_energy"))

    def raw_get(self, path, headers):
        connection = http.client.HTTPConnection(self.server.host, self.server.port, timeout=60)
        try:
            connection.request("GET", path, headers=headers)
            response = connection.getresponse()
            return response.status, {k.lower(): v for k, v in response.getheaders()}, response.read()
        finally:
            connection.close()

    def test_browsers_get_gzip_never_brotli(self):
        # cpp-httplib 0.11.4's Brotli (quality 11) takes seconds for a large body; gzip is offered instead.
        path = f"/v1/jobs/{self.job['id']}/history?max_points=2000"
        plain = self.get(path)
        for accept, expected in (("gzip, deflate, br", "gzip"), ("br", None), ("BR;q=1.0, gzip;q=0.5", "gzip"), ("identity", None)):
            status, headers, body = self.raw_get(path, {"Accept-Encoding": accept})
            self.assertEqual(status, 200)
            self.assertEqual(headers.get("content-encoding"), expected, accept)
            self.assertEqual(json.loads(gzip.decompress(body) if expected == "gzip" else body), plain, accept)

    def test_the_dashboard_is_served(self):
        _, _, page = self.raw_get("/", {})
        if b"built without its dashboard" in page:
            self.skipTest("this manipid was built without web/node_modules (npm ci did not run)")
        for path in ("/", f"/jobs/{self.job['id']}"):
            status, headers, body = self.raw_get(path, {})
            self.assertEqual(status, 200, path)
            self.assertTrue(headers["content-type"].startswith("text/html"), path)
            self.assertIn("default-src 'self'", headers["content-security-policy"])
            self.assertIn(b'<script type="module" src="/assets/app.js">', body)
        for name, kind in (("app.js", "text/javascript"), ("app.css", "text/css"), ("uPlot.iife.min.js", "text/javascript")):
            status, headers, body = self.raw_get(f"/assets/{name}", {})
            self.assertEqual(status, 200, name)
            self.assertTrue(headers["content-type"].startswith(kind), name)
            self.assertEqual(headers["x-content-type-options"], "nosniff")
            self.assertGreater(len(body), 1000, name)
        status, _, problem = self.server.request("GET", "/assets/secret.db")
        self.assertEqual(status, 404)
        status, _, _ = self.server.request("GET", "/assets/..%2Fmanipid.db")
        self.assertEqual(status, 404)

    def test_errors_name_the_field(self):
        _, _, problem = self.server.request("GET", f"/v1/jobs/{self.job['id']}/fit?max_points=1")
        self.assertEqual((problem["status"], problem["field"]), (422, "max_points"))
        _, _, problem = self.server.request("GET", f"/v1/jobs/{self.job['id']}/history?max_points=x")
        self.assertEqual((problem["status"], problem["field"]), (422, "max_points"))
        _, _, problem = self.server.request("GET", f"/v1/jobs/{self.job['id']}/history?max_points=10&page_size=5")
        self.assertEqual((problem["status"], problem["field"]), (422, "max_points"))
        _, _, problem = self.server.request("GET", "/v1/jobs/job_0000000000000000/fit")
        self.assertEqual(problem["status"], 404)
        _, _, problem = self.server.request("GET", "/v1/datasets/ds_0000000000000000/data")
        self.assertEqual(problem["status"], 404)
        status, _, simulation = self.server.request("POST", "/v1/simulations", {"duration": 0.5})
        self.assertEqual(status, 202, simulation)
        self.server.wait_job(simulation["id"])
        _, _, problem = self.server.request("GET", f"/v1/jobs/{simulation['id']}/fit")
        self.assertEqual((problem["status"], problem["code"]), (409, "CONFLICT"))


if __name__ == "__main__":
    unittest.main()
