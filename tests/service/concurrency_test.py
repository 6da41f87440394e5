"""concurrency_test.py — 200 submissions from 8 client threads, with repeated Idempotency-Keys
mixed in: exactly the right number of jobs, all succeed, and no client ever sees a 5xx (no
SQLITE_BUSY surfaces).

Run: MANIPID_BIN=build/debug/server/manipid python3 -m unittest tests/service/concurrency_test.py
"""
import os
import sys
import threading
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, temporary_directory  # noqa: E402

THREADS = 8
PER_THREAD = 25
REPEATED_KEYS = 10  # submissions 0..9 of every thread reuse keys shared by all threads


class ConcurrentSubmissions(unittest.TestCase):
    def test_200_submissions_from_8_threads(self):
        with temporary_directory() as directory:
            with Server(os.path.join(directory, "jobs.db"), workers=2) as server:
                status, _, dataset = server.request("POST", "/v1/datasets", {
                    "dt": 0.001, "q": [[0.001 * i * i * (j + 1) for i in range(300)] for j in range(4)],
                    "tau": [[0.1 * i + j for i in range(300)] for j in range(4)]})
                self.assertEqual(status, 201, dataset)
                results, failures = [], []
                lock = threading.Lock()

                def submit(thread):
                    for n in range(PER_THREAD):
                        if n < REPEATED_KEYS:
                            key = f"shared-{n}"  # all 8 threads race on these 10 keys
                            body = {"duration": 0.05 + 0.01 * n}
                            path = "/v1/simulations"
                        else:
                            key = f"thread-{thread}-{n}"
                            if n % 2:
                                body = {"duration": 0.05}
                                path = "/v1/simulations"
                            else:
                                body = {"dataset_id": dataset["id"], "preset": "cedro2009", "half_length": 20,
                                        "band": 0.5, "free": ["m2"], "max_evaluations": 60}
                                path = "/v1/identifications"
                        try:
                            status, _, job = server.request("POST", path, body, {"Idempotency-Key": key})
                        except Exception as error:  # noqa: BLE001 - recorded, asserted below
                            with lock:
                                failures.append(repr(error))
                            continue
                        with lock:
                            (results if status == 202 else failures).append((key, status, job))

                threads = [threading.Thread(target=submit, args=(t,)) for t in range(THREADS)]
                for thread in threads:
                    thread.start()
                for thread in threads:
                    thread.join()

                self.assertEqual(failures, [])
                self.assertEqual(len(results), THREADS * PER_THREAD)
                by_key = {}
                for key, _, job in results:
                    by_key.setdefault(key, set()).add(job["id"])
                self.assertTrue(all(len(ids) == 1 for ids in by_key.values()), "a key produced two jobs")
                expected_jobs = REPEATED_KEYS + THREADS * (PER_THREAD - REPEATED_KEYS)
                self.assertEqual(len(by_key), expected_jobs)

                listed, token = [], None
                while True:
                    path = "/v1/jobs?page_size=100" + (f"&page_token={token}" if token else "")
                    status, _, page = server.request("GET", path)
                    self.assertEqual(status, 200)
                    listed += page["items"]
                    token = page.get("next_page_token")
                    if not token:
                        break
                self.assertEqual(len(listed), expected_jobs)
                for ids in by_key.values():
                    job = server.wait_job(next(iter(ids)))
                    self.assertEqual(job["state"], "succeeded", job)
                self.assertNotIn("SQLITE_BUSY", server.read_log())
                self.assertNotIn("database is locked", server.read_log())


if __name__ == "__main__":
    unittest.main()
