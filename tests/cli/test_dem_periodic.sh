#!/usr/bin/env bash
# Periodic cells (issue 29): netsolve pack --periodic writes a periodic packing ('# periodic',
# its seed, summary.json with density, coordination, psi6 and overlaps), deterministically;
# demsolve compact --boundary periodic runs it (history.csv with the kinetic stress apart, the
# cell drawn in cell_*.vtp); the options' bad values and the commands that cannot use a periodic
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
ok compact_density grep -q '"D": 0\.85' "$tmp/c/summary.json"
"$ds" compact --dim 3 --boundary periodic --packing "$tmp/p3/packing.csv" --to-density 0.7 --inertial-number 1e-2 \
  --increments 5 --quiet --out "$tmp/c3" >/dev/null 2>&1
ok compact3d_exit [ $? -eq 0 ]
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
bad2 compact_save "--save-state" compact --boundary periodic --save-state --packing "$p"
bad2 compact_boundary "is not 'layer', 'walls' or 'periodic'" compact --boundary torus --packing "$p"
bad2 yield_periodic_needs_periodic_bc "run it with --compact-bc periodic" yield --packing "$p"
bad2 prepare_periodic "periodic packing" prepare --packing "$p"
tool="$ns"
bad2 sinter_periodic "is periodic" sinter --packing "$tmp/p3/packing.csv"
finish
