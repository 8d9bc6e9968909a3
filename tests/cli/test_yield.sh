#!/usr/bin/env bash
# Command-line checks of `netsolve yield` and `netsolve yield-merge` (docs/yield.md): bad input gives
# one clear line on stderr, a non-zero exit and no output folder; a tiny good run writes
# yield_points.csv with the documented columns, one curve per probe and summary.json, and no plot
# (apps/scripts/plot_yield.py draws surface.png from it); two job-array slices merged give the same
# points as the whole run; the default iteration follows the boundary modes and merging refuses to mix
# iterations.
# usage: test_yield.sh PATH/TO/netsolve
set -u
ns="$1"
tool="$1"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
check_bad yield_precompact "precompact" yield --precompact sideways
check_bad yield_directions0 "directions" yield --directions 0
check_bad yield_probe_slice "probe" yield --directions 4 --probe 5/3
check_bad yield_unloading "normal-unloading" yield --normal-unloading plastic
check_bad yield_probe_list "probes" yield --directions 4 --probes 1,7
check_bad yield_bad_bc "probe-bc" yield --probe-bc sideways
check_bad yield_mixed_friction "friction 0" yield --compact-bc die --probe-bc affine --friction inf
check_bad yield_low_density "impossible target" yield --to-density 0.5
check_bad yield_unknown "bogus" yield --bogus
check_bad yield_merge_missing "probes/" yield-merge "$tmp/does_not_exist"

ok() { pass=$((pass + 1)); }
ko() { fail=$((fail + 1)); echo "FAIL $1: $(cat "$tmp/stderr" 2>/dev/null)"; }
has_columns() {  # FILE COLUMN...: the CSV header names every COLUMN
  local f="$1" c
  shift
  for c in "$@"; do head -1 "$f" | tr ',' '\n' | grep -qx "$c" || return 1; done
}
# W = 12 with 10 increments does not converge (exit 3): these checks are about the files and
# reproducibility, so they accept the status (summary.json keeps it)
args=(yield --width 12 --directions 4 --increments 10 --to-density 0.83 --quiet --allow-unconverged)
good="$tmp/ygood"
if "$ns" "${args[@]}" --out "$good" >/dev/null 2>"$tmp/stderr" &&
   head -1 "$good/yield_points.csv" | grep -q "theta" &&
   has_columns "$good/yield_points.csv" theta S11 S22 S11_offset S22_offset S11_analytic S22_analytic status &&
   [ "$(tail -n +2 "$good/yield_points.csv" | wc -l)" -eq 4 ] &&
   ! grep -qiE '(^|,)[-+]?(nan|inf)(,|$)' "$good"/yield_points.csv "$good"/probes/probe_*.csv &&
   [ "$(ls "$good"/probes/probe_*.csv | wc -l)" -eq 4 ] &&
   [ -s "$good/summary.json" ] && grep -q '"unloading"' "$good/summary.json" && grep -q '"share"' "$good/summary.json" &&
   [ ! -e "$good/surface.svg" ] && [ -s "$good/unload.csv" ] &&
   [ "$(find "$good" -name '.*tmp*' | wc -l)" -eq 0 ] &&
   /usr/bin/python3 "$(dirname "${BASH_SOURCE[0]}")/../../apps/scripts/plot_yield.py" "$good" >/dev/null 2>>"$tmp/stderr" &&
   [ -s "$good/surface.png" ]; then
  ok
else
  ko yield_good_run
fi
# job-array slices + merge reproduce the whole run (same packing, same unloaded state)
if "$ns" "${args[@]}" --probe 0/2 --out "$tmp/ys0" >/dev/null 2>"$tmp/stderr" &&
   "$ns" "${args[@]}" --probes 1,3 --out "$tmp/ys1" >/dev/null 2>"$tmp/stderr" &&
   [ "$(tail -n +2 "$tmp/ys0/yield_points.csv" | wc -l)" -eq 2 ] &&
   "$ns" yield-merge "$tmp/ys0" "$tmp/ys1" --out "$tmp/ymerged" >/dev/null 2>"$tmp/stderr" &&
   cmp -s <(cut -d, -f1-8 "$good/yield_points.csv") <(cut -d, -f1-8 "$tmp/ymerged/yield_points.csv"); then
  ok
else
  ko yield_slices_merge
fi
# the probes run in worker processes from the saved unloaded state: one at a time in this
# process gives the same points, byte for byte, as two workers
if "$ns" "${args[@]}" --jobs 1 --out "$tmp/yj1" >/dev/null 2>"$tmp/stderr" &&
   cmp -s "$good/yield_points.csv" "$tmp/yj1/yield_points.csv" && [ -s "$good/probes/unloaded_state.txt" ]; then
  ok
else
  ko yield_jobs1_equals_parallel
fi
# restart: `compact --save-state` then `yield --from-state` gives the points of the uninterrupted
# yield run (same preset, same increments), byte for byte; a state along another path is refused
cargs=(compact --width 12 --increments 10 --to-density 0.83 --quiet --allow-unconverged)
if "$ns" "${cargs[@]}" --save-state --out "$tmp/cstate" >/dev/null 2>"$tmp/stderr" &&
   [ -s "$tmp/cstate/state.txt" ] &&
   "$ns" yield --from-state "$tmp/cstate/state.txt" --directions 4 --quiet --out "$tmp/yfs" >/dev/null 2>"$tmp/stderr" &&
   cmp -s "$good/yield_points.csv" "$tmp/yfs/yield_points.csv" && cmp -s "$good/unload.csv" "$tmp/yfs/unload.csv"; then
  ok
else
  ko yield_from_state_equals_uninterrupted
fi
check_bad yield_from_state_path "does not lie along" yield --from-state "$tmp/cstate/state.txt" --precompact closed-die --directions 4
check_bad yield_from_state_missing "cannot open state file" yield --from-state "$tmp/no_such_state.txt" --directions 4
# merging runs of different setups is refused
if "$ns" "${args[@]}" --friction 0 --probes 0 --out "$tmp/ysf" >/dev/null 2>"$tmp/stderr"; then
  check_bad yield_merge_mismatch "different setup" yield-merge "$tmp/ys0" "$tmp/ysf"
else
  ko yield_friction_run
fi
# the default iteration (docs/quasistatic.md "Which iteration by default"): the legacy drag when a
# phase runs in the die, the pseudo-transient iteration otherwise; the setup records it, so that
# yield-merge refuses to mix the two
iteration_is() {  # folder, expected solver.iteration and setup.iteration
  /usr/bin/python3 -c "import json, sys; s = json.load(open(sys.argv[1] + '/summary.json'))
sys.exit(0 if s['solver']['iteration'] == s['setup']['iteration'] == sys.argv[2] else 1)" "$1" "$2"
}
if "$ns" "${args[@]}" --compact-bc affine --probe-bc die --friction 0 --probes 0 --out "$tmp/yad" >/dev/null 2>"$tmp/stderr" &&
   "$ns" "${args[@]}" --compact-bc affine --probes 0 --out "$tmp/yaa" >/dev/null 2>"$tmp/stderr" &&
   "$ns" "${args[@]}" --iteration pseudo-transient --probes 0 --out "$tmp/ypt" >/dev/null 2>"$tmp/stderr" &&
   iteration_is "$good" legacy-drag && iteration_is "$tmp/yad" legacy-drag && iteration_is "$tmp/yaa" pseudo-transient &&
   iteration_is "$tmp/ypt" pseudo-transient; then
  ok
  check_bad yield_merge_iterations "different setup" yield-merge "$tmp/ys1" "$tmp/ypt"
else
  ko yield_default_iteration
fi
finish
