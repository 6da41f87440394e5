"""postgres_kill_test.py — kill one of three: three `manipid serve` processes on one PostgreSQL
database (lease 2 s) take identification jobs submitted with Idempotency-Keys spread over all
three (a tenth of the keys sent twice, to another process); one process is killed (SIGKILL) while
it holds a running job, then another is paused (SIGSTOP) past its lease and resumed (SIGCONT).
Then: every acknowledged id ends succeeded; each job's history is one attempt's (indices
0..evaluations-1, once each); the killed process's job ran twice (attempts = 2); no job is left
running; there are as many jobs as distinct keys. Each repetition uses a new database and its own
seed (which keys repeat, where each submission goes).

Needs the private cluster of the ctest fixture "postgres" (MANIPID_TEST_POSTGRES_FILE); exits 77
(skipped) without it.

  MANIPID_BIN=build/debug/server/manipid MANIPID_TEST_POSTGRES_FILE=... \\
      python3 tests/service/postgres_kill_test.py [--jobs 300] [--repeat 3] [--seed 1]
"""
import argparse
import os
import random
import signal
import sys
import time

sys.path.insert(0, os.path.dirname(__file__))
from harness import Server, postgres_database, postgres_sql, postgres_template, temporary_directory  # noqa: E402

LEASE = "2"
JOB = {"simulation": {"duration": 0.5}, "half_length": 50, "band": 0.2, "free": ["m2"]}
SLOW_JOB = {"simulation": {"duration": 3.0}, "method": "output-error", "max_evaluations": 40}


def runs(server, job):
    """Whether `job` (its JSON) is held by `server`'s process ("HOST:PID", or with ":THREAD")."""
    name = f"{os.uname().nodename}:{server.process.pid}"
    worker = job.get("worker") or ""
    return job["state"] == "running" and (worker == name or worker.startswith(name + ":"))


def kill_while_running(servers, key):
    """Submits a slow job (output-error: a simulation per evaluation), waits until a process
    runs it, freezes that process (so the job cannot end between the look and the kill) and
    kills it. Returns (the killed server, the job id)."""
    status, _, job = servers[0].request("POST", "/v1/identifications", SLOW_JOB, headers={"Idempotency-Key": key})
    assert status == 202, (status, job)
    deadline = time.time() + 300
    while time.time() < deadline:
        _, _, seen = servers[0].request("GET", f"/v1/jobs/{job['id']}")
        holder = next((s for s in servers if runs(s, seen)), None)
        if holder is not None:
            holder.process.send_signal(signal.SIGSTOP)
            _, _, again = servers[0 if holder is not servers[0] else 1].request("GET", f"/v1/jobs/{job['id']}")
            if runs(holder, again):
                holder.kill()
                return holder, job["id"]
            holder.process.send_signal(signal.SIGCONT)
        time.sleep(0.05)
    raise AssertionError(f"the slow job never ran: {seen}")


def run_once(directory, repetition, jobs, seed):
    rng = random.Random(seed)
    name, db = postgres_database(directory, f"kill{repetition}")
    servers = []
    for letter in "abc":
        server = Server(db, "--lease", LEASE, workers=1)
        server.log_path = os.path.join(directory, f"{repetition}-{letter}.log")
        servers.append(server.start())
    try:
        keys = [f"key-{repetition}-{i}" for i in range(jobs)]
        sends = keys + rng.sample(keys, jobs // 10)  # a tenth sent twice
        acknowledged = {}
        killed = paused = None
        killed_job = None
        for count, key in enumerate(sends):
            alive = [s for s in servers if s is not killed]
            target = rng.choice(alive)
            status, _, job = target.request("POST", "/v1/identifications", JOB, headers={"Idempotency-Key": key})
            assert status in (200, 201, 202), (status, job)
            if key in acknowledged:
                assert acknowledged[key] == job["id"], (key, acknowledged[key], job["id"])
            acknowledged[key] = job["id"]
            # A third of the way in: kill a process while it runs a job.
            if killed is None and count >= len(sends) // 3:
                slow_key = f"slow-{repetition}"
                killed, killed_job = kill_while_running(servers, slow_key)
                acknowledged[slow_key] = killed_job
            # Two thirds of the way in: pause another past its lease, then let it go on.
            if killed is not None and paused is None and count >= 2 * len(sends) // 3:
                paused = next(s for s in servers if s is not killed)
                paused.process.send_signal(signal.SIGSTOP)
                time.sleep(float(LEASE) * 2)
                paused.process.send_signal(signal.SIGCONT)

        alive = [s for s in servers if s is not killed]
        for key, job_id in acknowledged.items():
            done = alive[0].wait_job(job_id, timeout=600)
            assert done["state"] == "succeeded", done
            status, _, page = alive[1].request("GET", f"/v1/jobs/{job_id}/history?page_size=1000")
            assert status == 200, page
            indices = [entry["index"] for entry in page["items"]]
            assert indices == list(range(done["result"]["evaluations"])), (job_id, len(indices), done["result"]["evaluations"])
        killed_state = alive[0].request("GET", f"/v1/jobs/{killed_job}")[2]
        assert killed_state["attempts"] == 2, killed_state
        status, _, running = alive[0].request("GET", "/v1/jobs?state=running")
        assert running["items"] == [], running
        count, token = 0, ""
        while True:
            status, _, page = alive[1].request("GET", "/v1/jobs?page_size=1000" + (f"&page_token={token}" if token else ""))
            count += len(page["items"])
            token = page.get("next_page_token") or ""
            if not token:
                break
        assert count == len(acknowledged) == jobs + 1, (count, len(acknowledged), jobs)  # and the slow job
        print(f"repetition {repetition} (seed {seed}): {jobs} jobs, {len(sends) - jobs} keys sent twice, "
              f"killed one process while it ran {killed_job} (attempts 2), paused another past its lease: "
              "every job succeeded once", flush=True)
    finally:
        for server in servers:
            if server.process is not None and server.process.poll() is None:
                server.process.send_signal(signal.SIGCONT)
                server.stop()
        postgres_sql("postgres", f"DROP DATABASE {name} WITH (FORCE)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--jobs", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    arguments = parser.parse_args()
    if postgres_template() is None:
        print("no PostgreSQL cluster (ctest fixture postgres; Debian package postgresql): skipped")
        return 77
    with temporary_directory() as directory:
        for repetition in range(arguments.repeat):
            run_once(directory, repetition, arguments.jobs, arguments.seed + repetition)
    return 0


if __name__ == "__main__":
    sys.exit(main())
