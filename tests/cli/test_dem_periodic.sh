#!/usr/bin/env bash
# Periodic cells (issue 29): netsolve pack --periodic writes a periodic packing ('# periodic',
# its seed, summary.json with density, coordination, psi6 and overlaps), deterministically;
# demsolve compact --boundary periodic runs it (history.csv with the kinetic stress apart, the
# cell drawn in cell_*.vtp); both tools run it with --precompact-density and --to-strain (issue 29's
# pure-shear path: the legs in history.csv, |E| of the shear leg = the target to 1e-9); demsolve
# compact --simple-shear re-maps the cell (Lees-Edwards); the options' bad values and the commands that cannot use a periodic
# packing are refused with one line and exit 2, nothing written.
# usage: test_dem_periodic.sh PATH/TO/netsolve PATH/TO/demsolve
set -u
ns="$1"
ds="$2"
tool="$ns"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
ok() {  # name condition-command...
  local name="$1"
  shift
  if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL $name"; fi
}
bad2() {  # check_bad with exit status 2
  local name="$1"
  check_bad "$@"
  "$tool" "${@:3}" --out "$tmp/$name.again" >/dev/null 2>&1
  ok "${name}_exit2" [ $? -eq 2 ]
  rm -rf "$tmp/$name.again"
}
"$ns" pack --periodic --n 100 --jam-pressure 1e-3 --seed 4 --quiet --out "$tmp/p" >"$tmp/stdout" 2>"$tmp/stderr"
ok pack_exit [ $? -eq 0 ]
p="$tmp/p/packing.csv"
ok pack_periodic_line grep -qx '# periodic' "$p"
ok pack_seed_line grep -qx '# seed 4' "$p"
ok pack_rows [ "$(grep -c '^[0-9]' "$p")" -eq 100 ]
ok pack_summary_route grep -q '"route": "periodic"' "$tmp/p/summary.json"
ok pack_summary_density grep -q '"density": 0\.8' "$tmp/p/summary.json"
ok pack_summary_psi6 grep -q '"psi6"' "$tmp/p/summary.json"
ok pack_summary_overlap grep -q '"overlap_over_R"' "$tmp/p/summary.json"
ok pack_summary_ok grep -q '"status": "ok"' "$tmp/p/summary.json"
ok pack_cell_vtp grep -q 'NumberOfLines="4"' "$tmp/p/cell.vtp"
"$ns" pack --periodic --n 100 --jam-pressure 1e-3 --seed 4 --quiet --out "$tmp/p2" >/dev/null 2>&1
ok pack_deterministic cmp -s "$p" "$tmp/p2/packing.csv"
"$ns" pack --periodic --dim 3 --n 64 --jam-pressure 3e-4 --quiet --out "$tmp/p3" >/dev/null 2>&1
ok pack3d_exit [ $? -eq 0 ]
ok pack3d_lines grep -qx '# dim 3' "$tmp/p3/packing.csv"
ok pack3d_cell_vtp grep -q 'NumberOfLines="12"' "$tmp/p3/cell.vtp"
# the periodic DEM compaction of it
"$ds" compact --boundary periodic --packing "$p" --to-density 0.85 --inertial-number 1e-2 --increments 5 --quiet \
  --out "$tmp/c" >/dev/null 2>"$tmp/stderr"
ok compact_exit [ $? -eq 0 ]
ok compact_kinetic head -1 "$tmp/c/history.csv" | grep -q 'S11_kinetic,S22_kinetic,S12_kinetic$'
ok compact_mode grep -q '"mode": "periodic"' "$tmp/c/summary.json"
ok compact_cell grep -q 'NumberOfLines="4"' "$tmp/c/cell_final.vtp"
check_pvd compact_pvd "$tmp/c" particles,contacts,cell --history history.csv:D
ok compact_density grep -q '"D": 0\.85' "$tmp/c/summary.json"
"$ds" compact --dim 3 --boundary periodic --packing "$tmp/p3/packing.csv" --to-density 0.7 --inertial-number 1e-2 \
  --increments 5 --quiet --out "$tmp/c3" >/dev/null 2>&1
ok compact3d_exit [ $? -eq 0 ]
# issue 29's cross-check path in one run, both tools: hydrostatic precompaction to D1 = 0.86, then pure
# shear (1,-1,0) to |E| = 0.02; history.csv with the column 'leg', |E| of leg 1 from the end of leg 0
"$ns" compact --boundary periodic --packing "$p" --precompact-density 0.86 --precompact-increments 6 --path 1,-1,0 \
  --to-strain 0.02 --increments 5 --iteration pseudo-transient --friction inf --quiet --out "$tmp/ns_shear" >/dev/null 2>&1
