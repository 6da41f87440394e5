#!/usr/bin/env python3
"""address_limit.py — `manipid serve` under an address-space limit (RLIMIT_AS, as `ulimit -v`): the
hardening issue's "one upload ends in std::bad_alloc → terminate". Release build only: ASan reserves
terabytes of address space and cannot run under such a limit, so this is a probe, not a ctest.

1. Under --limit MiB with 4 HTTP threads: three ~60 MB JSON uploads one after the other; each is
   stored (201) or refused 503 MEMORY_BUSY, the process stays up and /healthz answers.
2. Under a limit too small for the HTTP threads' stacks (32 threads × 8 MiB): the server exits 1
   naming the cause, rather than listening without serving.

Usage: python3 bench/address_limit.py [--binary build/release/server/manipid] [--limit 600]
"""
import argparse
import os
import resource
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests", "service"))
import harness  # noqa: E402
from upload_memory import dataset_body  # noqa: E402


def limited(mib):
    return lambda: resource.setrlimit(resource.RLIMIT_AS, (mib << 20, mib << 20))


def uploads_under(binary, directory, mib, body):
    log_path = os.path.join(directory, f"serve-{mib}.log")
    with open(log_path, "wb") as log:
        process = subprocess.Popen([binary, "serve", "--port", "0", "--db", os.path.join(directory, f"{mib}.db"),
                                    "--max-body", "256MiB", "--workers", "1", "--http-threads", "4"],
                                   stdout=subprocess.PIPE, stderr=log, preexec_fn=limited(mib))
        line = process.stdout.readline().decode()
        server = harness.Server.__new__(harness.Server)
        server.host, port = line.split()[-1][len("http://"):].rsplit(":", 1)
        server.port = int(port)
        answers = []
        for _ in range(3):
            status, _, answer = server.request("POST", "/v1/datasets", body, {"Content-Type": "application/json"},
                                               timeout=120)
            answers.append(f"{status} {answer.get('code', '') if isinstance(answer, dict) else ''}".strip())
        alive = process.poll() is None
        health = server.request("GET", "/healthz")[0] if alive else None
        process.terminate()
        process.wait(30)
    print(f"RLIMIT_AS {mib} MiB, 4 HTTP threads: {len(body) / 1e6:.1f} MB uploads -> {', '.join(answers)}; "
          f"process {'up' if alive else 'DEAD'}, /healthz {health}")


def too_small_for_threads(binary, directory, mib):
    result = subprocess.run([binary, "serve", "--port", "0", "--db", os.path.join(directory, "small.db"), "--workers", "1"],
                            capture_output=True, timeout=60, preexec_fn=limited(mib))
    last = result.stderr.decode().strip().splitlines()[-1] if result.stderr else ""
    print(f"RLIMIT_AS {mib} MiB, 32 HTTP threads: exit {result.returncode}: {last}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--binary", default=os.environ.get("MANIPID_BIN", "build/release/server/manipid"))
    parser.add_argument("--limit", type=int, default=300, help="MiB of address space for the upload probe")
    arguments = parser.parse_args()
    binary = os.path.abspath(arguments.binary)
    body, _ = dataset_body(60)
    with tempfile.TemporaryDirectory(prefix="manipid-address-limit-") as directory:
        uploads_under(binary, directory, arguments.limit, body)
        too_small_for_threads(binary, directory, 300)


if __name__ == "__main__":
    main()
