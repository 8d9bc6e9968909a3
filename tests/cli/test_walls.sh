#!/usr/bin/env bash
# netsolve compact --boundary walls (issue 12): four rigid frictionless walls at the box faces move
# with the box, nothing is prescribed. A W = 20 R sticking hydrostatic compaction to D = 0.85
# ends in equilibrium: the wall (Eq 13) stress within 2 % of the contact stress (wall contacts
# included), Z > 3, summary mode "walls"; the option's limits exit 2 with one line, nothing written.
# The closed form (a square lattice between walls) is the unit test
# NetworkSolver.SquareLatticeBetweenWallsMatchesClosedForm.
# usage: test_walls.sh PATH/TO/netsolve
set -u
ns="$(readlink -f "$1")"
tool="$ns"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"

"$ns" compact --boundary walls --width 20 --max-newton 40 --quiet --allow-unconverged --out "$tmp/w" >/dev/null 2>"$tmp/stderr"
if /usr/bin/python3 - "$tmp/w" <<'PY'; then pass=$((pass + 1)); else fail=$((fail + 1)); fi
import csv, json, math, sys
d = sys.argv[1]
rows = list(csv.DictReader(l for l in open(d + "/history.csv") if not l.startswith("#")))
s = json.load(open(d + "/summary.json"))
last = rows[-1]
a = [float(last[k]) for k in ("S11", "S22", "S11_contacts", "S22_contacts")]
gap = math.hypot(a[0] - a[2], a[1] - a[3]) / math.hypot(a[2], a[3])
print(f"walls W = 20: D {float(last['D']):.4f}, S11 {a[0]:.4f} (contacts {a[2]:.4f}), S22 {a[1]:.4f} "
      f"(contacts {a[3]:.4f}), gap {100 * gap:.2f} %, Z {last['Z']}, mode {s['mode']}, status {s['status']}")
ok = s["mode"] == "walls" and abs(float(last["D"]) - 0.85) < 1e-6 and gap < 0.02 and float(last["Z"]) > 3.0
ok = ok and a[1] < 0 and a[0] < 0 and last["converged"] == "1"
sys.exit(0 if ok else 1)
PY
check_bad walls_shear "E12" compact --width 12 --boundary walls --path 1,0,0.5
check_bad walls_affine "exclude" compact --width 12 --boundary walls --affine
check_bad walls_state_packing "exclude" compact --width 12 --boundary walls --state "$tmp/none.json" --packing x.csv
check_bad walls_word "boundary" compact --width 12 --boundary wall
finish