ok ns_shear_exit [ $? -eq 0 ]
"$ds" compact --boundary periodic --packing "$p" --precompact-density 0.86 --precompact-increments 6 --path 1,-1,0 \
  --to-strain 0.02 --increments 5 --inertial-number 1e-2 --friction inf --quiet --out "$tmp/ds_shear" >/dev/null 2>&1
ok ds_shear_exit [ $? -eq 0 ]
for run in ns_shear ds_shear; do
  ok "${run}_legs" /usr/bin/python3 - "$tmp/$run" <<'PY'
import csv, json, math, sys
d = sys.argv[1]
lines = [l for l in open(d + "/history.csv") if not l.startswith("#")]
ok = lines[0].startswith("increment,leg,E11,E22,E12,D,S11,S22,S12,")
rows = list(csv.DictReader(lines))
legs = [int(r["leg"]) for r in rows]
ok = ok and legs == [0] * 7 + [1] * 5 and [int(r["increment"]) for r in rows] == list(range(12))
end0, end1 = rows[6], rows[-1]
dE = [float(end1[k]) - float(end0[k]) for k in ("E11", "E22", "E12")]
strain = math.sqrt(dE[0] ** 2 + dE[1] ** 2 + 2 * dE[2] ** 2)
s = json.load(open(d + "/summary.json"))
j = s["legs"]
ok = ok and abs(strain - 0.02) < 1e-9 and abs(float(end0["D"]) - 0.86) < 1e-8 and abs(float(end1["D"]) - 0.86) < 1e-8
ok = ok and abs(dE[0] - 0.02 / math.sqrt(2)) < 1e-9 and dE[2] == 0
ok = ok and len(j) == 2 and j[0]["to_density"] == 0.86 and j[1]["to_strain"] == 0.02 and j[1]["path"] == "1,-1,0"
ok = ok and abs(j[1]["end"]["strain"] - 0.02) < 1e-12 and j[0]["end"]["increment"] == 6 and s["status"] == "ok"
print(f"{d.split('/')[-1]}: |E| of leg 1 = {strain!r} (summary {j[1]['end']['strain']!r}), D {end0['D']} -> {end1['D']}, "
      f"S11 - S22 = {float(end1['S11']) - float(end1['S22']):.4f}, S12 = {float(end1['S12']):.4f}")
sys.exit(0 if ok else 1)
PY
done
ok ds_shear_to_strain grep -q '"to_strain": 0.02' "$tmp/ds_shear/summary.json"
ok default_no_leg_column /usr/bin/python3 -c "import sys; sys.exit(',leg,' in open(sys.argv[1]).readline())" "$tmp/c/history.csv"
# a to-strain run without a precompaction: no 'leg' column, |E| from the start
"$ds" compact --boundary periodic --packing "$p" --path 1,-1,0 --to-strain 0.01 --increments 4 --inertial-number 1e-2 \
  --quiet --out "$tmp/ds_strain" >/dev/null 2>&1
ok ds_strain_exit [ $? -eq 0 ]
ok ds_strain_end /usr/bin/python3 - "$tmp/ds_strain/history.csv" <<'PY'
import csv, math, sys
lines = open(sys.argv[1]).readlines()
last = list(csv.DictReader(lines))[-1]
e = math.sqrt(float(last["E11"]) ** 2 + float(last["E22"]) ** 2 + 2 * float(last["E12"]) ** 2)
sys.exit(0 if lines[0].startswith("increment,E11,") and abs(e - 0.01) < 1e-9 else 1)
PY
# simple shear (issue 29, Lees-Edwards): the shear rate as L12 = 2 E12, to |E| = 0.5 (gamma = 0.71):
# the cell's tilt passes half its width once and the cell is re-mapped; E12 of the rows is the
# symmetric part, to the target
"$ds" compact --boundary periodic --packing "$p" --path 0,0,1 --simple-shear --to-strain 0.5 --increments 5 \
  --inertial-number 1e-2 --quiet --out "$tmp/ds_simple" >/dev/null 2>&1
