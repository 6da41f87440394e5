#!/usr/bin/env bash
# cli_test.sh — whole-process tests of the `manipid` command line, driven as a user would:
# the real binary, real files in a temporary directory. Run by ctest as
#     bash cli_test.sh /path/to/manipid
# Prints one line per check and a final "N passed, M failed"; exits non-zero on any failure.
set -u

manipid=${1:?usage: bash cli_test.sh /path/to/manipid}
[[ -x $manipid ]] || { echo "cli_test.sh: $manipid is not an executable"; exit 2; }
manipid=$(realpath "$manipid")  # the tests run inside a temporary directory
robots=$(realpath "$(dirname "${BASH_SOURCE[0]}")/../../examples/robots")  # before the cd below
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 2

passed=0
failed=0
pass() { passed=$((passed + 1)); echo "ok   $1"; }
fail() { failed=$((failed + 1)); echo "FAIL $1${2:+: $2}"; }
# check NAME COMMAND...: passes when the command succeeds.
check() {
  local name=$1
  shift
  if "$@"; then pass "$name"; else fail "$name"; fi
}

# expect_error NAME STATUS TEXT COMMAND...: the command must exit with STATUS and print exactly
# one line, "manipid: error: ...", that contains TEXT (a fixed string), and nothing on stdout.
expect_error() {
  local name=$1 status=$2 text=$3
  shift 3
  "$@" >stdout.txt 2>stderr.txt
  local actual=$?
  local lines
  lines=$(wc -l <stderr.txt)
  if [[ $actual -ne $status ]]; then
    fail "$name" "exit status $actual, expected $status; stderr: $(cat stderr.txt)"
  elif [[ $lines -ne 1 ]] || ! grep -q '^manipid: error: ' stderr.txt; then
    fail "$name" "expected one 'manipid: error:' line, got: $(cat stderr.txt)"
  elif ! grep -qF -- "$text" stderr.txt; then
    fail "$name" "message lacks '$text': $(cat stderr.txt)"
  elif [[ -s stdout.txt ]]; then
    fail "$name" "wrote to stdout on failure"
  else
    pass "$name"
  fi
}

# differ A B: both files have data and are not identical.
differ() { [[ -s $1 && -s $2 ]] && ! cmp -s "$1" "$2"; }

# near VALUE EXPECTED TOLERANCE: |VALUE − EXPECTED| ≤ TOLERANCE.
near() {
  [[ -n $1 ]] || return 1
  awk -v v="$1" -v e="$2" -v tol="$3" 'BEGIN { d = v - e; if (d < 0) d = -d; exit !(d <= tol) }'
}

# column FILE NAME: the values of a named CSV column, one per line.
column() {
  awk -F, -v name="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i; next }
                        c { print $c }' "$1"
}

# field FILE ROW NAME: one value (ROW counts data rows from 1).
field() { column "$1" "$3" | sed -n "$2p"; }

# all_near FILE NAME EXPECTED TOLERANCE: every value of the column within tolerance.
all_near() {
  column "$1" "$2" | awk -v e="$3" -v tol="$4" '
    { d = $1 - e; if (d < 0) d = -d; if (d > tol) bad++; n++ }
    END { exit !(n > 0 && bad == 0) }'
}

header="t,q1,q2,q3,q4,tau1,tau2,tau3,tau4,ref1,ref2,ref3,ref4"

# ---- version and help ----------------------------------------------------------------------

check "--version prints the version" bash -c "'$manipid' --version | grep -Eq '^manipid [0-9]+\.[0-9]+\.[0-9]+$'"
check "--help lists the commands" bash -c "'$manipid' --help | grep -q simulate && '$manipid' --help | grep -q torque && '$manipid' --help | grep -q filter"
check "simulate --help lists its options" bash -c "'$manipid' simulate --help | grep -q -- --noise-q"

# ---- simulate: the paper's scenario ---------------------------------------------------------

"$manipid" simulate --out run.csv 2>summary.txt
check "simulate exits 0" test $? -eq 0
check "simulate header" test "$(head -1 run.csv)" = "$header"
check "simulate writes 9,701 data rows (0..9.7 s every 1 ms)" test "$(($(wc -l <run.csv) - 1))" -eq 9701
check "simulate starts at rest at t = 0" test "$(sed -n 2p run.csv)" = "0,0,0,0,0,0,0,0,0,0,0,0,0"
check "simulate ends at t = 9.7" near "$(field run.csv 9701 t)" 9.7 1e-9
check "simulate: t steps by 0.001" near "$(field run.csv 2 t)" 0.001 1e-15
check "simulate: q1 has followed its 0.5 rad step" near "$(field run.csv 9701 q1)" 0.5 0.01
check "simulate: the reference ends at 0.5 rad" near "$(field run.csv 9701 ref4)" 0.5 1e-9
check "simulate prints a one-line summary" bash -c "test \$(wc -l <summary.txt) -eq 1 && grep -q '9701 samples' summary.txt"

"$manipid" simulate >stdout.csv 2>/dev/null
check "simulate without --out writes the same CSV to stdout" cmp -s run.csv stdout.csv
"$manipid" simulate --out - >dash.csv 2>/dev/null
check "simulate --out - writes to stdout" cmp -s run.csv dash.csv

# ---- simulate: measurement noise is reproducible ---------------------------------------------

noise=(--duration 2 --noise-q 1e-4 --noise-tau 0.5)
"$manipid" simulate "${noise[@]}" --seed 7 --out noise_a.csv 2>/dev/null
"$manipid" simulate "${noise[@]}" --seed 7 --out noise_b.csv 2>/dev/null
"$manipid" simulate "${noise[@]}" --seed 8 --out noise_c.csv 2>/dev/null
"$manipid" simulate --duration 2 --out clean.csv 2>/dev/null
check "noise: same seed, identical files" cmp -s noise_a.csv noise_b.csv
check "noise: different seed, different files" differ noise_a.csv noise_c.csv
check "noise: differs from the clean run" differ noise_a.csv clean.csv
check "noise: 2001 rows for --duration 2" test "$(($(wc -l <noise_a.csv) - 1))" -eq 2001
check "noise: t and ref are untouched" \
  cmp -s <(cut -d, -f1,10-13 noise_a.csv) <(cut -d, -f1,10-13 clean.csv)

"$manipid" simulate --duration 1 --quantize-q 12 --seed 3 --out quantized.csv 2>/dev/null
check "--quantize-q 12: q is a multiple of 2*pi/4096" bash -c "
  awk -F, 'NR > 1 { for (j = 2; j <= 5; j++) { k = \$j / (6.283185307179586 / 4096);
                    r = k - int(k + (k < 0 ? -0.5 : 0.5)); if (r < 0) r = -r; if (r > 1e-6) bad++ } }
           END { exit bad > 0 }' quantized.csv"

# ---- simulate: parameters and kinetic energy --------------------------------------------------

"$manipid" simulate --duration 2 --param m2=24 --out m2.csv 2>/dev/null
check "--param m2=24 changes the output" differ m2.csv clean.csv
"$manipid" simulate --duration 2 --param m2=25,l3=0.6 --param m4=5 --out same.csv 2>/dev/null
check "--param with the true values changes nothing" cmp -s same.csv clean.csv
"$manipid" simulate --duration 2 --kinetic-energy paper --out paper.csv 2>/dev/null
check "--kinetic-energy paper changes the output" differ paper.csv clean.csv

