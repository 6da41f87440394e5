#!/usr/bin/env python3
"""upload_memory.py — peak memory of `manipid serve` per byte of upload (issue 13 item 7's figure):
the process's VmHWM (/proc/PID/status) after one ~60 MB JSON dataset upload, after 8 at once
(each admitted against --memory-budget or refused with 503), and after reading a large dataset
back (GET /v1/datasets/{id}/data). A fresh server for each, so each high-water mark is its own.

Numbers are written as a logger writes them (~18 significant digits), 4 joints of q and tau.

Usage: python3 bench/upload_memory.py [--binary build/release/server/manipid] [--megabytes 60]
       [--at-once 8] [--memory-budget 1GiB]
"""
import argparse
import json
import os
import random
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests", "service"))
import harness  # noqa: E402


def status_kib(pid, field):
    with open(f"/proc/{pid}/status") as stream:
        for line in stream:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise RuntimeError(f"no {field} in /proc/{pid}/status")


def dataset_body(megabytes, joints=4, seed=1):
    """A JSON upload of about `megabytes` MB: q and tau for `joints` joints, logger-like numbers."""
    random.seed(seed)
    per_sample = 2 * joints * 21  # "-0.12345678901234567, "
    samples = int(megabytes * 1e6 / per_sample)
    base = [random.uniform(-1, 1) for _ in range(1000)]
    block = lambda offset: [[base[(i + offset + 7 * j) % 1000] for i in range(samples)] for j in range(joints)]  # noqa: E731
    return json.dumps({"name": "memory bench", "dt": 0.001, "q": block(0), "tau": block(500)}).encode(), samples


def fresh_server(binary, directory, name, budget):
    harness.binary = lambda: binary  # the harness reads MANIPID_BIN otherwise
    return harness.Server(os.path.join(directory, name + ".db"), "--max-body", "256MiB",
                          "--memory-budget", budget, workers=1).start()


def measure(server, label, body_bytes, action):
    pid = server.process.pid
    before = status_kib(pid, "VmHWM")
    started = time.time()
    outcome = action()
    seconds = time.time() - started
    peak = status_kib(pid, "VmHWM")
    print(f"{label}: VmHWM {before / 1024:.0f} MiB idle -> {peak / 1024:.0f} MiB "
          f"({peak * 1024 / body_bytes:.2f} x the body, {(peak - before) * 1024 / body_bytes:.2f} x above idle); "
          f"{seconds:.1f} s; {outcome}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default=os.environ.get("MANIPID_BIN", "build/release/server/manipid"))
    parser.add_argument("--megabytes", type=float, default=60)
    parser.add_argument("--at-once", type=int, default=8)
    parser.add_argument("--memory-budget", default="1GiB")
    arguments = parser.parse_args()
    binary = os.path.abspath(arguments.binary)
    body, samples = dataset_body(arguments.megabytes)
    print(f"{binary}\nbody: {len(body) / 1e6:.1f} MB, {samples} samples x 4 joints (q, tau); "
          f"--memory-budget {arguments.memory_budget}")

    with tempfile.TemporaryDirectory(prefix="manipid-memory-bench-") as directory:
        server = fresh_server(binary, directory, "one", arguments.memory_budget)
        try:
            created = {}

            def one():
                status, _, answer = server.request("POST", "/v1/datasets", body, {"Content-Type": "application/json"},
                                                   timeout=600)
                created.update(answer if status == 201 else {})
                return f"HTTP {status}"
            measure(server, "one upload", len(body), one)
        finally:
            server.stop()

        server = fresh_server(binary, directory, "many", arguments.memory_budget)
        try:
            def many():
                statuses = []
                lock = threading.Lock()

                def upload():
                    status, _, _ = server.request("POST", "/v1/datasets", body, {"Content-Type": "application/json"},
                                                  timeout=600)
                    with lock:
                        statuses.append(status)
                threads = [threading.Thread(target=upload) for _ in range(arguments.at_once)]
                for thread in threads:
                    thread.start()
                for thread in threads:
                    thread.join()
                return "HTTP " + ", ".join(f"{statuses.count(s)} x {s}" for s in sorted(set(statuses)))
            measure(server, f"{arguments.at_once} uploads at once", len(body), many)
        finally:
            server.stop()

        # The data endpoint of the stored dataset, on a fresh process over the same file.
        server = harness.Server(os.path.join(directory, "one.db"), "--max-body", "256MiB",
                                "--memory-budget", arguments.memory_budget, workers=1).start()
        try:
            def read_back():
                status, headers, data = server.request("GET", f"/v1/datasets/{created['id']}/data", timeout=600)
                return f"HTTP {status}, answer {len(json.dumps(data)) / 1e6:.0f} MB"
            measure(server, "GET /v1/datasets/{id}/data (JSON)", len(body), read_back)
        finally:
            server.stop()


if __name__ == "__main__":
    main()
