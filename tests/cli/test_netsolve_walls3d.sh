#!/usr/bin/env bash
# netsolve compact --dim 3 --boundary walls (issue 30): six rigid frictionless walls, started from the
# jammed state both solvers share. Physics that could fail, and bad input.
#  * the DEM's limit: a 3D deposition jammed between walls by demsolve (--save-state), then compacted
#    hydrostatically by 1 % from that state by both solvers. A DEM row is a window mean, so netsolve
#    is compared through its window means (rows k - 1 and k). The DEM's gap to netsolve shrinks
#    linearly with the inertial number I (3e-4 -> 1e-4: measured 0.06 % -> 0.02 %), and its linear
#    extrapolation to I = 0 is within 0.03 % of netsolve (measured 0.003-0.006 %) in S11, S22, S33;
#  * the walls' Eq 13 stress equals the Love-Weber stress with the wall contacts (1e-3; the tolerance
#    is 1e-5), every increment accepted on the undragged residual, the same contacts as the DEM;
#  * netsolve's jammed.json (--save-state) starts demsolve --dim 3 (the state both solvers share);
#  * bad input: one line, exit 2, no folder.
# usage: test_netsolve_walls3d.sh PATH/TO/netsolve PATH/TO/demsolve
set -u
ns="$1"
ds="$2"
tool="$ns"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
"$ns" pack --dim 3 --width 10 --out "$tmp/p3" >/dev/null 2>"$tmp/stderr"
result pack3d $?
"$ns" pack --width 10 --out "$tmp/p2" >/dev/null 2>"$tmp/stderr"
result pack2d $?
"$ds" compact --dim 3 --packing "$tmp/p3/packing.csv" --boundary walls --to-density 0.62 --inertial-number 1e-3 \
  --save-state --quiet --out "$tmp/jam" >/dev/null 2>"$tmp/stderr"
result dem_jam $?
"$ds" compact --packing "$tmp/p2/packing.csv" --boundary walls --to-density 0.8 --increments 5 --save-state --quiet \
  --out "$tmp/jam2" >/dev/null 2>"$tmp/stderr"
result dem_jam_2d $?
jam="$tmp/jam/jammed.json"

check_bad walls_shear "E23 = E13 = E12 = 0" compact --dim 3 --boundary walls --state "$jam" --path=-1,-1,-1,0,0,0.5
check_bad state_2d "is a 2D state" compact --dim 3 --boundary walls --state "$tmp/jam2/jammed.json"
check_bad state_without_walls "contact walls" compact --dim 3 --boundary layer --state "$jam"
check_bad state_and_packing "exclude each other" compact --dim 3 --boundary walls --state "$jam" --packing "$tmp/p3/packing.csv"
check_bad state_law "friction" compact --dim 3 --boundary walls --state "$jam" --friction 0.1

"$ns" compact --dim 3 --boundary walls --state "$jam" --to-strain 0.01 --increments 10 --tol 1e-5 --save-state --quiet \
  --out "$tmp/net" >/dev/null 2>"$tmp/stderr"
result netsolve_walls $?
for I in 3e-4 1e-4; do
  "$ds" compact --dim 3 --boundary walls --state "$jam" --to-strain 0.01 --increments 10 --inertial-number "$I" --quiet \
    --out "$tmp/dem_$I" >/dev/null 2>"$tmp/stderr"
  result "dem_walls_$I" $?
done
/usr/bin/python3 - "$tmp" <<'PY' 2>"$tmp/stderr"
import csv, json, math, sys
tmp = sys.argv[1]
rows = lambda d: [r for r in csv.DictReader(l for l in open(f"{tmp}/{d}/history.csv") if not l.startswith("#"))]
net, d3, d1 = rows("net"), rows("dem_3e-4"), rows("dem_1e-4")
s = json.load(open(f"{tmp}/net/summary.json"))
ok = s["status"] == "ok" and s["mode"] == "walls" and s["solver"]["unconverged_increments"] == 0
ok = ok and s["solver"]["max_eq13_vs_contacts"] < 1e-3 and s["jammed_state"]["saved"] == "jammed.json"
ok = ok and len(net) == len(d1) == 11 and abs(float(net[-1]["D"]) - float(d1[-1]["D"])) < 1e-6
ok = ok and abs(float(net[-1]["Z"]) - float(d1[-1]["Z"])) < 0.05
for c in ("S11", "S22", "S33"):
    nm = 0.5 * (float(net[-1][c]) + float(net[-2][c]))  # netsolve's window mean
    g3 = (float(d3[-1][c]) - nm) / abs(nm)
    g1 = (float(d1[-1][c]) - nm) / abs(nm)
    g0 = g1 - (g3 - g1) / 2  # linear in I: I = 3e-4, 1e-4 -> 0
    print(f"{c}: netsolve {nm:.6f}, DEM gap {100 * g3:.3f} % (I = 3e-4), {100 * g1:.3f} % (1e-4), {100 * g0:.4f} % (I -> 0)")
    ok = ok and nm < 0 and abs(g1) < abs(g3) and abs(g1) < 1e-3 and abs(g0) < 3e-4
sys.exit(0 if ok else 1)
PY
result dem_limit $?
"$ds" compact --dim 3 --boundary walls --state "$tmp/net/jammed.json" --to-strain 0.002 --increments 2 --inertial-number 1e-3 \
  --quiet --out "$tmp/back" >/dev/null 2>"$tmp/stderr" && grep -q '"status": "ok"' "$tmp/back/summary.json"
result dem_reads_netsolve_state $?
finish
