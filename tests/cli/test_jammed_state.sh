#!/usr/bin/env bash
# The jammed state both solvers share (issue 28 item 6; docs/quasistatic.md "Jammed state"):
# netsolve compact --boundary walls --save-state writes jammed.json and state.txt (the network state
# file, with the wall contacts since 2026-12-06); demsolve compact --state starts from it and saves its own;
# netsolve compact --state starts from the DEM's at its density with its Z (the DEM's history row is a
# window mean, its stresses are not compared here). Bad states
# and mismatched options exit 2 with one line, nothing written. The per-contact forces and the
# byte-identical round trips are the unit tests JammedState.* (tests/system/test_jammed_state.cpp).
# usage: test_jammed_state.sh PATH/TO/netsolve PATH/TO/demsolve
set -u
ns="$(readlink -f "$1")"
dm="$(readlink -f "$2")"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
ok() { if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL: $*"; fi; }

# (a loose deposition between walls is a mechanism: this run only makes a state, so it keeps the
# fast legacy drag; the default iteration there is the pseudo-transient one)
"$ns" compact --width 16 --boundary walls --to-density 0.80 --increments 20 --save-state --quiet --allow-unconverged \
  --iteration legacy-drag \
  --out "$tmp/n1" >/dev/null 2>&1
ok test -s "$tmp/n1/jammed.json"
ok test -s "$tmp/n1/state.txt"
"$dm" compact --state "$tmp/n1/jammed.json" --boundary walls --to-density 0.82 --inertial-number 1e-3 --increments 10 \
  --save-state --quiet --out "$tmp/d1" >/dev/null 2>&1
ok test $? -eq 0
ok test -s "$tmp/d1/jammed.json"
"$ns" compact --state "$tmp/d1/jammed.json" --boundary walls --to-density 0.84 --increments 20 --save-state --quiet \
  --out "$tmp/n2" >/dev/null 2>&1
ok test $? -eq 0
# the network solver's first row is the DEM's state at rest: the contact stress of both from the same contacts
if /usr/bin/python3 - "$tmp" <<'PY'; then pass=$((pass + 1)); else fail=$((fail + 1)); fi
import csv, json, sys
t = sys.argv[1]
rows = lambda d: list(csv.DictReader(l for l in open(f"{t}/{d}/history.csv") if not l.startswith("#")))
dem, net = rows("d1")[-1], rows("n2")[0]
s = json.load(open(f"{t}/n2/summary.json"))
print(f"DEM end: D {dem['D']} Z {dem['Z']} S22_contacts {dem['S22_contacts']}; netsolve start: D {net['D']} Z {net['Z']} "
      f"S22_contacts {net['S22_contacts']}; jammed_state {s['jammed_state']}")
ok = abs(float(dem["D"]) - float(net["D"])) < 1e-6 and s["jammed_state"]["from"].endswith("d1/jammed.json")
ok = ok and float(net["Z"]) > 3.0 and s["jammed_state"]["saved"] == "jammed.json"
sys.exit(0 if ok else 1)
PY
cp "$tmp/d1/jammed.json" "$tmp/good.json"
/usr/bin/python3 - "$tmp" <<'PY'
import json, sys
t = sys.argv[1]
j = json.load(open(f"{t}/good.json"))
def bad(name, edit):
    k = json.loads(json.dumps(j)); edit(k); json.dump(k, open(f"{t}/{name}.json", "w"))
bad("negative_r", lambda k: k["particles"]["r"].__setitem__(0, -1.0))
bad("short_y", lambda k: k["particles"]["y"].pop())
bad("nan", lambda k: k["particles"]["x"].__setitem__(0, "nan"))
i = j["pairs"]["i"][0]
far = max(range(len(j["particles"]["x"])), key=lambda p: abs(j["particles"]["y"][p] - j["particles"]["y"][i]))
def apart(k):  # the first pair's history (a tangential spring) moved to a pair that does not touch
    k["pairs"]["j"][0] = far if far > i else k["pairs"]["j"][0]
    if far < i: k["pairs"]["i"][0], k["pairs"]["j"][0] = far, i
    k["pairs"]["history"][0]["f_t"] = 0.1
bad("apart", apart)
PY
tool="$ns"
check_bad ns_missing "jammed state file" compact --boundary walls --state "$tmp/none.json"
check_bad ns_negative_r "/particles/r/0" compact --boundary walls --state "$tmp/negative_r.json"
check_bad ns_short_y "/particles/y" compact --boundary walls --state "$tmp/short_y.json"
check_bad ns_nan "/particles/x/0" compact --boundary walls --state "$tmp/nan.json"
check_bad ns_walls "contact walls" compact --state "$tmp/good.json"
check_bad ns_law "friction" compact --boundary walls --friction 0.1 --state "$tmp/good.json"
check_bad ns_packing "exclude" compact --boundary walls --state "$tmp/good.json" --packing "$tmp/n1/packing.csv"
tool="$dm"
check_bad dm_negative_r "/particles/r/0" compact --boundary walls --state "$tmp/negative_r.json"
check_bad dm_dim "--dim 2" compact --dim 3 --boundary walls --state "$tmp/good.json"
check_bad dm_law "k_t" compact --boundary walls --k-t 100 --state "$tmp/good.json"
check_bad dm_walls "contact walls" compact --state "$tmp/good.json"
finish
