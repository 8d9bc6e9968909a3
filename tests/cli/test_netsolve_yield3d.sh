#!/usr/bin/env bash
# netsolve yield --dim 3 (issue 30 item 2): physics that could fail, and bad input.
#  * the fabric-resolved bound (every compressed contact keeps its force, the others carry none) is
#    recomputed in the test from contacts_loaded.vtp and the packing file alone, for every probe
#    direction, frictionless: netsolve's p_fabric, q_fabric within 1e-8 of the loading stress;
#  * along psi = 0 (hydrostatic reloading of a hydrostatically precompacted affine network) every
#    contact is compressed again: the bound is the loading point itself (1e-9);
#  * affine probing reaches the bound: the 0.1 % offset point of every direction the bound loads with
#    at least 10 % of the loading stress lies within [0.85, 1.1] of it (the rigid-plastic bound from
#    below; the elastic branch's 1e3 stiffness and the hardening of the probe shift it by a few %);
#  * the isotropic analytic vertex of summary.json is (3 D Z sigma_y / 10)(tr E I + 2E) of its own
#    D, Z and E (docs/yield_analytic.md "3D"), and the psi = 0 analytic point is that vertex;
#  * invariance: the deposition rotated by 90 degrees about x and shifted, probed along the rotated
#    six-component rate (--rate), gives the rotated stress tensor at the offset point (1e-9);
#  * an affine precompaction in a periodic cell (--compact-bc affine, every centre follows the cell):
#    its psi = 0 bound is the loading point too;
#  * a periodic cell, frictionless, pseudo-transient, the slice --probe 1/4 of 8 directions (psi =
#    45 and 225 deg): every probe with a point lies below 1.1 x the affine bound (relaxation only
#    lowers it; measured 0.85), the unloading reaches --unload-tol;
#  * apps/scripts/plot_yield.py's own (p, q) closed form equals netsolve's analytic columns (1e-7:
#    the CSV's 9 digits) and it draws surface.png of a 3D run;
#  * the files: yield_points.csv, probes/probe_K.csv, unload.csv, summary.json, snapshots.pvd with
#    the cell; no NaN;
#  * --jobs (threads) and yield-merge --dim 3: the 12 affine probes in one job, in two, and as three
#    slices --probe i/3 merged give the same yield_points.csv and probe curves, byte for byte; a merge
#    with a slice missing is "incomplete" and names the missing probes;
#  * --jobs 2 with linear solves (periodic probes, sticking) gives --jobs 1's files byte for byte (full
#    scale only);
#  * --from-state: compact --dim 3 --save-state's state.txt as the loading point gives the yield points
#    and probe curves of the run that precompacts itself, byte for byte;
#  * bad input: one line, exit 2, no folder (a merge of runs with different setups, or of a folder
#    that is not a 3D yield run; --from-state with --packing, off the path, or not a 3D state).
# usage: test_netsolve_yield3d.sh PATH/TO/netsolve
set -u
ns="$1"
tool="$ns"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
"$ns" pack --dim 3 --width 8 --out "$tmp/p3" >/dev/null 2>"$tmp/stderr"
result pack3d $?
"$ns" pack --dim 3 --periodic --n 120 --seed 3 --out "$tmp/pp" --quiet >/dev/null 2>"$tmp/stderr"
result pack_periodic $?
p3="$tmp/p3/packing.csv"

# the deposition rotated by 90 degrees about x, (x, y, z) -> (x, -z, y), then shifted
/usr/bin/python3 - "$tmp" "$p3" <<'PY'
import sys
tmp, p3 = sys.argv[1], sys.argv[2]
out = []
for l in open(p3).read().splitlines():
    if l.startswith("# box"):
        x0, y0, z0, x1, y1, z1 = map(float, l.split()[2:])
        out.append(f"# box {x0 + 3.5!r} {-z1 - 7.25!r} {y0 + 1.5!r} {x1 + 3.5!r} {-z0 - 7.25!r} {y1 + 1.5!r}")
    elif l.startswith("#") or l.startswith("id"):
        out.append(l)
    else:
        i, x, y, z, r = l.split(",")
        out.append(f"{i},{float(x) + 3.5!r},{-float(z) - 7.25!r},{float(y) + 1.5!r},{r}")
open(f"{tmp}/rotated.csv", "w").write("\n".join(out) + "\n")
PY
result rotate $?