# ---- torque: gravity at rest, checked by hand ---------------------------------------------------
# cedro2009 at q = 0: links 2..4 lie along the base x axis in the vertical x-z plane, gravity is
# (0,0,+9.81) with V = -sum m_k g z_k, so tau = dV/dq:
#   tau1 = 0
#   tau2 = -g [(m2+m3+m4) l2 + (m3+m4) l3 + m4 l4] = -9.81 (45*0.8 + 20*0.6 + 5*0.2) = -480.69
#   tau3 = -g [(m3+m4) l3 + m4 l4]                 = -9.81 (20*0.6 + 5*0.2)          = -127.53
#   tau4 = -g m4 l4                                = -9.81 (5*0.2)                   = -9.81
# Row 2 adds qdd4 = 1 rad/s^2: tau += M(0) e4 with M44 = m4 l4^2 (1 + 1/12) = 0.21667,
# M34 = m4 l4 (l3 + l4) = 0.8, M24 = m4 l4 (l2 + l3 + l4) = 1.6 (complete kinetic energy; the
# paper's variant drops the cross terms M24, M34). Row 3: q2 = pi/2 points the arm up: no torque.
cat >states.csv <<'EOF'
t,q1,q2,q3,q4,qd1,qd2,qd3,qd4,qdd1,qdd2,qdd3,qdd4
0,0,0,0,0,0,0,0,0,0,0,0,0
0.001,0,0,0,0,0,0,0,0,0,0,0,1
0.002,0.3,1.5707963267948966,0,0,0,0,0,0,0,0,0,0
EOF
"$manipid" torque --in states.csv --out tau.csv 2>/dev/null
check "torque exits 0" test $? -eq 0
check "torque header keeps t" test "$(head -1 tau.csv)" = "t,tau1,tau2,tau3,tau4"
check "torque passes t through" test "$(column tau.csv t | tr '\n' ' ')" = "0 0.001 0.002 "
check "torque at rest: tau1 = 0" near "$(field tau.csv 1 tau1)" 0 1e-9
check "torque at rest: tau2 = -480.69" near "$(field tau.csv 1 tau2)" -480.69 1e-9
check "torque at rest: tau3 = -127.53" near "$(field tau.csv 1 tau3)" -127.53 1e-9
check "torque at rest: tau4 = -9.81" near "$(field tau.csv 1 tau4)" -9.81 1e-9
check "torque with qdd4 = 1: tau2 = -480.69 + 1.6" near "$(field tau.csv 2 tau2)" -479.09 1e-9
check "torque with qdd4 = 1: tau3 = -127.53 + 0.8" near "$(field tau.csv 2 tau3)" -126.73 1e-9
check "torque with qdd4 = 1: tau4 = -9.81 + 0.216667" near "$(field tau.csv 2 tau4)" -9.593333333333333 1e-9
check "torque with the arm vertical: tau2 = 0" near "$(field tau.csv 3 tau2)" 0 1e-9
"$manipid" torque --in states.csv --kinetic-energy paper --out tau_paper.csv 2>/dev/null
check "torque, paper kinetic energy: no cross term in tau3" near "$(field tau_paper.csv 2 tau3)" -127.53 1e-9
"$manipid" torque --in states.csv --param m2=24 --out tau_m2.csv 2>/dev/null
check "torque --param m2=24: tau2 = -9.81 * 48.2" near "$(field tau_m2.csv 1 tau2)" -472.842 1e-9
cut -d, -f2- states.csv | "$manipid" torque --in - >tau_stdin.csv 2>/dev/null
check "torque reads stdin; no t column in, none out" test "$(head -1 tau_stdin.csv)" = "tau1,tau2,tau3,tau4"
check "torque from stdin matches" cmp -s <(cut -d, -f2- tau.csv) tau_stdin.csv

# ---- simulate -> filter -> torque: the input-error method's premise ---------------------------
# With filtered signals, tau(q^f, qd^f, qdd^f) ≈ tau^f (the paper's eq. 6): within 1% rms.
"$manipid" filter --order 0 --in run.csv --out f0.csv 2>/dev/null
"$manipid" filter --order 1 --in run.csv --out f1.csv 2>/dev/null
"$manipid" filter --order 2 --in run.csv --out f2.csv 2>/dev/null
paste -d, <(cut -d, -f1-5 f0.csv) <(cut -d, -f2-5 f1.csv | sed '1s/q/qd/g') \
  <(cut -d, -f2-5 f2.csv | sed '1s/q/qdd/g') >filtered_states.csv
"$manipid" torque --in filtered_states.csv --out filtered_tau.csv 2>/dev/null
check "filtered round trip: t aligned" cmp -s <(cut -d, -f1 filtered_tau.csv) <(cut -d, -f1 f0.csv)
check "filtered round trip: inverse dynamics of filtered motion matches filtered torque" bash -c "
  paste -d, <(cut -d, -f2-5 filtered_tau.csv) <(cut -d, -f6-9 f0.csv) | awk -F, '
    NR > 1 { for (j = 1; j <= 4; j++) { d = \$j - \$(j + 4); e[j] += d * d; s[j] += \$(j + 4)^2 } }
    END { for (j = 1; j <= 4; j++) if (sqrt(e[j] / s[j]) > 0.01) exit 1 }'"

# ---- filter: ramps and parabolas ------------------------------------------------------------
awk 'BEGIN { print "t,x,y,c"; for (i = 0; i < 500; i++) { t = i * 0.001; printf "%.3f,%.17g,%.17g,4.5\n", t, 3 * t + 1, t * t } }' >ramp.csv
"$manipid" filter --order 1 --half-length 20 --band 0.5 --in ramp.csv --out d1.csv 2>/dev/null
check "filter exits 0" test $? -eq 0
check "filter keeps the column names" test "$(head -1 d1.csv)" = "t,x,y,c"
check "filter: 500 rows in, 500 - 2*20 - 1 = 459 out" test "$(($(wc -l <d1.csv) - 1))" -eq 459
check "filter: t of output row 1 is input t[M] = 0.02" test "$(field d1.csv 1 t)" = "0.02"
check "filter: t of the last output row is t[M + 458] = 0.478" test "$(field d1.csv 459 t)" = "0.478"
check "filter --order 1 of 3t + 1 is 3" all_near d1.csv x 3 1e-9
check "filter --order 1 of t^2 is 2t" bash -c "
  cut -d, -f1,3 d1.csv |
  awk -F, 'NR > 1 { d = \$2 - 2 * \$1; if (d < 0) d = -d; if (d > 1e-9) bad++ } END { exit bad > 0 }'"
check "filter --order 1 of a constant is 0" all_near d1.csv c 0 1e-9
"$manipid" filter --order 2 --half-length 20 --band 0.5 --in ramp.csv --out d2.csv 2>/dev/null
check "filter --order 2 of t^2 is 2" all_near d2.csv y 2 1e-6
"$manipid" filter --order 0 --half-length 20 --band 0.5 --in ramp.csv --out d0.csv 2>/dev/null
check "filter --order 0 keeps a constant" all_near d0.csv c 4.5 1e-12
"$manipid" filter --order 1 --half-length 20 --band 0.5 --dt 0.001 --in - <ramp.csv >d1_stdin.csv 2>/dev/null
check "filter reads stdin, --dt consistent with t" cmp -s d1.csv d1_stdin.csv
cut -d, -f2 ramp.csv >x_only.csv
"$manipid" filter --order 1 --half-length 20 --band 0.5 --dt 0.001 --in x_only.csv --out x_d1.csv 2>/dev/null
check "filter without t uses --dt" all_near x_d1.csv x 3 1e-9
check "filter without t writes no t" test "$(head -1 x_d1.csv)" = "x"

# ---- errors: one line, the problem named, status 2 (1 when output cannot be written) ---------
printf 'q1,q2,q3,q4,qd1,qd2,qd4,qdd1,qdd2,qdd3,qdd4\n0,0,0,0,0,0,0,0,0,0,0\n' >no_qd3.csv
expect_error "missing column" 2 "no_qd3.csv: missing column qd3" "$manipid" torque --in no_qd3.csv
{ head -12 run.csv; echo "1,2,3,4,5,6,7,8,9,10,11,12"; } >ragged.csv
expect_error "ragged row" 2 "ragged.csv line 13: expected 13 fields, got 12" "$manipid" filter --order 0 --half-length 2 --in ragged.csv
{ head -40 run.csv; echo "0.039,0,0,0,0,0,0,0,abc,0,0,0,0"; } >text.csv
expect_error "non-number" 2 "text.csv line 41, column tau4: 'abc' is not a number" "$manipid" filter --order 0 --half-length 2 --in text.csv
printf 't,x\n0,1\n0.001,nan\n' >nan.csv
expect_error "NaN field" 2 "nan.csv line 3, column x: 'nan' is not a finite number" "$manipid" filter --order 0 --in nan.csv
printf 't,x\n0,1\n0.001,\n' >empty_field.csv
expect_error "empty field" 2 "line 3, column x: empty field" "$manipid" filter --order 0 --in empty_field.csv
printf 't,x,x\n0,1,2\n' >duplicate.csv
expect_error "duplicate column" 2 "duplicate column name 'x'" "$manipid" filter --order 0 --in duplicate.csv
: >empty.csv
expect_error "empty file" 2 "empty.csv: empty input" "$manipid" filter --order 0 --in empty.csv
printf 'q1,q2,q3,q4,q5,qd1,qd2,qd3,qd4,qdd1,qdd2,qdd3,qdd4\n0,0,0,0,0,0,0,0,0,0,0,0,0\n' >five.csv
expect_error "too many joints for the robot" 2 "unexpected column q5" "$manipid" torque --in five.csv
expect_error "unknown preset" 2 "unknown preset 'puma560'" "$manipid" simulate --preset puma560
expect_error "unknown preset (torque)" 2 "--preset" "$manipid" torque --preset nope --in states.csv
expect_error "unknown parameter" 2 "unknown parameter 'm5'" "$manipid" simulate --param m5=3
expect_error "parameter value not a number" 2 "'abc' is not a finite number" "$manipid" simulate --param m2=abc
expect_error "parameter without value" 2 "expected NAME=VALUE" "$manipid" torque --param m2 --in states.csv
expect_error "negative mass" 2 "m2 must not be negative" "$manipid" simulate --param m2=-1
expect_error "unknown kinetic energy" 2 "unknown kinetic energy 'exact'" "$manipid" simulate --kinetic-energy exact
expect_error "too few samples for the filter" 2 "needs at least 2M+2 = 202 rows, got 50" \
  "$manipid" filter --order 1 --in <(head -51 ramp.csv)
