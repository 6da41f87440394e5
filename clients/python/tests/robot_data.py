"""Test data for the clients' robot tests, made with the real `manipid` binary.

- an excitation of a URDF robot (`manipid excitation`, a small deterministic evaluation budget);
- `run.csv`: its samples through `manipid torque --with-states` with a known truth (some
  parameters off the URDF's values) and measurement noise: t,q,qd,qdd,tau at a uniform 1 kHz;
- `jitter.csv`: the same motion as a real logger records it: time stamps jittered around
  1 ms, a few samples missing (2 ms gaps) and about one row in eighteen a stale repeat of the
  row before under a new time stamp. q, qd, qdd are the excitation's Fourier series evaluated
  at the jittered times (from the design's coefficients, checked against the uniform samples
  first), so the torques are consistent with the times;
- `check.csv`: a second, different excitation through the same truth: a validation run;
- `clean.csv`: run.csv's motion and truth without noise (an estimate a URDF can hold);
- `tool.csv`: run.csv's motion and truth with a tool of known mass, centre of mass and inertia (TOOL)
  mounted on the tip link (`tool.urdf`: the URDF with the tool as a fixed link), with noise: a
  payload identification's run;
- `truth.json`: the parameter values by name the torques were made with.

Shared by the Python tests and the curl batch test:

    python3 clients/python/tests/robot_data.py MANIPID_BIN URDF DIR   # prints the files as JSON

Making them takes ~40 s under the sanitizers, so ctest makes them once (the `robot_data` fixture)
and names the folder in MANIPID_ROBOT_DATA; robot_runs() copies from there when that folder was
made by the same binary from the same URDF, and makes them itself otherwise.
"""
from __future__ import annotations

import csv
import json
import math
import os
import random
import shutil
import subprocess
import sys
from typing import Dict, List, Mapping, Sequence

# Off the panda_like URDF's values: link 3's mass, joint 2's viscous and Coulomb friction and
# joint 3's offset. Names absent keep the URDF's values (giving fc2 keeps the Coulomb block).
# Link 3 is heavier, not lighter: with its first moments and inertia kept, a lighter link 3
# would not be a real rigid body (its inertia about the centre of mass would not be positive).
TRUTH = {"m3": 3.0, "fv2": 0.4, "fc2": 0.7, "fo3": 0.05}


# A tool on the tip link, in the tip link's frame: kg, m, kg m² about its centre of mass (URDF entries).
TOOL = {"mass": 1.5, "centre_of_mass": [0.02, -0.01, 0.06],
        "inertia": {"ixx": 0.004, "ixy": 0.0003, "ixz": -0.0002, "iyy": 0.005, "iyz": 0.0001, "izz": 0.003}}


def with_tool(document: str, tip: str, tool: Mapping = TOOL) -> str:
    """The URDF document with `tool` mounted on the link `tip` by a fixed joint at the identity (a link
    "test_tool"): a URDF parser merges it into the tip body, so the arm carries the tool."""
    x, y, z = tool["centre_of_mass"]
    inertia = " ".join(f'{key}="{value!r}"' for key, value in tool["inertia"].items())
    mounted = (f'<link name="test_tool"><inertial><origin xyz="{x!r} {y!r} {z!r}" rpy="0 0 0"/>'
               f'<mass value="{tool["mass"]!r}"/><inertia {inertia}/></inertial></link>'
               f'<joint name="test_tool_joint" type="fixed"><parent link="{tip}"/><child link="test_tool"/>'
               '<origin xyz="0 0 0" rpy="0 0 0"/></joint>')
    end = document.rindex("</robot>")
    return document[:end] + mounted + document[end:]


def tip_link(document: str) -> str:
    """The URDF's only leaf link (the default tip)."""
    import xml.etree.ElementTree as ElementTree
    root = ElementTree.fromstring(document)
    parents = {joint.find("parent").get("link") for joint in root.iter("joint")}
    leaves = [link.get("name") for link in root.iter("link") if link.get("name") not in parents]
    if len(leaves) != 1:
        raise ValueError(f"the URDF has {len(leaves)} leaf links, expected one: {leaves}")
    return leaves[0]


def run(binary: str, *arguments: str) -> None:
    done = subprocess.run([binary, *arguments], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"manipid {' '.join(arguments)} failed ({done.returncode}): {done.stderr.strip()}")