check_bad bad_rate_count "six components" yield --dim 3 --packing "$p3" --rate 1,2
check_bad bad_rate_zero "no direction" yield --dim 3 --packing "$p3" --rate 0,0,0,0,0,0
check_bad bad_precompact "not 'hydrostatic'" yield --dim 3 --packing "$p3" --precompact shear
check_bad bad_walls "2D only" yield --dim 3 --packing "$p3" --compact-bc walls
check_bad bad_periodic "needs a periodic packing" yield --dim 3 --packing "$p3" --compact-bc periodic
check_bad bad_probe_bc "--probe-bc" yield --dim 3 --packing "$tmp/pp/packing.csv" --probe-bc die
check_bad bad_slice "is not a slice" yield --dim 3 --packing "$p3" --probe 5/2
check_bad bad_dim "--dim must be 2 or 3" yield --dim 4
check_bad bad_jobs "--jobs" yield --dim 3 --packing "$p3" --jobs -1
check_bad bad_ratio "--unload-ratio" yield --dim 3 --packing "$p3" --unload-ratio 0.5
check_bad bad_density "not above the current density" yield --dim 3 --packing "$p3" --to-density 0.2
check_bad bad_missing "missing.csv" yield --dim 3 --packing "$tmp/missing.csv"

run() {  # name args...: a run that must exit 0
  local name="$1" t0=$SECONDS
  shift
  "$ns" yield --dim 3 --quiet "$@" --out "$tmp/$name" >/dev/null 2>"$tmp/stderr"
  result "$name" $?
  echo "$name: $((SECONDS - t0)) s"
}
run affine --packing "$p3" --friction 0 --directions 12 --to-density 0.47
rate="-1,0.3,0.2,0.1,-0.2,0.4"
run along --packing "$p3" --rate="$rate" --to-density 0.47
# the rotated rate Q E Q^T for (x, y, z) -> (x, -z, y): E11 -> E11, E22 <- E33, E33 <- E22, E23 <- -E23,
# E13 <- E12, E12 <- -E13 (Voigt order 11, 22, 33, 23, 13, 12)
run along_rotated --packing "$tmp/rotated.csv" --rate="-1,0.2,0.3,-0.1,0.4,0.2" --to-density 0.47
run periodic --packing "$tmp/pp/packing.csv" --friction 0 --directions 8 --probe 1/4 --max-strain 2e-3
run periodic_affine --packing "$tmp/pp/packing.csv" --compact-bc affine --friction 0 --directions 4
check_pvd pvd_periodic "$tmp/periodic" particles,contacts,cell
# --jobs and yield-merge --dim 3: the affine run (its default --jobs, the number of cores) in one job and
# as three slices merged gives the same yield_points.csv and probe curves, byte for byte
run affine_j1 --packing "$p3" --friction 0 --directions 12 --to-density 0.47 --jobs 1
for i in 0 1 2; do run "affine_s$i" --packing "$p3" --friction 0 --directions 12 --to-density 0.47 --probe "$i/3"; done
"$ns" yield-merge --dim 3 "$tmp/affine_s0" "$tmp/affine_s1" "$tmp/affine_s2" --out "$tmp/merged" >/dev/null 2>"$tmp/stderr" &&
  cmp -s "$tmp/affine/yield_points.csv" "$tmp/affine_j1/yield_points.csv" &&
  cmp -s "$tmp/affine/yield_points.csv" "$tmp/merged/yield_points.csv" &&
  for k in 000 001 005 011; do cmp -s "$tmp/affine/probes/probe_$k.csv" "$tmp/merged/probes/probe_$k.csv" || exit 1; done &&
  /usr/bin/python3 -c 'import csv, json, sys; s = json.load(open(sys.argv[1]))
not_ok = [int(r["probe"]) for r in csv.DictReader(open(sys.argv[2])) if r["status"] != "ok"]  # the single run'"'"'s
ok = s["probes"]["found"] == 12 and s["dim"] == 3 and "analytic" in s and s["probes"]["not_ok"] == not_ok
sys.exit(0 if ok and s["status"] == ("incomplete" if not_ok else "ok") else 1)' \
    "$tmp/merged/summary.json" "$tmp/affine/yield_points.csv"
result jobs_and_merge_identical $?
"$ns" yield-merge --dim 3 "$tmp/affine_s0" "$tmp/affine_s1" --out "$tmp/merged2" >/dev/null 2>"$tmp/stderr" &&
  /usr/bin/python3 -c 'import json, sys; s = json.load(open(sys.argv[1]))