expect_error "unreadable file" 2 "cannot read missing.csv: No such file or directory" "$manipid" filter --order 1 --in missing.csv
expect_error "directory as input" 2 "Is a directory" "$manipid" torque --in "$work"
expect_error "unwritable output" 1 "cannot write no/such/dir/out.csv" "$manipid" simulate --duration 0.01 --out no/such/dir/out.csv
expect_error "negative noise" 2 "--noise-q: expected a number >= 0, got '-1'" "$manipid" simulate --noise-q -1
expect_error "NaN option" 2 "--noise-tau: expected a number >= 0, got 'nan'" "$manipid" simulate --noise-tau nan
expect_error "quantization out of range" 2 "--quantize-q: expected an integer in 0..62" "$manipid" simulate --quantize-q 63
expect_error "negative seed" 2 "--seed" "$manipid" simulate --seed -1
expect_error "bad tolerance text" 2 "--rtol: expected a positive number, got 'abc'" "$manipid" simulate --rtol abc
expect_error "tolerance out of range" 2 "--rtol: relative_tolerance must lie in" "$manipid" simulate --rtol 2
expect_error "duration shorter than a sample" 2 "--duration" "$manipid" simulate --duration 0.0001
expect_error "filter order 3" 2 "--order: expected an integer in 0..2, got '3'" "$manipid" filter --order 3 --in ramp.csv
expect_error "filter order missing" 2 "--order is required" "$manipid" filter --in ramp.csv
expect_error "filter band beyond pi" 2 "--band" "$manipid" filter --order 1 --band 4 --in ramp.csv
expect_error "filter half-length 1" 2 "--half-length" "$manipid" filter --order 1 --half-length 1 --in ramp.csv
expect_error "filter --dt contradicts t" 2 "--dt 0.002 s does not match the spacing of the t column" \
  "$manipid" filter --order 1 --half-length 20 --dt 0.002 --in ramp.csv
expect_error "filter without t or --dt" 2 "--dt is required when the input has no t column" \
  "$manipid" filter --order 1 --half-length 20 --in x_only.csv
printf 't,x\n0,1\n0.001,1\n0.003,1\n0.004,1\n0.005,1\n0.006,1\n0.007,1\n' >jumpy.csv
expect_error "filter: non-uniform t" 2 "jumpy.csv: t is not uniformly sampled at data row 3" \
  "$manipid" filter --order 0 --half-length 2 --in jumpy.csv
expect_error "filter: only t" 2 "no columns to filter" "$manipid" filter --order 0 --in <(printf 't\n0\n')
expect_error "torque without --in" 2 "--in is required" "$manipid" torque
expect_error "unknown option" 2 "--bogus" "$manipid" simulate --bogus
expect_error "unknown command" 2 "unknown command 'frobnicate'" "$manipid" frobnicate
expect_error "no command" 2 "no command given" "$manipid"

# ---- identify --------------------------------------------------------------------------------
"$manipid" simulate --out paper.csv 2>/dev/null
"$manipid" identify paper.csv --preset cedro2009 --history history.csv >table.txt 2>identify.err
check "identify: exit 0" [ $? -eq 0 ]
check "identify: m1 and l1 not printed as numbers" grep -Eq '^m1 +50.1 +not alone' table.txt
check "identify: reports m1*l1^2" grep -q 'enter the model only as m1\*l1\^2' table.txt
check "identify: the filter was chosen from the data" grep -q 'chosen from the data' table.txt
m2=$(awk '$1 == "m2" { print $3 }' table.txt)
check "identify: m2 within 0.1 % of 25 (noise-free, complete model)" near "$m2" 25 0.025
check "identify: history CSV has the header" grep -q '^index,cost,m1,m2,m3,m4,l1,l2,l3,l4$' history.csv
check "identify: history starts at evaluation 0" near "$(sed -n 2p history.csv | cut -d, -f1)" 0 0
"$manipid" identify paper.csv --json --half-length 100 --band 0.2 --algorithm LD_SLSQP >result.json
check "identify --json: estimates by name" grep -q '"m2": 24.9' result.json
check "identify --json: m1 has no standard error" grep -q '"m1": null' result.json
check "identify --json: the filter it used" grep -q '"band": 0.2' result.json
"$manipid" simulate --kinetic-energy paper --out paper_model.csv 2>/dev/null
"$manipid" identify paper_model.csv --kinetic-energy paper --half-length 100 --band 0.2 \
  --torque-source reference --json >paper.json
cost=$(grep -o '"final_cost": [0-9.e+-]*' paper.json | awk '{print $2}')
check "identify: reproduces the paper's cost (J <= 0.0223076)" awk -v c="$cost" 'BEGIN { exit !(c <= 0.0223076) }'
expect_error "identify: unknown free parameter" 2 "unknown parameter 'm9' in the free list" \
  "$manipid" identify paper.csv --free m2,m9
expect_error "identify: bad initial value" 2 "--init m2=abc: 'abc' is not a finite number" \
  "$manipid" identify paper.csv --init m2=abc
expect_error "identify: wrong gain count" 2 "--kp needs 4 comma-separated values" \
  "$manipid" identify paper.csv --kp 1,2,3
expect_error "identify: too few samples for the filter" 2 "needs at least 2M+2 = 202 samples, got 99" \
  "$manipid" identify <(head -100 paper.csv) --half-length 100 --band 0.2
expect_error "identify: output-error without ref, saying why" 2 "needs the reference r the controller followed" \
  "$manipid" identify <(cut -d, -f1-9 paper.csv) --method output-error

# ---- identify: true values only when known ----------------------------------------------------
# A CSV says nothing of the robot it came from: no "true" column unless the user gives --truth.
check "identify: no true column for a CSV without --truth" bash -c "grep -E '^parameter ' table.txt | grep -vq true"
check "identify: no true value beside an estimate" bash -c "awk '\$1 == \"m2\" { exit NF != 4 }' table.txt"
check "identify --json: truth null without --truth" grep -q '"truth": null' result.json
"$manipid" identify paper.csv --half-length 100 --band 0.2 --truth m2=25,l2=0.8 --truth m3=15 >truth.txt
check "identify --truth: the true column" bash -c "grep -E '^parameter ' truth.txt | grep -q true"
check "identify --truth: m2's true value beside its estimate" bash -c "awk '\$1 == \"m2\" { exit \$5 != 25 }' truth.txt"
check "identify --truth: l2 and m3 too" bash -c "awk '\$1 == \"l2\" && \$5 == 0.8 { a = 1 } \$1 == \"m3\" && \$5 == 15 { b = 1 } END { exit !(a && b) }' truth.txt"
check "identify --truth: m4 not given, no value" bash -c "awk '\$1 == \"m4\" { exit \$5 != \"-\" }' truth.txt"
"$manipid" identify paper.csv --json --half-length 100 --band 0.2 --truth m2=25 >truth.json
check "identify --json --truth: the given values" bash -c "grep -A2 '\"truth\"' truth.json | grep -q '\"m2\": 25'"
expect_error "identify --truth: unknown name" 2 "--truth m9=1" \
  "$manipid" identify paper.csv --truth m9=1
expect_error "identify --truth: not a number" 2 "--truth m2=abc: 'abc' is not a finite number" \
  "$manipid" identify paper.csv --truth m2=abc

