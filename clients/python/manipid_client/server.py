"""local_server(): run a private `manipid serve` for a script or an integration test.

It starts `manipid serve --port 0` (the OS picks a free port) on a temporary database, reads
the URL from the first stdout line ("listening on http://HOST:PORT"), yields it, and on exit
sends SIGTERM (the server requeues running jobs and exits 0), kills it if it has not exited
after `stop_timeout`, and removes the temporary directory.
"""
from __future__ import annotations

import contextlib
import os
import selectors
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from pathlib import Path
from typing import Iterator, List, Optional, Sequence, Union

from .errors import BinaryNotFound, ServerStartError

BUILD_CANDIDATES = ("build/release/server/manipid", "build/debug/server/manipid")


class ServerURL(str):
    """The URL local_server() yields: a plain str ("http://127.0.0.1:PORT") that also carries
    `process` (the subprocess.Popen), `db` (the database path), `log_path` (the server's
    stderr: one line per request and per job transition) and read_log()."""

    process: subprocess.Popen
    db: str
    log_path: str

    def read_log(self) -> str:
        with open(self.log_path, "rb") as stream:
            return stream.read().decode(errors="replace")


def _repository_roots() -> List[Path]:
    """The current directory, then the repository holding this package when it is used
    in place (PYTHONPATH=clients/python or pip install -e), found by its top-level layout."""
    roots = [Path.cwd()]
    for parent in Path(__file__).resolve().parents:
        if (parent / "clients" / "python").is_dir() and (parent / "CMakeLists.txt").is_file():
            roots.append(parent)
            break
    return roots


def find_binary(binary: Union[str, "os.PathLike[str]", None] = None) -> str:
    """The `manipid` executable: `binary`, else $MANIPID_BIN, else `manipid` on PATH, else
    build/release/server/manipid then build/debug/server/manipid under the current directory
    and under the repository root. Raises BinaryNotFound listing what was tried."""
    if binary is not None:
        return _executable(os.fspath(binary), "binary= argument")
    from_env = os.environ.get("MANIPID_BIN")
    if from_env:
        return _executable(from_env, "MANIPID_BIN")
    on_path = shutil.which("manipid")
    if on_path:
        return on_path
    tried = ["manipid on PATH"]
    for root in _repository_roots():
        for candidate in BUILD_CANDIDATES:
            path = root / candidate
            if path.is_file() and os.access(path, os.X_OK):
                return str(path)
            tried.append(str(path))
    raise BinaryNotFound("no manipid executable found; tried " + ", ".join(tried) +
                         ". Pass local_server(binary=...) or set MANIPID_BIN, or build it "
                         "(cmake --preset release && cmake --build build/release)")


def _executable(path: str, source: str) -> str:
    if os.path.isfile(path) and os.access(path, os.X_OK):
        return path
    found = shutil.which(path)  # a bare name from the caller: look it up on PATH
    if found:
        return found
    raise BinaryNotFound(f"{source} names {path!r}, which is not an executable file")


@contextlib.contextmanager
def local_server(binary: Union[str, "os.PathLike[str]", None] = None,
                 db: Union[str, "os.PathLike[str]", None] = None,
                 workers: Optional[int] = None, extra_args: Sequence[str] = (),
                 host: str = "127.0.0.1", start_timeout: float = 60.0,
                 stop_timeout: float = 30.0) -> Iterator[ServerURL]:
    """Runs `manipid serve --port 0` for the duration of a `with` block; yields its URL.

    binary: see find_binary(). db: the SQLite file (default: a new one in a temporary
    directory, removed afterwards). workers: identification threads (default the server's).
    extra_args: more `manipid serve` options, e.g. ("--token", "s3cret"). The server's
    stderr log goes to a file (url.log_path), quoted in the error if it fails to start.
    """
    executable = find_binary(binary)
    directory = tempfile.mkdtemp(prefix="manipid-server-")
    process: Optional[subprocess.Popen] = None
    log = None
    try:
        database = os.fspath(db) if db is not None else os.path.join(directory, "manipid.db")
        log_path = os.path.join(directory, "server.log")
        log = open(log_path, "wb")
        command = [executable, "serve", "--host", host, "--port", "0", "--db", database]
        if workers is not None:
            command += ["--workers", str(int(workers))]
        command += [str(argument) for argument in extra_args]
        process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log)
        line = _first_line(process, start_timeout)
        if not line.startswith("listening on http://"):
            _stop(process, stop_timeout)
            process.stdout.close()
            raise ServerStartError(f"{' '.join(command)} did not start (first line {line!r}, exit status "
                                   f"{process.returncode}); its log:\n{_read(log_path)[-4000:]}")
        # Keep reading stdout so that anything the server prints later can never fill the pipe
        # (closing it instead would turn a late print into SIGPIPE).
        threading.Thread(target=_drain, args=(process.stdout,), daemon=True).start()
        url = ServerURL(line.split()[-1])
        url.process, url.db, url.log_path = process, database, log_path
        yield url
    finally:
        if process is not None:
            _stop(process, stop_timeout)
        if log is not None:
            log.close()
        shutil.rmtree(directory, ignore_errors=True)


def _first_line(process: subprocess.Popen, timeout: float) -> str:
    """The server's first stdout line, or "" if it exits or stays silent for `timeout` s."""
    assert process.stdout is not None
    deadline = time.monotonic() + timeout
    buffer = b""
    with selectors.DefaultSelector() as selector:
        selector.register(process.stdout, selectors.EVENT_READ)
        while b"\n" not in buffer:
            remaining = deadline - time.monotonic()
            if remaining <= 0 or not selector.select(remaining):
                break
            chunk = os.read(process.stdout.fileno(), 4096)
            if not chunk:
                break
            buffer += chunk
    return buffer.split(b"\n", 1)[0].decode(errors="replace").strip()


def _drain(stream) -> None:
    """Reads the server's stdout to its end (the server's exit), then closes it."""
    try:
        while stream.read1(65536):
            pass
    except (OSError, ValueError):
        pass
    finally:
        stream.close()


def _stop(process: subprocess.Popen, timeout: float) -> None:
    """SIGTERM, wait up to `timeout` s, then SIGKILL."""
    if process.poll() is None:
        try:
            process.send_signal(signal.SIGTERM)
            process.wait(timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def _read(path: str) -> str:
    try:
        with open(path, "rb") as stream:
            return stream.read().decode(errors="replace")
    except OSError:
        return ""
