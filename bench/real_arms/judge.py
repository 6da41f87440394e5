# Neutral judge of predicted joint torque on a held-out run: 5 Hz zero-phase low-pass, 0.3 s trims, relative RMS.
import argparse

import numpy as np
from scipy.signal import butter, filtfilt

CUTOFF = 5.0
TRIM = 0.3


def read_csv(path):
    """Columns of a CSV with a header row, by name."""
    with open(path) as f:
        names = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {name: data[:, i] for i, name in enumerate(names)}


def joint_columns(columns, prefix):
    """prefix1..prefixN stacked as an (N samples, joints) array."""
    found = []
    while f"{prefix}{len(found) + 1}" in columns:
        found.append(columns[f"{prefix}{len(found) + 1}"])
    return np.column_stack(found)


def read_run(path):
    """t, q, tau of a run CSV t,q1..qn,tau1..taun."""
    columns = read_csv(path)
    return columns["t"], joint_columns(columns, "q"), joint_columns(columns, "tau")


def uniform(t, *signals):
    """The signals linearly interpolated onto a uniform grid at the median step of t."""
    dt = np.median(np.diff(t))
    grid = t[0] + dt * np.arange(int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1)
    resampled = [np.column_stack([np.interp(grid, t, x[:, j]) for j in range(x.shape[1])]) for x in signals]
    return (grid, dt, *resampled)


def lowpass(x, dt, cutoff=CUTOFF):
    """Zero-phase 4th-order Butterworth low-pass along the samples."""
    b, a = butter(4, cutoff, fs=1.0 / dt)
    return filtfilt(b, a, x, axis=0)


def inner(t, trim=TRIM):
    """Mask of the samples at least `trim` seconds from both ends."""
    return (t >= t[0] + trim) & (t <= t[-1] - trim)


def states(path, cutoff=CUTOFF):
    """The judge's states of a run: stale repeated rows removed, uniform grid, q low-passed, q̇ and q̈ by
    np.gradient. Returns t, q, qd, qdd and the measured tau (resampled, not filtered)."""
    t, q, tau = read_run(path)
    keep = np.r_[True, np.any(q[1:] != q[:-1], axis=1)]
    t, dt, q, tau = uniform(t[keep], q[keep], tau[keep])
    q = lowpass(q, dt, cutoff)
    qd = np.gradient(q, dt, axis=0)
    qdd = np.gradient(qd, dt, axis=0)
    return t, q, qd, qdd, tau


def write_states(path, t, q, qd, qdd, tau=None):
    """A CSV t,q1..,qd1..,qdd1..[,tau1..] that `manipid torque --in` reads."""
    n = q.shape[1]
    blocks = [("q", q), ("qd", qd), ("qdd", qdd)] + ([("tau", tau)] if tau is not None else [])
    header = ["t"] + [f"{name}{i + 1}" for name, _ in blocks for i in range(n)]
    data = np.column_stack([t] + [x for _, x in blocks])
    np.savetxt(path, data, delimiter=",", header=",".join(header), comments="", fmt="%.17g")


def score(measured, predicted, t, joints=None, cutoff=CUTOFF, trim=TRIM):
    """Relative RMS of predicted against measured torque, both low-passed and trimmed.
    Returns (overall relative, per-joint relative, per-joint RMS in N·m) over the judged joints (0-based)."""
    t, dt, measured, predicted = uniform(np.asarray(t, float), np.asarray(measured, float), np.asarray(predicted, float))
    joints = list(range(measured.shape[1])) if joints is None else list(joints)
    keep = inner(t, trim)
    m = lowpass(measured[:, joints], dt, cutoff)[keep]
    p = lowpass(predicted[:, joints], dt, cutoff)[keep]
    error = p - m
    overall = np.linalg.norm(error) / np.linalg.norm(m)
    per_joint = np.linalg.norm(error, axis=0) / np.linalg.norm(m, axis=0)
    rms = np.sqrt(np.mean(error**2, axis=0))
    return overall, per_joint, rms


def report(overall, per_joint, rms, joints):
    lines = [f"overall {100 * overall:.3f} %"]
    for j, rel, r in zip(joints, per_joint, rms):
        lines.append(f"  joint {j + 1}: {100 * rel:8.3f} %  {r:.4f} N·m RMS")
    return "\n".join(lines)


def parse_joints(text, count):
    """'1-6' or '1,2,4' (1-based) to 0-based indices; None for all."""
    if not text:
        return list(range(count))
    joints = []
    for part in text.split(","):
        low, _, high = part.partition("-")
        joints.extend(range(int(low) - 1, int(high or low)))
    return joints


def main():
    parser = argparse.ArgumentParser(description="Neutral torque judge.")
    sub = parser.add_subparsers(dest="command", required=True)
    s = sub.add_parser("states", help="write the judge's states and measured torque (t,q,qd,qdd,tau) of a run t,q..,tau..")
    s.add_argument("run")
    s.add_argument("--out", required=True)
    s.add_argument("--cutoff", type=float, default=CUTOFF)
    j = sub.add_parser("score", help="judge predicted torque (CSV with tau1..) against measured (the states CSV: t,..,tau1..)")
    j.add_argument("measured")
    j.add_argument("predicted")
    j.add_argument("--joints", help="judged joints, 1-based, e.g. 1-6 (default all)")
    j.add_argument("--cutoff", type=float, default=CUTOFF)
    args = parser.parse_args()
    if args.command == "states":
        write_states(args.out, *states(args.run, args.cutoff))
        return
    measured = read_csv(args.measured)
    predicted = joint_columns(read_csv(args.predicted), "tau")
    tau = joint_columns(measured, "tau")
    joints = parse_joints(args.joints, tau.shape[1])
    print(report(*score(tau, predicted, measured["t"], joints, args.cutoff), joints))


if __name__ == "__main__":
    main()