# ---- identify: the PD gains from the data ----------------------------------------------------
# Another arm (lighter, other lengths) under other gains (Kp 300, Kd 30): the gains are read from
# its tau, q and ref; the paper's gains, given, are named as contradicted, with what the data suggest.
other=(--param m1=8,m2=4,m3=2,m4=1,l1=0.3,l2=0.5,l3=0.4,l4=0.25)
"$manipid" simulate "${other[@]}" --kp 300,300,300,300 --kd 30,30,30,30 --out other.csv 2>/dev/null
check "simulate --kp/--kd: other gains change the run" differ other.csv paper.csv
init=(--init m1=8.1,m2=4.1,m3=2.1,m4=1.1,l1=0.31,l2=0.51,l3=0.41,l4=0.26 --half-length 100 --band 0.2)
"$manipid" identify other.csv "${init[@]}" --json >other.json
gains_ok() {  # the estimated gains in the JSON within 1 % of Kp 300, Kd 30
  python3 -c '
import json, sys
gains = json.load(open(sys.argv[1]))["gains"]
estimated = gains["estimated"]
ok = all(abs(k - 300) < 3 for k in estimated["kp"]) and all(abs(k - 30) < 0.3 for k in estimated["kd"])
sys.exit(0 if ok and gains["source"] == sys.argv[2] else 1)' "$@"
}
check "identify: the gains estimated from the data (input-error uses none)" gains_ok other.json none
"$manipid" identify other.csv "${init[@]}" --torque-source reference --json >other_reference.json
check "identify --torque-source reference: the estimated gains form the torque" gains_ok other_reference.json estimated
"$manipid" identify other.csv "${init[@]}" --torque-source reference \
  --kp 3800,40000,10000,500 --kd 159.5,120,50,2 >other_paper_gains.txt
check "identify: given gains the data contradict are named" \
  grep -q 'joint 2: the given PD gains Kp = 40000, Kd = 120 do not fit the data' other_paper_gains.txt
check "identify: ... with the gains the data suggest" grep -q '^PD gains the data suggest: Kp = (300' other_paper_gains.txt
# No tau: the gains cannot be estimated; the preset's are assumed, and the result says so.
cut -d, -f1-5,10-13 paper.csv >no_tau.csv
"$manipid" identify no_tau.csv --half-length 100 --band 0.2 >no_tau.txt
check "identify without tau: the preset's gains, said to be assumed" bash -c "
  grep -q '^PD gains (assumed: the preset.s): Kp = (3800, 40000, 10000, 500)' no_tau.txt &&
  grep -q 'the PD gains were neither given nor estimable' no_tau.txt"
expect_error "simulate --kp: one per joint" 2 "--kp needs 4 comma-separated values" \
  "$manipid" simulate --kp 1,2 --out never.csv

# ---- identify: is the residual noise? -------------------------------------------------------
# Clean data: the residual is the method's bias and the standard errors say nothing of the error.
check "identify: bias-dominated residual on clean data is named" grep -q "the residual is the method's bias, not noise" table.txt
"$manipid" simulate --noise-q 1e-4 --quantize-q 16 --noise-tau-relative 0.01 --out noisy.csv 2>/dev/null
"$manipid" identify noisy.csv >noisy_table.txt
check "identify: noisy data, no bias warning" bash -c "grep -q '^cost' noisy_table.txt && ! grep -q 'the method.s bias, not noise' noisy_table.txt"

# ---- excitation: optimal excitation trajectories for URDF robots -------------------------------

# limits URDF: "lower upper velocity" per moving joint, in file order (the chain's order in the examples).
limits() {
  grep -o '<limit [^>]*>' "$1" |
    sed -E 's/.*lower="([^"]*)".*upper="([^"]*)".*velocity="([^"]*)".*/\1 \2 \3/'
}

# within_limits STATES URDF N MARGIN ACCELERATION: every row inside [lower + margin, upper − margin],
# |qd| ≤ velocity, |qdd| ≤ ACCELERATION, with the limits read from the URDF itself.
within_limits() {
  awk -F, -v n="$3" -v margin="$4" -v amax="$5" '
    FNR == NR { lo[FNR] = $1; hi[FNR] = $2; vel[FNR] = $3; next }
    FNR == 1 { next }
    { for (k = 1; k <= n; k++) {
        q = $(1 + k); qd = $(1 + n + k); qdd = $(1 + 2 * n + k)
        if (q < lo[k] + margin || q > hi[k] - margin) { print "q" k " = " q " at t = " $1; bad++ }
        if (qd > vel[k] || -qd > vel[k]) { print "qd" k " = " qd " at t = " $1; bad++ }
        if (qdd > amax || -qdd > amax) { print "qdd" k " = " qdd " at t = " $1; bad++ }
      } }
    END { exit bad > 0 }' FS=' ' <(limits "$2") FS=, "$1" >/dev/null
}

# at_rest STATES N ROW: q̇ and q̈ of that data row are exactly 0.
at_rest() {
  awk -F, -v n="$2" -v row="$3" 'NR == row + 1 { for (c = 2 + n; c <= 1 + 3 * n; c++) if ($c != 0) bad++; found = 1 }
                                  END { exit !(found && bad == 0) }' "$1"
}

ur5_header="t,q1,q2,q3,q4,q5,q6,qd1,qd2,qd3,qd4,qd5,qd6,qdd1,qdd2,qdd3,qdd4,qdd5,qdd6"
"$manipid" excitation --robot "$robots/ur5_like.urdf" --period 10 --harmonics 5 --dt 0.01 --max-evaluations 30 \
  --out ur5_excitation.csv --coefficients ur5_excitation.json 2>ur5_excitation.err
check "excitation (UR5-like): exit 0" test $? -eq 0
check "excitation (UR5-like): header t,q1..q6,qd1..qd6,qdd1..qdd6" test "$(head -1 ur5_excitation.csv)" = "$ur5_header"
check "excitation (UR5-like): one period at 0.01 s is 1001 rows" test "$(($(wc -l <ur5_excitation.csv) - 1))" -eq 1001
check "excitation (UR5-like): t runs 0..10" bash -c "test \"\$(sed -n 2p ur5_excitation.csv | cut -d, -f1)\" = 0 && test \"\$(tail -1 ur5_excitation.csv | cut -d, -f1)\" = 10"
check "excitation (UR5-like): starts at rest" at_rest ur5_excitation.csv 6 1
check "excitation (UR5-like): ends at rest" at_rest ur5_excitation.csv 6 1001
check "excitation (UR5-like): ends where it started" \
  bash -c "first=\$(sed -n 2p ur5_excitation.csv | cut -d, -f2-7); test -n \"\$first\" && test \"\$first\" = \"\$(tail -1 ur5_excitation.csv | cut -d, -f2-7)\""
check "excitation (UR5-like): moves (q1 spans more than 0.5 rad)" bash -c "
  cut -d, -f2 ur5_excitation.csv | awk 'NR == 2 { lo = hi = \$1 } NR > 2 { if (\$1 < lo) lo = \$1; if (\$1 > hi) hi = \$1 }
                                        END { exit !(hi - lo > 0.5) }'"
check "excitation (UR5-like): within the URDF's limits (margin 0.1 rad, 7.5 rad/s^2)" \
  within_limits ur5_excitation.csv "$robots/ur5_like.urdf" 6 0.1 7.5
check "excitation (UR5-like): one summary line" bash -c "test \$(grep -c '^manipid excitation: ur5_like, 6 joints, 5 harmonics, period 10 s: condition ' ur5_excitation.err) -eq 1"
check "excitation (UR5-like): the parser's warning is passed on" grep -q '^manipid: warning: .*ur5_like.urdf: link tool0 has no <inertial>' ur5_excitation.err
check "excitation (UR5-like): coefficients name the robot and its joints" \
  bash -c "grep -q '\"robot\": \"ur5_like\"' ur5_excitation.json && grep -q '\"wrist_3_joint\"' ur5_excitation.json"
check "excitation (UR5-like): coefficients carry period, harmonics, criterion" \
  bash -c "grep -q '\"period\": 10.0' ur5_excitation.json && grep -q '\"harmonics\": 5' ur5_excitation.json &&
           grep -q '\"criterion\": \"condition\"' ur5_excitation.json && grep -q '\"criterion_value\": [0-9]' ur5_excitation.json"
"$manipid" excitation --robot "$robots/ur5_like.urdf" --dt 0.01 --max-evaluations 30 --out ur5_again.csv 2>/dev/null
check "excitation: same seed, same file" cmp -s ur5_excitation.csv ur5_again.csv
"$manipid" excitation --robot "$robots/ur5_like.urdf" --dt 0.01 --max-evaluations 30 --seed 2 --out ur5_seed2.csv 2>/dev/null
check "excitation: another seed, another trajectory" differ ur5_excitation.csv ur5_seed2.csv

panda_limits_ok=1
"$manipid" excitation --robot "$robots/panda_like.urdf" --period 10 --harmonics 5 --dt 0.01 --duration 20 \
  --max-evaluations 100 --max-acceleration 5 --criterion logdet --out panda_excitation.csv 2>panda_excitation.err
check "excitation (Panda-like): exit 0" test $? -eq 0
check "excitation (Panda-like): 7 joints, columns q7, qd7, qdd7 last of each" \
  test "$(head -1 panda_excitation.csv)" = "t,q1,q2,q3,q4,q5,q6,q7,qd1,qd2,qd3,qd4,qd5,qd6,qd7,qdd1,qdd2,qdd3,qdd4,qdd5,qdd6,qdd7"
