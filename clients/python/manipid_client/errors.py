"""Exceptions raised by manipid_client: every server error carries the problem+json fields.

The service answers every error with `application/problem+json` (RFC 9457): `type`, `title`,
`status`, `detail`, a stable `code` scripts can switch on, and the `field` at fault. They are
attributes of `ManipidError`, so callers write `except ManipidError as e: if e.code == ...`.
"""
from __future__ import annotations

from typing import Any, Mapping, Optional


class ManipidError(Exception):
    """An error answer of the service (or a failure to get one), with the problem+json fields.

    Attributes (None when the answer did not carry them): `status` (HTTP status), `code`
    (e.g. "INVALID_FIELD", "NOT_FOUND"), `title`, `detail`, `field` (the input at fault, e.g.
    "q[2]" or "max_evaluations"), `type`, `instance`; `problem` is the whole parsed body and
    `retry_after` the Retry-After header in seconds (429 QUEUE_FULL, 503 SHUTTING_DOWN, 503 MEMORY_BUSY,
    503 UPLOADS_BUSY).
    """

    def __init__(self, message: Optional[str] = None, *, status: Optional[int] = None,
                 problem: Optional[Mapping[str, Any]] = None, retry_after: Optional[float] = None) -> None:
        self.problem: dict = dict(problem or {})
        self.status: Optional[int] = status if status is not None else self.problem.get("status")
        self.code: Optional[str] = self.problem.get("code")
        self.title: Optional[str] = self.problem.get("title")
        self.detail: Optional[str] = self.problem.get("detail")
        self.field: Optional[str] = self.problem.get("field")
        self.type: Optional[str] = self.problem.get("type")
        self.instance: Optional[str] = self.problem.get("instance")
        self.retry_after = retry_after
        self.message = message
        super().__init__(str(self))

    def __str__(self) -> str:
        # e.g. "422 INVALID_FIELD [max_evaluations]: max_evaluations must be an integer ..."
        head = " ".join(str(part) for part in (self.status, self.code) if part is not None)
        if self.field:
            head += f" [{self.field}]"
        text = self.message or self.detail or self.title or "error"
        return f"{head}: {text}" if head else text


class ManipidConnectionError(ManipidError, ConnectionError):
    """The server could not be reached or did not answer (refused, reset, timed out, bad URL)."""


class BinaryNotFound(ManipidError, FileNotFoundError):
    """local_server() found no `manipid` executable; the message lists the places searched."""


class ServerStartError(ManipidError, RuntimeError):
    """`manipid serve` did not print its "listening on" line; the message has its log."""


class JobError(ManipidError):
    """A job ended without a result: base of JobFailed and JobCancelled. `job` is its JSON."""

    def __init__(self, message: Optional[str] = None, *, job: Mapping[str, Any],
                 problem: Optional[Mapping[str, Any]] = None) -> None:
        self.job: dict = dict(job)
        self.job_id: Optional[str] = self.job.get("id")
        super().__init__(message, problem=problem)


class JobFailed(JobError):
    """The job ended `failed`; the problem fields are the job's `error` (code e.g. JOB_FAILED)."""

    def __init__(self, job: Mapping[str, Any]) -> None:
        error = job.get("error") or {}
        super().__init__(None if error else f"job {job.get('id')} failed", job=job, problem=error)

    def __str__(self) -> str:
        return f"job {self.job.get('id')} failed: " + super().__str__() if self.problem else super().__str__()


class JobCancelled(JobError):
    """The job ended `cancelled`. `result` is the best point an identification had reached (or None)."""

    def __init__(self, job: Mapping[str, Any]) -> None:
        self.result: Optional[dict] = job.get("result")
        super().__init__(f"job {job.get('id')} was cancelled", job=job)


class JobTimeout(ManipidError, TimeoutError):
    """Job.wait(timeout=...) ran out of time; the job goes on (cancel it if it should not)."""

    def __init__(self, message: str, *, job: Mapping[str, Any]) -> None:
        self.job: dict = dict(job)
        super().__init__(message)
