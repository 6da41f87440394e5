#!/usr/bin/env python3
"""print_result.py — a job's JSON (GET /v1/jobs/{id}) as the table `manipid identify` prints:
estimates with standard errors, beside the true values when the result knows them (its "truth": a
simulation's parameters or values the request gave; none for uploaded data), and the identifiability findings.
Usage: python3 scripts/print_result.py job.json
"""
import json
import sys

def true_value(truth, name):
    """The known true value of a parameter or of a product such as "m1*l1^2"; None if unknown."""
    value = 1.0
    for factor in name.split("*"):
        base, _, power = factor.partition("^")
        if base not in truth:
            return None
        value *= truth[base] ** int(power or 1)
    return value


def number(value, digits=6):
    return "-" if value is None else f"{value:.{digits}g}"


def main():
    with open(sys.argv[1]) as stream:
        job = json.load(stream)
    if job["state"] != "succeeded":
        print(f"job {job['id']} {job['state']}: {json.dumps(job.get('error'), indent=2)}")
        return 1
    result = job["result"]
    unidentifiable = set(result["identifiability"]["unidentifiable"])
    filter_ = result["filter"]
    print(f"{result['method']}, {result['algorithm']}; filter M = {filter_['half_length']}, band = {filter_['band']:g} "
          f"rad/sample{' (chosen from the data)' if filter_['automatic'] else ''}; torque from {result['torque_source']}")
    gains = result.get("gains") or {}
    listed = lambda values, digits=6, unit="": "(" + ", ".join(number(v, digits) + unit for v in values) + ")"
    source = {"given": "given", "estimated": "estimated from the data", "assumed": "assumed: the preset's"}
    if gains.get("kp") is not None:
        print(f"PD gains ({source.get(gains['source'], gains['source'])}): Kp = {listed(gains['kp'])}, Kd = {listed(gains['kd'])}")
    estimated = gains.get("estimated")
    if estimated and gains.get("source") != "estimated":
        print(f"PD gains the data suggest: Kp = {listed(estimated['kp'])}, Kd = {listed(estimated['kd'])}")
    if estimated:
        fit = listed([100 * value for value in estimated["relative_residual"]], 3, " %")
        print(f"PD law fit: {fit} of each joint's filtered torque unexplained by the estimated gains")
    truth = result.get("truth")
    true_column = (lambda name: f" {number(true_value(truth, name)):>10}") if truth else (lambda name: "")
    print(f"\n{'parameter':<10} {'initial':>12} {'estimate':>14} {'std error':>12}" + (f" {'true':>10}" if truth else ""))
    for name, estimate in result["estimates"].items():
        shown = "not alone" if name in unidentifiable else number(estimate)
        error = "-" if name in unidentifiable else number(result["std_errors"][name], 3)
        print(f"{name:<10} {number(result['initial'][name]):>12} {shown:>14} {error:>12}" + true_column(name))
    for combination in result["identifiability"]["combinations"]:
        print(f"{combination['name']:<10} {'':>12} {number(combination['value']):>14} "
              f"{number(combination['std_error'], 3):>12}" + true_column(combination["name"]))
    print(f"\ncost {number(result['initial_cost'])} -> {number(result['final_cost'])} after {result['evaluations']} "
          f"evaluations in {result['wall_seconds']:.3f} s; stopped: {result['stop_reason']}")
    findings = result["identifiability"]["findings"]
    print("\nidentifiability:" if findings else "\nidentifiability: every free parameter is determined by the data")
    for finding in findings:
        print(f"  - {finding}")
    for warning in result["warnings"]:
        print(f"\nwarning: {warning}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
