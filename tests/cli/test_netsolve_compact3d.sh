#!/usr/bin/env bash
# netsolve compact --dim 3 (issue 30): physics that could fail, and bad input.
#  * closed form: a simple cubic lattice of n^3 touching spheres (n = 4) compacted affinely and
#    hydrostatically to D = 0.6 has S = -(3 pi / 4) sigma_y (u/R) exp(-2E) (n - 1)/n per axis, u =
#    2R (1 - e^E) (every bond carries the 3D plastic force 3 pi sigma_y R u over L = 2R e^E); the
#    same lattice in a periodic cell has it without (n - 1)/n, its free spheres staying in
#    equilibrium in every increment, and the same with every centre following the cell (--affine
#    --boundary periodic);
#  * the DEM: affine frictionless compaction of a 3D deposition gives demsolve compact's stresses
#    (the same contacts, the DEM's own force loop, no dashpots);
#  * the affine formula S = -(1/V) sum 6 pi sigma_y R* u L n n over the deposition's touching pairs at
#    e^E x0, computed in the test from the packing file alone, equals netsolve's affine stress (1e-9);
#  * invariance: the deposition rotated by 90 degrees about x, y or z and shifted gives the rotated stresses
#    (signs included, S' = Q S Q^T), affine (about x) and in the die of the peripheral layer, closed
#    die along z (along y, x, z after the rotation about x, y, z) with sticking friction and rotations
#    (all 1e-9; measured 9e-14 affine, 3e-16 to 1e-15 in the die);
#  * the kept factor (--factor-reuse 20) ends a periodic compaction at --tol 1e-6 in the state of a
#    factorisation per fresh tangent (1e-4 of max |S|), with fewer factorisations;
#  * the preconditioner (the translations' factor by default, the whole matrix's with --preconditioner
#    full) changes the linear solves only: with solves to 1e-8 every increment's stresses agree to
#    1e-8 of max |S| with the same contacts and sliding contacts;
#  * the files: history.csv with the six components, the fabric (trace 1), no NaN; summary.json;
#    snapshots.pvd with z;
#  * apps/scripts/plot_run.py writes a 3D run's report (the six stress components of summary.json)
#    and its pictures;
#  * bad input: one line, exit 2, no folder.
# usage: test_netsolve_compact3d.sh PATH/TO/netsolve PATH/TO/demsolve
set -u
ns="$1"
ds="$2"
tool="$ns"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
"$ns" pack --dim 3 --width 6 --out "$tmp/p3" >/dev/null 2>"$tmp/stderr"
result pack3d $?
"$ns" pack --width 10 --out "$tmp/p2" >/dev/null 2>"$tmp/stderr"
result pack2d $?
p3="$tmp/p3/packing.csv"

# the lattices (touching spheres of radius 1 at spacing 2, box [0, 2n]^3) and the rotated deposition
/usr/bin/python3 - "$tmp" "$p3" <<'PY'
import sys
tmp, p3 = sys.argv[1], sys.argv[2]
n = 4
rows = [f"{k},{2*i+1},{2*j+1},{2*l+1},1" for k, (i, j, l) in
        enumerate((i, j, l) for i in range(n) for j in range(n) for l in range(n))]
for name, periodic in (("lattice", False), ("lattice_periodic", True)):
    with open(f"{tmp}/{name}.csv", "w") as f:
        f.write(f"# box 0 0 0 {2*n} {2*n} {2*n}\n# dim 3\n" + ("# periodic\n" if periodic else "") + "id,x,y,z,r\n")
        f.write("\n".join(rows) + "\n")
