#!/usr/bin/env bash
# netsolve compact --boundary periodic (issue 29): a periodic triangular lattice of touching disks
# (6 x 6, a '# periodic' packing file) compacted hydrostatically to 1.03 x its density follows the
# infinite lattice's closed form, Sigma = -(3/2) N F L / V with F = 3 sigma_y sqrt(8 u R/2),
# L = 2 R e^E (no edge factor), to 1e-8; summary mode "periodic", exit 0. The door refuses a
# periodic packing without --boundary periodic, --boundary periodic without a periodic packing,
# --state and --affine with it, and yield's die or mixed modes on it: one line, exit 2, nothing
# written. --save-state writes state.txt with the cell (no jammed.json: a jammed state has no
# periodic cell yet), and yield --compact-bc periodic --from-state starts from it. The default
# iteration reaches the undragged equilibrium and its answer is independent of the drag (below).
# usage: test_periodic.sh PATH/TO/netsolve
set -u
ns="$(readlink -f "$1")"
tool="$ns"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"

/usr/bin/python3 - "$tmp/lat.csv" <<'PY'
import math, sys
nc = nr = 6
h = math.sqrt(3.0)
rows = [f"# box 0 0 {2 * nc!r} {h * nr!r}", "# periodic", "id,x,y,r"]
for r in range(nr):
    for c in range(nc):
        rows.append(f"{r * nc + c},{(r % 2) + 2 * c + 0.5!r},{h * r + 0.5 * h!r},1")
open(sys.argv[1], "w").write("\n".join(rows) + "\n")
PY
"$ns" compact --boundary periodic --packing "$tmp/lat.csv" --to-density 0.934 --increments 10 --tol 1e-10 \
  --max-newton 50 --quiet --out "$tmp/p" >/dev/null 2>"$tmp/stderr"
rc=$?
if /usr/bin/python3 - "$tmp/p" "$rc" <<'PY'; then pass=$((pass + 1)); else fail=$((fail + 1)); fi
import csv, json, math, sys
d, rc = sys.argv[1], int(sys.argv[2])
rows = list(csv.DictReader(l for l in open(d + "/history.csv") if not l.startswith("#")))
s = json.load(open(d + "/summary.json"))
last = rows[-1]
E = float(last["E11"])
L = 2 * math.exp(E)
F = 3 * math.sqrt(8 * (2 - L) / 2)  # per sigma_y
V = 12 * 6 * math.sqrt(3) * math.exp(2 * E)
expect = -1.5 * 36 * F * L / V
got = [float(last["S11"]), float(last["S22"]), float(last["S12"])]
err = max(abs(got[0] - expect), abs(got[1] - expect), abs(got[2])) / abs(expect)
print(f"periodic lattice: D {float(last['D']):.4f}, S11 {got[0]:.9f} S22 {got[1]:.9f} against {expect:.9f} "
      f"(relative {err:.1e}), contacts {last['contacts']}, mode {s['mode']}, exit {rc}")
ok = rc == 0 and s["mode"] == "periodic" and err < 1e-8 and int(last["contacts"]) == 108
sys.exit(0 if ok else 1)
PY
# snapshots.pvd: the cell as a third part; the default --snapshots densities lie below the
# lattice's 0.907, written at the start (the initial state's files), so only initial and final are listed
check_pvd periodic_pvd "$tmp/p" particles,contacts,cell --tags initial,final --history history.csv:D
/usr/bin/python3 -c "
import sys; t = open(sys.argv[1]).read().replace('# periodic\n', ''); open(sys.argv[2], 'w').write(t)" "$tmp/lat.csv" "$tmp/walled.csv"
check_bad periodic_no_packing "periodic packing" compact --boundary periodic
check_bad periodic_walled_packing "no '# periodic'" compact --boundary periodic --packing "$tmp/walled.csv"
check_bad periodic_packing_layer "--boundary periodic" compact --packing "$tmp/lat.csv"
check_bad periodic_state "periodic cell" compact --boundary periodic --packing "$tmp/lat.csv" --state "$tmp/none.json"
check_bad yield_periodic_die "--compact-bc periodic" yield --packing "$tmp/lat.csv" --jobs 1
check_bad yield_periodic_probe_die "periodic" yield --packing "$tmp/lat.csv" --compact-bc periodic --probe-bc die --jobs 1
# the state file carries the cell: compact --save-state, then yield --from-state probes the same lattice
"$ns" compact --boundary periodic --packing "$tmp/lat.csv" --to-density 0.934 --increments 10 --tol 1e-10 \
  --max-newton 50 --save-state --quiet --out "$tmp/s" >/dev/null 2>&1
"$ns" yield --compact-bc periodic --from-state "$tmp/s/state.txt" --to-density 0.934 --directions 4 --jobs 1 \
  --quiet --out "$tmp/y" >/dev/null 2>"$tmp/stderr"
