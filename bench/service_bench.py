#!/usr/bin/env python3
"""service_bench.py — the service's speed figures (issue 4), against the release binary:

  1. the paper case over HTTP, end to end: upload the CSV, submit the identification, long-poll
     the job until it succeeds — p50/p95 latency over sequential runs;
  2. jobs per second the worker pool sustains with the paper case (submissions from 4 threads,
     clock from the first submission to the last job's end);
  3. GET /v1/jobs/{id} requests per second under wrk, 16 connections.

Each for the paper's own filter (M = 100, Ωg = 0.2, fixed) and for the default request, whose
filter is chosen from the data (a grid search: slower, much more accurate on the complete model).

Usage: python3 bench/service_bench.py [--binary build/release/server/manipid] [--runs 40] [--jobs 200]
Needs wrk for part 3 (Debian package wrk); skipped with a note when it is missing.
"""
import argparse
import concurrent.futures
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests", "service"))
import harness  # noqa: E402

REQUESTS = {
    "paper filter (M=100, band 0.2)": {"preset": "cedro2009", "half_length": 100, "band": 0.2},
    "default (filter chosen from the data)": {"preset": "cedro2009"},
}


def percentile(values, fraction):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(fraction * (len(ordered) - 1))))]


def end_to_end(server, csv, request, runs):
    latencies = []
    for _ in range(runs):
        started = time.perf_counter()
        status, _, dataset = server.request("POST", "/v1/datasets", csv, {"Content-Type": "text/csv"})
        assert status == 201, dataset
        status, _, job = server.request("POST", "/v1/identifications", {"dataset_id": dataset["id"], **request})
        assert status == 202, job
        job = server.wait_job(job["id"])
        assert job["state"] == "succeeded", job
        latencies.append(1000 * (time.perf_counter() - started))
    return statistics.median(latencies), percentile(latencies, 0.95)


def throughput(server, dataset_id, request, jobs):
    started = time.perf_counter()

    def submit(_):
        status, _, job = server.request("POST", "/v1/identifications", {"dataset_id": dataset_id, **request})
        assert status == 202, job
        return job["id"]

    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        ids = list(pool.map(submit, range(jobs)))
    for job_id in ids:
        job = server.wait_job(job_id)
        assert job["state"] == "succeeded", job
    return jobs / (time.perf_counter() - started)


def status_requests(server, job_id, seconds=10):
    if shutil.which("wrk") is None:
        return None
    output = subprocess.run(["wrk", "-t2", "-c16", f"-d{seconds}s", f"{server.url}/v1/jobs/{job_id}"],
                            capture_output=True, text=True, check=True).stdout
    for line in output.splitlines():
        if line.startswith("Requests/sec:"):
            return float(line.split()[1])
    raise RuntimeError(output)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--binary", default="build/release/server/manipid")
    parser.add_argument("--runs", type=int, default=40)
    parser.add_argument("--jobs", type=int, default=200)
    parser.add_argument("--workers", type=int, default=2)
    arguments = parser.parse_args()
    os.environ["MANIPID_BIN"] = os.path.abspath(arguments.binary)

    with tempfile.TemporaryDirectory(prefix="manipid-bench-") as directory:
        csv = harness.simulate_csv(os.path.join(directory, "paper.csv"))
        with harness.Server(os.path.join(directory, "jobs.db"), workers=arguments.workers) as server:
            server.request("GET", "/healthz")
            status, _, dataset = server.request("POST", "/v1/datasets", csv, {"Content-Type": "text/csv"})
            print(f"manipid service bench: {arguments.workers} workers, {os.cpu_count()} CPUs, "
                  f"{arguments.runs} sequential runs, {arguments.jobs} jobs for throughput")
            last_job = None
            for label, request in REQUESTS.items():
                p50, p95 = end_to_end(server, csv, request, arguments.runs)
                rate = throughput(server, dataset["id"], request, arguments.jobs)
                print(f"{label}: end to end p50 {p50:.1f} ms, p95 {p95:.1f} ms; sustained {rate:.1f} jobs/s")
            _, _, jobs = server.request("GET", "/v1/jobs?page_size=1")
            last_job = jobs["items"][0]["id"]
            rate = status_requests(server, last_job)
            if rate is None:
                print("GET /v1/jobs/{id}: wrk not installed (apt-get install wrk); skipped")
            else:
                print(f"GET /v1/jobs/{{id}} under wrk -t2 -c16 -d10s: {rate:.0f} requests/s")


if __name__ == "__main__":
    main()