check "excitation (Panda-like): --duration 20 is two periods, 2001 rows" test "$(($(wc -l <panda_excitation.csv) - 1))" -eq 2001
check "excitation (Panda-like): at rest at 0, 10 and 20 s" \
  bash -c "$(declare -f at_rest); at_rest panda_excitation.csv 7 1 && at_rest panda_excitation.csv 7 1001 && at_rest panda_excitation.csv 7 2001"
check "excitation (Panda-like): the file is there" test -s panda_excitation.csv
check "excitation (Panda-like): the second period repeats the first" \
  cmp -s <(sed -n 2,1001p panda_excitation.csv | cut -d, -f2-) <(sed -n 1002,2001p panda_excitation.csv | cut -d, -f2-)
check "excitation (Panda-like): within the URDF's limits (margin 0.1 rad, 5 rad/s^2)" \
  within_limits panda_excitation.csv "$robots/panda_like.urdf" 7 0.1 5
check "excitation (Panda-like): the summary names the criterion" grep -q '^manipid excitation: panda_like, 7 joints, .*: logdet ' panda_excitation.err

# A lab's run: where the arm stands, slower than the URDF allows, torque and jerk limited.
"$manipid" excitation --robot "$robots/panda_like.urdf" --dt 0.01 --max-evaluations 60 --start-pose 0,-0.5,0,-2,0,1.5,0 \
  --max-velocity 1 --max-torque 60 --max-jerk 40 --out panda_lab.csv --coefficients panda_lab.json 2>panda_lab.err
check "excitation --start-pose: exit 0" test $? -eq 0
check "excitation --start-pose: starts and ends at the pose, at rest" bash -c "
  $(declare -f at_rest); at_rest panda_lab.csv 7 1 && at_rest panda_lab.csv 7 \$((\$(wc -l <panda_lab.csv) - 1)) &&
  test \"\$(sed -n 2p panda_lab.csv | cut -d, -f2-8)\" = '0,-0.5,0,-2,0,1.5,0' &&
  test \"\$(tail -1 panda_lab.csv | cut -d, -f2-8)\" = '0,-0.5,0,-2,0,1.5,0'"
check "excitation --start-pose: stderr gives the ramps' length" grep -Eq '^manipid excitation: ramps of [0-9.]+ s from the start pose' panda_lab.err
check "excitation --start-pose: within the URDF's limits, ramps included" within_limits panda_lab.csv "$robots/panda_like.urdf" 7 0 7.5
check "excitation --max-velocity 1: no joint faster" \
  awk -F, 'NR > 1 { for (c = 9; c <= 15; c++) if ($c > 1 || -$c > 1) bad++ } END { exit bad > 0 }' panda_lab.csv
"$manipid" torque --robot "$robots/panda_like.urdf" --in panda_lab.csv --out panda_lab_tau.csv 2>/dev/null
check "excitation --max-torque 60: the URDF's torque within 60 N m (12 on the wrist), ramps included" \
  awk -F, 'NR > 1 { for (c = 2; c <= 8; c++) { limit = c <= 5 ? 60 : 12; if ($c > limit || -$c > limit) bad++ } } END { exit bad > 0 }' panda_lab_tau.csv
check "excitation: the JSON gives the limits, peaks and usage per joint, and the ramp" /usr/bin/python3 -c "
import json; d = json.load(open('panda_lab.json'))
assert d['limits']['torque'] == [60, 60, 60, 60, 12, 12, 12] and d['limits']['jerk'] == [40] * 7, d['limits']
assert all(p <= 40 for p in d['peaks']['jerk']) and all(u <= 1 for u in d['usage']['torque'])
assert d['ramp']['pose'] == [0, -0.5, 0, -2, 0, 1.5, 0] and d['ramp']['duration'] > 0
assert d['max_evaluations'] == 60 and d['evaluations'] == 60"
expect_error "excitation: --start-pose with the wrong count" 2 "--start-pose: start_pose needs one value per joint (7), got 2" \
  "$manipid" excitation --robot "$robots/panda_like.urdf" --start-pose 0,0
expect_error "excitation: --start-pose outside the URDF's limits" 2 "--start-pose: the start pose puts joint 4 (panda_joint4) at 0 rad, outside its URDF limits" \
  "$manipid" excitation --robot "$robots/panda_like.urdf" --start-pose 0,0,0,0,0,0,0
# Found by the design, so after the URDF's warnings: the error is the last line.
"$manipid" excitation --robot "$robots/panda_like.urdf" --max-torque 0.01 --max-evaluations 20 --out weak.csv 2>weak.err
check "excitation: --max-torque that cannot hold the arm: exit 2, said, nothing written" bash -c "
  test $? -eq 2 && tail -1 weak.err | grep -q '^manipid: error: --max-torque: the torque limits cannot hold the arm at rest' && test ! -e weak.csv"
expect_error "excitation: --max-jerk not positive" 2 "--max-jerk: max_jerk must be positive and finite" \
  "$manipid" excitation --robot "$robots/panda_like.urdf" --max-jerk 0

printf '<robot name="broken"><link name="a"/><joint name="j" type="revolute"><parent link="a"/></joint></robot>\n' >broken.urdf
expect_error "excitation without --robot" 2 "--robot is required" "$manipid" excitation --out x.csv
expect_error "excitation --period 0" 2 "--period: the period must be a positive number" \
  "$manipid" excitation --robot "$robots/ur5_like.urdf" --period 0
expect_error "excitation --harmonics 0" 2 "--harmonics: harmonics must lie in 2..20" \
  "$manipid" excitation --robot "$robots/ur5_like.urdf" --harmonics 0
expect_error "excitation: a URDF that fails to parse" 2 "broken.urdf" "$manipid" excitation --robot broken.urdf
expect_error "excitation: an unreadable URDF" 2 "cannot read missing.urdf" "$manipid" excitation --robot missing.urdf
expect_error "excitation: --dt that does not divide the period" 2 "--dt: dt = 0.003 s does not divide the period" \
  "$manipid" excitation --robot "$robots/ur5_like.urdf" --dt 0.003
expect_error "excitation: --duration not a whole number of periods" 2 "--duration: duration 15 s is not a whole number of periods" \
  "$manipid" excitation --robot "$robots/ur5_like.urdf" --duration 15
expect_error "excitation: --max-acceleration count" 2 "one per joint (6), got 2" \
  "$manipid" excitation --robot "$robots/ur5_like.urdf" --max-acceleration 1,2
expect_error "excitation: a margin wider than a joint's range" 2 "joint panda_joint2: its range" \
  "$manipid" excitation --robot "$robots/panda_like.urdf" --position-margin 2
expect_error "excitation: unknown friction term" 2 "--friction: unknown friction term 'stiction'" \
  "$manipid" excitation --robot "$robots/ur5_like.urdf" --friction viscous,stiction

# ---- payload: a tool's mass, centre of mass and inertia on the tip link ---------------------------
# The UR5-like arm with a 3 kg tool on tool0 (its centre of mass off the axis): an excitation, the torques
# with the tool and without it, the payload from the URDF's arm.
sed 's|<link name="tool0"/>|<link name="tool0"><inertial><origin xyz="0.04 -0.03 0.09"/><mass value="3"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.012" iyz="0" izz="0.006"/></inertial></link>|' \
  "$robots/ur5_like.urdf" >ur5_tool.urdf
"$manipid" excitation --robot "$robots/ur5_like.urdf" --period 15 --dt 0.002 --max-evaluations 30 --out payload_motion.csv 2>/dev/null
"$manipid" torque --robot ur5_tool.urdf --in payload_motion.csv --with-states --out payload_run.csv 2>/dev/null
"$manipid" torque --robot "$robots/ur5_like.urdf" --in payload_motion.csv --with-states --out payload_none.csv 2>/dev/null
"$manipid" payload payload_run.csv --robot "$robots/ur5_like.urdf" --json >payload.json 2>/dev/null
check "payload: exit 0" test $? -eq 0
check "payload: 3 kg at (0.04, -0.03, 0.09) m, ixx 0.01, izz 0.006 kg m^2 (noise-free)" /usr/bin/python3 -c "
import json; d = json.load(open('payload.json'))
assert d['detected'] and abs(d['mass'] - 3) < 1e-4, d['mass']
assert all(abs(a - b) < 1e-5 for a, b in zip(d['centre_of_mass'], [0.04, -0.03, 0.09])), d['centre_of_mass']
assert abs(d['inertia_about_com']['ixx'] - 0.01) < 1e-4 and abs(d['inertia_about_com']['izz'] - 0.006) < 1e-4
assert d['fit']['with_payload_error'] < 1e-3 * d['fit']['arm_only_error'] and d['undetermined'] == []"
"$manipid" payload payload_run.csv --robot "$robots/ur5_like.urdf" --mass 3 --validate payload_run.csv >payload.txt 2>/dev/null
check "payload --mass 3: the table gives the given mass and the held-out figures" \
  bash -c "grep -q '^mass kg  *3 ± 0' payload.txt && grep -q '^held-out runs (judged at 5 Hz): arm alone' payload.txt"
