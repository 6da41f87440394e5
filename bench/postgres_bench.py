#!/usr/bin/env python3
"""postgres_bench.py — SQLite beside PostgreSQL (issue 12), on this machine, against the release
binary, with the paper case (fixed filter M = 100, Ωg = 0.2):

  1. end to end (upload the CSV, submit, long-poll to the end), p50/p95 over sequential runs;
  2. sustained jobs/s: jobs submitted from 4 threads (round robin over the processes), clock from
     the first submission to the last job's end; every job must succeed (none lost);
  for SQLite with one process, PostgreSQL with one process and with two (the same number of job
  threads in all three: --workers W in one process, W/2 in each of two);
  3. GET /v1/jobs/{id} under wrk (16 connections) on PostgreSQL;
  4. the store alone (build/release/bench/store_bench): 16 threads claiming and ending empty jobs,
     and status reads, on each backend.

PostgreSQL runs as a private cluster (tests/server/postgres_cluster.sh: Unix socket, fsync off —
what a test cluster trades; a production server with fsync on commits slower).

The three cases run in turn, --rounds times (default 3); the ratio is of the medians.

Usage: python3 bench/postgres_bench.py [--binary build/release/server/manipid] [--runs 30] [--jobs 200]
       [--workers 2] [--rounds 3]
"""
import argparse
import concurrent.futures
import os
import statistics
import subprocess
import sys
import tempfile
import time

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, os.path.join(root, "tests", "service"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from service_bench import end_to_end, status_requests  # noqa: E402

REQUEST = {"half_length": 100, "band": 0.2}


def throughput(servers, dataset_id, jobs):
    started = time.perf_counter()

    def submit(index):
        server = servers[index % len(servers)]
        status, _, job = server.request("POST", "/v1/identifications", {"dataset_id": dataset_id, **REQUEST})
        assert status == 202, job
        return job["id"]

    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        ids = list(pool.map(submit, range(jobs)))
    for index, job_id in enumerate(ids):
        job = servers[index % len(servers)].wait_job(job_id)
        assert job["state"] == "succeeded", job
    return jobs / (time.perf_counter() - started)


def run_case(label, db, processes, workers, csv, arguments, directory):
    servers = []
    try:
        for index in range(processes):
            server = harness.Server(db, workers=workers // processes)
            server.log_path = os.path.join(directory, f"{label.replace(' ', '_')}-{index}.log")
            servers.append(server.start())
        status, _, dataset = servers[0].request("POST", "/v1/datasets", csv, {"Content-Type": "text/csv"})
        assert status == 201, dataset
        p50, p95 = end_to_end(servers[0], csv, REQUEST, arguments.runs)
        rate = throughput(servers, dataset["id"], arguments.jobs)
        print(f"{label}: end to end p50 {p50:.1f} ms, p95 {p95:.1f} ms; sustained {rate:.1f} jobs/s "
              f"({arguments.jobs} jobs, none lost)", flush=True)
        reads = None
        if label.startswith("PostgreSQL, 1"):
            _, _, page = servers[0].request("GET", "/v1/jobs?page_size=1")
            reads = status_requests(servers[0], page["items"][0]["id"])
            print("  GET /v1/jobs/{id} under wrk -t2 -c16 -d10s: " +
                  (f"{reads:.0f} requests/s" if reads else "wrk not installed; skipped"), flush=True)
        return rate
    finally:
        for server in servers:
            server.stop()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--binary", default="build/release/server/manipid")
    parser.add_argument("--runs", type=int, default=30)
    parser.add_argument("--jobs", type=int, default=200)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=3)
    arguments = parser.parse_args()
    os.environ["MANIPID_BIN"] = os.path.abspath(arguments.binary)
    store_bench = os.path.join(os.path.dirname(os.path.abspath(arguments.binary)), "..", "bench", "store_bench")
    cluster = os.path.join(root, "tests", "server", "postgres_cluster.sh")

    with tempfile.TemporaryDirectory(prefix="manipid-pg-bench-") as directory:
        state = os.path.join(directory, "cluster")
        subprocess.run(["bash", cluster, "start", state], check=True)
        if not os.path.exists(state):
            print("no PostgreSQL server binaries: nothing to compare")
            return 1
        try:
            with open(state) as stream:
                template = stream.readline().strip()

            def database(name):
                subprocess.run(["psql", template.replace("%s", "postgres"), "-qc", f"CREATE DATABASE {name}"],
                               check=True, stdout=subprocess.DEVNULL)
                return template.replace("%s", name)

            csv = harness.simulate_csv(os.path.join(directory, "paper.csv"))
            print(f"manipid PostgreSQL bench: {os.cpu_count()} CPUs, {arguments.workers} job threads in all, "
                  f"{arguments.runs} sequential runs, {arguments.jobs} jobs for throughput", flush=True)
            # The three cases in turn, --rounds times: on a shared machine one run's figure moves
            # by ±5 %; rounds side by side and their medians compare like with like.
            rates = {"sqlite": [], "one": [], "two": []}
            for round_ in range(arguments.rounds):
                print(f"round {round_ + 1} of {arguments.rounds}", flush=True)
                rates["sqlite"].append(run_case("SQLite, 1 process", os.path.join(directory, f"jobs{round_}.db"), 1,
                                                arguments.workers, csv, arguments, directory))
                rates["one"].append(run_case("PostgreSQL, 1 process", database(f"bench_one{round_}"), 1,
                                             arguments.workers, csv, arguments, directory))
                rates["two"].append(run_case("PostgreSQL, 2 processes", database(f"bench_two{round_}"), 2,
                                             arguments.workers, csv, arguments, directory))
            sqlite, one, two = (statistics.median(rates[case]) for case in ("sqlite", "one", "two"))
            print(f"median sustained over {arguments.rounds} round(s): SQLite {sqlite:.1f}, PostgreSQL {one:.1f} "
                  f"(1 process), {two:.1f} jobs/s (2 processes)")
            print(f"PostgreSQL / SQLite, sustained: {one / sqlite:.2f} (1 process), {two / sqlite:.2f} (2 processes)")
            if os.access(store_bench, os.X_OK):
                for url in (os.path.join(directory, "claims.db"), database("bench_claims")):
                    subprocess.run([store_bench, url, "5000", "16"], check=True)
            else:
                print(f"{store_bench} not built (cmake --build --preset release --target store_bench): claims skipped")
        finally:
            subprocess.run(["bash", cluster, "stop", state], check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