def excitation(binary: str, urdf: str, out: str, *, period: float, harmonics: int, duration: float,
               seed: int, max_evaluations: int = 300) -> dict:
    """`manipid excitation` into `out` (t,q,qd,qdd); returns its coefficients."""
    coefficients = out + ".json"
    run(binary, "excitation", "--robot", urdf, "--period", repr(period), "--harmonics", str(harmonics),
        "--duration", repr(duration), "--seed", str(seed), "--max-evaluations", str(max_evaluations),
        "--max-seconds", "60", "--out", out, "--coefficients", coefficients)
    with open(coefficients) as stream:
        return json.load(stream)


def fourier_states(coefficients: Mapping, t: float) -> List[float]:
    """q, qd, qdd of every joint at time t from the design's series:
    q_k = q0_k + sum_l [a_kl/(w l) sin(w l t) - b_kl/(w l) cos(w l t)], qd_k = sum_l [a_kl cos + b_kl sin]."""
    w = coefficients["angular_frequency"]
    q, qd, qdd = [], [], []
    for q0, a, b in zip(coefficients["q0"], coefficients["a"], coefficients["b"]):
        position, rate, acceleration = q0, 0.0, 0.0
        for l, (a_l, b_l) in enumerate(zip(a, b), start=1):
            wl = w * l
            s, c = math.sin(wl * t), math.cos(wl * t)
            position += a_l / wl * s - b_l / wl * c
            rate += a_l * c + b_l * s
            acceleration += wl * (b_l * c - a_l * s)
        q.append(position)
        qd.append(rate)
        qdd.append(acceleration)
    return q + qd + qdd


def read_rows(path: str) -> (List[str], List[List[float]]):
    with open(path, newline="") as stream:
        reader = csv.reader(stream)
        header = next(reader)
        return header, [[float(x) for x in row] for row in reader if row]


def write_rows(path: str, header: Sequence[str], rows: Sequence[Sequence[float]]) -> None:
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(header)
        writer.writerows([repr(x) for x in row] for row in rows)