"$manipid" payload payload_run.csv --robot "$robots/ur5_like.urdf" --physical --json >payload_physical.json 2>/dev/null
check "payload --physical: a real body already, unchanged and said so" /usr/bin/python3 -c "
import json; d = json.load(open('payload_physical.json')); e = json.load(open('payload.json'))
assert d['consistent'] and d['physical']['least_squares_consistent'] and d['mass'] == e['mass'], d['physical']
assert e['physical'] is None and 'real rigid bodies' in d['method']"
"$manipid" payload payload_none.csv --robot "$robots/ur5_like.urdf" --json >payload_none.json 2>/dev/null
check "payload: a run without the tool answers no payload, said in a warning" /usr/bin/python3 -c "
import json; d = json.load(open('payload_none.json'))
assert not d['detected'] and abs(d['mass']) < 1e-3 and d['centre_of_mass'] == [None] * 3, d
assert any(w.startswith('no payload: the mass') for w in d['warnings'])"
"$manipid" payload payload_run.csv --robot "$robots/ur5_like.urdf" --write-urdf ur5_with_payload.urdf >/dev/null 2>&1
"$manipid" payload payload_run.csv --robot ur5_with_payload.urdf --json >payload_again.json 2>/dev/null
check "payload --write-urdf: the written arm explains the run, no payload left" /usr/bin/python3 -c "
import json; d = json.load(open('payload_again.json'))
assert not d['detected'] and abs(d['mass']) < 1e-3, d['mass']"
check "payload --write-urdf: a fixed link on tool0" grep -q '<parent link="tool0" />' ur5_with_payload.urdf
"$manipid" excitation --robot "$robots/ur5_like.urdf" --payload --moving-joints 4-6 --period 4 --harmonics 3 --dt 0.01 \
  --max-evaluations 30 --coefficients payload_excitation.json --out payload_excitation.csv 2>payload_excitation.txt
check "excitation --payload --moving-joints 4-6: the payload's 10 columns, joints 1-3 hold still" /usr/bin/python3 -c "
import csv, json; d = json.load(open('payload_excitation.json'))
assert d['target'] == 'payload' and d['base_parameters'] == 10 and len(d['moving_joints']) == 3, d['moving_joints']
rows = list(csv.reader(open('payload_excitation.csv')))[1:]
assert len({r[1] for r in rows}) == 1 and len({r[6] for r in rows}) > 100"
check "excitation --payload: the summary names the payload's parameters" grep -q "10 payload parameters" payload_excitation.txt
expect_error "excitation: --moving-joints beyond the arm" 2 "--moving-joints: '7' is not a whole number in 1..6" \
  "$manipid" excitation --robot "$robots/ur5_like.urdf" --payload --moving-joints 4-7
expect_error "payload: --mass not positive" 2 "--mass: a known payload mass must be a positive number of kg, got -2" \
  "$manipid" payload payload_run.csv --robot "$robots/ur5_like.urdf" --mass -2
expect_error "payload: --com needs three numbers" 2 "--com needs X,Y,Z" \
  "$manipid" payload payload_run.csv --robot "$robots/ur5_like.urdf" --com 0,0
expect_error "payload: --arm that is not JSON" 2 "payload_run.csv: not JSON" \
  "$manipid" payload payload_run.csv --robot "$robots/ur5_like.urdf" --arm payload_run.csv
"$manipid" torque --robot "$robots/panda_like.urdf" --in panda_lab.csv --with-states --out panda_lab_run.csv 2>/dev/null
expect_error "payload: a run of another arm" 2 "the data has 7 joints, the robot (ur5_like) has 6" \
  "$manipid" payload panda_lab_run.csv --robot "$robots/ur5_like.urdf"

# ---- identify --robot, torque --robot: a URDF arm end to end -------------------------------------
# An excitation (short: 5 s at 2 ms), the torques of the URDF's own values with a little noise, identify,
# validate on a second seed, write the identified URDF.
"$manipid" excitation --robot "$robots/ur5_like.urdf" --period 5 --harmonics 4 --dt 0.002 --duration 10 \
  --max-evaluations 200 --out states.csv 2>/dev/null
"$manipid" torque --robot "$robots/ur5_like.urdf" --in states.csv --with-states --noise-tau-relative 0.005 --seed 1 \
  --out robot_run.csv 2>torque.err
check "torque --robot --with-states: exit 0" test $? -eq 0
check "torque --robot --with-states: a dataset header" \
  test "$(head -1 robot_run.csv | cut -d, -f1,2,8,14,20,25)" = "t,q1,qd1,qdd1,tau1,tau6"
check "torque --robot: one summary line, noise said" grep -q "measurement noise added -> robot_run.csv" torque.err
"$manipid" torque --robot "$robots/ur5_like.urdf" --in states.csv --with-states --noise-tau-relative 0.005 --seed 2 \
  --out robot_run2.csv 2>/dev/null
"$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --friction viscous,coulomb --validate robot_run2.csv \
  >robot_table.txt 2>robot_identify.err
check "identify --robot: exit 0" test $? -eq 0
check "identify --robot: base parameters listed" grep -q "^base parameter" robot_table.txt
check "identify --robot: 48 base parameters" grep -q "48 base parameters" robot_table.txt
check "identify --robot: friction per joint" grep -Eq "^shoulder_pan_joint +[-0-9.e]+ +[-0-9.e]+" robot_table.txt
check "identify --robot: validation against the URDF's own values" grep -q "validation, URDF" robot_table.txt
overall=$(awk '/validation, estimate/ { for (i = 1; i <= NF; i++) if ($i == "overall") print $(i + 1) }' robot_table.txt)
check "identify --robot: the second run predicted within 1 %" awk -v e="$overall" 'BEGIN { exit !(e + 0 < 1.0) }'
check "identify --robot: says what the figures are judged under" \
  grep -q "judged under a zero-phase 4th-order Butterworth low-pass at 5 Hz, 0.3 s trimmed" robot_table.txt
check "identify --robot: the choice by held-out prediction, every candidate listed" \
  test "$(grep -c "^  [ *] comparison .* held-out" robot_table.txt)" -ge 7
# Two runs at once, a judge of one's own, the torque joints named: figures over those joints only.
"$manipid" identify robot_run.csv robot_run2.csv --robot "$robots/ur5_like.urdf" --friction viscous,coulomb \
  --judge-cutoff 3 --torque-joints 1-5 --json >robot_two.json 2>/dev/null
check "identify --robot: two runs, 5 torque joints, judged at 3 Hz" python3 -c '
import json, sys
r = json.load(open("robot_two.json"))
sys.exit(not (r["runs"] == 2 and len(r["torque_joints"]) == 5 and r["judge"]["cutoff_hz"] == 3
              and len(r["fit"]["relative_error"]) == 5 and r["fit"]["overall_relative_error"] < 0.01))'
expect_error "identify --robot: a torque joint the robot does not have" 2 "--torque-joints" \
  "$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --torque-joints 1-7
expect_error "identify --robot: the judge's cut-off above Nyquist" 2 "--judge-cutoff: the judge's low-pass cut-off must lie between 0 and the data's Nyquist frequency (250 Hz), not 400 Hz" \
  "$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --judge-cutoff 400
expect_error "identify: several runs are for a URDF robot" 2 "several runs (2 given) are for a URDF robot" \
  "$manipid" identify paper.csv paper.csv
expect_error "identify --robot: the former comparison filter option" 2 "--comparison-half-length no longer exists: the comparison low-pass is a zero-phase Butterworth filter, set by --comparison-cutoff" \
  "$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --comparison-half-length 100
# The same run as a lab logs it: ';' between fields, time in ms, angles in degrees, columns named by joint.
python3 - <<'PY'
import csv, math
rows = list(csv.reader(open("robot_run.csv")))
header = rows[0]
names = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
keep = ["t"] + [f"q{j}" for j in range(1, 7)] + [f"tau{j}" for j in range(1, 7)]
index = [header.index(name) for name in keep]
with open("lab_log.csv", "w") as out:
    out.write(";".join(["time_ms"] + [f"{n}.position" for n in names] + [f"{n}.effort" for n in names]) + "\n")
    for row in rows[1:]:
        values = [float(row[i]) for i in index]
        values[0] *= 1000.0
        values[1:7] = [v * 180.0 / math.pi for v in values[1:7]]
        out.write(";".join(repr(v) for v in values) + "\n")
