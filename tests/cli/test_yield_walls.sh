#!/usr/bin/env bash
# netsolve yield between walls (issue 28: the yield lines on frictionless precompaction, re-evaluated
# on converged runs between walls). A frictionless DEM jammed state (W = 20, D = 0.83 in the walls'
# box) is precompacted to 0.84 by the pseudo-transient iteration, unloaded and probed between the
# same walls. Asserted:
# * the loading point is the end state of `netsolve compact --state` with the same options, to 2e-8
#   relative, from the jammed state (--state) and from compact's state.txt with the wall contacts
#   (--from-state), and the probe from either is the same;
# * the loading point is on the surface: the probe along the loading direction (225 degrees) yields
#   within 5 % of the loading stress (measured 2026-12-06: offset point +2.4 %, maximum-curvature
#   point -2.0 %), and it is a vertex (Redanz & Fleck 3.4): the probes 45 degrees to either side
#   (180, 270) also yield within 5 % of the loading point (offset points 1.7 % and 1.8 % from it),
#   where a smooth surface would put them well away from it;
# * the answer is the equilibrium's, not the drag's: --regularisation-scale 10 moves the loading point
#   by less than 1 % and the probes' offset points by less than 2 % (measured 0.31 % and 0.1-1.0 %);
# * bad combinations exit non-zero with one line and no folder.
# usage: test_yield_walls.sh PATH/TO/netsolve PATH/TO/demsolve
set -u
ns="$(readlink -f "$1")"
dm="$(readlink -f "$2")"
tool="$ns"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
"$dm" compact --width 20 --boundary walls --friction 0 --to-density 0.83 --save-state --snapshots "" --quiet \
  --out "$tmp/jam" >/dev/null 2>&1 || { echo "FAIL: demsolve compact --save-state"; exit 1; }
"$ns" pack --width 12 --seed 2 --out "$tmp/w" >/dev/null 2>&1
check_bad probe_walls_needs_walls "--probe-bc walls" yield --compact-bc die --probe-bc walls --friction 0 --packing "$tmp/w/packing.csv"
check_bad walls_probe_not_die "--probe-bc" yield --compact-bc walls --probe-bc die --friction 0 --packing "$tmp/w/packing.csv"
check_bad walls_state_needs_walls "walls" yield --compact-bc die --friction 0 --state "$tmp/jam/jammed.json"
check_bad state_law_is_the_commands "law" yield --compact-bc walls --friction inf --state "$tmp/jam/jammed.json"
check_bad state_and_from_state "exclude" yield --compact-bc walls --friction 0 --state "$tmp/jam/jammed.json" \
  --from-state "$tmp/jam/jammed.json"
check_bad state_not_periodic "periodic" yield --compact-bc periodic --friction 0 --state "$tmp/jam/jammed.json"
law=(--friction 0 --iteration pseudo-transient --quiet)
pre=(--to-density 0.84 --increments 10)
probes=(yield --compact-bc walls --directions 8 --probes 3,4,5,6,7 --jobs 1 "${law[@]}")
"$ns" compact --boundary walls --state "$tmp/jam/jammed.json" "${pre[@]}" "${law[@]}" --save-state --snapshots "" \
  --out "$tmp/c" >/dev/null 2>"$tmp/stderr"
compact_rc=$?
check_bad walls_state_file_needs_walls "wall contacts" yield --compact-bc die --friction 0 --from-state "$tmp/c/state.txt"
if [ "$compact_rc" -eq 0 ] &&
   "$ns" "${probes[@]}" --state "$tmp/jam/jammed.json" "${pre[@]}" --out "$tmp/y" >/dev/null 2>>"$tmp/stderr" &&
   "$ns" "${probes[@]}" --from-state "$tmp/c/state.txt" --out "$tmp/yf" >/dev/null 2>>"$tmp/stderr" &&
   "$ns" "${probes[@]}" --state "$tmp/jam/jammed.json" "${pre[@]}" --regularisation-scale 10 --out "$tmp/y10" \
     >/dev/null 2>>"$tmp/stderr" &&
   /usr/bin/python3 - "$tmp" <<'PY'
import csv, json, math, sys
t = sys.argv[1]
end = [r for r in csv.DictReader(l for l in open(f"{t}/c/history.csv") if not l.startswith("#"))][-1]
def run(d):
    s = json.load(open(f"{t}/{d}/summary.json"))
    return s, {r["probe"]: r for r in csv.DictReader(open(f"{t}/{d}/yield_points.csv"))}
ok = True
(sy, py), (sf, pf), (s10, p10) = run("y"), run("yf"), run("y10")
S = (float(end["S11"]), float(end["S22"]))
load = math.hypot(*S)
for name, s in (("--state", sy), ("--from-state", sf)):
    pc = s["precompaction"]
    d = math.hypot(pc["S11"] - S[0], pc["S22"] - S[1]) / load
    print(f"  loading point from {name}: {d:.2e} of |S| from compact's end state")
    ok = ok and d < 2e-8 and s["status"] == "ok"  # history.csv has 9 significant digits
same = all(py[k]["stress_offset"] == pf[k]["stress_offset"] for k in py)
print(f"  probes from --state and --from-state identical: {same}")
p = py["5"]
off, curv = float(p["stress_offset"]) / load - 1, float(p["stress"]) / load - 1
print(f"  loading direction (225 deg): offset point {off:+.2%}, maximum curvature {curv:+.2%} of the loading stress")
side = [math.hypot(float(py[k]["S11_offset"]) - S[0], float(py[k]["S22_offset"]) - S[1]) / load for k in ("4", "6")]
print(f"  vertex: the offset points at 180 and 270 deg are {side[0]:.2%} and {side[1]:.2%} of |S| from the loading point")
ok = ok and max(side) < 0.05
pc10 = s10["precompaction"]
dl = math.hypot(pc10["S11"] - S[0], pc10["S22"] - S[1]) / load
dy = max(abs(float(p10[k]["stress_offset"]) / float(py[k]["stress_offset"]) - 1) for k in py)
print(f"  --regularisation-scale 10: loading point {dl:.2%}, offset points up to {dy:.2%}")
ok = ok and same and abs(off) < 0.05 and abs(curv) < 0.05 and dl < 0.01 and dy < 0.02
ok = ok and all(r["status"] == "ok" for r in list(py.values()) + list(pf.values()) + list(p10.values()))
sys.exit(0 if ok else 1)
PY
then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL yield_between_walls: $(tail -3 "$tmp/stderr")"; fi
finish
