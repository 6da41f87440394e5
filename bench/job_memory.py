#!/usr/bin/env python3
"""job_memory.py — peak memory of `manipid serve` while one job runs (issue 13 item 7's job figure),
beside the estimate the server admits the job by (`job_memory` in the job resource, --job-memory).

For each job, a fresh server (one worker): VmHWM (/proc/PID/status) before the job and after it,
the rise divided by samples × joints, and the rise against the server's own estimate. Jobs: the
paper's preset simulated for D seconds (a simulation job; an input-error and a two-stage
identification that simulate first) and a 7-joint URDF robot's run of D seconds (uploaded as CSV,
identified with viscous, Coulomb and offset friction; and a payload identified on it, the URDF's values as the
arm). Two lengths each, so the per-sample slope
shows apart from the fixed part.

Usage: python3 bench/job_memory.py [--binary build/release/server/manipid] [--seconds 60,240]
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests", "service"))
import harness  # noqa: E402
from upload_memory import status_kib  # noqa: E402

URDF = os.path.join(os.path.dirname(__file__), "..", "examples", "robots", "panda_like.urdf")


def robot_run(binary, directory, seconds):
    """A 7-joint run of `seconds` at 1 ms made by the project itself (excitation, then torque with noise)."""
    states = os.path.join(directory, f"states{seconds}.csv")
    run = os.path.join(directory, f"run{seconds}.csv")
    subprocess.run([binary, "excitation", "--robot", URDF, "--period", "20", "--duration", str(seconds), "--dt", "0.001",
                    "--max-evaluations", "500", "--out", states], check=True, stderr=subprocess.DEVNULL)
    subprocess.run([binary, "torque", "--robot", URDF, "--in", states, "--with-states", "--noise-q", "2e-5",
                    "--noise-tau-relative", "0.01", "--seed", "1", "--out", run], check=True, stderr=subprocess.DEVNULL)
    with open(run, "rb") as stream:
        return stream.read()


def run_job(binary, directory, label, submit, samples, joints):
    db = os.path.join(directory, label.replace(" ", "_") + ".db")
    server = harness.Server(db, "--max-body", "256MiB", "--job-memory", "64GiB", workers=1).start()
    try:
        path, body = submit(server)  # uploads, if any, on a server of their own: their peak is not the job's
    finally:
        server.stop()
    server = harness.Server(db, "--max-body", "256MiB", "--job-memory", "64GiB", workers=1).start()
    try:
        pid = server.process.pid
        before = status_kib(pid, "VmHWM")
        started = time.time()
        status, _, job = server.request("POST", path, body)
        if status != 202:
            print(f"{label}: HTTP {status} {job}")
            return
        job = server.wait_job(job["id"], timeout=1800)
        seconds = time.time() - started
        peak = status_kib(pid, "VmHWM")
        rise = (peak - before) * 1024
        found = re.search(rf"job {job['id']} \w+: running \(attempt \d+; holds about ([0-9.]+) (MiB|GiB)",
                          server.read_log())
        estimate = float(found.group(1)) * (2**30 if found.group(2) == "GiB" else 2**20) if found else None
        against = f"{rise / estimate:.2f} x the estimate, {estimate / 2**20:.0f} MiB" if estimate else "no estimate"
        print(f"{label}: {job['state']} in {seconds:.1f} s; VmHWM {before / 1024:.0f} -> {peak / 1024:.0f} MiB, "
              f"rise {rise / 2**20:.0f} MiB = {rise / (samples * joints):.0f} bytes per sample and joint; {against}")
    finally:
        server.stop()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default=os.environ.get("MANIPID_BIN", "build/release/server/manipid"))
    parser.add_argument("--seconds", default="60,240", help="run lengths, s (comma-separated; whole multiples of 20)")
    arguments = parser.parse_args()
    binary = os.path.abspath(arguments.binary)
    harness.binary = lambda: binary
    lengths = [int(s) for s in arguments.seconds.split(",")]
    print(binary)
    with tempfile.TemporaryDirectory(prefix="manipid-job-memory-") as directory:
        for seconds in lengths:
            samples = seconds * 1000 + 1
            simulation = {"duration": seconds}
            run_job(binary, directory, f"simulation {seconds} s", lambda _: ("/v1/simulations", simulation), samples, 4)
            run_job(binary, directory, f"input-error on a {seconds} s simulation",
                    lambda _: ("/v1/identifications", {"simulation": simulation}), samples, 4)
            run_job(binary, directory, f"two-stage on a {seconds} s simulation",
                    lambda _: ("/v1/identifications", {"simulation": simulation, "method": "two-stage"}), samples, 4)
        for seconds in lengths:
            csv = robot_run(binary, directory, seconds)

            def submit(server, csv=csv):
                with open(URDF, "rb") as stream:
                    status, _, robot = server.request("POST", "/v1/robots", stream.read(), {"Content-Type": "application/xml"})
                assert status == 201, robot
                status, _, dataset = server.request("POST", "/v1/datasets", csv, {"Content-Type": "text/csv"}, timeout=600)
                assert status == 201, dataset
                return "/v1/identifications", {"robot_id": robot["id"], "dataset_id": dataset["id"],
                                               "friction": ["viscous", "coulomb", "offset"]}
            run_job(binary, directory, f"7-joint robot, {seconds} s run", submit, seconds * 1000, 7)

            def submit_payload(server, submit=submit):
                path, body = submit(server)
                return path, {"payload": True, "robot_id": body["robot_id"], "dataset_id": body["dataset_id"]}
            run_job(binary, directory, f"payload on a 7-joint robot, {seconds} s run", submit_payload, seconds * 1000, 7)


if __name__ == "__main__":
    main()