# rotations by 90 degrees about x, y and z, then a shift: x (x, y, z) -> (x, -z, y) in rotated.csv,
# y -> (z, y, -x) in rotated_y.csv, z -> (-y, x, z) in rotated_z.csv
rot = {"": lambda x, y, z: (x, -z, y), "_y": lambda x, y, z: (z, y, -x), "_z": lambda x, y, z: (-y, x, z)}
shift = (3.5, -7.25, 1.5)
lines = open(p3).read().splitlines()
for tag, q in rot.items():
    out = []
    for l in lines:
        if l.startswith("# box"):
            x0, y0, z0, x1, y1, z1 = map(float, l.split()[2:])
            a, b = q(x0, y0, z0), q(x1, y1, z1)
            lo = [min(u, v) + s for u, v, s in zip(a, b, shift)]
            hi = [max(u, v) + s for u, v, s in zip(a, b, shift)]
            out.append("# box " + " ".join(repr(v) for v in lo + hi))
        elif l.startswith("#") or l.startswith("id"):
            out.append(l)
        else:
            i, x, y, z, r = l.split(",")
            c = [v + s for v, s in zip(q(float(x), float(y), float(z)), shift)]
            out.append(f"{i},{c[0]!r},{c[1]!r},{c[2]!r},{r}")
    open(f"{tmp}/rotated{tag}.csv", "w").write("\n".join(out) + "\n")
PY
result lattices $?

check_bad dim3_2d_file "is a 2D packing" compact --dim 3 --affine --packing "$tmp/p2/packing.csv"
check_bad dim2_3d_file "is a 3D packing" compact --packing "$p3"
check_bad dim3_no_compaction "does not compact" compact --dim 3 --affine --packing "$p3" --path 1,1,-1
check_bad dim3_bad_path "3 or 6 finite numbers" compact --dim 3 --affine --packing "$p3" --path=-1,-1
check_bad dim3_target "not above the current density" compact --dim 3 --affine --packing "$p3" --to-density 0.3
check_bad dim3_periodic_plain "has no '# periodic' line" compact --dim 3 --boundary periodic --packing "$p3"
check_bad dim3_periodic_file "is a periodic packing" compact --dim 3 --affine --packing "$tmp/lattice_periodic.csv"
check_bad dim3_lid "--lid inside" compact --dim 3 --affine --width 6 --lid centre
check_bad dim4 "--dim" compact --dim 4

run() {  # name args...: a run that must exit 0
  local name="$1"
  shift
  "$ns" compact --dim 3 --quiet "$@" --out "$tmp/$name" >/dev/null 2>"$tmp/stderr"
  result "$name" $?
}
run lattice --affine --packing "$tmp/lattice.csv" --to-density 0.6 --increments 10 --snapshots 0.55,0.6
run lattice_periodic --boundary periodic --packing "$tmp/lattice_periodic.csv" --to-density 0.6 --increments 10 --snapshots ''
run lattice_periodic_affine --affine --boundary periodic --packing "$tmp/lattice_periodic.csv" --to-density 0.6 --increments 10 --snapshots ''

/usr/bin/python3 - "$tmp" <<'PY'
import csv, json, math, sys
tmp = sys.argv[1]
n, ok = 4, True
for name, factor in (("lattice", (n - 1) / n), ("lattice_periodic", 1.0), ("lattice_periodic_affine", 1.0)):
    s = json.load(open(f"{tmp}/{name}/summary.json"))
    f = s["final"]
    E = f["E11"]  # the accumulated strain per axis
    u = 2 * (1 - math.exp(E))
    want = -(3 * math.pi / 4) * u * math.exp(-2 * E) * factor
    err = max(abs(f[f"S{a}"] - want) / abs(want) for a in ("11", "22", "33"))
    shear = max(abs(f[f"S{a}"]) for a in ("23", "13", "12"))
    print(f"{name}: E = {E:.6f}, S = {f['S11']:.9f} {f['S22']:.9f} {f['S33']:.9f}, closed form {want:.9f}, "
          f"rel err {err:.2e}, Z {f['Z']}, D {f['D']:.12f}, status {s['status']}")
    ok &= err < 1e-9 and shear < 1e-12 and abs(f["D"] - 0.6) < 1e-12 and s["status"] == "ok"
    ok &= abs(f["Z"] - 6 * factor) < 1e-12 and math.exp(E) > 1 / math.sqrt(2)
    rows = list(csv.DictReader(l for l in open(f"{tmp}/{name}/history.csv") if not l.startswith("#")))
    ok &= len(rows) == 11 and all(r["converged"] == "1" for r in rows[1:])
    ok &= all(math.isfinite(float(v)) for r in rows for v in r.values())
    last = rows[-1]
    ok &= abs(float(last["fabric11"]) + float(last["fabric22"]) + float(last["fabric33"]) - 1) < 1e-8
    ok &= abs(float(last["fabric11"]) - 1 / 3) < 1e-8  # the three bond directions in equal numbers
    if name == "lattice_periodic":
        ok &= s["solver"]["iteration"] == "pseudo-transient" and float(last["residual_rms"]) <= 1e-3
    ok &= s["mode"] == {"lattice": "affine", "lattice_periodic": "periodic",
                        "lattice_periodic_affine": "affine (periodic cell)"}[name]