rc=$?
if /usr/bin/python3 - "$tmp/s" "$tmp/y" "$rc" <<'PY'; then pass=$((pass + 1)); else fail=$((fail + 1)); fi
import csv, json, os, sys
s, y, rc = sys.argv[1], sys.argv[2], int(sys.argv[3])
last = list(csv.DictReader(l for l in open(s + "/history.csv") if not l.startswith("#")))[-1]
j = json.load(open(y + "/summary.json"))
print(f"periodic state: state.txt {os.path.exists(s + '/state.txt')}, jammed.json {os.path.exists(s + '/jammed.json')}; "
      f"yield --from-state exit {rc}, loading S22 {j['setup']['loading']['S22']:.9f} against compact's {float(last['S22']):.9f}")
ok = rc == 0 and os.path.exists(s + "/state.txt") and not os.path.exists(s + "/jammed.json")
ok = ok and abs(j["setup"]["loading"]["S22"] - float(last["S22"])) < 1e-8
sys.exit(0 if ok else 1)
PY
# --affine --boundary periodic: every centre follows the cell; the lattice is exactly affine, so the
# same stress as the periodic run above (its free disks in equilibrium) at the same density
"$ns" compact --boundary periodic --affine --packing "$tmp/lat.csv" --to-density 0.934 --increments 10 --quiet \
  --out "$tmp/pa" >/dev/null 2>"$tmp/stderr"
rc=$?
if /usr/bin/python3 - "$tmp/s" "$tmp/pa" "$rc" <<'PY'; then pass=$((pass + 1)); else fail=$((fail + 1)); fi
import csv, json, sys
s, a, rc = sys.argv[1], sys.argv[2], int(sys.argv[3])
ls = list(csv.DictReader(l for l in open(s + "/history.csv") if not l.startswith("#")))[-1]
la = list(csv.DictReader(l for l in open(a + "/history.csv") if not l.startswith("#")))[-1]
j = json.load(open(a + "/summary.json"))
err = max(abs(float(la[k]) - float(ls[k])) for k in ("S11", "S22", "S12")) / abs(float(ls["S22"]))
print(f"periodic affine: mode {j['mode']}, exit {rc}, S22 {float(la['S22']):.9f} against {float(ls['S22']):.9f} ({err:.1e})")
sys.exit(0 if rc == 0 and j["mode"] == "affine (periodic cell)" and err < 1e-8 else 1)
PY
check_bad periodic_affine_walls "exclude" compact --boundary walls --packing "$tmp/lat.csv" --affine
# the default iteration in a periodic cell is the pseudo-transient one (docs/quasistatic.md "Which
# iteration by default"): on a disordered 100-disk packing every increment ends in equilibrium of
# the undragged equations (RMS <= --tol, max <= 10 --tol), and the answer does not move when the
# drag is scaled by 0.1 and 10 (S11, S22 within 0.2 %, issue 28 (a); Z within 0.05), while the
# legacy drag's answer, which keeps its drag, lies more than 0.5 % away (measured 1.1 %)
"$ns" pack --periodic --n 100 --seed 2 --quiet --out "$tmp/pk" >/dev/null 2>&1
for run in "d:" "s01:--regularisation-scale 0.1" "s10:--regularisation-scale 10" "leg:--iteration legacy-drag"; do
  # shellcheck disable=SC2086
  "$ns" compact --boundary periodic --packing "$tmp/pk/packing.csv" --to-density 0.86 --increments 10 --tol 1e-4 \
    --snapshots "" --allow-unconverged --quiet ${run#*:} --out "$tmp/i_${run%%:*}" >/dev/null 2>&1
done
if /usr/bin/python3 - "$tmp" <<'PY'; then pass=$((pass + 1)); else fail=$((fail + 1)); fi
import csv, json, sys
t = sys.argv[1]
def load(k):
    rows = list(csv.DictReader(l for l in open(f"{t}/i_{k}/history.csv") if not l.startswith("#")))
    return rows, json.load(open(f"{t}/i_{k}/summary.json"))
(d, sd), (a, _), (b, _), (g, _) = load("d"), load("s01"), load("s10"), load("leg")
eq = all(float(r["residual_rms"]) <= 1e-4 and float(r["residual"]) <= 1e-3 and r["converged"] == "1" for r in d[1:])
rel = lambda x, y, k: abs(float(x[-1][k]) / float(y[-1][k]) - 1)
spread = max(rel(x, d, k) for x in (a, b) for k in ("S11", "S22"))
dz = max(abs(float(x[-1]["Z"]) - float(d[-1]["Z"])) for x in (a, b))
leg = max(rel(g, d, k) for k in ("S11", "S22"))
print(f"periodic default iteration {sd['solver']['iteration']}: every increment in undragged equilibrium {eq}, "
      f"S11/S22 spread over drag x0.1/x10 {100 * spread:.3f} %, Z {dz:.3f}; legacy drag {100 * leg:.2f} % away")
ok = sd["solver"]["iteration"] == "pseudo-transient" and eq and spread <= 2e-3 and dz <= 0.05 and leg > 5e-3
sys.exit(0 if ok else 1)
PY
finish