sys.exit(0 if s["status"] == "incomplete" and s["probes"]["missing"] == [2, 5, 8, 11] else 1)' "$tmp/merged2/summary.json"
result merge_missing_incomplete $?
# --from-state: netsolve compact --dim 3 --save-state writes the loading point (state.txt, kind network3d),
# and yield --from-state probes from it: the same yield points and probe curves, byte for byte, as the
# run that precompacts itself with the same options (periodic cell, sticking, pseudo-transient; yield's
# precompaction keeps no factor, hence --factor-reuse 0)
dpp=$(/usr/bin/python3 -c 'import json, sys; print("%.6f" % (json.load(open(sys.argv[1]))["density"] + 0.02))' "$tmp/pp/summary.json")
"$ns" compact --dim 3 --boundary periodic --packing "$tmp/pp/packing.csv" --to-density "$dpp" --increments 8 \
  --factor-reuse 0 --snapshots '' --save-state --quiet --out "$tmp/cstate" >/dev/null 2>"$tmp/stderr" &&
  /usr/bin/python3 -c 'import json, sys; s = json.load(open(sys.argv[1]))
sys.exit(0 if s["state"] == "state.txt" and s["jammed_state"]["saved"] == "" and s["status"] == "ok" else 1)' "$tmp/cstate/summary.json"
result compact3d_save_state $?
run own_pre --packing "$tmp/pp/packing.csv" --to-density "$dpp" --increments 8 --directions 4 --probe-bc affine
run from_state --from-state "$tmp/cstate/state.txt" --directions 4 --probe-bc affine
cmp -s "$tmp/own_pre/yield_points.csv" "$tmp/from_state/yield_points.csv" &&
  for k in 000 001 002 003; do cmp -s "$tmp/own_pre/probes/probe_$k.csv" "$tmp/from_state/probes/probe_$k.csv" || exit 1; done &&
  /usr/bin/python3 -c 'import json, sys; a, b = (json.load(open(f)) for f in sys.argv[1:3])
pa, pb = a["precompaction"], b["precompaction"]
ok = pb["from_state"].endswith("state.txt") and pb["increments_done"] is None and pa["increments_done"] == 8
ok &= all(pa[k] == pb[k] for k in ("S11", "S22", "S33", "Z", "D"))
print("from a state: loading point S33 %.9f / %.9f, probes identical" % (pa["S33"], pb["S33"]))
sys.exit(0 if ok and a["status"] == b["status"] else 1)' "$tmp/own_pre/summary.json" "$tmp/from_state/summary.json"
result from_state_identical $?
# --jobs with linear solves (a periodic cell, sticking, periodic probes): two probes factorise and
# solve at once on two threads, and the files equal --jobs 1's byte for byte. Before the process-wide
# lock on CHOLMOD's calls (src/quasistatic/cholmod_factor.cpp) they differed in every run, with
# factors "not positive definite". Full scale only: about 20 s in Release, and the sanitizers do not
# see this kind of race.
if [ "${NETDEM_TEST_SCALE:-}" != small ]; then
  run solves_j1 --packing "$tmp/pp/packing.csv" --directions 2 --max-strain 3e-4 --offset 1e-4 --jobs 1
  run solves_j2 --packing "$tmp/pp/packing.csv" --directions 2 --max-strain 3e-4 --offset 1e-4 --jobs 2
  cmp -s "$tmp/solves_j1/yield_points.csv" "$tmp/solves_j2/yield_points.csv" &&
    cmp -s "$tmp/solves_j1/probes/probe_000.csv" "$tmp/solves_j2/probes/probe_000.csv" &&
    cmp -s "$tmp/solves_j1/probes/probe_001.csv" "$tmp/solves_j2/probes/probe_001.csv"
  result jobs_with_solves_identical $?
fi
check_bad from_state_packing "exclude each other" yield --dim 3 --from-state "$tmp/cstate/state.txt" --packing "$p3"
check_bad from_state_path "does not lie along" yield --dim 3 --from-state "$tmp/cstate/state.txt" --precompact closed-die
sed 's/"network3d"/"network"/' "$tmp/cstate/state.txt" > "$tmp/state2d_kind.txt"
check_bad from_state_kind "expected a network3d state" yield --dim 3 --from-state "$tmp/state2d_kind.txt"
check_bad merge_setup "different setup" yield-merge --dim 3 "$tmp/affine_s0" "$tmp/periodic"
check_bad merge_not_3d "not a finished netsolve yield --dim 3 run" yield-merge --dim 3 "$tmp/affine_s0" "$tmp/pp"