sys.exit(0 if ok else 1)
PY
result lattice_closed_form $?
check_pvd lattice_snapshots "$tmp/lattice" particles,contacts
grep -q 'NumberOfComponents="3"' "$tmp/lattice/particles_D0.600.vtp" && grep -q '"peripheral"' "$tmp/lattice/particles_D0.600.vtp"
result lattice_vtp_3d $?

# a shear direction reaches its own Voigt component (E12 = |E|/sqrt 2, nothing else; the affine shear
# opens contacts and Z < 3 reads "unstable", hence --allow-unconverged), and the default
# 3D deposition is W = 20 R (about 1000 spheres), not the 2D default width
run shear12 --snapshots '' --affine --packing "$tmp/lattice.csv" --path 0,0,0,0,0,1 --to-strain 0.01 --increments 4 --allow-unconverged
run default_width --snapshots '' --affine --to-density 0.6 --increments 4
# two legs: a hydrostatic precompaction to D = 0.55, then the closed die to |E| = 0.01 (summary.json legs)
run legs --snapshots '' --affine --packing "$tmp/lattice.csv" --precompact-density 0.55 --precompact-increments 3 \
  --path closed-die --to-strain 0.01 --increments 4
/usr/bin/python3 - "$tmp" <<'PY'
import json, sys
legs = json.load(open(f"{sys.argv[1]}/legs/summary.json"))["legs"]
ok = legs[0]["to_density"] == 0.55 and abs(legs[0]["end"]["D"] - 0.55) < 1e-12 and legs[1]["to_strain"] == 0.01
ok &= abs(legs[1]["end"]["strain"] - 0.01) < 1e-12 and legs[1]["end"]["increment"] == 7
print(f"legs: {legs[0]['end']['D']}, {legs[1]['end']['strain']}, increment {legs[1]['end']['increment']}")
sys.exit(0 if ok else 1)
PY
result legs_summary $?
/usr/bin/python3 - "$tmp" <<'PY'
import csv, json, math, sys
tmp = sys.argv[1]
last = list(csv.DictReader(l for l in open(f"{tmp}/shear12/history.csv") if not l.startswith("#")))[-1]
e = {c: float(last["E" + c]) for c in ("11", "22", "33", "23", "13", "12")}
s = json.load(open(f"{tmp}/default_width/summary.json"))
print(f"shear path 0,0,0,0,0,1 to |E| = 0.01: E = {e}; default 3D deposition: {s['particles']} spheres")
ok = abs(e["12"] - 0.01 / math.sqrt(2)) < 1e-10 and all(abs(e[c]) < 1e-15 for c in ("11", "22", "33", "23", "13"))
sys.exit(0 if ok and 700 <= s["particles"] <= 1300 else 1)
PY
result shear_component_and_default_width $?

