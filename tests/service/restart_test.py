"""restart_test.py — nothing acknowledged is lost: SIGKILL the server while jobs are queued and
running, restart it on the same database, and every job that got a 202 finishes with a result.

Run: MANIPID_BIN=build/debug/server/manipid python3 -m unittest tests/service/restart_test.py
"""
import os
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, temporary_directory  # noqa: E402


class KillAndRestart(unittest.TestCase):
    def test_sigkill_with_queued_and_running_jobs(self):
        with temporary_directory() as directory:
            db = os.path.join(directory, "jobs.db")
            server = Server(db, workers=1).start()
            accepted = []
            # A slow job first (output-error simulates 12 s per evaluation) so the rest stay queued and the kill finds it
            # running in a Release build too.
            requests = [{"simulation": {"duration": 12.0}, "method": "output-error", "max_evaluations": 40}]
            requests += [{"simulation": {"duration": 1.0}, "half_length": 100, "band": 0.2, "free": ["m2", "m3"]}] * 3
            requests += [{"duration": 0.5}]  # a simulation job
            for index, body in enumerate(requests):
                path = "/v1/simulations" if "simulation" not in body else "/v1/identifications"
                status, _, job = server.request("POST", path, body)
                self.assertEqual(status, 202, job)
                accepted.append(job["id"])
            deadline = time.time() + 60
            while time.time() < deadline:
                _, _, first = server.request("GET", f"/v1/jobs/{accepted[0]}")
                if first["state"] == "running" and first["progress"]["evaluations"] > 0:
                    break
                time.sleep(0.05)
            self.assertEqual(first["state"], "running")
            server.kill()

            with Server(db, workers=2) as again:
                self.assertIn("interrupted job(s) queued again", again.read_log())
                for job_id in accepted:
                    job = again.wait_job(job_id)
                    self.assertEqual(job["state"], "succeeded", job)
                    self.assertIn("result", job)
                first = again.wait_job(accepted[0])
                self.assertGreaterEqual(first["attempts"], 2)
                # The history of the re-run is whole: indices 0..evaluations-1, once each.
                _, _, page = again.request("GET", f"/v1/jobs/{accepted[0]}/history?page_size=1000")
                indices = [entry["index"] for entry in page["items"]]
                self.assertEqual(indices, list(range(first["result"]["evaluations"])))
                _, _, jobs = again.request("GET", "/v1/jobs?page_size=1000")
                self.assertEqual(sorted(j["id"] for j in jobs["items"]), sorted(accepted))


if __name__ == "__main__":
    unittest.main()