with open("ns_log.csv", "w") as out:
    out.write(",".join(keep) + "\n")
    for row in rows[1:]:
        out.write(",".join([str(round(float(row[0]) * 1e9) + 1700000000000000000)] + [row[i] for i in index[1:]]) + "\n")
PY
expect_error "identify --robot: a log's own columns answered with a map that reads them" 2 \
  "the file's columns are time_ms, shoulder_pan_joint.position" \
  "$manipid" identify lab_log.csv --robot "$robots/ur5_like.urdf"
expect_error "identify --robot: nanosecond stamps named" 2 "if t is in nanoseconds (as ROS logs stamp them)" \
  "$manipid" identify ns_log.csv --robot "$robots/ur5_like.urdf"
"$manipid" identify lab_log.csv --robot "$robots/ur5_like.urdf" --columns 'time_ms=t,{joint}.position=q{j},{joint}.effort=tau{j}' \
  --time-unit ms >lab_degrees.txt 2>lab_degrees.err
check "identify --robot: angles in degrees are named with --angle-unit" \
  grep -q "^warning: the angles look like degrees.*--angle-unit deg" lab_degrees.txt
"$manipid" identify lab_log.csv --robot "$robots/ur5_like.urdf" --columns 'time_ms=t,{joint}.position=q{j},{joint}.effort=tau{j}' \
  --time-unit ms --angle-unit deg --json >lab.json 2>/dev/null
"$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --json >plain.json 2>/dev/null
check "identify --robot --columns --time-unit ms --angle-unit deg: the estimate of the run in manipid's columns" python3 -c '
import json, sys
a, b = json.load(open("lab.json")), json.load(open("plain.json"))
pa, pb = a["point"], b["point"]
sys.exit(not (a["fit"]["overall_relative_error"] < 0.01 and
              all(abs(pa[k] - pb[k]) <= 1e-6 * (1 + abs(pb[k])) for k in pb)))'
# The same run as a ROS 2 bag (rosbag2's sqlite3 storage, CDR JointState), its joints in another order,
# beside a gripper's own JointState on the same topic and a /tf topic.
python3 - <<'PY'
import csv, sqlite3, struct
rows = list(csv.reader(open("robot_run.csv")))
header = rows[0]
names = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
order = [5, 0, 4, 1, 3, 2]  # the driver's order
def cdr(sec, nanosec, joint_names, position, velocity, effort):
    body = bytearray()
    def align(n):
        while len(body) % n:
            body.append(0)
    def u32(v):
        align(4); body.extend(struct.pack("<I", v))
    def string(text):
        u32(len(text) + 1); body.extend(text.encode() + b"\0")
    def doubles(values):  # CDR aligns an empty sequence's (absent) elements not at all
        u32(len(values))
        if values:
            align(8); body.extend(struct.pack(f"<{len(values)}d", *values))
    u32(sec); u32(nanosec); string("base_link")
    u32(len(joint_names))
    for name in joint_names:
        string(name)
    doubles(position); doubles(velocity); doubles(effort)
    return b"\0\1\0\0" + bytes(body)
