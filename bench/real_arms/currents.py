# What the Kinova Gen3's motor currents say about its joint torque: per joint, the gain from current to the sensor's torque, alone and beside friction and rotor inertia, its stability from run to run, and held-out prediction against the logger's own current-based torque.
#
# Per joint j (1-6, the joints with a torque sensor), every signal through the judge's low-pass (judge.py), q̇ and q̈
# by central differences, 0.3 s trimmed at each end, the sensor's torque modelled as
#     plain:     tau_j = k_j i_j + b_j
#     friction:  tau_j = k_j i_j - fv_j qd_j - fc_j tanh(qd_j / 0.01) - Ia_j qdd_j + b_j
# (what a motor's current drives that the joint's sensor does not see: the gear's friction, the rotor's
# inertia). Least squares on columns scaled to unit norm, directions below 1e-6 of the largest singular value
# left out (a run whose joint moves one way only makes tanh(qd) a second offset). Figures: the gain per run
# (how stable it is), and the relative RMS error of the torque predicted on held-out runs from their
# currents — beside the logger's own current-based torque (taucur: fixed constants 9.13 on joints 1-4, 5.85
# on 5-7).
# Usage: python3 bench/real_arms/currents.py   (Debian's python3 with python3-numpy and python3-scipy)
import os

import numpy as np

import judge

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.normpath(os.path.join(HERE, "../../../shared/real-robots/kinova"))
RUNS = ["train", "validation", "quadratic", "run1"]
JOINTS = 6
SMALLEST = 1e-6  # relative singular value below which a direction is left out


def load(run):
    """The judge's view of one run with its currents: i, the sensor's tau and the logger's taucur low-passed,
    q̇ and q̈, all trimmed."""
    currents = judge.read_csv(os.path.join(DATA, run + "_current.csv"))
    t, q, tau = judge.read_run(os.path.join(DATA, run + ".csv"))
    dt = float(np.median(np.diff(t)))
    qd = np.gradient(judge.lowpass(q, dt), dt, axis=0)
    keep = judge.inner(t)
    return {"i": judge.lowpass(judge.joint_columns(currents, "i"), dt)[keep],
            "taucur": judge.lowpass(judge.joint_columns(currents, "taucur"), dt)[keep],
            "tau": judge.lowpass(tau, dt)[keep],
            "qd": qd[keep], "qdd": np.gradient(qd, dt, axis=0)[keep]}


def columns(run, j, friction):
    c = [run["i"][:, j], np.ones(len(run["i"]))]
    if friction:
        c += [run["qd"][:, j], np.tanh(run["qd"][:, j] / 0.01), run["qdd"][:, j]]
    return np.column_stack(c)


def fit(A, y):
    """Least squares on unit-norm columns, directions below SMALLEST of the largest singular value left out."""
    scale = np.linalg.norm(A, axis=0)
    scale[scale == 0] = 1.0
    U, s, Vt = np.linalg.svd(A / scale, full_matrices=False)
    keep = s > SMALLEST * s[0]
    return (Vt[keep].T @ ((U[:, keep].T @ y) / s[keep])) / scale


def relative(predicted, measured):
    return np.linalg.norm(predicted - measured) / np.linalg.norm(measured)


def main():
    runs = {name: load(name) for name in RUNS}
    print("gain k (N m/A at the link) fitted on each run alone:")
    for friction in (False, True):
        print(f"  {'with friction and rotor inertia' if friction else 'current alone'}:")
        for name in RUNS:
            gains = [fit(columns(runs[name], j, friction), runs[name]["tau"][:, j])[0] for j in range(JOINTS)]
            print(f"    {name:10s} " + "  ".join(f"j{j + 1} {k:6.2f}" for j, k in enumerate(gains)))
    train, held_out = ["train", "quadratic"], ["validation", "run1"]
    print(f"held-out torque error (relative RMS; fitted on {' + '.join(train)}, judged on {' / '.join(held_out)}):")
    for friction in (False, True):
        cells = []
        for j in range(JOINTS):
            x = fit(np.vstack([columns(runs[name], j, friction) for name in train]),
                    np.concatenate([runs[name]["tau"][:, j] for name in train]))
            errors = [relative(columns(runs[name], j, friction) @ x, runs[name]["tau"][:, j]) for name in held_out]
            cells.append(f"j{j + 1} k {x[0]:5.2f}: " + "/".join(f"{100 * e:.0f}" for e in errors) + " %")
        print(f"  {'with friction' if friction else 'current alone':14s} " + "; ".join(cells))
    logger = [("/".join(f"{100 * relative(runs[name]['taucur'][:, j], runs[name]['tau'][:, j]):.0f}" for name in held_out))
              for j in range(JOINTS)]
    print("  logger taucur  " + "; ".join(f"j{j + 1}: {text} %" for j, text in enumerate(logger)))


if __name__ == "__main__":
    main()