# the DEM: affine, frictionless, no dashpots. A DEM row is the mean over its window (docs/dynamic.md),
# a netsolve row the state at the increment's end: each of the DEM's 20 windows is compared with the
# trapezoidal mean of netsolve's 16 increments in it (measured: 1e-4 of max |S| apart, half a DEM
# sample's delay; Z equal where no contact forms)
run affine_mu0 --snapshots '' --affine --packing "$p3" --friction 0 --to-density 0.62 --increments 320
"$ds" compact --dim 3 --affine --packing "$p3" --friction 0 --damping 0 --to-density 0.62 --increments 20 --quiet \
  --snapshots '' --out "$tmp/dem_mu0" >/dev/null 2>"$tmp/stderr"
result dem_affine_mu0 $?
/usr/bin/python3 - "$tmp" <<'PY'
import csv, sys
tmp = sys.argv[1]
def rows(d):
    return list(csv.DictReader(l for l in open(f"{tmp}/{d}/history.csv") if not l.startswith("#")))
n, d = rows("affine_mu0"), rows("dem_mu0")
comp = ["S" + c for c in ("11", "22", "33", "23", "13", "12")]
k = 16
scale = max(abs(float(n[-1][c])) for c in comp)
worst, worst_z = 0.0, 0.0
for w in range(1, 21):
    seg = n[(w - 1) * k:w * k + 1]
    for c in comp + ["Z"]:
        v = [float(r[c]) for r in seg]
        mean = (sum(v) - 0.5 * (v[0] + v[-1])) / k
        if c == "Z":
            worst_z = max(worst_z, abs(float(d[w][c]) - mean))
        else:
            worst = max(worst, abs(float(d[w][c]) - mean) / scale)
print(f"netsolve vs DEM, affine mu = 0, 20 windows to D = 0.62: max |S_DEM - S_netsolve| / max |S| = {worst:.2e} "
      f"(band 1e-3), max |Z_DEM - Z_netsolve| = {worst_z:.4f} (band 0.01); S33 at the end {n[-1]['S33']}")
sys.exit(0 if len(d) == 21 and len(n) == 321 and worst < 1e-3 and worst_z < 0.01 else 1)
PY
result netsolve_equals_dem_affine $?

# invariance under rotations by 90 degrees about x, y and z and a shift: S' = Q S Q^T
run affine_a --snapshots '' --affine --packing "$p3" --to-density 0.62 --increments 20
run affine_b --snapshots '' --affine --packing "$tmp/rotated.csv" --to-density 0.62 --increments 20
run die_a --snapshots '' --packing "$p3" --path closed-die --to-density 0.62 --increments 20 --allow-unconverged
run die_b --snapshots '' --packing "$tmp/rotated.csv" --path 0,-1,0 --to-density 0.62 --increments 20 --allow-unconverged
run die_y --snapshots '' --packing "$tmp/rotated_y.csv" --path=-1,0,0 --to-density 0.62 --increments 20 --allow-unconverged
run die_z --snapshots '' --packing "$tmp/rotated_z.csv" --path closed-die --to-density 0.62 --increments 20 --allow-unconverged
/usr/bin/python3 - "$tmp" <<'PY'
import json, sys
import numpy as np
tmp = sys.argv[1]
ok = True
Q = {"x": [[1, 0, 0], [0, 0, -1], [0, 1, 0]], "y": [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], "z": [[0, -1, 0], [1, 0, 0], [0, 0, 1]]}

def tensor(f):
    return np.array([[f["S11"], f["S12"], f["S13"]], [f["S12"], f["S22"], f["S23"]], [f["S13"], f["S23"], f["S33"]]])

for a, b, axis, tol in (("affine_a", "affine_b", "x", 1e-9), ("die_a", "die_b", "x", 1e-9), ("die_a", "die_y", "y", 1e-9),
                        ("die_a", "die_z", "z", 1e-9)):
    fa, fb = json.load(open(f"{tmp}/{a}/summary.json"))["final"], json.load(open(f"{tmp}/{b}/summary.json"))["final"]
    q = np.array(Q[axis], dtype=float)
    sa, sb = tensor(fa), tensor(fb)
    diff = np.abs(q @ sa @ q.T - sb).max() / np.abs(sa).max()
    print(f"{a} vs {b} (90 degrees about {axis}): diag {np.diag(sa).round(6)} -> {np.diag(sb).round(6)}, "
          f"max |Q S Q^T - S'| / max |S| = {diff:.2e} (band {tol:g}), Z {fa['Z']} / {fb['Z']}")
    ok &= diff < tol and fa["S33"] < 0 and fa["contacts"] == fb["contacts"]
