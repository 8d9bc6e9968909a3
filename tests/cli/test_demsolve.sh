#!/usr/bin/env bash
# Command-line checks of demsolve prepare and sinter: bad input gives one clear line on stderr, a
# non-zero exit and no output folder; short good runs write every documented file, are
# deterministic, and a sinter run restarted from its own state after preparation ends in the
# same final state, bit for bit.
# With netsolve given, a netsolve packing read by demsolve prepare --packing starts the DEM at the
# file's positions times the documented length unit.
# usage: test_demsolve.sh PATH/TO/demsolve [PATH/TO/netsolve]
set -u
ds="$1"
ns="${2:-}"
tool="$1"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
check_bad unknown_option "bogus" prepare --bogus
check_bad negative_pressure "pressure" prepare --pressure -1
check_bad nan_pressure "pressure" prepare --pressure nan
check_bad zero_n "--n" prepare --n 0
check_bad zero_time "--time" prepare --time 0
check_bad negative_sinter_time "sintering time" sinter --sinter-time -1
check_bad missing_state "cannot open state file" sinter --state "$tmp/nonexistent.txt"
check_bad unknown_param "unknown contact parameter 'bogus'" sinter --param bogus=1
check_bad bad_param_value "k2" sinter --param k2=-5
check_bad param_not_number "not a number" sinter --param k2=abc
check_bad line_needs_three "n must be 3" sinter --arrangement line --n 5
check_bad unstable_dt "steps per contact" sinter --steps-per-contact 2
printf '{"format":"netdem-state","kind":"dem","version":1,"dim":2,"time":0' >"$tmp/truncated.txt"
check_bad truncated_state "truncated.txt: /: not a JSON state archive" sinter --state "$tmp/truncated.txt"
# an old text state (before issue 26) is refused with how to convert it
printf '# demsolve state v2 (docs/dynamic.md)\ntime 0\n' >"$tmp/old.txt"
check_bad old_text_state "convert it with apps/scripts/convert_state.py" sinter --state "$tmp/old.txt"
files_ok() {  # out-dir files...
  local d="$1" f
  shift
  for f in "$@"; do
    [ -s "$d/$f" ] || return 1
  done
}
has_columns() {  # csv columns...: the header line holds every named column
  local csv="$1" c
  shift
  for c in "$@"; do
    head -1 "$csv" | tr ',' '\n' | grep -qx "$c" || return 1
  done
}
result() {  # name ok?
  if [ "$2" -eq 0 ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL $1: $(cat "$tmp/stderr")"; fi
}
good() {  # out-dir
  "$ds" prepare --n 30 --time 0.003 --seed 7 --quiet --out "$1" >/dev/null 2>"$tmp/stderr"
}
good "$tmp/a" && good "$tmp/b" &&
  files_ok "$tmp/a" command.txt parameters.json timeseries.csv summary.json particles_initial.vtp \
    particles_final.vtp state.txt state_prepare.txt &&
  has_columns "$tmp/a/timeseries.csv" t nu C sxx szz Ekin && grep -q '"seed": 7' "$tmp/a/summary.json" &&
  cmp -s "$tmp/a/state.txt" "$tmp/b/state.txt"
result good_prepare $?
check_pvd good_prepare_pvd "$tmp/a" particles,contacts --tags initial,prepare  # final: prepare's state

# particle friction in the preparation (--mu-prepare, an investigation option): the prepared
# contacts carry tangential forces with it and none without it (the paper's frictionless compression)
fric() {  # out-dir extra-args...
  local out="$1"
  shift
  "$ds" prepare --n 30 --time 0.01 --seed 7 --quiet --out "$out" "$@" >/dev/null 2>"$tmp/stderr"
}
fric "$tmp/f0" && fric "$tmp/f5" --mu-prepare 0.5 && grep -q '"mu_prepare": 0.5' "$tmp/f5/parameters.json" &&
  /usr/bin/env python3 - "$tmp/f0/contacts_prepare.csv" "$tmp/f5/contacts_prepare.csv" <<'PY' 2>"$tmp/stderr"
import csv, sys
def ft(path):
    rows = list(csv.DictReader(open(path)))
    return len(rows), max((abs(float(r["f_t"])) for r in rows), default=0.0)
(n0, t0), (n5, t5) = ft(sys.argv[1]), ft(sys.argv[2])
print(f"  --mu-prepare: {n0} contacts, max |f_t| {t0:.3g} N without; {n5} contacts, max |f_t| {t5:.3g} N with 0.5")
sys.exit(0 if n0 > 0 and n5 > 0 and t0 == 0.0 and t5 > 0.0 else 1)
PY
result mu_prepare $?
check_bad negative_mu_prepare "--mu-prepare" prepare --mu-prepare -1
check_bad zero_threads "--threads" prepare --threads 0
# --threads: the pair loop and the integration on two threads give the same run to the last bit
# (5000 disks: above the thresholds of the threaded loops, docs/dynamic.md "Threads")
thr() {  # out-dir threads
  "$ds" prepare --n 5000 --time 0.0003 --seed 7 --quiet --threads "$2" --out "$1" >/dev/null 2>"$tmp/stderr"
}
thr "$tmp/t1" 1 && thr "$tmp/t2" 2 && cmp -s "$tmp/t1/state.txt" "$tmp/t2/state.txt" &&
  cmp -s "$tmp/t1/timeseries.csv" "$tmp/t2/timeseries.csv" && grep -q '"threads": 2' "$tmp/t2/parameters.json"
result threads_identical $?
check_bad zero_samples "--samples" prepare --samples 0
# --samples: the rows of timeseries.csv (the first at t = 0, then equal steps apart; the last step ends it)
"$ds" prepare --n 30 --time 0.003 --seed 7 --samples 40 --quiet --out "$tmp/smp" >/dev/null 2>"$tmp/stderr" &&
  rows=$(($(wc -l <"$tmp/smp/timeseries.csv") - 1)) && [ "$rows" -ge 41 ] && [ "$rows" -le 42 ] &&
  grep -q '"samples": 40' "$tmp/smp/parameters.json"
result samples $?

# a short whole protocol, then the same run restarted from its state after preparation
times=(--t-heat 0.002 --heat-time 0.001 --sinter-time 0.001 --cool-time 0.001 --relax-time 0.001)
"$ds" sinter --n 25 --seed 3 "${times[@]}" --quiet --out "$tmp/s" >/dev/null 2>"$tmp/stderr" &&
  files_ok "$tmp/s" timeseries.csv summary.json state_prepare.txt state_heat.txt state_sinter.txt \
    state_cool.txt state_relax.txt contacts_sinter.csv contacts_relax.csv particles_sinter.vtp \
    contacts_sinter.vtp &&
  has_columns "$tmp/s/timeseries.csv" t T k1 nu C szz_over_p &&
  has_columns "$tmp/s/contacts_sinter.csv" overlap_rel f_n f_t mu_t &&
  grep -q '"densification"' "$tmp/s/summary.json"
result good_sinter $?
check_pvd good_sinter_pvd "$tmp/s" particles,contacts --tags initial,prepare,heat,sinter,cool,relax
"$ds" sinter --state "$tmp/s/state_prepare.txt" "${times[@]}" --quiet --out "$tmp/r" >/dev/null 2>"$tmp/stderr" &&
  cmp -s "$tmp/s/state.txt" "$tmp/r/state.txt"
result restart_from_prepare_is_exact $?
# zero-length trailing phases: the run ends hot (the last step must not fall into 'relax' at T_cold)
"$ds" sinter --n 25 --seed 3 --t-heat 0.002 --heat-time 0.001 --sinter-time 0 --cool-time 0 --relax-time 0 \
  --quiet --out "$tmp/z" >/dev/null 2>"$tmp/stderr" &&
  /usr/bin/env python3 -c "import json,sys; f=json.load(open('$tmp/z/summary.json'))['final']; sys.exit(0 if f['T'] == 140.0 else 1)"
result zero_length_phases_end_hot $?
# the phases of no length end where heat ends: one time step of the .pvd (their files are heat's)
check_pvd zero_length_phases_pvd "$tmp/z" particles,contacts --tags initial,prepare,heat
check_bad state_past_end "past the end" sinter --state "$tmp/s/state.txt" "${times[@]}"
# --param m_wall / gamma_wall given with --state reach the state's stress-controlled walls (Eq 1)
"$ds" sinter --state "$tmp/s/state_prepare.txt" "${times[@]}" --param gamma_wall=7 --param m_wall=0.5 --quiet \
  --out "$tmp/w" >/dev/null 2>"$tmp/stderr" &&
  /usr/bin/env python3 -c '
import json, sys
w = json.load(open(sys.argv[1]))["moving_walls"]
sys.exit(0 if all(x["mode"] == "stress" and x["mass"] == 0.5 and x["damping"] == 7.0 for x in w) else 1)' "$tmp/w/state.txt" &&
  ! cmp -s "$tmp/s/state.txt" "$tmp/w/state.txt"
result state_walls_take_param $?

# a packing CSV (netsolve's format) as the starting sample
printf '# box 0 0 10 10\nid,x,y,r\n0,2,2,1\n1,5,5,1.5\n' >"$tmp/two.csv"
printf '# box 0 0 10 10\nid,x,y,r\n0,2,2,1\n1,9,5,1.5\n' >"$tmp/through_wall.csv"
printf '# box 0 0 10 10\nid,x,y,r\n0,2,2,1\n1,5,5,0\n' >"$tmp/zero_radius.csv"
check_bad packing_missing "cannot open" prepare --packing "$tmp/none.csv"
check_bad packing_zero_radius "r <= 0" prepare --packing "$tmp/zero_radius.csv"
check_bad packing_through_wall "side wall" prepare --packing "$tmp/through_wall.csv"
check_bad packing_radius_range "length unit" prepare --packing "$tmp/two.csv" --length-unit 1
check_bad packing_bad_unit "length unit" prepare --packing "$tmp/two.csv" --length-unit -1
check_bad packing_and_state "use one of them" sinter --packing "$tmp/two.csv" --state "$tmp/two.csv"
if [ -n "$ns" ]; then
  "$ns" pack --width 12 --seed 4 --out "$tmp/np" >/dev/null 2>"$tmp/stderr" &&
    "$ds" prepare --packing "$tmp/np/packing.csv" --length-unit 2e-4 --time 1e-9 --quiet --out "$tmp/dp" \
      >/dev/null 2>"$tmp/stderr" &&
    grep -q '"length_unit_m": 0.0002' "$tmp/dp/summary.json" &&
    /usr/bin/env python3 - "$tmp/np/packing.csv" "$tmp/dp/state.txt" <<'PY'
import json, sys
rows = [l.strip().split(",") for l in open(sys.argv[1]) if l[0].isdigit()]
p = json.load(open(sys.argv[2]))["particles"]
state = [{c: p[c][i] for c in ("x", "y", "radius_ref")} for i in range(len(p["x"]))]
s = 2e-4
ok = len(state) == len(rows) and all(
    float(d["radius_ref"]) == s * float(r[3]) and abs(float(d["x"]) - s * float(r[1])) <= 1e-15 and
    abs(float(d["y"]) - s * float(r[2])) <= 1e-15 for d, r in zip(state, rows))
sys.exit(0 if ok else 1)
PY
  result packing_from_netsolve $?
  "$ds" prepare --packing "$tmp/np/packing.csv" --time 1e-9 --quiet --out "$tmp/dq" >/dev/null 2>"$tmp/stderr" &&
    /usr/bin/env python3 - "$tmp/dq/state.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["particles"]["radius_ref"]
sys.exit(0 if r and abs(sum(r) / len(r) - 1e-3) < 1e-15 else 1)  # the mean radius becomes a0
PY
  result packing_default_unit_is_a0 $?
fi

# material tests on the sintered sample
check_bad compress_needs_state "state" compress
check_bad compress_bad_rate "strain-rate" compress --state "$tmp/s/state.txt" --strain-rate 0
check_bad compress_bad_strain "max-strain" compress --state "$tmp/s/state.txt" --max-strain 2
check_bad vibrate_bad_frequency "frequency" vibrate --state "$tmp/s/state.txt" --frequency -100
check_bad vibrate_missing_state "cannot open state file" vibrate --state "$tmp/none.txt"
"$ds" compress --state "$tmp/s/state.txt" --max-strain 0.002 --quiet --out "$tmp/c" >/dev/null 2>"$tmp/stderr" &&
  files_ok "$tmp/c" compress.csv summary.json state.txt particles_final.vtp &&
  has_columns "$tmp/c/compress.csv" t eps_zz szz szz_over_p nu C &&
  grep -q '"peak_szz"' "$tmp/c/summary.json" && grep -q '"stiffness"' "$tmp/c/summary.json"
result good_compress $?
check_pvd good_compress_pvd "$tmp/c" particles,contacts --tags eps0,final  # t0.005 lies past --max-strain 0.002
"$ds" vibrate --state "$tmp/s/state.txt" --time 0.002 --quiet --out "$tmp/v" >/dev/null 2>"$tmp/stderr" &&
  files_ok "$tmp/v" clusters.csv summary.json timeseries.csv particles_final.vtp &&
  grep -q '"largest_cluster_fraction"' "$tmp/v/summary.json" &&
  [ "$(tail -n +2 "$tmp/v/clusters.csv" | awk -F, '{s += $2} END {print s}')" = 25 ]
result good_vibrate $?
check_pvd good_vibrate_pvd "$tmp/v" particles,contacts --tags initial,final
finish
