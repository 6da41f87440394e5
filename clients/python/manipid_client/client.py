"""The HTTP client of the manipid service: Client, Dataset, Job and History.

Standard library only (http.client + json). One fresh connection per request: the server
closes idle keep-alive connections after 2 s, and a lab script's request rate makes reuse
pointless. numpy is used only when the caller hands numpy arrays in or asks for them out.
"""
from __future__ import annotations

import http.client
import json
import os
import socket
import sys
import time
import urllib.parse
from typing import Any, Dict, Iterator, List, Mapping, NamedTuple, Optional, Sequence, TextIO, Union

from .errors import JobCancelled, JobFailed, JobTimeout, ManipidConnectionError, ManipidError
from .results import RobotResult

TERMINAL_STATES = ("succeeded", "failed", "cancelled")
LONG_POLL_LIMIT = 30.0  # the server caps ?wait= at 30 s
PROGRESS_POLL = 1.0  # seconds per long-poll while a live progress line is shown

PathLike = Union[str, "os.PathLike[str]"]


class _Resource:
    """A stored resource: `id` plus the server's fields as attributes, as items (res["name"])
    and in `data`. str(resource) is its id."""

    def __init__(self, client: "Client", data: Mapping[str, Any]) -> None:
        self.client = client
        self.data: dict = dict(data)
        self._retry_after = 0.0  # > 0 after a long-poll the server declined (refresh)

    @property
    def id(self) -> str:
        return self.data["id"]

    def __getattr__(self, name: str) -> Any:
        # Metadata fields as attributes without freezing the list: new server fields just work.
        try:
            return self.__dict__["data"][name]
        except KeyError:
            raise AttributeError(name) from None

    def __getitem__(self, key: str) -> Any:
        return self.data[key]

    def get(self, key: str, default: Any = None) -> Any:
        return self.data.get(key, default)

    def __str__(self) -> str:
        return self.id


class Dataset(_Resource):
    """A stored dataset: `id` plus the server's metadata (`name`, `joints`, `samples`, `dt`,
    `uniform`, `has_torque`, `has_reference`, `has_rates`, `has_accelerations`, `source_job`,
    `created_at`) as attributes, as items and in `data`.

    Pass it (or its id string) to Client.identify(). str(dataset) is its id.
    """

    def csv(self) -> str:
        """The samples as CSV text (header t,q1..qn[,qd..][,qdd..][,tau1..taun][,ref1..refn])."""
        return self.client.dataset_csv(self.id)

    def delete(self) -> None:
        self.client.delete_dataset(self.id)

    def __repr__(self) -> str:
        return f"<Dataset {self.id} {self.data.get('joints')} joints × {self.data.get('samples')} samples>"


class Robot(_Resource):
    """An uploaded URDF robot: `id` ("rb_…") plus the server's description as attributes, as
    items (robot["joints"]) and in `data`: `name`, `robot_name`, `base_link`, `tip_link`,
    `joints` (name, link, type, axis, limits, damping, friction per moving joint, from the
    base), `gravity`, `parameters`
    (`names`: m1 mx1 my1 mz1 Ixx1 … fv1 … fc1 …, `urdf_values`), `base_parameters`
    (`count`), `warnings`, `created_at`.

    Pass it (or its id) to Client.identify(robot=...) and Client.design_excitation().
    """

    @property
    def joint_names(self) -> List[str]:
        """The moving joints' URDF names, k = 1..n (parameter names end in k)."""
        return [joint["name"] for joint in self.data.get("joints", [])]

    def urdf(self) -> str:
        """The URDF document as uploaded (byte for byte; see Client.robot_urdf)."""
        return self.client.robot_urdf(self.id)

    def delete(self) -> None:
        """Deletes the robot (409 CONFLICT while a queued or running job uses it)."""
        self.client.delete_robot(self.id)

    def __repr__(self) -> str:
        return f"<Robot {self.id} {self.data.get('name')!r} {len(self.data.get('joints', []))} joints>"


class History(NamedTuple):
    """A job's cost history as numpy arrays (Job.history(as_numpy=True)).

    index: (n,) int64; cost: (n,) float64; theta: (n, p) float64, column k is names[k].
    """

    index: Any
    cost: Any
    theta: Any
    names: List[str]