def check_series(coefficients: Mapping, excitation_csv: str) -> None:
    """The series evaluated here equals the binary's own samples (else the formula was misread)."""
    _, rows = read_rows(excitation_csv)
    for row in rows[:: max(1, len(rows) // 50)]:
        mine = fourier_states(coefficients, row[0])
        worst = max(abs(x - y) for x, y in zip(mine, row[1:]))
        if worst > 1e-9:
            raise AssertionError(f"the Fourier series differs from manipid excitation's samples by {worst} at t = {row[0]}")


def jittered_rows(coefficients: Mapping, duration: float, rng: random.Random) -> List[List[float]]:
    """States at a logger's times: 1 ms ± 0.25 ms, 2 % of the samples missing."""
    count = int(round(duration / 0.001))
    times = [0.0]
    for i in range(1, count):
        if rng.random() < 0.02:
            continue  # a missing sample: a 2 ms gap
        times.append(i * 0.001 + rng.uniform(-0.25e-3, 0.25e-3))
    times.append(duration)
    return [[t] + fourier_states(coefficients, t) for t in times]


def stale_repeats(rows: List[List[float]], every: int = 18) -> int:
    """Every `every`-th row becomes the previous row's values under its own time stamp (as a
    logger that missed a fresh measurement writes); returns how many."""
    repeated = 0
    for i in range(every // 2, len(rows) - 1, every):
        rows[i] = [rows[i][0]] + rows[i - 1][1:]
        repeated += 1
    return repeated


def make_robot_runs(binary: str, urdf: str, directory: str, truth: Mapping[str, float] = TRUTH) -> Dict[str, object]:
    """Writes excitation.csv, run.csv, clean.csv, jitter.csv, check.csv, tool.urdf, tool.csv and
    truth.json into `directory`; returns their paths ("run", "clean", "jitter", "check", "excitation",
    "tool"), the truth, the tool, the joint count, and jitter.csv's rows and stale repeats."""
    os.makedirs(directory, exist_ok=True)
    files = {name: os.path.join(directory, name) for name in
             ("excitation.csv", "states.csv", "run.csv", "clean.csv", "jitter.csv", "check-excitation.csv", "check.csv",
              "tool.urdf", "tool.csv", "truth.json")}
    with open(files["truth.json"], "w") as stream:
        json.dump(dict(truth), stream)
    noise = ["--noise-tau-relative", "0.01", "--noise-q", "2e-5", "--quantize-q", "18"]

    coefficients = excitation(binary, urdf, files["excitation.csv"], period=10.0, harmonics=5, duration=20.0, seed=1)
    check_series(coefficients, files["excitation.csv"])
    run(binary, "torque", "--robot", urdf, "--in", files["excitation.csv"], "--with-states", "--params",
        files["truth.json"], *noise, "--seed", "11", "--out", files["run.csv"])
    run(binary, "torque", "--robot", urdf, "--in", files["excitation.csv"], "--with-states", "--params",
        files["truth.json"], "--out", files["clean.csv"])
    with open(urdf) as stream:
        document = stream.read()
    with open(files["tool.urdf"], "w") as stream:
        stream.write(with_tool(document, tip_link(document)))
    run(binary, "torque", "--robot", files["tool.urdf"], "--in", files["excitation.csv"], "--with-states", "--params",
        files["truth.json"], *noise, "--seed", "14", "--out", files["tool.csv"])

    rows = jittered_rows(coefficients, 20.0, random.Random(5))
    joints = len(coefficients["q0"])
    header = ["t"] + [f"{block}{k}" for block in ("q", "qd", "qdd") for k in range(1, joints + 1)]
    write_rows(files["states.csv"], header, rows)
    run(binary, "torque", "--robot", urdf, "--in", files["states.csv"], "--with-states", "--params",
        files["truth.json"], *noise, "--seed", "12", "--out", files["jitter.csv"])
    header, measured = read_rows(files["jitter.csv"])
    repeats = stale_repeats(measured)
    write_rows(files["jitter.csv"], header, measured)

    excitation(binary, urdf, files["check-excitation.csv"], period=5.0, harmonics=4, duration=10.0, seed=2,
               max_evaluations=100)
    run(binary, "torque", "--robot", urdf, "--in", files["check-excitation.csv"], "--with-states", "--params",
        files["truth.json"], *noise, "--seed", "13", "--out", files["check.csv"])
    return {"run": files["run.csv"], "clean": files["clean.csv"], "jitter": files["jitter.csv"], "check": files["check.csv"],
            "excitation": files["excitation.csv"], "tool": files["tool.csv"], "truth": dict(truth), "tool_truth": TOOL,
            "joints": joints,
            "jitter_rows": len(measured), "jitter_repeats": repeats}


MANIFEST = "manifest.json"
# The files a manifest names, copied from a shared folder.
FILES = ("run", "clean", "jitter", "check", "excitation", "tool")


def robot_runs(binary: str, urdf: str, directory: str) -> Dict[str, object]:
    """make_robot_runs with the default truth, or a copy of the files the ctest fixture made
    (MANIPID_ROBOT_DATA) when the same binary made them from the same URDF. Writes a manifest
    into `directory` either way, so that it can serve as such a fixture."""
    made_by = {"binary": os.path.realpath(binary), "urdf": os.path.realpath(urdf)}
    shared = os.environ.get("MANIPID_ROBOT_DATA")
    runs = None
    if shared and os.path.realpath(shared) != os.path.realpath(directory):
        try:
            with open(os.path.join(shared, MANIFEST)) as stream:
                manifest = json.load(stream)
        except (OSError, ValueError):
            manifest = {}
        if manifest.get("made_by") == made_by and all(key in manifest.get("runs", {}) for key in FILES):
            os.makedirs(directory, exist_ok=True)
            runs = dict(manifest["runs"])
            for key in FILES:
                copy = os.path.join(directory, os.path.basename(runs[key]))
                shutil.copyfile(runs[key], copy)
                runs[key] = copy
    if runs is None:
        runs = make_robot_runs(binary, urdf, directory)
    with open(os.path.join(directory, MANIFEST), "w") as stream:
        json.dump({"made_by": made_by, "runs": runs}, stream)
    return runs


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit("usage: robot_data.py MANIPID_BIN URDF DIR")
    print(json.dumps(robot_runs(*sys.argv[1:4])))