sys.exit(0 if ok else 1)
PY
result rotation_invariance $?
# the affine formula on the packing's own contacts, computed here from the packing file alone: the
# centres at e^E x0 (hydrostatic, every centre affine), each touching pair with F = 6 pi sigma_y R* u
# (the loading branch: every pair approaches monotonically), S = -(1/V) sum F L n n
/usr/bin/python3 - "$tmp" "$p3" <<'PY'
import json, math, sys
tmp, p3 = sys.argv[1], sys.argv[2]
box, pts = None, []
for l in open(p3):
    if l.startswith("# box"):
        box = [float(v) for v in l.split()[2:]]
    elif l[0].isdigit():
        pts.append([float(v) for v in l.split(",")[1:]])
f = json.load(open(f"{tmp}/affine_a/summary.json"))["final"]
E = f["E11"]
s = math.exp(E)
V = (box[3] - box[0]) * (box[4] - box[1]) * (box[5] - box[2]) * math.exp(3 * E)
S = [[0.0] * 3 for _ in range(3)]
pairs = 0
for i, (xi, yi, zi, ri) in enumerate(pts):
    for xj, yj, zj, rj in pts[i + 1:]:
        d = ((xj - xi) * s, (yj - yi) * s, (zj - zi) * s)
        L = math.sqrt(sum(c * c for c in d))
        u = ri + rj - L
        if u <= 0:
            continue
        F = 6 * math.pi * (ri * rj / (ri + rj)) * u
        for a in range(3):
            for b in range(3):
                S[a][b] -= F * L * (d[a] / L) * (d[b] / L) / V
        pairs += 1
comp = {"11": (0, 0), "22": (1, 1), "33": (2, 2), "23": (1, 2), "13": (0, 2), "12": (0, 1)}
scale = max(abs(S[a][b]) for a in range(3) for b in range(3))
err = max(abs(f["S" + c] - S[a][b]) for c, (a, b) in comp.items()) / scale
print(f"affine formula on the deposition's contacts at E = {E:.6f}: S33 {S[2][2]:.9f} (netsolve {f['S33']:.9f}), "
      f"{pairs} pairs (netsolve {f['contacts']}), max diff / max |S| = {err:.2e}")
sys.exit(0 if err < 1e-9 and pairs == f["contacts"] else 1)
PY
result affine_formula_on_contacts $?
# the kept factor (--factor-reuse): a 200-sphere periodic packing compacted with and without it at
# --tol 1e-6 ends in the same state (both every increment accepted; the stresses within 1e-4 of
# max |S|) with fewer factorisations
"$ns" pack --dim 3 --periodic --n 200 --quiet --out "$tmp/pp" >/dev/null 2>"$tmp/stderr"
result periodic_pack3d $?
d0=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["density"])' "$tmp/pp/summary.json")
for fr in 0 20; do
  run reuse$fr --snapshots '' --boundary periodic --packing "$tmp/pp/packing.csv" --tol 1e-6 --factor-reuse $fr \
    --to-density "$(/usr/bin/python3 -c "print(f'{$d0 + 0.02:.6f}')")" --increments 10
done
# the preconditioner: the translations' factor (the 3D default) and the whole matrix's, with linear
# solves to 1e-8 (so that both follow the same Newton path)
for pc in translations full; do
  run pc_$pc --snapshots '' --boundary periodic --packing "$tmp/pp/packing.csv" --tol 1e-6 --linear-tol 1e-8 \
    --preconditioner $pc --to-density "$(/usr/bin/python3 -c "print(f'{$d0 + 0.01:.6f}')")" --increments 5