class Job:
    """A simulation, identification (the paper's preset), robot_identification (a URDF robot's),
    payload_identification (a payload on one's tip link) or excitation job. `data` is the JSON last seen from the server; `refresh()` fetches it again,
    `wait()` long-polls until the job ends."""

    def __init__(self, client: "Client", data: Mapping[str, Any]) -> None:
        self.client = client
        self.data: dict = dict(data)

    # --- the job's fields -------------------------------------------------------------
    @property
    def id(self) -> str:
        return self.data["id"]

    @property
    def state(self) -> str:
        """queued, running, succeeded, failed or cancelled, as last seen (refresh() to update)."""
        return self.data["state"]

    @property
    def kind(self) -> Optional[str]:
        """simulation, identification (the paper's preset), robot_identification (submitted with a
        robot: a URDF robot's base parameters), payload_identification (identify_payload) or
        excitation."""
        return self.data.get("kind")

    @property
    def done(self) -> bool:
        return self.state in TERMINAL_STATES

    @property
    def progress(self) -> dict:
        """{"evaluations": int, "best_cost": float | None} as last seen."""
        return dict(self.data.get("progress") or {})

    @property
    def dataset_id(self) -> Optional[str]:
        """The dataset identified, or the one a simulation or an excitation made (once it has
        succeeded)."""
        result = self.data.get("result") or {}
        return self.data.get("dataset_id") or result.get("dataset_id")

    @property
    def robot_id(self) -> Optional[str]:
        """The URDF robot a robot identification or an excitation works on (None otherwise)."""
        return self.data.get("robot_id")

    def __repr__(self) -> str:
        return f"<Job {self.id} {self.kind} {self.state}>"

    # --- life cycle --------------------------------------------------------------------
    def refresh(self, wait: Optional[float] = None) -> "Job":
        """Fetches the job again; with `wait` (s, ≤ 30) long-polls until it ends or that time passes."""
        path = f"/v1/jobs/{_quote(self.id)}"
        timeout = None
        if wait is not None and wait > 0:
            wait = min(float(wait), LONG_POLL_LIMIT)
            path += f"?wait={wait:g}"
            timeout = self.client.timeout + wait  # the answer may legitimately take `wait` seconds
        headers: dict = {}
        self.data = self.client._request("GET", path, timeout=timeout, answer_headers=headers)
        # The server lets only so many long-polls wait at once; beyond that it answers at once with
        # Manipid-Wait: declined and Retry-After, and wait() sleeps that long instead of asking again.
        self._retry_after = (float(headers.get("retry-after", "1"))
                             if headers.get("manipid-wait") == "declined" else 0.0)
        return self

    def wait(self, timeout: Optional[float] = None, progress: Union[bool, TextIO] = False) -> dict:
        """Waits until the job ends and returns its `result` dict.

        Long-polls `GET /v1/jobs/{id}?wait=S` (S ≤ 30 s). Raises JobFailed (with the job's
        problem fields) or JobCancelled (its `.result` has the best point reached), and
        JobTimeout when `timeout` seconds pass first (the job goes on).

        progress=True shows a live line (state, evaluations, best cost, elapsed time) on stderr
        when stderr is a terminal, rewritten in place with '\\r'; when it is not a terminal
        (a log file, CI) one line per state change is printed instead. A stream may be given
        instead of True.
        """
        stream = sys.stderr if progress is True else (progress or None)
        display = _Progress(stream, self.id) if stream is not None else None
        deadline = None if timeout is None else time.monotonic() + timeout
        try:
            while True:
                if display:
                    display.update(self.data)
                if self.done:
                    break
                step = PROGRESS_POLL if display and display.live else LONG_POLL_LIMIT
                if deadline is not None:
                    remaining = deadline - time.monotonic()
                    if remaining <= 0:
                        raise JobTimeout(f"job {self.id} still {self.state} after {timeout:g} s", job=self.data)
                    step = min(step, remaining)
                self.refresh(wait=step)
                if self._retry_after > 0 and not self.done:
                    pause = self._retry_after
                    if deadline is not None:
                        pause = min(pause, max(0.0, deadline - time.monotonic()))
                    time.sleep(pause)
        finally:
            if display:
                display.close()
        return self._outcome()

    def result(self, timeout: Optional[float] = None) -> dict:
        """The job's result dict, waiting for it if the job has not ended (like a future).

        Identification: estimates, std_errors, correlation, identifiability, final_cost,
        evaluations, ...; simulation: dataset_id, samples, ... Raises as wait() does.
        """
        if self.done:
            return self._outcome()
        return self.wait(timeout=timeout)

    def _outcome(self) -> dict:
        if self.state == "failed":
            raise JobFailed(self.data)
        if self.state == "cancelled":
            raise JobCancelled(self.data)
        return self.data.get("result") or {}

    def cancel(self) -> "Job":
        """Asks the server to cancel (idempotent). A queued job ends at once, a running
        identification at its next cost evaluation: wait() then raises JobCancelled."""
        self.data = self.client._request("POST", f"/v1/jobs/{_quote(self.id)}/cancel", b"")
        return self

    def delete(self) -> None:
        """Deletes a finished job and its history (409 CONFLICT while queued or running)."""
        self.client._request("DELETE", f"/v1/jobs/{_quote(self.id)}")

    def history(self, as_numpy: bool = False, page_size: int = 1000) -> Union[List[dict], History]:
        """Every cost evaluation so far (live while the job runs), following next_page_token.

        Default: a list of {"index": int, "cost": float, "parameters": {"m1": ..., ...}}.
        as_numpy=True: a History(index, cost, theta, names) of numpy arrays, theta being
        evaluations × parameters in the order of `names`; ImportError when numpy is missing.
        """
        if as_numpy:
            try:
                import numpy
            except ImportError as error:
                raise ImportError("Job.history(as_numpy=True) needs numpy; the default list needs nothing") from error
        entries: List[dict] = []
        token: Optional[str] = None
        while True:
            query = {"page_size": page_size}
            if token:
                query["page_token"] = token
            page = self.client._request("GET", f"/v1/jobs/{_quote(self.id)}/history", query=query)
            entries.extend(page.get("items", []))
            token = page.get("next_page_token")
            if not token:
                break
        if not as_numpy:
            return entries
        names = list(entries[0]["parameters"]) if entries else []
        return History(
            index=numpy.array([entry["index"] for entry in entries], dtype=numpy.int64),
            cost=numpy.array([entry["cost"] for entry in entries], dtype=numpy.float64),
            theta=numpy.array([[entry["parameters"][name] for name in names] for entry in entries],
                              dtype=numpy.float64).reshape(len(entries), len(names)),
            names=names)

    def history_csv(self) -> str:
        """The whole history as CSV text: index,cost,m1..mn,l1..ln."""
        return self.client._request("GET", f"/v1/jobs/{_quote(self.id)}/history", accept="text/csv")

    def history_overview(self, max_points: int = 2000) -> dict:
        """The history thinned for plotting: {"total", "stride", "best_index", "items"}, every
        stride-th evaluation plus the first, the best and the last (the stored history is whole)."""
        return self.client._request("GET", f"/v1/jobs/{_quote(self.id)}/history", query={"max_points": max_points})

    def fit(self, max_points: int = 2000) -> dict:
        """A finished identification's torque fit: the filtered measured torque beside the model
        torque at the estimate, per joint ({"t", "joints": [{"measured", "model", "residual",
        "rms_measured", "rms_residual"}], "filter", ...}), thinned to max_points for plotting."""
        return self.client.fit(self, max_points=max_points)

    # --- robot identifications and excitations ------------------------------------------
    def robot_result(self, timeout: Optional[float] = None) -> "RobotResult":
        """A robot identification's result by name (a RobotResult), waiting for it if needed
        (raises as wait() does)."""
        return RobotResult(self.result(timeout=timeout))

    def validation(self, max_points: int = 2000) -> dict:
        """A robot identification's prediction of its validation run (see Client.validation)."""
        return self.client.validation(self, max_points=max_points)

    def to_urdf(self, path: Optional[PathLike] = None) -> str:
        """The identified URDF (see Client.to_urdf); written to `path` when given."""
        return self.client.to_urdf(self, path)

    def trajectory(self, path: Optional[PathLike] = None, max_points: Optional[int] = None,
                   timeout: Optional[float] = None) -> dict:
        """An excitation's trajectory (see Client.excitation_trajectory), waiting for it if needed."""
        return self.client.excitation_trajectory(self, path=path, max_points=max_points, timeout=timeout)