/usr/bin/python3 - "$tmp" "${BASH_SOURCE[0]}" <<'PY'
import csv, json, math, os, sys
import xml.etree.ElementTree as ET
import numpy as np
tmp = sys.argv[1]
bad = []

def rows(d):
    return list(csv.DictReader(open(f"{tmp}/{d}/yield_points.csv")))

def f(x):
    return float(x) if x != "" else math.nan

def pq(s):
    return -np.trace(s) / 3.0, s[2, 2] - 0.5 * (s[0, 0] + s[1, 1])

def rate(psi_deg):  # qs::axisymmetric_rate, unit Frobenius norm
    ev, eq = math.cos(math.radians(psi_deg)), math.sin(math.radians(psi_deg))
    e11, e33 = -ev / 3 - eq / 2, -ev / 3 + eq
    r = np.diag([e11, e11, e33])
    return r / np.linalg.norm(r)

def contacts(d, tag):  # centres, pairs, normal forces of contacts_TAG.vtp
    root = ET.parse(f"{tmp}/{d}/contacts_{tag}.vtp").getroot()
    piece = root.find(".//Piece")
    pts = np.array(piece.find("Points/DataArray").text.split(), float).reshape(-1, 3)
    arrays = {a.get("Name"): a for a in piece.iter("DataArray")}
    conn = np.array(arrays["connectivity"].text.split(), int).reshape(-1, 2)
    fn = np.array(arrays["normal_force"].text.split(), float)
    return pts, conn, fn

# ---- affine, frictionless: the fabric bound from the files, its psi = 0 point, the offset points
s = json.load(open(f"{tmp}/affine/summary.json"))
if s["status"] != "ok" or s["probes"]["run"] != 12:
    bad.append(f"affine: status {s['status']} ({s['status_reason']}), probes {s['probes']}")
pre = s["precompaction"]
p_load, q_load = pre["p"], pre["q"]
pts, conn, fn = contacts("affine", "loaded")
r = np.array([float(l.split(",")[4]) for l in open(f"{tmp}/affine/packing.csv")
              if l.strip() and not l.startswith("#") and not l.startswith("id")])
volume = (4.0 / 3.0) * math.pi * np.sum(r ** 3) / pre["D"]
worst_fabric = 0.0
for row in rows("affine"):
    R = rate(f(row["psi"]))
    S = np.zeros((3, 3))
    for (i, j), fc in zip(conn, fn):
        l = pts[j] - pts[i]
        L = np.linalg.norm(l)
        n = l / L
        if n @ R @ n < 0:
            S -= fc * L * np.outer(n, n)
    p, q = pq(S / volume)
    worst_fabric = max(worst_fabric, abs(p - f(row["p_fabric"])) / p_load, abs(q - f(row["q_fabric"])) / p_load)
    if f(row["psi"]) == 0.0:
        if not (abs(f(row["p_fabric"]) - p_load) < 1e-9 * p_load and abs(f(row["q_fabric"]) - q_load) < 1e-9 * p_load):
            bad.append(f"affine psi=0: fabric ({row['p_fabric']}, {row['q_fabric']}) != loading ({p_load}, {q_load})")
    sf, so = f(row["stress_fabric"]), f(row["stress_offset"])
    if sf > 0.1 * math.hypot(p_load * math.sqrt(3), q_load):
        if not (0.85 * sf <= so <= 1.1 * sf):
            bad.append(f"affine psi={row['psi']}: offset stress {so:.5g} not within [0.85, 1.1] of the bound {sf:.5g}")
if worst_fabric > 1e-8:
    bad.append(f"affine: fabric bound from the files differs by {worst_fabric:.2e} of p_load")
an = s["analytic"]
E = np.array([[an["E11"], an["E12"], an["E13"]], [an["E12"], an["E22"], an["E23"]], [an["E13"], an["E23"], an["E33"]]])
v = 0.3 * an["D"] * an["Z"] * (np.trace(E) * np.eye(3) + 2 * E)
pv, qv = pq(v)
if not (abs(pv - an["vertex"]["p"]) < 1e-12 * pv and abs(qv - an["vertex"]["q"]) < 1e-12 * pv):
    bad.append(f"analytic vertex {an['vertex']} != ({pv}, {qv})")
if an["Z"] != pre["Z"] or an["D"] != pre["D"]:
    bad.append("analytic input is not the precompaction's D and Z")