done
/usr/bin/python3 - "$tmp" <<'PY'
import json, sys
tmp = sys.argv[1]
a, b = (json.load(open(f"{tmp}/reuse{k}/summary.json")) for k in (0, 20))
comp = ("11", "22", "33", "23", "13", "12")
scale = max(abs(a["final"]["S" + c]) for c in comp)
diff = max(abs(a["final"]["S" + c] - b["final"]["S" + c]) for c in comp) / scale
fa, fb = a["solver"]["factorisations"], b["solver"]["factorisations"]
print(f"kept factor: S33 {a['final']['S33']:.8f} / {b['final']['S33']:.8f}, max diff / max |S| = {diff:.2e} (band 1e-4), "
      f"factorisations {fa} / {fb}, unconverged {a['solver']['unconverged_increments']} / {b['solver']['unconverged_increments']}")
ok = diff < 1e-4 and fb < fa and a["status"] == b["status"] == "ok" and b["solver"]["factor_reuse"] == 20
sys.exit(0 if ok else 1)
PY
result factor_reuse_same_state $?
# the preconditioner changes the linear solves only: with solves to 1e-8 both preconditioners give
# every increment's stresses within 1e-8 of max |S| and the same contacts and sliding contacts; each
# run records the preconditioner it used, and a frictionless run (no rotations to split) the full one
/usr/bin/python3 - "$tmp" <<'PY'
import csv, json, sys
tmp = sys.argv[1]
a, b = (list(csv.DictReader(open(f"{tmp}/pc_{k}/history.csv"))) for k in ("translations", "full"))
comp = ("11", "22", "33", "23", "13", "12")
scale = max(abs(float(r["S" + c])) for r in a for c in comp)
diff = max(abs(float(x["S" + c]) - float(y["S" + c])) for x, y in zip(a, b) for c in comp) / scale
same = len(a) == len(b) == 6 and all(x["contacts"] == y["contacts"] and x["sliding"] == y["sliding"] for x, y in zip(a, b))
sa, sb = (json.load(open(f"{tmp}/pc_{k}/summary.json")) for k in ("translations", "full"))
pa, pb = sa["solver"]["preconditioner"], sb["solver"]["preconditioner"]
pmu0 = json.load(open(f"{tmp}/affine_mu0/summary.json"))["solver"]["preconditioner"]
print(f"preconditioner {pa} / {pb} (frictionless: {pmu0}): max diff / max |S| over the increments = {diff:.2e} "
      f"(band 1e-8), same contacts and sliding contacts: {same}, status {sa['status']} / {sb['status']}")
ok = diff < 1e-8 and same and sa["status"] == sb["status"] == "ok" and (pa, pb, pmu0) == ("translations", "full", "full")
sys.exit(0 if ok else 1)
PY
result preconditioner_same_state $?
# apps/scripts/plot_run.py (README command 1's report) on a 3D run: report.md lists the six stress
# components as summary.json has them, compaction.png and packing.png (the spheres) are drawn
/usr/bin/python3 "$(dirname "${BASH_SOURCE[0]}")/../../apps/scripts/plot_run.py" "$tmp/pc_full" >/dev/null 2>"$tmp/stderr" &&
  [ -s "$tmp/pc_full/compaction.png" ] && [ -s "$tmp/pc_full/packing.png" ] &&
  /usr/bin/python3 - "$tmp/pc_full" <<'PY'
import json, sys
run = sys.argv[1]
s = json.load(open(f"{run}/summary.json"))["final"]
rep = open(f"{run}/report.md").read()
ok = "(3D: spheres)" in rep
for c in ("11", "22", "33", "23", "13", "12"):
    ok &= f"| Σ{c}/σy | {s['S' + c]:.4f} |" in rep
ok &= f"| Σ33/Σ11 | {s['S33'] / s['S11']:.3f} |" in rep
sys.exit(0 if ok else 1)
PY
result plot_run_3d $?
finish
