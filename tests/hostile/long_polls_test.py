"""long_polls_test.py — hostile-client suite: long-polls must not take every HTTP thread (item 6).

Each `GET /v1/jobs/{id}?wait=S` holds an HTTP thread while it waits (cpp-httplib 0.11.4 has no
other way), so `manipid serve` lets at most half of `--http-threads` wait at once; beyond that a
long-poll is answered at once with the job as it stands, `Retry-After: 1` and
`Manipid-Wait: declined`, and /healthz, uploads and reads keep their threads.

Run: MANIPID_BIN=build/debug/server/manipid python3 tests/hostile/long_polls_test.py -v
"""
import os
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "service"))
from harness import Server, temporary_directory  # noqa: E402

LONG_JOB = {"simulation": {"preset": "cedro2009"}, "preset": "cedro2009", "method": "output-error"}


class LongPolls(unittest.TestCase):
    def test_waiters_beyond_half_the_threads_are_answered_at_once(self):
        with temporary_directory() as directory:
            # 4 HTTP threads: 2 may wait. One worker busy with a long job keeps the second queued.
            with Server(os.path.join(directory, "jobs.db"), "--http-threads", "4", workers=1) as server:
                status, _, busy = server.request("POST", "/v1/identifications", LONG_JOB)
                self.assertEqual(status, 202, busy)
                status, _, queued = server.request("POST", "/v1/identifications", LONG_JOB)
                self.assertEqual(status, 202, queued)
                path = f"/v1/jobs/{queued['id']}?wait=8"

                answers = []
                def wait():
                    started = time.monotonic()
                    status, headers, job = server.request("GET", path)
                    answers.append((status, headers, job, time.monotonic() - started))
                waiters = [threading.Thread(target=wait) for _ in range(2)]
                for waiter in waiters:
                    waiter.start()
                time.sleep(1.0)  # both are waiting now

                started = time.monotonic()
                status, headers, job = server.request("GET", path)
                declined_after = time.monotonic() - started
                self.assertEqual(status, 200, job)
                self.assertEqual(headers.get("manipid-wait"), "declined", headers)
                self.assertEqual(headers.get("retry-after"), "1", headers)
                self.assertEqual(job["state"], "queued")
                self.assertLess(declined_after, 4.0, "a declined long-poll is answered at once")

                started = time.monotonic()
                status, _, health = server.request("GET", "/healthz")
                self.assertEqual(status, 200, health)
                self.assertLess(time.monotonic() - started, 4.0, "/healthz keeps a thread")

                for waiter in waiters:
                    waiter.join(60)
                self.assertEqual(len(answers), 2)
                for status, headers, job, seconds in answers:
                    self.assertEqual(status, 200, job)
                    self.assertNotIn("manipid-wait", headers)
                    self.assertGreater(seconds, 5.0, "the first two really waited")

                # Their slots are free again: the next long-poll waits.
                started = time.monotonic()
                status, headers, job = server.request("GET", f"/v1/jobs/{queued['id']}?wait=1")
                self.assertNotIn("manipid-wait", headers)
                self.assertGreater(time.monotonic() - started, 0.8)
                sys.stderr.write(f"declined long-poll answered in {1000 * declined_after:.0f} ms\n")

                for job_id in (queued["id"], busy["id"]):
                    server.request("POST", f"/v1/jobs/{job_id}/cancel")


if __name__ == "__main__":
    unittest.main()