ok ds_simple_exit [ $? -eq 0 ]
ok ds_simple_remapped /usr/bin/python3 - "$tmp/ds_simple" <<'PY'
import csv, json, sys
d = sys.argv[1]
s = json.load(open(d + "/summary.json"))
last = list(csv.DictReader(open(d + "/history.csv")))[-1]
h = s["final"]["cell"]  # vector a at [D a, D a + D)
q = (h[2] * h[0] + h[3] * h[1]) / (h[0] ** 2 + h[1] ** 2)
ok = s["simple_shear"] is True and s["final"]["cell_remaps"] == 1 and abs(q) < 0.6 and h[1] == 0.0
ok = ok and abs(float(last["E12"]) - 0.5 / 2 ** 0.5) < 1e-9 and float(last["E11"]) == 0.0 and s["status"] == "ok"
ok = ok and "dev_ut_centres" not in last  # the Figs 7-8 columns: not under simple shear (the cell's spin)
print(f"simple shear: cell {h}, projection {q:.3f}, remaps {s['final']['cell_remaps']}, E12 {last['E12']}")
sys.exit(0 if ok else 1)
PY
# refusals of the legs' options, both tools: one line, exit 2, nothing written
for t in "$ns" "$ds"; do
  tool="$t"
  name=$(basename "$t")
  bad2 "${name}_pre_below" "not above the start density" compact --boundary periodic --packing "$p" --precompact-density 0.8 --to-strain 0.02
  bad2 "${name}_pre_above1" "--precompact-density" compact --boundary periodic --packing "$p" --precompact-density 1.2 --to-strain 0.02
  bad2 "${name}_pre_target" "not above the precompaction density" compact --boundary periodic --packing "$p" --precompact-density 0.86 --to-density 0.855
  bad2 "${name}_pre_shear_density" "does not compact" compact --boundary periodic --packing "$p" --precompact-density 0.86 --path 1,-1,0 --to-density 0.87
  bad2 "${name}_pre_no_target" "--to-density or --to-strain" compact --boundary periodic --packing "$p" --precompact-density 0.86
  bad2 "${name}_pre_n_alone" "is an option of --precompact-density" compact --boundary periodic --packing "$p" --precompact-increments 5
  bad2 "${name}_pre_n_zero" "increments" compact --boundary periodic --packing "$p" --precompact-density 0.86 --precompact-increments 0 --to-strain 0.02
  bad2 "${name}_strain_zero" "--to-strain" compact --boundary periodic --packing "$p" --to-strain 0
  bad2 "${name}_strain_big" "--to-strain" compact --boundary periodic --packing "$p" --to-strain 2
  bad2 "${name}_strain_density" "excludes" compact --boundary periodic --packing "$p" --to-strain 0.02 --to-density 0.86
  bad2 "${name}_strain_dense" "impossible target" compact --boundary periodic --packing "$p" --precompact-density 0.95 --to-strain 0.1
done
tool="$ns"
# refusals: pack
bad2 pack_width "--width is an option of the deposition" pack --periodic --width 10
bad2 pack_green "exclude each other" pack --periodic --dim 3 --route green-body
bad2 pack_pressure "--jam-pressure" pack --periodic --jam-pressure 1
bad2 pack_n "--n" pack --periodic --n 5
bad2 pack_friction "--pack-friction" pack --periodic --pack-friction -1
bad2 pack_pressure_alone "--jam-pressure is an option of --periodic" pack --jam-pressure 1e-4
bad2 pack_friction_alone "--pack-friction is an option of --periodic" pack --pack-friction 0.1
# refusals: a periodic packing where a box is needed, a walled one where a cell is needed
"$ns" pack --width 12 --out "$tmp/w" >/dev/null 2>&1
tool="$ds"
bad2 compact_layer "run it with --boundary periodic" compact --packing "$p"
bad2 compact_walls "run it with --boundary periodic" compact --boundary walls --packing "$p"
bad2 compact_walled "needs a periodic packing" compact --boundary periodic --packing "$tmp/w/packing.csv"
bad2 compact_no_packing "needs --packing" compact --boundary periodic
bad2 compact_affine "exclude each other" compact --boundary periodic --affine --packing "$p"
bad2 compact_simple_walls "--simple-shear needs --boundary periodic" compact --boundary walls --path 0,0,1 --simple-shear
bad2 compact_simple_hydro "--simple-shear: simple shear needs a path with a shear rate" compact --boundary periodic --packing "$p" --simple-shear --to-density 0.86
bad2 compact_save "--save-state" compact --boundary periodic --save-state --packing "$p"
bad2 compact_boundary "is not 'layer', 'walls' or 'periodic'" compact --boundary torus --packing "$p"
bad2 yield_periodic_needs_periodic_bc "run it with --compact-bc periodic" yield --packing "$p"
bad2 prepare_periodic "periodic packing" prepare --packing "$p"
tool="$ns"
bad2 sinter_periodic "is periodic" sinter --packing "$tmp/p3/packing.csv"
finish