db = sqlite3.connect("robot_run.db3")
db.executescript("""
CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL,
                    offered_qos_profiles TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);
INSERT INTO topics VALUES (1, '/tf', 'tf2_msgs/msg/TFMessage', 'cdr', ''), (2, '/joint_states', 'sensor_msgs/msg/JointState', 'cdr', '');
""")
q = [header.index(f"q{j}") for j in range(1, 7)]
qd = [header.index(f"qd{j}") for j in range(1, 7)]
tau = [header.index(f"tau{j}") for j in range(1, 7)]
for row in rows[1:]:
    ns = 1700000000 * 10**9 + round(float(row[0]) * 1e9)
    pick = lambda columns: [float(row[columns[k]]) for k in order]
    data = cdr(ns // 10**9, ns % 10**9, [names[k] for k in order], pick(q), pick(qd), pick(tau))
    db.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (2, ?, ?)", (ns + 150000, data))
    db.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (2, ?, ?)",
               (ns + 200000, cdr(ns // 10**9, ns % 10**9, ["finger"], [0.01], [], [])))
    db.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (1, ?, ?)", (ns, b"\0\1\0\0"))
db.commit()
db.close()
PY
"$manipid" identify robot_run.db3 --robot "$robots/ur5_like.urdf" --json >bag.json 2>bag.err
check "identify --robot: a ROS 2 bag, its joints matched by name: the estimate of the CSV" python3 -c '
import json, sys
a, b = json.load(open("bag.json")), json.load(open("plain.json"))
pa, pb = a["point"], b["point"]
sys.exit(not all(abs(pa[k] - pb[k]) <= 1e-6 * (1 + abs(pb[k])) for k in pb))'
check "identify --robot: the bag's summary names the topic and the skipped gripper messages" \
  grep -q "robot_run.db3: topic /joint_states: .* messages, 6 joints (shoulder_pan_joint, .*messages without every joint skipped" bag.err
mkdir -p bag_directory && cp robot_run.db3 bag_directory/robot_run_0.db3 && echo "rosbag2_bagfile_information: {}" >bag_directory/metadata.yaml
"$manipid" identify bag_directory --robot "$robots/ur5_like.urdf" --topic /joint_states --json >bag_directory.json 2>/dev/null
check "identify --robot: a bag's directory, its topic named" cmp -s <(python3 -c 'import json; print(json.load(open("bag.json"))["point"])') \
  <(python3 -c 'import json; print(json.load(open("bag_directory.json"))["point"])')
expect_error "identify --robot: a bag's topic that is not a JointState" 2 "--topic: robot_run.db3: topic /tf in the bag holds tf2_msgs/msg/TFMessage" \
  "$manipid" identify robot_run.db3 --robot "$robots/ur5_like.urdf" --topic /tf
expect_error "identify --robot: a bag of another arm" 2 "no message on /joint_states names every joint of the robot (panda_joint1" \
  "$manipid" identify robot_run.db3 --robot "$robots/panda_like.urdf"
expect_error "identify --robot: a column map for a bag" 2 "is a ROS 2 bag: its JointState messages name their joints" \
  "$manipid" identify robot_run.db3 --robot "$robots/ur5_like.urdf" --time-unit ns
expect_error "identify --robot: --topic for a CSV" 2 "--topic is for ROS 2 bags; robot_run.csv is not one" \
  "$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --topic /joint_states
expect_error "identify --robot: a column map rule that matches nothing" 2 "'speed_{j}=qd{j}' matches no column" \
  "$manipid" identify lab_log.csv --robot "$robots/ur5_like.urdf" --columns 'time_ms=t,speed_{j}=qd{j}'
expect_error "identify --robot: an unknown time unit" 2 "--time-unit" \
  "$manipid" identify lab_log.csv --robot "$robots/ur5_like.urdf" --time-unit h
"$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --json >robot.json 2>/dev/null
check "identify --robot --json: base parameters by name" grep -q '"base_parameters"' robot.json
check "identify --robot --json: the point has every standard parameter" grep -q '"Izz6":' robot.json
"$manipid" torque --robot "$robots/ur5_like.urdf" --params robot.json --in states.csv --out estimate_tau.csv 2>/dev/null
check "torque --robot --params: the estimate's torques" test "$(head -1 estimate_tau.csv)" = "t,tau1,tau2,tau3,tau4,tau5,tau6"
# An arm whose third link is no rigid body (0.5 kg with the URDF's first moments): its estimate follows,
# so the URDF is refused — after the result, which is printed first, with the way to one that is not.
"$manipid" torque --robot "$robots/ur5_like.urdf" --params <(echo '{"m3": 0.5}') --in states.csv --with-states \
  --noise-tau-relative 0.005 --seed 1 --out odd_run.csv 2>/dev/null
"$manipid" identify odd_run.csv --robot "$robots/ur5_like.urdf" --write-urdf odd.urdf >odd.txt 2>odd.err
check "identify --write-urdf: an unphysical estimate: exit 2" test $? -eq 2
check "identify --write-urdf: ... the result printed first" grep -q "^base parameter" odd.txt
check "identify --write-urdf: ... the link table flags the link that is no body" grep -q "(not a real body)" odd.txt
check "identify --write-urdf: ... not written, saying why and offering --physical" \
  grep -q -- "--write-urdf: odd.urdf not written: link .* not positive semi-definite.*identify again with --physical" odd.err
check "identify --write-urdf: ... and no file" test ! -e odd.urdf
"$manipid" identify odd_run.csv --robot "$robots/ur5_like.urdf" --physical --write-urdf identified.urdf >physical.txt 2>/dev/null
check "identify --physical --write-urdf: exit 0" test $? -eq 0
check "identify --write-urdf: the identified URDF parses" "$manipid" torque --robot identified.urdf --in states.csv --out urdf_tau.csv
check "identify --write-urdf: a comment says where it came from and what the data determine" python3 -c '
import re, sys
text = open("identified.urdf").read()
note = re.search(r"<!--\s*(Identified by manipid.*?)-->\s*<robot", text, re.S)
sys.exit(not (note and "from 1 run (odd_run.csv)" in note.group(1) and "constrained to physically consistent links" in note.group(1)
              and "of 48 base parameters" in note.group(1) and "judge" in note.group(1)))'
check "identify --robot: a link table, mass to inertia, what the data determine" \
  grep -Eq "^forearm_link +[0-9.e-]+ .* (all|mass|only in combinations)" physical.txt
expect_error "identify --robot: joint count" 2 "the data has 4 joints, the robot (ur5_like) has 6" \
  "$manipid" identify paper.csv --robot "$robots/ur5_like.urdf"
expect_error "identify --robot: the paper's options do not apply" 2 "--preset excludes --robot" \
  "$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --preset cedro2009
expect_error "identify --robot: two-stage is the paper's" 2 "output-error and two-stage identify the paper's" \
  "$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --method two-stage
expect_error "identify --robot: unknown friction term" 2 "unknown friction term 'sticky'" \
  "$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --friction viscous,sticky
expect_error "identify --robot: --trim needs two numbers" 2 "--trim needs START,END" \
  "$manipid" identify robot_run.csv --robot "$robots/ur5_like.urdf" --trim 1
expect_error "torque --robot: unknown parameter in --params" 2 "'Iww3' is not a parameter" \
  "$manipid" torque --robot "$robots/ur5_like.urdf" --params <(echo '{"Iww3": 1}') --in states.csv
# A flat --params object overrides the URDF: the friction it does not name stays (fv2 as the URDF has it:
# the same torques as no --params at all).
"$manipid" torque --robot "$robots/ur5_like.urdf" --in states.csv --out urdf_own_tau.csv 2>/dev/null
"$manipid" torque --robot "$robots/ur5_like.urdf" --params <(echo '{"fv2": 0.5}') --in states.csv \
  --out override_tau.csv 2>/dev/null
check "torque --robot --params: a flat override keeps the URDF's other friction" cmp -s urdf_own_tau.csv override_tau.csv
# A lighter link whose first moments were not changed with it is no rigid body: computed, but said.
"$manipid" torque --robot "$robots/ur5_like.urdf" --params <(echo '{"m3": 0.001}') --in states.csv \
  --out light_tau.csv 2>light.err
check "torque --robot --params: an unphysical body still gives torques" test -s light_tau.csv
check "torque --robot --params: an unphysical body is named in a warning" \
  grep -q "not a physical robot: forearm_link" light.err
expect_error "identify: --friction needs --robot" 2 "--friction requires --robot" \
  "$manipid" identify paper.csv --friction viscous

# ---- doctor, and serve refusing a damaged database ----
python3 - <<'PY'
import sqlite3
database = sqlite3.connect("sound.db")
database.execute("CREATE TABLE samples (i INTEGER PRIMARY KEY, text TEXT)")
database.executemany("INSERT INTO samples (text) VALUES (?)", [("x" * 200,)] * 400)
database.commit()
database.close()
PY
cp sound.db damaged.db
python3 - <<'PY'
import sqlite3
database = sqlite3.connect("damaged.db")
page, size = database.execute("SELECT rootpage, (SELECT page_size FROM pragma_page_size) FROM sqlite_master "
                              "WHERE name = 'samples'").fetchone()
database.close()
with open("damaged.db", "r+b") as file:  # the root page's cell count: 65535
    file.seek((page - 1) * size + 3)
    file.write(b"\xff\xff")
PY
"$manipid" doctor --db sound.db >doctor.txt 2>&1
check "doctor: a sound file exits 0" test $? -eq 0
check "doctor: a sound file says so" grep -q "^sound.db: sound (schema version 0;" doctor.txt
damaged_before=$(sha256sum <damaged.db)
"$manipid" doctor --db sqlite:damaged.db >doctor.txt 2>&1
check "doctor: a damaged file exits 1" test $? -eq 1
check "doctor: a damaged file lists the page" grep -q "^  - Page [0-9]*: " doctor.txt
check "doctor: reads only" test "$(sha256sum <damaged.db)" = "$damaged_before"
# Rows stored before the service refused text that is not UTF-8 (?name=%FF): sound, but named to mend.
python3 - <<'PY'
import sqlite3
database = sqlite3.connect("latin1.db")
database.execute("CREATE TABLE datasets (id TEXT PRIMARY KEY, name TEXT)")
database.execute("CREATE TABLE robots (id TEXT PRIMARY KEY, name TEXT, base TEXT, tip TEXT, urdf TEXT)")
database.execute("INSERT INTO datasets VALUES ('ds_1', 'run one'), ('ds_2', CAST(X'6CFF' AS TEXT))")
database.execute("INSERT INTO robots VALUES ('rb_1', 'arm', NULL, NULL, '<robot/>'), "
                 "('rb_2', CAST(X'FF' AS TEXT), NULL, NULL, '<robot/>')")
database.commit()
database.close()
PY
"$manipid" doctor --db latin1.db >doctor.txt 2>&1
check "doctor: rows whose text is not UTF-8 exit 1" test $? -eq 1
check "doctor: ... and are named, the file sound" bash -c "grep -q '^latin1.db: sound (schema version 0), but 2 row(s) hold text that is not UTF-8' doctor.txt &&
  grep -q '^  - dataset ds_2: its name is not UTF-8' doctor.txt && grep -q '^  - robot rb_2: its name is not UTF-8' doctor.txt &&
  ! grep -q 'ds_1\|rb_1' doctor.txt"
expect_error "doctor: a missing file" 2 "no database file 'missing.db'" "$manipid" doctor --db missing.db
check "doctor: a missing file is not created" test ! -e missing.db
expect_error "serve: a damaged database is refused at start" 2 "the database file is damaged (PRAGMA quick_check: Page" \
  "$manipid" serve --port 0 --db damaged.db
expect_error "worker: a damaged database is refused at start" 2 "the database file is damaged (PRAGMA quick_check: Page" \
  "$manipid" worker --db damaged.db
expect_error "worker: runs at least one job thread" 2 "--workers" "$manipid" worker --db sound.db --workers 0
expect_error "worker: a lease below 0.1 s" 2 "--lease" "$manipid" worker --db sound.db --lease 0.01
expect_error "serve: an unreachable PostgreSQL database exits 1" 1 "--db: cannot connect to PostgreSQL" \
  "$manipid" serve --port 0 --db "postgresql:///db?host=/nonexistent-manipid-socket-dir"
expect_error "worker: an unreachable PostgreSQL database exits 1" 1 "--db: cannot connect to PostgreSQL" \
  "$manipid" worker --db "postgresql:///db?host=/nonexistent-manipid-socket-dir"

# ---- serve's HTTP side is a module beside the executable (manipid-http.so) ----
# A copy of the binary without it: serve says where it looked and stops before opening the
# database; the one-shot commands do not need it.
mkdir -p alone/bin
cp "$manipid" alone/bin/manipid
expect_error "serve: without manipid-http.so it exits 1 naming the module" 1 "cannot load the HTTP module manipid-http.so" \
  alone/bin/manipid serve --port 0 --db alone/jobs.db
check "serve: without the module, no database is created" test ! -e alone/jobs.db
alone/bin/manipid simulate --duration 0.05 --out alone/run.csv >/dev/null 2>&1
check "simulate runs without the module" test -s alone/run.csv
if [[ -f "$(dirname "$manipid")/manipid-http.so" ]]; then
  # ../lib/manipid/ from the executable, as the Docker image installs it.
  mkdir -p alone/lib/manipid
  cp "$(dirname "$manipid")/manipid-http.so" alone/lib/manipid/
  alone/bin/manipid serve --port 0 --db alone/jobs.db >alone/serve.out 2>alone/serve.err &
  serve_pid=$!
  for _ in $(seq 100); do grep -q "^listening on" alone/serve.out 2>/dev/null && break; sleep 0.05; done
  check "serve finds the module in ../lib/manipid/" grep -q "^listening on http://127.0.0.1:" alone/serve.out
  kill -TERM "$serve_pid" 2>/dev/null
  wait "$serve_pid"
  check "serve with the module in ../lib/manipid/ stops on SIGTERM with 0" test $? -eq 0
else
  fail "the module is built beside the binary" "no $(dirname "$manipid")/manipid-http.so"
fi

echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