class Client:
    """A connection to a manipid server.

    url: e.g. "http://127.0.0.1:8080" (a path prefix behind a proxy is kept);
    token: sent as `Authorization: Bearer <token>` (the server's --token, or your group's token
        of its --token-file: then you see your group's datasets, robots and jobs only);
    timeout: seconds for one request (a long-poll adds its wait to it).
    """

    def __init__(self, url: str, token: Optional[str] = None, timeout: float = 60.0) -> None:
        parts = urllib.parse.urlsplit(str(url))
        if parts.scheme not in ("http", "https") or not parts.hostname:
            raise ValueError(f"url must look like http://HOST:PORT, got {url!r}")
        self.url = str(url).rstrip("/")
        self.token = token
        self.timeout = float(timeout)
        self._parts = parts
        self._prefix = parts.path.rstrip("/")

    def __repr__(self) -> str:
        return f"Client({self.url!r})"

    # --- datasets ----------------------------------------------------------------------
    def upload_dataset(self, path_or_arrays: Union[PathLike, Mapping[str, Any]], name: Optional[str] = None,
                       idempotency_key: Optional[str] = None, columns: Optional[str] = None,
                       time_unit: Optional[str] = None, angle_unit: Optional[str] = None,
                       robot: Union["Robot", str, None] = None, topic: Optional[str] = None) -> Dataset:
        """Stores a trajectory and returns its Dataset.

        path_or_arrays is either
        - a CSV file path (str or os.PathLike) with header t,q1..qn[,qd1..qdn][,qdd1..qddn]
          [,tau1..taun][,ref1..refn] (what `manipid simulate --out` and `manipid torque
          --with-states` write), sent as it is; or
        - a dict with `t` (sample times) or `dt` (with optional `t0`), `q`, and optionally `qd`,
          `qdd`, `tau` and `ref`. Plain lists are per joint, as the API has them: q[j][i] is
          joint j+1 at sample i. numpy arrays are samples × joints (one row per sample, like the
          CSV) and are transposed; a 1-D array is one joint.
        Time stamps may jitter (a real logger's): the server stores them as measured and an
        identification resamples them (Dataset.uniform is then False).
        name: stored with the dataset. idempotency_key: a retry with the same key returns the
        first dataset.
        A CSV log with its own column names and units (CSV paths only): columns, a column map
        such as "time=t,position_{j}=q{j},effort_{j}=tau{j}" ({j} a joint number, {joint} one of
        `robot`'s joint names); time_unit "s", "ms", "us" or "ns"; angle_unit "rad" or "deg".
        A ROS 2 bag file (.db3, sensor_msgs/JointState) is sent as one: its joints matched by
        `robot`'s names, `topic` when it has several JointState topics.
        """
        query: Dict[str, Any] = {}
        if isinstance(path_or_arrays, (str, os.PathLike)):
            with open(path_or_arrays, "rb") as stream:
                body: Union[bytes, dict] = stream.read()
            content_type = "application/vnd.sqlite3" if body.startswith(b"SQLite format 3\0") else "text/csv"
            if name is not None:
                query["name"] = name
            for key, value in (("columns", columns), ("time_unit", time_unit), ("angle_unit", angle_unit),
                               ("topic", topic)):
                if value is not None:
                    query[key] = value
            if robot is not None:
                query["robot_id"] = robot if isinstance(robot, str) else robot.id
        elif any(value is not None for value in (columns, time_unit, angle_unit, robot, topic)):
            raise TypeError("columns, time_unit, angle_unit, robot and topic describe a log file: give its path")
        elif isinstance(path_or_arrays, Mapping):
            body, content_type = _arrays_to_json(path_or_arrays), "application/json"
            if name is not None:
                body["name"] = name
        else:
            raise TypeError("upload_dataset takes a CSV path or a dict of arrays (t or dt, q, qd, qdd, tau, ref), "
                            f"not {type(path_or_arrays).__name__}")
        data = self._request("POST", "/v1/datasets", body, query=query, content_type=content_type,
                             headers=_idempotency(idempotency_key))
        return Dataset(self, data)

    def dataset(self, dataset_id: Union[str, Dataset]) -> Dataset:
        """A dataset's metadata."""
        return Dataset(self, self._request("GET", f"/v1/datasets/{_quote(_dataset_id(dataset_id))}"))

    def datasets(self, page_size: int = 50) -> Iterator[Dataset]:
        """Every stored dataset, newest first (fetched page by page as you iterate)."""
        for item in self._pages("/v1/datasets", {"page_size": page_size}):
            yield Dataset(self, item)

    def dataset_csv(self, dataset_id: Union[str, Dataset]) -> str:
        """A dataset's samples as CSV text."""
        return self._request("GET", f"/v1/datasets/{_quote(_dataset_id(dataset_id))}",
                             query={"format": "csv"}, accept="text/csv")

    def dataset_data(self, dataset_id: Union[str, Dataset], max_points: Optional[int] = None) -> dict:
        """A dataset's samples as {"t", "q": [[joint 1...], ...], "tau"?, "ref"?} — the shape
        upload_dataset takes — all of them, or about max_points for plotting."""
        query = {"max_points": max_points} if max_points else None
        return self._request("GET", f"/v1/datasets/{_quote(_dataset_id(dataset_id))}/data", query=query)

    def preset(self, name: str = "cedro2009", kinetic_energy: str = "complete") -> dict:
        """A robot preset: true and initial parameters, PD gains, reference, horizon."""
        return self._request("GET", f"/v1/presets/{_quote(name)}", query={"kinetic_energy": kinetic_energy})

    def delete_dataset(self, dataset_id: Union[str, Dataset]) -> None:
        self._request("DELETE", f"/v1/datasets/{_quote(_dataset_id(dataset_id))}")

    # --- robots ------------------------------------------------------------------------
    def upload_robot(self, path_or_text: Union[PathLike, bytes], name: Optional[str] = None,
                     base: Optional[str] = None, tip: Optional[str] = None,
                     idempotency_key: Optional[str] = None, form: str = "xml") -> Robot:
        """Stores a robot's URDF (POST /v1/robots) and returns its Robot (id "rb_…").

        path_or_text: a URDF file's path (str or os.PathLike), or the document itself (a str
        starting with "<", or bytes). name: the robot's name (default: the URDF's robot name);
        base / tip: the links the chain runs between (default: the root and its only leaf).
        idempotency_key: a retry with the same key and document returns the first robot; a key
        derived from the file (e.g. "arm-" + its SHA-256) makes a script safe to re-run.
        form: "xml" sends the document as the body, as it is (name, base and tip as query
        parameters); "json" sends {"urdf": text, "name", "base", "tip"}. The server keeps the
        document byte for byte either way (robot_urdf gives it back). A URDF the server cannot
        use is refused: ManipidError 422 INVALID_FIELD with field "urdf" (or "base"/"tip").
        """
        document = _urdf_bytes(path_or_text)
        options = {key: value for key, value in (("name", name), ("base", base), ("tip", tip)) if value is not None}
        headers = _idempotency(idempotency_key)
        if form == "xml":
            data = self._request("POST", "/v1/robots", document, query=options, content_type="application/xml",
                                 headers=headers)
        elif form == "json":
            try:
                text = document.decode("utf-8")
            except UnicodeDecodeError as error:
                raise ValueError(f"form='json' needs a UTF-8 document ({error}); send it with form='xml'") from None
            data = self._request("POST", "/v1/robots", {"urdf": text, **options}, headers=headers)
        else:
            raise ValueError(f"form must be 'xml' or 'json', not {form!r}")
        return Robot(self, data)

    def robot(self, robot_id: Union[str, Robot, Mapping[str, Any]]) -> Robot:
        """A robot's description (404 NOT_FOUND when there is none)."""
        return Robot(self, self._request("GET", f"/v1/robots/{_quote(_robot_id(robot_id))}"))

    def robots(self, page_size: int = 50) -> Iterator[Robot]:
        """Every stored robot, newest first (fetched page by page as you iterate)."""
        for item in self._pages("/v1/robots", {"page_size": page_size}):
            yield Robot(self, item)

    def robot_urdf(self, robot_id: Union[str, Robot, Mapping[str, Any]]) -> str:
        """A robot's URDF document exactly as uploaded (GET /v1/robots/{id}?format=urdf), as text
        (UTF-8; the bytes themselves: robot_urdf_bytes)."""
        return self.robot_urdf_bytes(robot_id).decode("utf-8")

    def robot_urdf_bytes(self, robot_id: Union[str, Robot, Mapping[str, Any]]) -> bytes:
        """A robot's URDF document exactly as uploaded, byte for byte."""
        return self._request("GET", f"/v1/robots/{_quote(_robot_id(robot_id))}", query={"format": "urdf"},
                             accept="application/xml", raw=True)

    def delete_robot(self, robot_id: Union[str, Robot, Mapping[str, Any]]) -> None:
        """Deletes a robot: 404 NOT_FOUND if there is none, 409 CONFLICT while a queued or running
        job uses it (its finished jobs keep their results; their /fit and /urdf then answer 409)."""
        self._request("DELETE", f"/v1/robots/{_quote(_robot_id(robot_id))}")

    def design_excitation(self, robot: Union[str, Robot, Mapping[str, Any]], period: Optional[float] = None,
                          harmonics: Optional[int] = None, duration: Optional[float] = None,
                          criterion: Optional[str] = None, idempotency_key: Optional[str] = None,
                          **options: Any) -> Job:
        """Queues an excitation design for a robot (POST /v1/excitations); returns its Job.

        Per joint a Fourier series of `period` s (server default 10) with `harmonics` (5),
        at rest at both ends, within the URDF's position (less position_margin, 0.1 rad),
        velocity and effort limits, minimising the condition number of the base regressor
        (criterion "condition") or maximising log det ("logdet"); sampled every `dt` (0.001 s)
        over `duration` (whole periods; default one). Other keyword options are the request's
        fields: name (of the dataset it makes), max_velocity, max_acceleration (7.5), max_jerk,
        max_torque (each one number or one per joint), torque_parameters (an identification's
        result: the model whose torque max_torque holds), start_pose (a list, rad: the run
        ramps from it and back), position_margin, dt, friction, armature, seed,
        max_evaluations (8000: the same design on every machine), max_seconds (300, a cap).
        Options left at None are not sent (the server's default applies).

        The job's result names the dataset it made (job.dataset_id; t, q, qd, qdd) and carries
        the coefficients; excitation_trajectory(job) fetches the samples.
        """
        body = _drop_none({"robot_id": _robot_id(robot), "period": period, "harmonics": harmonics,
                           "duration": duration, "criterion": criterion, **options})
        if "friction" in body:
            body["friction"] = _friction(body["friction"])
        return Job(self, self._request("POST", "/v1/excitations", body, headers=_idempotency(idempotency_key)))

    def excitation_trajectory(self, job: Union[str, Job, Mapping[str, Any]], path: Optional[PathLike] = None,
                              max_points: Optional[int] = None, timeout: Optional[float] = None) -> dict:
        """An excitation job's trajectory, waiting for the job if it has not ended: {"t", "q",
        "qd", "qdd"}, each of q, qd, qdd one list per joint (q[j][i] is joint j+1 at sample i),
        all the samples or about max_points for plotting. With `path`, also writes the whole
        trajectory there as CSV (t,q1..qn,qd1..qdn,qdd1..qddn), for the robot's controller.
        """
        job = job if isinstance(job, Job) else self.job(_job_id(job))
        result = job.result(timeout=timeout)
        dataset_id = result.get("dataset_id")
        if not dataset_id:
            raise ValueError(f"job {job.id} ({job.kind}) made no dataset: not an excitation")
        if path is not None:
            with open(path, "w", encoding="utf-8", newline="") as stream:
                stream.write(self.dataset_csv(dataset_id))
        return self.dataset_data(dataset_id, max_points=max_points)

    # --- results of robot identifications ------------------------------------------------
    def fit(self, job: Union[str, Job], max_points: int = 2000) -> dict:
        """GET /v1/jobs/{id}/fit: a finished identification's filtered measured torque beside the
        model torque at the estimate, with the residual, per joint ({"t", "joints": [{"measured",
        "model", "residual", "rms_measured", "rms_residual", ...}], ...}), thinned to max_points
        for plotting. 409 CONFLICT for jobs without an estimate."""
        return self._request("GET", f"/v1/jobs/{_quote(_job_id(job))}/fit", query={"max_points": max_points})

    def validation(self, job: Union[str, Job], max_points: int = 2000) -> dict:
        """GET /v1/jobs/{id}/validation: the validation run's filtered torque beside what the
        estimate predicts, per joint, with the error ({"t", "joints": [{"measured", "model",
        "residual", "relative_error", ...}], "overall_relative_error", "prior": the URDF's own
        values' errors}; a payload identification's: "model" with the payload, "arm_only" without
        it). 409 CONFLICT unless the job is a succeeded robot or payload identification that was
        given validate=."""
        return self._request("GET", f"/v1/jobs/{_quote(_job_id(job))}/validation", query={"max_points": max_points})

    def to_urdf(self, job: Union[str, Job], path: Optional[PathLike] = None) -> str:
        """The identified URDF: GET /v1/jobs/{id}/urdf, the robot's document with the estimate
        (each body's <inertial>, each joint's <dynamics>) written in by the server. Returns the
        text; with `path`, also writes it there (byte for byte). A payload identification's: the
        robot's document with the payload mounted on its tip link as a fixed link
        (manipid_payload). 409 CONFLICT for a job that is not a succeeded robot or payload
        identification, whose estimate no URDF can hold (a body with a negative mass: identify with
        physical=True), or that found no payload."""
        document = self._request("GET", f"/v1/jobs/{_quote(_job_id(job))}/urdf", accept="application/xml", raw=True)
        if path is not None:
            with open(path, "wb") as stream:
                stream.write(document)
        return document.decode("utf-8")

    # --- jobs --------------------------------------------------------------------------
    def simulate(self, idempotency_key: Optional[str] = None, **options: Any) -> Job:
        """Queues a closed-loop simulation (POST /v1/simulations); returns its Job.

        Keyword options are the request's JSON fields: preset, kinetic_energy, name,
        parameters, kp, kd, reference, duration, dt, noise, ... (none: the paper's run).
        Job.wait() returns {"dataset_id": ..., "samples": ..., ...}.
        """
        return Job(self, self._request("POST", "/v1/simulations", options, headers=_idempotency(idempotency_key)))

    def identify(self, dataset: Union[str, Dataset, Mapping[str, Any], Sequence[Any], None] = None,
                 idempotency_key: Optional[str] = None, *,
                 robot: Union[str, Robot, Mapping[str, Any], None] = None,
                 validate: Union[str, Dataset, Mapping[str, Any], Sequence[Any], None] = None,
                 friction: Union[Sequence[str], str, None] = None, armature: Optional[bool] = None,
                 physical: Optional[bool] = None, trim: Optional[Sequence[float]] = None,
                 dt: Optional[float] = None, weights: Optional[str] = None,
                 comparison_cutoff: Union[float, str, None] = None, ridge: Union[float, str, None] = None,
                 judge_cutoff: Optional[float] = None, judge_trim: Optional[float] = None,
                 torque_joints: Optional[Sequence[int]] = None, **options: Any) -> Job:
        """Queues an identification (POST /v1/identifications); returns its Job.

        dataset: a Dataset, a dataset id (or the dict of one), or None with simulation={...}
        (simulate, then identify). With robot=, also a list of them: several runs, each filtered
        alone, then fitted together.

        Without robot: the paper's preset model. Keyword options are the request's JSON fields:
        preset, method, algorithm, free, initial, lower, upper, kp, kd, half_length, band,
        torque_source, weights, max_evaluations, max_seconds, ... (unknown ones are refused by
        the server, 422).

        With robot (a Robot, its id, or its dict): that URDF robot's base parameters by linear
        input-error (a RobotIdentificationRequest). Each dataset needs q and tau for the robot's
        joints (422 naming the dataset otherwise); its time stamps may jitter.
        - validate: runs (a Dataset or id, or a list) the estimate then predicts under the judge
          (result's "validation", Client.validation(job));
        - friction: "auto" (the server's default: chosen by held-out prediction) or any of
          "viscous", "coulomb", "offset" (a list, or "viscous,coulomb"; [] or "none" for none);
        - armature: each joint's rotor inertia Ia; physical: a physically consistent estimate;
        - trim: (start, end) seconds dropped at each end; dt: the resampling period (default the
          median step); weights: "unit" or "per-joint";
        - comparison_cutoff: the low-pass (Hz) applied to tau and the regressor alike, ridge: the
          relative ridge toward the URDF's values (0: least squares) — both "auto" by default,
          chosen by held-out prediction;
        - judge_cutoff (Hz, default 5), judge_trim (s, default 0.3): the fixed low-pass every
          torque figure is judged under; torque_joints: the joints with torque sensors (1-based;
          default every joint whose torque is not zero throughout);
        - options: half_length, band (the differentiation filter).
        job.robot_result() gives the result by name (RobotResult); to_urdf(job) the URDF.
        Arguments left at None are not sent (the server's default applies).
        """
        body = _drop_none(dict(options))
        robot_fields = _drop_none({"friction": _friction(friction) if friction is not None else None,
                                   "armature": armature, "physical": physical,
                                   "trim": list(trim) if trim is not None else None, "dt": dt, "weights": weights,
                                   "comparison_cutoff": comparison_cutoff, "ridge": ridge,
                                   "judge_cutoff": judge_cutoff, "judge_trim": judge_trim,
                                   "torque_joints": list(torque_joints) if torque_joints is not None else None})
        if dataset is not None:
            if "dataset_id" in body or "dataset_ids" in body:
                raise TypeError("give the dataset either positionally or as dataset_id=, not both")
            if _is_several(dataset):
                if robot is None:
                    raise TypeError("several datasets need robot=: the paper's model is identified from one run")
                body["dataset_ids"] = [_dataset_id(item) for item in dataset]
            else:
                body["dataset_id"] = _dataset_id(dataset)
        if robot is not None:
            if "robot_id" in body:
                raise TypeError("give the robot either as robot= or as robot_id=, not both")
            body["robot_id"] = _robot_id(robot)
        if validate is not None:
            if "robot_id" not in body:
                raise TypeError("validate= needs robot=: only robot identifications predict a validation run")
            if _is_several(validate):
                body["validation_dataset_ids"] = [_dataset_id(item) for item in validate]
            else:
                body["validation_dataset_id"] = _dataset_id(validate)
        body.update(robot_fields)
        return Job(self, self._request("POST", "/v1/identifications", body, headers=_idempotency(idempotency_key)))

    def identify_payload(self, dataset: Union[str, Dataset, Mapping[str, Any], Sequence[Any]],
                         robot: Union[str, Robot, Mapping[str, Any]],
                         arm: Union[str, Job, Mapping[str, Any], None] = None,
                         idempotency_key: Optional[str] = None, *,
                         validate: Union[str, Dataset, Mapping[str, Any], Sequence[Any], None] = None,
                         known_mass: Optional[float] = None, known_centre_of_mass: Optional[Sequence[float]] = None,
                         physical: Optional[bool] = None, trim: Optional[Sequence[float]] = None, dt: Optional[float] = None,
                         comparison_cutoff: Optional[float] = None, judge_cutoff: Optional[float] = None,
                         judge_trim: Optional[float] = None, torque_joints: Optional[Sequence[int]] = None,
                         **options: Any) -> Job:
        """Queues a payload identification (POST /v1/identifications with "payload": true); returns
        its Job (kind "payload_identification").

        A payload (a tool, a gripper, a part) rigidly fixed to the robot's tip link: its mass,
        centre of mass and inertia from the torque the arm leaves unexplained on runs carrying it.
        - dataset: the run(s) with the payload (a Dataset or id, or a list of them);
        - robot: the robot it is mounted on (a Robot, its id, or its dict);
        - arm: the arm as identified, a finished robot identification of the same robot without
          the payload (a Job or its id); None: the URDF's own values. One that is not a succeeded
          robot identification of this robot is refused (ManipidError 422 naming arm_job_id);
        - validate: runs with the payload the arm then predicts with and without it;
        - known_mass (kg) / known_centre_of_mass ((x, y, z) m, the tip link's frame): values you
          know; only the rest is estimated;
        - physical=True: a real rigid body (mass > 0, inertia about the centre of mass positive
          definite, triangle inequalities), which a URDF and a simulator take; the result's
          "consistent" says whether the payload is one either way;
        - trim, dt, judge_cutoff, judge_trim, torque_joints: as identify(robot=...) takes them;
          comparison_cutoff: the residual's low-pass, Hz (default: chosen by held-out error, as for the arm);
        - any other request field by name, e.g. weights="per-joint" (each joint by its residual).
        The result (job.wait()) is what `manipid payload --json` prints: "mass",
        "mass_std_error", "centre_of_mass", "inertia_about_com", their standard errors,
        "detected" (False for a run without a payload: ≈ 0 kg within its uncertainty, not an
        error), "undetermined", "warnings", "fit" and "validation" (torque error without and with
        the payload). fit(job) / validation(job) draw the torque with and without it;
        to_urdf(job) writes the robot's URDF with the payload mounted on its tip link.
        Arguments left at None are not sent (the server's default applies).
        """
        body = _drop_none({"payload": True, "robot_id": _robot_id(robot),
                           "arm_job_id": _job_id(arm) if arm is not None else None,
                           "known_mass": known_mass,
                           "known_centre_of_mass": list(known_centre_of_mass) if known_centre_of_mass is not None else None,
                           "physical": physical, "trim": list(trim) if trim is not None else None, "dt": dt,
                           "comparison_cutoff": comparison_cutoff, "judge_cutoff": judge_cutoff,
                           "judge_trim": judge_trim,
                           "torque_joints": list(torque_joints) if torque_joints is not None else None,
                           **options})
        if _is_several(dataset):
            body["dataset_ids"] = [_dataset_id(item) for item in dataset]
        else:
            body["dataset_id"] = _dataset_id(dataset)
        if validate is not None:
            if _is_several(validate):
                body["validation_dataset_ids"] = [_dataset_id(item) for item in validate]
            else:
                body["validation_dataset_id"] = _dataset_id(validate)
        return Job(self, self._request("POST", "/v1/identifications", body, headers=_idempotency(idempotency_key)))

    def job(self, job_id: Union[str, Job, Mapping[str, Any]]) -> Job:
        """A job by id (e.g. one submitted by another script), fetched anew."""
        return Job(self, self._request("GET", f"/v1/jobs/{_quote(_job_id(job_id))}"))

    def jobs(self, state: Optional[str] = None, kind: Optional[str] = None, page_size: int = 50,
             robot: Union[None, str, Robot, Mapping[str, Any]] = None) -> Iterator[Job]:
        """Every job, newest first, optionally of one state, kind (simulation, identification,
        robot_identification, payload_identification, excitation) and/or robot (its identifications,
        payload identifications and excitations), paged
        as you iterate. Listed jobs carry no `request`; refresh() one for the full record."""
        query: Dict[str, Any] = {"page_size": page_size}
        if state is not None:
            query["state"] = state
        if kind is not None:
            query["kind"] = kind
        if robot is not None:
            query["robot_id"] = _robot_id(robot)
        for item in self._pages("/v1/jobs", query):
            yield Job(self, item)

    def health(self) -> dict:
        """GET /healthz: {"status": "ok"} while serving."""
        return self._request("GET", "/healthz")

    # --- HTTP --------------------------------------------------------------------------
    def _pages(self, path: str, query: Dict[str, Any]) -> Iterator[dict]:
        token: Optional[str] = None
        while True:
            page = self._request("GET", path, query={**query, **({"page_token": token} if token else {})})
            yield from page.get("items", [])
            token = page.get("next_page_token")
            if not token:
                return

    def _request(self, method: str, path: str, body: Union[bytes, Mapping, None] = None, *,
                 query: Optional[Mapping[str, Any]] = None, content_type: Optional[str] = None,
                 accept: str = "application/json", headers: Optional[Mapping[str, str]] = None,
                 timeout: Optional[float] = None, raw: bool = False,
                 answer_headers: Optional[dict] = None) -> Any:
        """One request; returns parsed JSON (or text for non-JSON answers, None for 204; with
        raw=True the body's bytes as they came). `answer_headers`, when given, receives the
        answer's headers (names in lower case)."""
        all_headers = {"Accept": accept, "User-Agent": "manipid-client-python"}
        if self.token:
            all_headers["Authorization"] = f"Bearer {self.token}"
        if isinstance(body, Mapping):
            try:
                # allow_nan=False: NaN/Infinity are not JSON; say so here rather than as a parse error there.
                body = json.dumps(body, allow_nan=False).encode()
            except ValueError as error:
                raise ValueError(f"every number sent must be finite: {error}") from None
            content_type = content_type or "application/json"
        if body is not None:
            all_headers["Content-Type"] = content_type or "application/octet-stream"
        elif method == "POST":
            body = b""  # a POST without Content-Length is refused (400), so send an empty body
        all_headers.update(headers or {})
        target = self._prefix + path
        if query:
            target += "?" + urllib.parse.urlencode(query)

        connection_class = http.client.HTTPSConnection if self._parts.scheme == "https" else http.client.HTTPConnection
        connection = connection_class(self._parts.hostname, self._parts.port,
                                      timeout=timeout if timeout is not None else self.timeout)
        try:
            connection.request(method, target, body=body, headers=all_headers)
            response = connection.getresponse()
            data = response.read()
            status = response.status
            answer_type = response.getheader("Content-Type", "")
            retry_after = response.getheader("Retry-After")
            if answer_headers is not None:
                answer_headers.update({name.lower(): value for name, value in response.getheaders()})
        except (OSError, http.client.HTTPException) as error:
            kind = "timed out" if isinstance(error, socket.timeout) else "failed"
            raise ManipidConnectionError(f"{method} {self.url}{path} {kind}: {error}") from error
        finally:
            connection.close()

        parsed: Any = None
        if "json" in answer_type and data:
            try:
                parsed = json.loads(data)
            except ValueError:
                parsed = None
        if status >= 400:
            problem = parsed if isinstance(parsed, dict) else {}
            message = None if problem.get("detail") or problem.get("title") else \
                f"{method} {path}: HTTP {status} {data[:200].decode(errors='replace')}".strip()
            raise ManipidError(message, status=status, problem=problem, retry_after=_seconds(retry_after))
        if raw:
            return data
        if status == 204 or not data:
            return None
        if parsed is not None:
            return parsed
        return data.decode("utf-8", errors="replace")


