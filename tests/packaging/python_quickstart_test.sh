#!/usr/bin/env bash
# python_quickstart_test.sh — the README's Python quick start, as a new user runs it: a fresh
# venv, `pip install ./clients/python` with no package index (it must work offline), a run.csv
# from `manipid simulate`, then the README's own ```python block, unedited, from a folder laid
# out like the repository after the main job (so local_server() finds
# build/release/server/manipid by itself). Checks that it prints the estimates.
#
#   tests/packaging/python_quickstart_test.sh path/to/manipid
#
# Needs python3 with the venv module (Debian: python3-venv, in the [test] package list).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
binary=$(realpath "${1:?usage: python_quickstart_test.sh path/to/manipid}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Debian's own interpreter, as on a lab machine (not a pyenv or conda one earlier on PATH).
python=/usr/bin/python3
[[ -x "$python" ]] || python=python3
"$python" -m venv "$work/venv" || { echo "python3 -m venv failed: install python3-venv (scripts/setup.sh)" >&2; exit 1; }
# --no-index: nothing may come from PyPI (the lab machines and CI have no route to it).
"$work/venv/bin/pip" install --quiet --no-index --disable-pip-version-check "$root/clients/python"

mkdir -p "$work/repo/build/release/server"
ln -s "$binary" "$work/repo/build/release/server/manipid"
"$binary" simulate --out "$work/repo/run.csv"

# The first ```python block of the README, exactly as printed there.
"$python" - "$root/README.md" >"$work/repo/quickstart.py" <<'PY'
import re, sys, textwrap
text = open(sys.argv[1], encoding="utf-8").read()
match = re.search(r"^( *)```python\n(.*?)^\1```", text, re.S | re.M)
if not match:
    sys.exit("README.md has no ```python block")
print(textwrap.dedent(match.group(2)))
PY
echo "--- the README's quick start:"; cat "$work/repo/quickstart.py"

# Neither MANIPID_BIN nor PATH may hand it the binary: the build folder must be found.
output=$(cd "$work/repo" && env -u MANIPID_BIN PATH=/usr/bin:/bin "$work/venv/bin/python" quickstart.py)
echo "--- it printed:"; echo "$output"

"$work/venv/bin/python" - "$output" <<'PY'
import ast, sys
last = sys.argv[1].strip().splitlines()[-1]
estimates = ast.literal_eval(last)  # print(result["estimates"]) prints a dict
truth = {"m2": 25.0, "m3": 15.0, "m4": 5.0, "l2": 0.8, "l3": 0.6, "l4": 0.2}
# m1 and l1 enter the paper's model only as m1*l1^2: no confident number for either.
if estimates["m1"] is not None or estimates["l1"] is not None:
    sys.exit(f"m1 and l1 must print as None (not identifiable alone), got {estimates['m1']}, {estimates['l1']}")
for name, value in truth.items():
    got = estimates[name]
    if abs(got - value) > 1e-3 * value:
        sys.exit(f"estimate {name} = {got}, expected {value} within 0.1 %")
print("ok: the quick start printed the estimates", {k: round(estimates[k], 5) for k in truth})
PY