r0 = [x for x in rows("affine") if f(x["psi"]) == 0.0][0]
if not abs(f(r0["p_analytic"]) - pv) < 1e-8 * pv:  # the CSV's 9 digits
    bad.append(f"psi = 0 analytic point {r0['p_analytic']} is not the vertex {pv}")

# ---- rotation invariance along a six-component rate
def offset_tensor(d):
    x = rows(d)[0]
    v = [f(x[f"S{k}_offset"]) for k in ("11", "22", "33", "23", "13", "12")]
    return np.array([[v[0], v[5], v[4]], [v[5], v[1], v[3]], [v[4], v[3], v[2]]]), x["status"]
A, sa = offset_tensor("along")
B, sb = offset_tensor("along_rotated")
Q = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], float)
dev = np.abs(Q @ A @ Q.T - B).max() / np.abs(A).max()
if sa != "ok" or sb != "ok" or not dev < 1e-9:
    bad.append(f"rotation: offset tensors differ by {dev:.2e} (status {sa}, {sb})")

# ---- periodic, frictionless: below 1.1 x the affine bound; unloaded
s = json.load(open(f"{tmp}/periodic/summary.json"))
if s["status"] != "ok" or not s["unloading"]["stress_norm"] < 1e-3 or s["probes"]["indices"] != [1, 5]:
    bad.append(f"periodic: status {s['status']} ({s['status_reason']}), unloading {s['unloading']}")
ok = 0
for row in rows("periodic"):
    if row["status"] != "ok":
        continue
    ok += 1
    so, sf = f(row["stress_offset"]), f(row["stress_fabric"])
    if not so <= 1.1 * sf + 1e-6:
        bad.append(f"periodic psi={row['psi']}: offset {so:.5g} above 1.1 x the affine bound {sf:.5g}")
if ok < 1:
    bad.append(f"periodic: only {ok} probes found their points")

# ---- an affine precompaction in the periodic cell: the psi = 0 bound is again the loading point
s = json.load(open(f"{tmp}/periodic_affine/summary.json"))
r0 = rows("periodic_affine")[0]
pl, ql = s["precompaction"]["p"], s["precompaction"]["q"]
if not (s["setup"]["compact_bc"] == "affine (periodic cell)" and s["status"] == "ok"
        and abs(f(r0["p_fabric"]) - pl) < 1e-8 * pl and abs(f(r0["q_fabric"]) - ql) < 1e-8 * pl):
    bad.append(f"periodic affine: {s['setup']['compact_bc']}, {s['status']}, fabric ({r0['p_fabric']}, {r0['q_fabric']}) "
               f"against the loading point ({pl}, {ql})")

# ---- apps/scripts/plot_yield.py's own (p, q) closed form against netsolve's analytic columns
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(sys.argv[2])), "..", "..", "apps", "scripts"))
import plot_yield
s = json.load(open(f"{tmp}/affine/summary.json"))
worst_an = 0.0
for row in rows("affine"):
    p, q = plot_yield.analytic_pq(s["analytic"], s["setup"]["mu_eff"], math.radians(f(row["psi"])))
    worst_an = max(worst_an, abs(p - f(row["p_analytic"])) / p_load, abs(q - f(row["q_analytic"])) / p_load)
if not worst_an < 1e-7:
    bad.append(f"plot_yield.analytic_pq differs from netsolve's analytic columns by {worst_an:.2e} of p_load")

# ---- no NaN in any file
import glob
for d in ("affine", "along", "periodic"):
    for path in glob.glob(f"{tmp}/{d}/*.csv") + glob.glob(f"{tmp}/{d}/probes/*.csv") + [f"{tmp}/{d}/summary.json"]:
        if "nan" in open(path).read().lower().replace("nanosec", ""):
            bad.append(f"{path}: NaN")
print(f"fabric bound from the files: {worst_fabric:.2e}; rotation: {dev:.2e}; periodic probes ok: {ok}; "
      f"plot_yield's closed form: {worst_an:.2e}")
for b in bad:
    print("FAIL", b)
sys.exit(1 if bad else 0)
PY
result physics $?
/usr/bin/python3 "$(dirname "${BASH_SOURCE[0]}")/../../apps/scripts/plot_yield.py" "$tmp/affine" >/dev/null 2>"$tmp/stderr" && [ -s "$tmp/affine/surface.png" ]
result plot_3d $?
finish