# --- helpers ---------------------------------------------------------------------------
class _Progress:
    """The progress display of Job.wait(progress=True): one line rewritten in place on a
    terminal, else a line per state change (so logs stay readable)."""

    def __init__(self, stream: TextIO, job_id: str) -> None:
        self.stream = stream
        self.job_id = job_id
        try:
            self.live = bool(stream.isatty())
        except (AttributeError, ValueError):
            self.live = False
        self.started = time.monotonic()
        self.last_state: Optional[str] = None
        self.width = 0

    def update(self, job: Mapping[str, Any]) -> None:
        state = job.get("state", "?")
        progress = job.get("progress") or {}
        evaluations = progress.get("evaluations")
        best = progress.get("best_cost")
        text = f"{self.job_id} {state}"
        if evaluations:
            text += f"  {evaluations} evaluations"
        if best is not None:
            text += f"  best cost {best:.6g}"
        try:
            if self.live:
                text += f"  {time.monotonic() - self.started:.1f} s"
                # Pad over the previous text: no terminal escape codes needed.
                self.stream.write("\r" + text.ljust(self.width))
                self.width = max(self.width, len(text))
                self.stream.flush()
            elif state != self.last_state:
                self.stream.write(text + "\n")
                self.stream.flush()
        except (OSError, ValueError):
            pass  # a closed or broken stderr must not fail the wait
        self.last_state = state

    def close(self) -> None:
        if self.live and self.width:
            try:
                self.stream.write("\n")
                self.stream.flush()
            except (OSError, ValueError):
                pass


