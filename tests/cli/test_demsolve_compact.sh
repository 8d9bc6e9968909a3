#!/usr/bin/env bash
# Command-line checks of demsolve compact (docs/dynamic.md "demsolve compact"): bad input gives one
# line on stderr, exit 2 and no output folder; a small run writes every documented file with
# netsolve's history.csv columns, no NaN, reaches the target density with compressive stresses; in
# affine mode the boundary stress is the contact stress; walls mode reports the wall/contact gap.
# Shear paths (E12 != 0) run in layer and affine modes (walls: refused).
# Physics: in affine mode (every centre prescribed, the spins free) the DEM stress extrapolated to
# I = 0 from I = 1e-3 and 3e-4 (stress linear in I) agrees with netsolve compact --affine on the same
# packing within 0.1 % for S11 and S22 at D = 0.85 (measured: 1.5e-5 relative at W = 20, 1.3e-5 at W = 14),
# and Z within 0.02 at D = 0.83 and 0.85 (measured: identical).
# NETDEM_TEST_SCALE=small (sanitizer builds): W = 14 instead of 20.
# usage: test_demsolve_compact.sh PATH/TO/demsolve PATH/TO/netsolve
set -u
ds="$1"
ns="$2"
tool="$1"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
W=20
[ "${NETDEM_TEST_SCALE:-}" = small ] && W=14
files_ok() {  # out-dir files...: every file there and not empty
  local d="$1" f
  shift
  for f in "$@"; do
    [ -s "$d/$f" ] || return 1
  done
}
result() {  # name ok?
  if [ "$2" -eq 0 ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL $1: $(cat "$tmp/stderr")"; fi
}

check_bad walls_shear "E12 = 0" compact --width 12 --boundary walls --path=-1,-0.5,0.4
check_bad kt_huge "--k-t must be in \[0, 1e6\]" compact --width 12 --k-t 1e300
check_bad negative_inertial_number "inertial-number" compact --width 12 --inertial-number -1e-3
check_bad nan_inertial_number "inertial-number" compact --width 12 --inertial-number nan
check_bad density_below_d0 "impossible target" compact --width 12 --to-density 0.5
check_bad nan_density "target density" compact --width 12 --to-density nan
check_bad bad_boundary "boundary" compact --width 12 --boundary box
check_bad affine_and_walls "exclude" compact --width 12 --affine --boundary walls
check_bad bad_friction "friction" compact --width 12 --friction -1
check_bad bad_damping "damping" compact --width 12 --damping 2
check_bad bad_first_touch "first-touch" compact --width 12 --first-touch 0
check_bad bad_unloading "normal-unloading" compact --width 12 --normal-unloading plastic
check_bad no_compaction "does not compact" compact --width 12 --path 1,1,0
check_bad missing_packing "cannot open" compact --packing "$tmp/none.csv"
check_bad too_many_steps "max-steps" compact --width 12 --max-steps 100

"$ns" pack --width "$W" --out "$tmp/pk" >/dev/null 2>"$tmp/stderr"
result pack $?
pk="$tmp/pk/packing.csv"

# --max-steps bounds the run, not only the door's estimate t_end / dt_first: the time step falls as
# contacts form (W = 12, I = 1e-2: about 12,100 steps estimated, 14,200 run). A limit between the two
# passes the door and stops the run: exit 3, "incomplete", history.csv with a "# stopped:" line.
"$ns" pack --width 12 --out "$tmp/pk12" >/dev/null 2>"$tmp/stderr"
result pack12 $?
"$ds" compact --packing "$tmp/pk12/packing.csv" --inertial-number 1e-2 --quiet --out "$tmp/ms_ref" >/dev/null 2>"$tmp/stderr"
max=$(/usr/bin/env python3 -c 'import json, math, sys; s = json.load(open(sys.argv[1]))
m = math.ceil(1.02 * s["t_end"] / s["dt"]["first"]); print(m if m < s["steps"] - 100 else 0)' "$tmp/ms_ref/summary.json")
"$ds" compact --packing "$tmp/pk12/packing.csv" --inertial-number 1e-2 --max-steps "$max" --quiet --out "$tmp/ms" \
  >/dev/null 2>"$tmp/stderr"
rc=$?
[ "$max" -gt 0 ] && [ "$rc" -eq 3 ] && [ "$(grep -c . "$tmp/stderr")" -eq 1 ] && grep -q "incomplete: stopped at the step limit" "$tmp/stderr" &&
  [ ! -e "$tmp/ms/.incomplete" ] && grep -q "^# stopped: stopped at the step limit" "$tmp/ms/history.csv" &&
  /usr/bin/env python3 -c 'import json, sys; s = json.load(open(sys.argv[1]))
sys.exit(0 if s["status"] == "incomplete" and s["steps"] == int(sys.argv[2]) and s["increments_done"] < 100 else 1)' \
    "$tmp/ms/summary.json" "$max"
result max_steps_enforced $?
check_pvd max_steps_pvd "$tmp/ms" particles,contacts --history history.csv:D  # the snapshots so far, no final

# layer mode (the default boundary), a small scene
"$ds" compact --packing "$pk" --inertial-number 1e-3 --quiet --out "$tmp/l" >/dev/null 2>"$tmp/stderr" &&
  files_ok "$tmp/l" command.txt packing.csv history.csv summary.json particles_initial.vtp particles_final.vtp \
    contacts_final.vtp particles_D0.820.vtp particles_D0.850.vtp &&
  [ ! -e "$tmp/l/.incomplete" ] &&
  /usr/bin/env python3 - "$tmp/l" <<'PY'
import csv, json, math, sys
d = sys.argv[1]
rows = list(csv.DictReader(l for l in open(d + "/history.csv") if not l.startswith("#")))
need = ("increment E11 E22 E12 D S11 S22 S12 S11_contacts S22_contacts Z contacts sliding mean_fn "
        "dev_un_mean_ratio dev_un_ratio_of_means dev_ut_centres dev_ut_rotations time I kinetic_ratio steps").split()
ok = all(c in rows[0] for c in need) and len(rows) == 101
ok = ok and not any(v.strip().lower() in ("nan", "inf", "-inf", "+inf") for r in rows for v in r.values())
last = rows[-1]
ok = ok and abs(float(last["D"]) - 0.85) < 1e-4 and float(last["S11"]) < 0 and float(last["S22"]) < 0
ok = ok and all(float(r["S22_contacts"]) < 0 for r in rows[1:]) and float(last["Z"]) > 3
s = json.load(open(d + "/summary.json"))
ok = ok and s["status"] == "ok" and s["mode"] == "die" and abs(s["final"]["S22"] - float(last["S22"])) < 1e-8
ok = ok and s["inertial_number"] == 1e-3 and s["friction"] == "inf" and s["prescribed"] > 0
sys.exit(0 if ok else 1)
PY
result layer_run $?
check_pvd layer_run_pvd "$tmp/l" particles,contacts --tags initial,D0.820,D0.840,D0.850 --history history.csv:D

# walls mode: the wall stress beside the contact stress
"$ds" compact --packing "$pk" --inertial-number 1e-3 --boundary walls --quiet --out "$tmp/w" >/dev/null 2>"$tmp/stderr" &&
  /usr/bin/env python3 - "$tmp/w" <<'PY'
import csv, json, sys
d = sys.argv[1]
rows = list(csv.DictReader(l for l in open(d + "/history.csv") if not l.startswith("#")))
s = json.load(open(d + "/summary.json"))
ok = "wall_vs_contact_gap" in rows[0] and "wall_vs_contact_gap" in s and s["mode"] == "walls"
ok = ok and float(rows[-1]["S22"]) < 0 and s["prescribed"] == 0
sys.exit(0 if ok else 1)
PY
result walls_run $?

# affine mode against netsolve compact --affine on the same packing
"$ns" compact --packing "$pk" --affine --quiet --out "$tmp/n" >/dev/null 2>"$tmp/stderr"
result netsolve_affine $?
for I in 1e-3 3e-4; do
  "$ds" compact --packing "$pk" --affine --inertial-number "$I" --quiet --out "$tmp/a$I" >/dev/null 2>"$tmp/stderr"
  result "affine_$I" $?
done
/usr/bin/env python3 - "$tmp" <<'PY'
import csv, sys
t = sys.argv[1]
def rows(f):
    return list(csv.DictReader(l for l in open(f) if not l.startswith("#")))
ok = True
hi, lo, ns = rows(t + "/a1e-3/history.csv"), rows(t + "/a3e-4/history.csv"), rows(t + "/n/history.csv")
for R in (hi, lo):  # every centre prescribed: the reactions' stress is the contact stress
    for r in R[1:]:
        for a, b in (("S11", "S11_contacts"), ("S22", "S22_contacts")):
            x, y = float(r[a]), float(r[b])
            if abs(x - y) > 1e-6 * abs(y):
                ok = False
                print(f"row {r['increment']}: {a} = {x} but {b} = {y}")
def near(R, D):
    return min(range(len(R)), key=lambda k: abs(float(R[k]["D"]) - D))
for D in (0.83, 0.85):
    kd, kn = near(lo, D), near(ns, D)
    if abs(float(lo[kd]["D"]) - float(ns[kn]["D"])) > 1e-6 or abs(float(lo[kd]["Z"]) - float(ns[kn]["Z"])) > 0.02:
        ok = False
        print(f"D = {D}: DEM Z {lo[kd]['Z']} (D {lo[kd]['D']}), netsolve Z {ns[kn]['Z']} (D {ns[kn]['D']})")
k, kn = near(lo, 0.85), near(ns, 0.85)
for c in ("S11", "S22"):
    s_hi, s_lo = float(hi[k][c]), float(lo[k][c])
    s0 = (s_lo * 1e-3 - s_hi * 3e-4) / (1e-3 - 3e-4)  # the linear fit through both, at I = 0
    # a DEM row is the mean over its window; netsolve's rows are at increment ends: their window mean
    n = 0.5 * (float(ns[kn][c]) + float(ns[kn - 1][c]))
    rel = abs(s0 - n) / abs(n)
    print(f"D = 0.85 {c}: DEM I=1e-3 {s_hi:.6f}, I=3e-4 {s_lo:.6f}, I->0 {s0:.6f}; netsolve {n:.6f}; rel {rel:.2e}")
    if rel > 1e-3:
        ok = False
sys.exit(0 if ok else 1)
PY
result affine_matches_netsolve $?

# a shear path (E12 != 0), affine, frictionless and sticking: the same equilibrium as netsolve
# (measured 1.4e-5 and 2-5e-4 at W = 20; sticking needs the peripheral layer's spins held in both, as
# Redanz & Fleck section 2.4: with them free in the DEM only, the two differed by 1.5-1.8 %).
"$ns" compact --packing "$pk" --affine --friction 0 --path=-1,-0.5,0.4 --quiet --out "$tmp/ns" >/dev/null 2>"$tmp/stderr"
result netsolve_shear $?
"$ns" compact --packing "$pk" --affine --path=-1,-0.5,0.4 --quiet --out "$tmp/nst" >/dev/null 2>"$tmp/stderr"
result netsolve_shear_sticking $?
for I in 1e-3 3e-4; do
  "$ds" compact --packing "$pk" --affine --friction 0 --path=-1,-0.5,0.4 --inertial-number "$I" --quiet --out "$tmp/s$I" \
    >/dev/null 2>"$tmp/stderr"
  result "shear_$I" $?
  "$ds" compact --packing "$pk" --affine --path=-1,-0.5,0.4 --inertial-number "$I" --quiet --out "$tmp/st$I" \
    >/dev/null 2>"$tmp/stderr"
  result "shear_sticking_$I" $?
done
/usr/bin/env python3 - "$tmp" <<'PY'
import csv, json, sys
t = sys.argv[1]
def rows(f):
    return list(csv.DictReader(l for l in open(f) if not l.startswith("#")))
ok = True
for tag, d, nd in (("frictionless", "s", "ns"), ("sticking", "st", "nst")):
    hi, lo, ns = rows(f"{t}/{d}1e-3/history.csv"), rows(f"{t}/{d}3e-4/history.csv"), rows(f"{t}/{nd}/history.csv")
    ok = ok and abs(float(lo[-1]["E12"]) - float(ns[-1]["E12"])) < 1e-5 * abs(float(ns[-1]["E12"])) and float(ns[-1]["E12"]) > 0
    ok = ok and json.load(open(f"{t}/{d}3e-4/summary.json"))["path"]["E12"] == 0.4
    for c in ("S11", "S22", "S12"):
        s0 = (float(lo[-1][c]) * 1e-3 - float(hi[-1][c]) * 3e-4) / (1e-3 - 3e-4)
        n = 0.5 * (float(ns[-1][c]) + float(ns[-2][c]))
        rel = abs(s0 - n) / abs(n)
        print(f"shear path, {tag}, D = 0.85 {c}: DEM I->0 {s0:.6f}, netsolve {n:.6f}, rel {rel:.2e} (band 1e-3)")
        ok = ok and rel < 1e-3
sys.exit(0 if ok else 1)
PY
result shear_matches_netsolve $?
finish
