#!/usr/bin/env bash
# netsolve pack --dim 3 (docs/packing.md "3D ballistic deposition"): writes a 3D packing.csv
# (# dim 3, six-number box, id,x,y,z,r), particles.vtp with the real z and summary.json with dim,
# density and coordination, deterministically; the 2D-only subcommands (netsolve compact, yield,
# demsolve compact, yield, prepare) refuse a 3D packing file with one line; bad --dim/--lateral
# combinations are refused with one line.
# usage: test_pack3d.sh PATH/TO/netsolve PATH/TO/demsolve
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
"$ns" pack --dim 3 --width 8 --out "$tmp/p3" >"$tmp/stdout" 2>"$tmp/stderr"
ok pack3d_exit [ $? -eq 0 ]
p3="$tmp/p3/packing.csv"
ok pack3d_box grep -qx '# box 0 0 0 8 8 8' "$p3"
ok pack3d_dim grep -qx '# dim 3' "$p3"
ok pack3d_header grep -qx 'id,x,y,z,r' "$p3"
ok pack3d_vtp [ -s "$tmp/p3/particles.vtp" ]
ok pack3d_vtp_z grep -q 'Name="z"' "$tmp/p3/particles.vtp"
ok pack3d_summary_dim grep -q '"dim": 3' "$tmp/p3/summary.json"
ok pack3d_summary_density grep -q '"density": 0\.[3-6]' "$tmp/p3/summary.json"
ok pack3d_summary_coordination grep -q '"coordination": [3-6]\.' "$tmp/p3/summary.json"
n=$(grep -c '^[0-9]' "$p3")
ok pack3d_particles grep -q "\"particles\": $n," "$tmp/p3/summary.json"
ok pack3d_fields [ "$(awk -F, '/^[0-9]/ && NF != 5' "$p3" | wc -l)" -eq 0 ]
# every sphere inside the box [0, 8]^3 (walls: entirely)
ok pack3d_inside [ "$(awk -F, '/^[0-9]/ && ($2 - $5 < -1e-9 || $2 + $5 > 8 + 1e-9 || $3 - $5 < -1e-9 || $3 + $5 > 8 + 1e-9 || $4 - $5 < -1e-9 || $4 + $5 > 8 + 1e-9)' "$p3" | wc -l)" -eq 0 ]
# deterministic for a seed
"$ns" pack --dim 3 --width 8 --out "$tmp/p3b" >/dev/null 2>&1
ok pack3d_deterministic cmp -s "$p3" "$tmp/p3b/packing.csv"
# periodic
"$ns" pack --dim 3 --width 8 --lateral periodic --seed 3 --out "$tmp/pp" >/dev/null 2>&1
ok periodic_exit [ $? -eq 0 ]
ok periodic_comment grep -qx '# lateral periodic (x, y)' "$tmp/pp/packing.csv"
ok periodic_summary grep -q '"lateral": "periodic"' "$tmp/pp/summary.json"
# the 2D default output has no dim key (unchanged format)
"$ns" pack --width 10 --out "$tmp/p2" >/dev/null 2>&1
ok pack2d_no_dim bash -c "! grep -q '\"dim\"' '$tmp/p2/summary.json' && grep -qx 'id,x,y,r' '$tmp/p2/packing.csv'"
# r_max / r_min above the packing limit of 100 is refused before depositing (a 3D deposition with
# --r-min 1e-300 never ended: campaign of issue 27)
check_bad pack3d_ratio "r_max / r_min" pack --dim 3 --width 5 --r-min 1e-300
check_bad pack2d_ratio "r_max / r_min" pack --width 5 --r-min 1e-3
# 2D-only subcommands refuse the 3D file (it is read as 3D: the reader accepted it)
check_bad compact_3d "packing.csv is a 3D packing; netsolve compact is 2D only" compact --packing "$p3"
check_bad yield_3d "is a 3D packing; netsolve yield is 2D only" yield --packing "$p3"
tool="$ds"
check_bad dem_compact_3d "is a 3D packing; demsolve compact is 2D only" compact --packing "$p3"
check_bad dem_yield_3d "is a 3D packing; demsolve yield is 2D only" yield --packing "$p3"
check_bad dem_prepare_3d "is a 3D packing (# dim 3)" prepare --packing "$p3"
tool="$ns"
# bad combinations
check_bad lateral_in_2d "--lateral is for --dim 3 only" pack --lateral periodic
check_bad dim_4 "--dim" pack --dim 4
check_bad lateral_bad "--lateral 'sideways'" pack --dim 3 --lateral sideways
check_bad lid_centre_3d "only --lid inside" pack --dim 3 --lid centre
check_bad periodic_narrow "periodic width 3" pack --dim 3 --lateral periodic --width 3
finish