def _quote(segment: str) -> str:
    return urllib.parse.quote(str(segment), safe="")


def _idempotency(key: Optional[str]) -> Dict[str, str]:
    return {"Idempotency-Key": str(key)} if key is not None else {}


def _seconds(value: Optional[str]) -> Optional[float]:
    try:
        return float(value) if value is not None else None
    except ValueError:
        return None


def _robot_id(robot: Union[str, Robot, Mapping[str, Any]]) -> str:
    if isinstance(robot, Robot):
        return robot.id
    if isinstance(robot, Mapping):
        return str(robot["id"])
    if isinstance(robot, str):
        return robot
    raise TypeError(f"expected a Robot or a robot id, not {type(robot).__name__}")


def _job_id(job: Union[str, Job, Mapping[str, Any]]) -> str:
    if isinstance(job, Job):
        return job.id
    if isinstance(job, Mapping):
        return str(job["id"])
    if isinstance(job, str):
        return job
    raise TypeError(f"expected a Job or a job id, not {type(job).__name__}")


def _drop_none(fields: Mapping[str, Any]) -> Dict[str, Any]:
    return {key: value for key, value in fields.items() if value is not None}


def _is_several(value: Any) -> bool:
    """A list or tuple of datasets (not one dataset's dict, id or Dataset)."""
    return isinstance(value, (list, tuple))


