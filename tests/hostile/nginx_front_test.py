"""nginx_front_test.py — hostile-client suite: the same probes through nginx (docker/nginx.conf) in front of manipid.

A proxy that reads requests in an event loop hands manipid only whole requests (manipid itself
now holds no HTTP thread for a connection waiting for its head: connections_test.py). This
test runs Debian's nginx with docker/nginx.conf itself — only its ports, pid file, temporary
directories and user are pointed at the test's own — in front of the real `manipid serve` on
port 0, and sends the hostile probes through it: trickling heads and bodies, a 10 GB
Content-Length, two Content-Lengths, a smuggled request in a refused body, 50 long-polls. manipid
runs with 4 HTTP threads, fewer than the trickling clients; through nginx /healthz answers at once.
Times printed are measurements; the bounds asserted are generous behaviour checks, not benchmarks.

Skips (exit 77) when nginx is not installed (Debian package nginx, in [test]).

Run: MANIPID_BIN=build/debug/server/manipid python3 tests/hostile/nginx_front_test.py -v
"""
import os
import re
import shutil
import socket
import subprocess
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "service"))
from harness import Server, temporary_directory  # noqa: E402
from slow_clients_test import Trickler  # noqa: E402

SKIP = 77
CONF = os.path.join(os.path.dirname(__file__), "..", "..", "docker", "nginx.conf")


