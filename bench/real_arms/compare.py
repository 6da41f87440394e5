# Textbook identification and manipid's default, judged alike on held-out motion of the real arms in ../shared/real-robots.
import argparse
import json
import os
import subprocess
import time

import numpy as np

import judge
import textbook

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.normpath(os.path.join(HERE, "../../../shared/real-robots"))
MANIPID = os.path.normpath(os.path.join(HERE, "../../build/release/server/manipid"))
WORK = "/tmp/real_arms"

CASES = [  # name, URDF, training runs, held-out run, judged joints (0-based)
    ("Panda", "panda/panda.urdf", ["panda/train.csv"], "panda/validation.csv", range(7)),
    ("KUKA LWR4+", "kuka/kuka_start.urdf", ["kuka/run2.csv"], "kuka/run1.csv", range(7)),
    ("Kinova Gen3 (j1-6)", "kinova/gen3_start.urdf", ["kinova/train.csv"], "kinova/validation.csv", range(6)),
    ("Kinova Gen3 (j1-6), train+quadratic", "kinova/gen3_start.urdf", ["kinova/train.csv", "kinova/quadratic.csv"],
     "kinova/validation.csv", range(6)),
]


def manipid(*args, out=None):
    """Run manipid; returns (stdout, wall seconds)."""
    start = time.perf_counter()
    done = subprocess.run([MANIPID, *args], capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"manipid {' '.join(args)}: {done.stderr.strip()}")
    if out:
        with open(out, "w") as f:
            f.write(done.stdout)
    return done.stdout, seconds


def manipid_torque(urdf, states_csv, params=None):
    args = ["torque", "--robot", urdf, "--in", states_csv, "--out", "-"] + (["--params", params] if params else [])
    lines = manipid(*args)[0].splitlines()
    names = lines[0].split(",")
    data = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    return data[:, [i for i, name in enumerate(names) if name.startswith("tau")]]


def rnea_check(urdf, folder, count=300, seed=1):
    """Largest |regressor x parameters - manipid torque| over random states, N·m: for the URDF's own inertials with
    random friction, and for random values of every standard parameter."""
    robot = textbook.Robot(urdf)
    names = robot.parameter_names()
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (count, robot.n))
    qd = rng.normal(0, 1.5, (count, robot.n))
    qd[::10] = 0.0
    qdd = rng.normal(0, 5, (count, robot.n))
    states_csv = os.path.join(folder, "rnea_states.csv")
    judge.write_states(states_csv, np.arange(count) * 1e-3, q, qd, qdd)
    own = robot.standard_parameters()
    own[10 * robot.n:] = rng.uniform(0.1, 2, 3 * robot.n)
    errors = []
    for pi, given in ((own, names[10 * robot.n:]), (rng.normal(0, 1, len(names)), names)):
        params = os.path.join(folder, "rnea_params.json")
        with open(params, "w") as f:
            json.dump({name: pi[names.index(name)] for name in given}, f)
        errors.append(np.max(np.abs(robot.regressor(q, qd, qdd) @ pi - manipid_torque(urdf, states_csv, params))))
    return errors


def run_case(name, urdf, train, held_out, joints):
    folder = os.path.join(WORK, name.split()[0].lower() + ("_2runs" if len(train) > 1 else ""))
    os.makedirs(folder, exist_ok=True)
    urdf, train, held_out = os.path.join(DATA, urdf), [os.path.join(DATA, p) for p in train], os.path.join(DATA, held_out)
    joints = list(joints)
    robot = textbook.Robot(urdf)
    t, q, qd, qdd, tau = judge.states(held_out)
    judged = lambda predicted: judge.score(tau, predicted, t, joints)
    columns, beta = textbook.identify(robot, train, joints)
    row = {"arm": name, "base": len(columns), "textbook": judged(textbook.predict(robot, columns, beta, q, qd, qdd)),
           "prior": judged(robot.regressor(q, qd, qdd) @ robot.standard_parameters())}
    states_csv = os.path.join(folder, "states.csv")
    judge.write_states(states_csv, t, q, qd, qdd)
    # The command (friction given), then manipid with every option at its default (friction chosen).
    for key, friction in (("manipid", ["--friction", "viscous,coulomb,offset"]), ("manipid_auto", [])):
        result = os.path.join(folder, key + ".json")
        identify = ["identify", *train, "--robot", urdf, *friction, "--json"]
        _, row[key + "_seconds"] = manipid(*identify, out=result)
        validated, _ = manipid(*identify, "--validate", held_out)
        with open(result) as f:
            estimate = json.load(f)
        row[key + "_base"] = len(estimate["base_parameters"])
        row[key] = judged(manipid_torque(urdf, states_csv, result))
        row[key + "_validate"] = json.loads(validated)["validation"]["overall_relative_error"]
        row[key + "_choice"] = (f"{estimate['filters']['comparison']['cutoff_hz']:g} Hz, ridge {estimate['selection']['ridge']:.2g}, "
                                f"{','.join(estimate['parameters']['friction']) or 'none'}")
    return row


def percent(x):
    return f"{100 * x:,.2f} %" if x is not None else "—"


def main():
    parser = argparse.ArgumentParser(description="Textbook and manipid's default on the real arms, neutral judge.")
    parser.add_argument("--verbose", action="store_true", help="per-joint figures too")
    args = parser.parse_args()
    if not os.path.isdir(DATA):
        print(f"compare.py: {DATA} is absent (the shared real-robot logs): nothing to compare")
        return
    os.makedirs(WORK, exist_ok=True)
    checks = {c[1]: rnea_check(os.path.join(DATA, c[1]), WORK) for c in CASES}
    rows = [run_case(*case) for case in CASES]
    print("| arm | textbook | manipid (friction v,c,o) | its own --validate | manipid default | its choice | URDF prior "
          "| base columns: textbook / manipid | manipid identify, s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['arm']} | {percent(r['textbook'][0])} | {percent(r['manipid'][0])} | {percent(r['manipid_validate'])} | "
              f"{percent(r['manipid_auto'][0])} | {r['manipid_auto_choice']} | {percent(r['prior'][0])} | "
              f"{r['base']} / {r['manipid_base']} | {r['manipid_seconds']:.3f} / {r['manipid_auto_seconds']:.3f} |")
    print(f"\nJudge: {judge.CUTOFF:g} Hz zero-phase 4th-order Butterworth on both torques, {judge.TRIM:g} s trimmed at each end, "
          "||pred - meas||_F / ||meas||_F over the judged joints. manipid identify times: friction given / chosen.")
    print("RNEA check, largest |textbook regressor x parameters - manipid torque| over 300 random states "
          "(URDF's inertials + random friction; every parameter random): "
          + ", ".join(f"{os.path.basename(u)} {a:.1e} / {b:.1e} N·m" for u, (a, b) in checks.items()))
    if args.verbose:
        for r in rows:
            for label in ("textbook", "manipid", "manipid_auto", "prior"):
                if label in r:
                    print(f"\n{r['arm']}, {label}:\n{judge.report(*r[label], list(range(len(r[label][1]))))}")


if __name__ == "__main__":
    main()