def _friction(terms: Union[Sequence[str], str]) -> Union[List[str], str]:
    """["viscous", "coulomb"] from a list or from "viscous,coulomb"; "none" or "" is []; "auto" stays "auto"."""
    if isinstance(terms, str) and terms.strip() == "auto":
        return "auto"
    if isinstance(terms, str):
        terms = [term.strip() for term in terms.split(",") if term.strip()]
    terms = list(terms)
    return [] if terms == ["none"] else terms


def _urdf_bytes(path_or_text: Union[PathLike, bytes]) -> bytes:
    """The URDF document: bytes as they are, a str that starts with '<' as UTF-8, else a file's bytes."""
    if isinstance(path_or_text, (bytes, bytearray)):
        return bytes(path_or_text)
    if isinstance(path_or_text, str) and path_or_text.lstrip("\ufeff \t\r\n").startswith("<"):
        return path_or_text.encode("utf-8")
    if isinstance(path_or_text, (str, os.PathLike)):
        with open(path_or_text, "rb") as stream:
            return stream.read()
    raise TypeError(f"upload_robot takes a URDF file path or the document (str or bytes), not {type(path_or_text).__name__}")


def _dataset_id(dataset: Union[str, Dataset, Mapping[str, Any]]) -> str:
    if isinstance(dataset, Dataset):
        return dataset.id
    if isinstance(dataset, Mapping):
        return str(dataset["id"])
    if isinstance(dataset, str):
        return dataset
    raise TypeError(f"expected a Dataset or a dataset id, not {type(dataset).__name__}")


def _per_joint(value: Any) -> Any:
    """numpy samples × joints → per-joint lists; plain lists pass through (already per joint)."""
    if hasattr(value, "ndim") and hasattr(value, "tolist"):
        if value.ndim == 1:
            return [value.tolist()]
        if value.ndim == 2:
            return value.T.tolist()
        raise ValueError(f"expected a samples × joints array, got {value.ndim} dimensions")
    return value


def _arrays_to_json(arrays: Mapping[str, Any]) -> dict:
    body: Dict[str, Any] = {}
    for key, value in arrays.items():
        if key in ("q", "qd", "qdd", "tau", "ref"):
            body[key] = _per_joint(value)
        elif hasattr(value, "tolist"):
            body[key] = value.tolist()  # numpy t, or numpy scalars for dt/t0
        else:
            body[key] = value
    return body