def free_port():
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class Nginx:
    """docker/nginx.conf with its user, pid file, temporary directories and both ports pointed at the test's."""

    def __init__(self, directory, upstream_port):
        self.directory = directory
        self.host, self.port = "127.0.0.1", free_port()
        with open(CONF) as stream:
            text = stream.read()
        replacements = [
            (r"^pid [^;\n]+;", f"pid {directory}/nginx.pid;"),
            (r"^  client_body_temp_path [^;\n]+;", f"  client_body_temp_path {directory}/body;"),
            (r"^  proxy_temp_path [^;\n]+;", f"  proxy_temp_path {directory}/proxy;"),
            (r"^    server manipid:8080;", f"    server 127.0.0.1:{upstream_port};"),
            (r"^    listen 8080 reuseport;", f"    listen {self.host}:{self.port};"),
            # Run by root (CI), nginx's workers switch to `user`, which must own the test's files;
            # run by anyone else, nginx stays that user and would warn about the directive.
            (r"^user [^;\n]+;", "user root;" if os.geteuid() == 0 else ""),
        ]
        for pattern, value in replacements:
            text, count = re.subn(pattern, value, text, flags=re.M)
            assert count == 1, f"docker/nginx.conf no longer has one line matching {pattern!r}"
        self.conf = os.path.join(directory, "nginx.conf")
        with open(self.conf, "w") as stream:
            stream.write(text)
        self.log = open(os.path.join(directory, "nginx.log"), "wb")
        self.process = subprocess.Popen(["nginx", "-p", directory, "-e", "stderr", "-c", self.conf, "-g", "daemon off;"],
                                        stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.time() + 10
        while time.time() < deadline:
            try:
                socket.create_connection((self.host, self.port), timeout=1).close()
                return
            except OSError:
                if self.process.poll() is not None:
                    break
                time.sleep(0.05)
        raise RuntimeError("nginx did not start: " + open(os.path.join(directory, "nginx.log")).read())

    def request(self, method, path, body=None, headers=None, timeout=120):
        return Server.request(self, method, path, body, headers, timeout)  # same client, other address

    def stop(self):
        self.process.terminate()
        self.process.wait(10)
        self.log.close()


def exchange(front, data, timeout=15.0, times=None):
    """Sends raw bytes on one connection; returns every byte received until the peer closes.
    `times`, a list, receives the seconds to the first byte of the answer."""
    connection = socket.create_connection((front.host, front.port), timeout=timeout)
    try:
        started = time.monotonic()
        connection.sendall(data)
        received = b""
        while True:
            try:
                chunk = connection.recv(65536)
            except socket.timeout:
                break
            if not chunk:
                break
            if not received and times is not None:
                times.append(time.monotonic() - started)
            received += chunk
        return received
    finally:
        connection.close()


def statuses(received):
    return [int(match) for match in re.findall(rb"HTTP/1\.1 (\d{3}) ", received)]


def healthz_seconds(front):
    started = time.monotonic()
    status = front.request("GET", "/healthz", timeout=30)[0]
    return status, time.monotonic() - started


@unittest.skipUnless(shutil.which("nginx"), "needs nginx (Debian package nginx)")
class ThroughNginx(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = temporary_directory()
        os.chmod(cls.directory.name, 0o755)
        cls.server = Server(os.path.join(cls.directory.name, "jobs.db"), "--http-threads", "4").start()
        cls.front = Nginx(cls.directory.name, cls.server.port)

    @classmethod
    def tearDownClass(cls):
        cls.front.stop()
        cls.server.stop()
        cls.directory.cleanup()

    def test_a_job_runs_end_to_end_through_the_proxy(self):
        status, headers, dataset = self.front.request(
            "POST", "/v1/datasets", {"name": "via nginx", "dt": 0.01, "q": [[0, 0.1, 0.2, 0.3]], "tau": [[1, 1, 1, 1]]})
        self.assertEqual(status, 201, dataset)
        status, _, found = self.front.request("GET", f"/v1/datasets/{dataset['id']}")
        self.assertEqual((status, found["name"]), (200, "via nginx"))
        status, _, job = self.front.request("POST", "/v1/simulations", {"duration": 0.5})
        self.assertEqual(status, 202, job)
        deadline = time.time() + 120
        while job["state"] not in ("succeeded", "failed", "cancelled") and time.time() < deadline:
            _, _, job = self.front.request("GET", f"/v1/jobs/{job['id']}?wait=5")
        self.assertEqual(job["state"], "succeeded", job)

    def test_32_trickling_heads_hold_no_manipid_thread(self):
        tricklers = [Trickler(self.front) for _ in range(32)]
        for trickler in tricklers:
            trickler.start()
        try:
            time.sleep(2.0)
            status, seconds = healthz_seconds(self.front)
            print(f"\n  /healthz through nginx with 32 trickling clients (manipid: 4 threads): "
                  f"{seconds * 1000:.1f} ms", file=sys.stderr)
            self.assertEqual(status, 200)
            self.assertLess(seconds, 5.0)  # straight to manipid: up to the 10 s header deadline
            status, direct = healthz_seconds(self.server)
            self.assertEqual(status, 200)
            self.assertLess(direct, 5.0)  # manipid's own threads are free: nginx holds the tricklers
        finally:
            for trickler in tricklers:
                trickler.stop()

    def test_stalled_bodies_are_held_and_cut_off_by_nginx(self):
        # Head and half a body, then nothing: nginx's client_body_timeout (10 s) ends each; manipid
        # never sees them (straight to manipid each would hold a thread, outside its 4, until its deadline).
        body = b'{"name": "stalled", "dt": 0.01, "q": [[0, 0.1, 0.2]], "tau": [[1, 1, 1]]}'
        head = (b"POST /v1/datasets HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                b"Content-Length: %d\r\n\r\n" % len(body))
        closed_after = [None] * 8

        def stall(index):
            connection = socket.create_connection((self.front.host, self.front.port), timeout=40)
            started = time.monotonic()
            try:
                connection.sendall(head + body[: len(body) // 2])
                while connection.recv(65536):
                    pass
                closed_after[index] = time.monotonic() - started
            except OSError:
                closed_after[index] = time.monotonic() - started
            finally:
                connection.close()

        stallers = [threading.Thread(target=stall, args=(index,), daemon=True) for index in range(8)]
        for staller in stallers:
            staller.start()
        time.sleep(1.0)
        status, seconds = healthz_seconds(self.front)
        self.assertEqual(status, 200)
        print(f"\n  /healthz through nginx with 8 stalled bodies (manipid: 4 threads): {seconds * 1000:.1f} ms",
              file=sys.stderr)
        self.assertLess(seconds, 5.0)
        for staller in stallers:
            staller.join(45)
        self.assertNotIn(None, closed_after, "nginx kept a stalled body for 40 s")
        print(f"  stalled bodies cut off by nginx after {min(closed_after):.1f}–{max(closed_after):.1f} s",
              file=sys.stderr)
        self.assertTrue(all(8.0 < seconds < 20.0 for seconds in closed_after), closed_after)
        _, _, datasets = self.front.request("GET", "/v1/datasets?page_size=100")
        self.assertNotIn("stalled", [item["name"] for item in datasets["items"]])

    def test_10_gb_declared_is_refused_from_the_headers(self):
        times = []
        received = exchange(self.front, b"POST /v1/datasets HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                                        b"Content-Length: 10737418240\r\n\r\n", times=times)
        print(f"\n  10 GB declared: {statuses(received)} after {times[0] * 1000:.1f} ms", file=sys.stderr)
        self.assertEqual(statuses(received), [413])
        self.assertLess(times[0], 5.0)  # from the headers: no body was sent at all

    def test_two_content_lengths_are_refused_by_nginx(self):
        received = exchange(self.front, b"POST /v1/datasets HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                                        b"Content-Length: 2\r\nContent-Length: 40\r\n\r\n{}")
        self.assertEqual(statuses(received), [400])

    def test_a_smuggled_request_in_a_refused_body_is_never_answered(self):
        smuggled = b"GET /v1/jobs HTTP/1.1\r\nHost: x\r\n\r\n"
        received = exchange(self.front, b"POST /v1/datasets HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                                        b"Content-Encoding: gzip\r\nContent-Length: %d\r\n\r\n" % len(smuggled) + smuggled,
                            timeout=3.0)
        self.assertEqual(statuses(received), [415])

    def test_50_long_polls_leave_healthz_answering(self):
        status, _, job = self.front.request("POST", "/v1/simulations", {"duration": 600, "kd": [1e5, 1e5, 1e5, 1e5]})
        self.assertEqual(status, 202, job)
        answers = []

        def wait():
            answers.append(self.front.request("GET", f"/v1/jobs/{job['id']}?wait=8", timeout=60)[0])

        waiters = [threading.Thread(target=wait, daemon=True) for _ in range(50)]
        try:
            for waiter in waiters:
                waiter.start()
            time.sleep(1.0)
            status, seconds = healthz_seconds(self.front)
            print(f"\n  /healthz through nginx with 50 long-polls: {seconds * 1000:.1f} ms", file=sys.stderr)
            self.assertEqual(status, 200)
            self.assertLess(seconds, 5.0)
            for waiter in waiters:
                waiter.join(60)
            self.assertEqual(answers, [200] * 50)
        finally:
            self.front.request("POST", f"/v1/jobs/{job['id']}/cancel")


if __name__ == "__main__":
    if not shutil.which("nginx"):
        print("SKIP: nginx is not installed (Debian package nginx)", file=sys.stderr)
        sys.exit(SKIP)
    unittest.main()
