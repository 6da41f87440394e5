#!/usr/bin/env python3
"""robot_service_bench.py — a URDF robot's identification over HTTP, end to end (issue 11's figure):
upload a 7-DOF, 20,000-sample run as CSV (jittery time stamps, as a real logger writes), submit the
identification with viscous, Coulomb and offset friction, long-poll the job until it succeeds.
p50/p95 over sequential runs against the release binary (target: p50 ≤ 300 ms).

The run is made by the project itself: `manipid excitation` (one 20 s period at 1 ms) and
`manipid torque --with-states` with sensor noise; each time stamp is then moved by up to ±0.3 ms.

Usage: python3 bench/robot_service_bench.py [--binary build/release/server/manipid] [--runs 30] [--workers 2]
"""
import argparse
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests", "service"))
import harness  # noqa: E402
from service_bench import percentile  # noqa: E402

URDF = os.path.join(os.path.dirname(__file__), "..", "examples", "robots", "panda_like.urdf")


def make_run(binary, directory):
    states = os.path.join(directory, "states.csv")
    run = os.path.join(directory, "run.csv")
    subprocess.run([binary, "excitation", "--robot", URDF, "--period", "20", "--dt", "0.001", "--max-evaluations", "2000",
                    "--out", states], check=True, stderr=subprocess.DEVNULL)
    subprocess.run([binary, "torque", "--robot", URDF, "--in", states, "--with-states", "--noise-q", "2e-5",
                    "--quantize-q", "18", "--noise-tau-relative", "0.01", "--seed", "1", "--out", run],
                   check=True, stderr=subprocess.DEVNULL)
    with open(run) as stream:
        lines = stream.read().splitlines()
    jitter = random.Random(1)
    rows = [lines[0]]
    for line in lines[1:]:
        t, rest = line.split(",", 1)
        rows.append(f"{float(t) + jitter.uniform(-3e-4, 3e-4) if float(t) > 0 else 0.0!r},{rest}")
    return "\n".join(rows) + "\n"


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--binary", default="build/release/server/manipid")
    parser.add_argument("--runs", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    arguments = parser.parse_args()
    binary = os.path.abspath(arguments.binary)
    os.environ["MANIPID_BIN"] = binary
    with tempfile.TemporaryDirectory(prefix="manipid-robot-bench-") as directory:
        csv = make_run(binary, directory)
        with open(URDF, "rb") as stream:
            urdf = stream.read()
        with harness.Server(os.path.join(directory, "jobs.db"), workers=arguments.workers) as server:
            status, _, robot = server.request("POST", "/v1/robots", urdf, {"Content-Type": "application/xml"})
            assert status == 201, robot
            request = {"robot_id": robot["id"], "friction": ["viscous", "coulomb", "offset"]}
            latencies, identify_seconds = [], []
            for _ in range(arguments.runs):
                started = time.perf_counter()
                status, _, dataset = server.request("POST", "/v1/datasets", csv, {"Content-Type": "text/csv"})
                assert status == 201, dataset
                status, _, job = server.request("POST", "/v1/identifications", {"dataset_id": dataset["id"], **request})
                assert status == 202, job
                job = server.wait_job(job["id"])
                assert job["state"] == "succeeded", job
                latencies.append(1000 * (time.perf_counter() - started))
                identify_seconds.append(1000 * job["result"]["wall_seconds"])
            p95 = percentile(latencies, 0.95)
            print(f"manipid robot service bench: {arguments.workers} workers, {os.cpu_count()} CPUs, "
                  f"{dataset['samples']} samples x {dataset['joints']} joints ({len(csv) / 1e6:.1f} MB CSV), "
                  f"{arguments.runs} sequential runs")
            print(f"upload CSV + identify + long-poll: p50 {statistics.median(latencies):.0f} ms, p95 {p95:.0f} ms; "
                  f"the identification itself (the job's wall_seconds) p50 {statistics.median(identify_seconds):.0f} ms")


if __name__ == "__main__":
    main()
