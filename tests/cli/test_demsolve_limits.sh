#!/usr/bin/env bash
# The demsolve reproducers of issue 13 (items 1-4): each bad input is refused at the door (exit 2,
# one line on stderr, no output folder), or the run stops at a detected instability (exit 3, one
# "unstable at step" line, summary.json "status": "unstable", state_last_good.txt, no NaN or inf in
# any file), or it finishes with a result checked against an invariant. None writes NaN with exit 0.
# Also: exit codes, run folders (--overwrite, .incomplete), messages quote at most 80 characters,
# mu_t defined in contacts_*.csv. Every case runs in well under a few seconds.
# usage: test_demsolve_limits.sh PATH/TO/demsolve
set -u
ds="$1"
tool="$1"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"

no_nan() {  # folder: no file holds nan or inf as a value
  ! grep -qiwE -- '-?nan|-?inf|infinity|null' "$1"/* 2>/dev/null
}
# launch NAME ARGS...: runs demsolve ARGS --quiet --out $tmp/NAME; sets rc and out
launch() {
  out="$tmp/$1"
  shift
  timeout 60 "$ds" "$@" --quiet --out "$out" >"$tmp/stdout" 2>"$tmp/stderr"
  rc=$?
}
verdict() {  # name ok?: counts, and shows stderr on a failure
  if [ "$2" -eq 0 ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL $1: rc=$rc stderr: $(head -c 600 "$tmp/stderr")"; fi
}
# usage NAME WORD ARGS...: exit 2, one line with WORD, no output folder
usage() {
  local name="$1" word="$2"
  shift 2
  launch "$name" "$@"
  [ "$rc" -eq 2 ] && [ "$(grep -c . "$tmp/stderr")" -eq 1 ] && grep -qi -- "$word" "$tmp/stderr" && [ ! -e "$out" ]
  verdict "$name" $?
}
# unstable NAME WORD ARGS...: exit 3, the last stderr line names the step and WORD, status unstable,
# state_last_good.txt accepted by demsolve at the door, no NaN
unstable() {
  local name="$1" word="$2"
  shift 2
  launch "$name" "$@"
  [ "$rc" -eq 3 ] && tail -1 "$tmp/stderr" | grep -q "unstable at step" && tail -1 "$tmp/stderr" | grep -qi -- "$word" &&
    grep -q '"status": "unstable"' "$out/summary.json" && [ -s "$out/state_last_good.txt" ] && [ ! -e "$out/.incomplete" ] &&
    no_nan "$out" &&
    { timeout 60 "$ds" compress --state "$out/state_last_good.txt" --max-strain 1e-4 --quiet --out "$tmp/$name.restart" \
      >/dev/null 2>&1; [ $? -ne 2 ]; }
  verdict "$name" $?
}
# good NAME PYTHON-CHECK ARGS...: exit 0, status ok, no NaN, and the check on summary.json (j) holds
good() {
  local name="$1" check="$2"
  shift 2
  launch "$name" "$@"
  [ "$rc" -eq 0 ] && grep -q '"status": "ok"' "$out/summary.json" && [ ! -e "$out/.incomplete" ] && no_nan "$out" &&
    /usr/bin/env python3 -c "import json,sys; j=json.load(open('$out/summary.json')); sys.exit(0 if ($check) else 1)"
  verdict "$name" $?
}
small=(--n 50 --time 0.02)

# a sample for the state-file commands (and the invariant of a good preparation: 0 < nu < 1)
good prepare_small "0 < j['final']['nu'] < 1 and j['final']['C'] > 0" prepare "${small[@]}"
S="$tmp/prepare_small/state.txt"

# NaN with exit 0 before: refused at the door now
usage pressure_1e12 "loading ratio 2p/k2 = 1e+07" prepare "${small[@]}" --pressure 1e12
usage gamma_n_100 "gamma_n dt / m12" prepare "${small[@]}" --param gamma_n=100
usage m_wall_1e-9 "wall" prepare "${small[@]}" --param m_wall=1e-9
usage gamma_wall_1e6 "gamma_wall dt / m_wall" prepare "${small[@]}" --param gamma_wall=1e6
usage T_hot_1e6 "thermal radius change" sinter --state "$S" --T-hot 1e6
usage steps_per_contact_inf "steps-per-contact" prepare "${small[@]}" --steps-per-contact inf
# issue 27: the work of a random sample is estimated before it is placed (placing 1e6 spheres took
# ~46 s before the refusal "needs about ..."); "at least": the heaviest pair's time step
usage prepare_3d_1e6_door "the run needs at least 3.*particle-steps (1000000 particles x" prepare --dim 3 --n 1000000
usage prepare_3d_1e6_max_steps "needs at least .* time steps of .* more than --max-steps = 1e+03" \
  prepare --dim 3 --n 1000000 --allow-long --max-steps 1000
usage rho_p_1e-300 "time step" prepare "${small[@]}" --param rho_p=1e-300
# (k2 = 1e300 would also need 7e152 steps, beyond --max-steps; the loading-ratio floor refuses it first)
usage k2_1e300 "loading ratio 2p/k2 = 2e-298, below 1e-9" prepare "${small[@]}" --param k2=1e300
# found by the campaign (tests/campaign/run_campaign.py): a subnormal pressure or gravity gave inf
usage pressure_subnormal "below 1e-9" compress --state "$S" --pressure 4.9e-324
usage gravity_subnormal "at least 1e-6" vibrate --state "$S" --gravity 4.9e-324
# impossible results before
usage pressure_1e5 "loading ratio 2p/k2 = 1," prepare "${small[@]}" --pressure 1e5
usage k2_1e2 "loading ratio 2p/k2 = 2," prepare "${small[@]}" --param k2=1e2
usage T_hot_1000 "thermal radius change" sinter --T-hot 1000
usage strain_rate_1e4 "strain-rate" compress --state "$S" --strain-rate 1e4
usage frequency_1e12 "per period" vibrate --state "$S" --frequency 1e12
usage T_hot_below_zero "absolute zero" sinter --T-hot -300
usage seed_minus_one "seed" prepare --seed -1
usage n_with_state "cannot be used with --state" sinter --state "$S" --n 30
usage seed_with_state "cannot be used with --state" sinter --state "$S" --seed 2
usage packing_empty "--packing is empty" prepare --packing ''
# hangs before
usage ramp_time_1e9 "more than --max-steps" compress --state "$S" --ramp-time 1e9
usage pressure_1e6 "loading ratio" prepare "${small[@]}" --pressure 1e6
usage max_steps "more than --max-steps" prepare "${small[@]}" --max-steps 1000
# detected while running: exit 3 with the quantity named
unstable k1_ratio_1e-6 "overlap" prepare "${small[@]}" --param k1_ratio=1e-6
unstable pressure_1e4 "overlap" prepare "${small[@]}" --pressure 1e4
unstable vibrate_3e4_Hz "overlaps a wall" vibrate --state "$S" --frequency 3e4
# below the limits: right answers
good compress_rate_50 "j['nu_final'] > j['nu_initial'] > 0 and j['peak_szz'] > 0" compress --state "$S" --strain-rate 50 --max-strain 0.01
good vibrate_default "0 < j['largest_cluster_fraction'] <= 1 and abs(j['peak_floor_acceleration_over_g'] - 2e-4 * (2 * 3.141592653589793 * 100) ** 2 / 9.81) < 1e-9" vibrate --state "$S" --time 0.005
good pressure_1e3 "0 < j['final']['nu'] < 1.25 and abs(j['final']['sxx_over_p'] - 1) < 1" prepare "${small[@]}" --pressure 1e3

# mu_t is defined in every row: |f_t| / (f_n - f_min), 0 where f_n <= f_min
times=(--t-heat 0.002 --heat-time 0.001 --sinter-time 0.002 --cool-time 0.001 --relax-time 0.001)
"$ds" sinter --n 40 --seed 5 "${times[@]}" --quiet --out "$tmp/mut" >/dev/null 2>"$tmp/stderr" &&
  /usr/bin/env python3 - "$tmp/mut" <<'PY'
import csv, glob, math, sys
rows = 0
for f in glob.glob(sys.argv[1] + "/contacts_*.csv"):
    for r in csv.DictReader(open(f)):
        rows += 1
        fn, fmin, ft, mut = (float(r[k]) for k in ("f_n", "f_min", "f_t", "mu_t"))
        want = abs(ft) / (fn - fmin) if fn - fmin > 0 else 0.0
        if not math.isfinite(mut) or abs(mut - want) > 1e-6 * max(1.0, want):
            sys.exit(1)
sys.exit(0 if rows > 0 else 1)
PY
result_rc=$?
if [ "$result_rc" -eq 0 ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL mu_t_defined: $(cat "$tmp/stderr")"; fi

# messages quote at most 80 characters of the input
long=$(head -c 5000 /dev/zero | tr '\0' 'x')
"$ds" prepare --param "$long=1" --out "$tmp/long" >/dev/null 2>"$tmp/stderr"
rc=$?
if [ "$rc" -eq 2 ] && [ "$(wc -c <"$tmp/stderr")" -lt 300 ] && [ "$(grep -c . "$tmp/stderr")" -eq 1 ]; then pass=$((pass + 1)); else
  fail=$((fail + 1)); echo "FAIL long_param: rc=$rc, $(wc -c <"$tmp/stderr") bytes"; fi
"$ds" prepare --n "$long" --out "$tmp/long" >/dev/null 2>"$tmp/stderr"
rc=$?
if [ "$rc" -eq 2 ] && [ "$(wc -c <"$tmp/stderr")" -lt 400 ]; then pass=$((pass + 1)); else
  fail=$((fail + 1)); echo "FAIL long_n: rc=$rc, $(wc -c <"$tmp/stderr") bytes"; fi

# run folders: another run's folder refused (exit 2, untouched), --overwrite clears it first
"$ds" sinter --n 20 --seed 2 "${times[@]}" --quiet --out "$tmp/f" >/dev/null 2>&1
usage_dir() {
  "$ds" prepare --n 20 --time 0.002 --quiet --out "$tmp/f" >/dev/null 2>"$tmp/stderr"
  [ $? -eq 2 ] && grep -q -- "--overwrite" "$tmp/stderr" && [ -e "$tmp/f/state_heat.txt" ]
}
if usage_dir; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL foreign_folder: $(cat "$tmp/stderr")"; fi
"$ds" prepare --n 20 --time 0.002 --quiet --overwrite --out "$tmp/f" >/dev/null 2>"$tmp/stderr" &&
  [ ! -e "$tmp/f/state_heat.txt" ] && [ -e "$tmp/f/state_prepare.txt" ] && [ ! -e "$tmp/f/.incomplete" ] &&
  grep -q -- "prepare --n 20" "$tmp/f/command.txt"
result_rc=$?
if [ "$result_rc" -eq 0 ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL overwrite: $(cat "$tmp/stderr")"; fi
# a killed run leaves .incomplete
"$ds" prepare --n 300 --time 0.5 --quiet --out "$tmp/k" >/dev/null 2>&1 &
pid=$!
for _ in $(seq 50); do [ -e "$tmp/k/command.txt" ] && break; sleep 0.05; done
sleep 0.2
kill "$pid" 2>/dev/null
wait "$pid" 2>/dev/null
if [ -e "$tmp/k/.incomplete" ] && [ ! -e "$tmp/k/summary.json" ]; then pass=$((pass + 1)); else
  fail=$((fail + 1)); echo "FAIL killed_run_incomplete"; fi
# a run error after the folder is opened is exit 1: an unwritable folder
mkdir -p "$tmp/ro" && chmod 555 "$tmp/ro"
if [ "$(id -u)" -ne 0 ]; then
  "$ds" prepare --n 20 --time 0.002 --quiet --out "$tmp/ro/x" >/dev/null 2>"$tmp/stderr"
  rc=$?
  if [ "$rc" -eq 1 ] || [ "$rc" -eq 2 ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL unwritable: rc=$rc"; fi
fi
chmod 755 "$tmp/ro"
finish
