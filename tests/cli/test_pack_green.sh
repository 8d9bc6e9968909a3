#!/usr/bin/env bash
# netsolve pack --dim 3 --route green-body (docs/packing.md "The green-body route"): a small run
# (60 spheres, soft spring, a few seconds) writes packing.csv in the 3D format (SI metres, readable
# back), laminar.csv (Eq 48 along x, y, z), particles.vtp, summary.json (status, densities,
# overlaps, phases) and command.txt, deterministically; --quiet silences stderr; an unreachable
# target exits 3 with the status in summary.json; bad input is one line, exit 2, nothing written.
# usage: test_pack_green.sh PATH/TO/netsolve
set -u
ns="$1"
tool="$ns"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
ok() {  # name condition-command...
  local name="$1"
  shift
  if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL $name"; fi
}
small=(pack --dim 3 --route green-body --n 60 --target-density 0.45 --stiffness-number 1e3 --wall-speed 0.05 --max-overlap 0.01)
"$ns" "${small[@]}" --quiet --out "$tmp/g" >"$tmp/stdout" 2>"$tmp/stderr"
ok green_exit [ $? -eq 0 ]
ok green_quiet [ ! -s "$tmp/stderr" ]
g="$tmp/g"
for f in packing.csv laminar.csv particles.vtp summary.json command.txt; do ok "green_file_$f" [ -s "$g/$f" ]; done
ok green_no_marker [ ! -e "$g/.incomplete" ]
ok green_dim grep -qx '# dim 3' "$g/packing.csv"
ok green_header grep -qx 'id,x,y,z,r' "$g/packing.csv"
ok green_units grep -q '# green-body route (Ivannikov et al. section 3.2): lengths in metres' "$g/packing.csv"
ok green_particles [ "$(grep -c '^[0-9]' "$g/packing.csv")" -eq 60 ]
ok green_laminar_header grep -qx 'axis,lamina,lo,hi,density' "$g/laminar.csv"
ok green_laminar_axes bash -c "grep -q '^x,0,' '$g/laminar.csv' && grep -q '^y,0,' '$g/laminar.csv' && grep -q '^z,0,' '$g/laminar.csv'"
ok green_status grep -q '"status": "ok"' "$g/summary.json"
ok green_route grep -q '"route": "green-body"' "$g/summary.json"
ok green_density grep -q '"box": 0.4[45]' "$g/summary.json"
ok green_phases bash -c "grep -q '\"name\": \"settle\"' '$g/summary.json' && grep -q '\"name\": \"compress\"' '$g/summary.json'"
ok green_no_nan bash -c "! grep -qi 'nan\|inf' '$g/summary.json' '$g/laminar.csv' '$g/packing.csv'"
# the packing is a valid 3D packing file: the 2D-only compact reads it and refuses it as 3D
check_bad green_read_back "is a 3D packing; netsolve compact is 2D only" compact --packing "$g/packing.csv"
# deterministic for a seed
"$ns" "${small[@]}" --quiet --out "$tmp/g2" >/dev/null 2>&1
ok green_deterministic cmp -s "$g/packing.csv" "$tmp/g2/packing.csv"
ok green_laminar_deterministic cmp -s "$g/laminar.csv" "$tmp/g2/laminar.csv"
# progress on stderr without --quiet is allowed; an unreachable target exits 3 and says so
"$ns" pack --dim 3 --route green-body --n 60 --target-density 0.62 --stiffness-number 1e3 --wall-speed 0.05 \
  --max-overlap 0.005 --quiet --out "$tmp/u" >/dev/null 2>"$tmp/stderr_u"
ok unreachable_exit [ $? -eq 3 ]
ok unreachable_status grep -q '"status": "unreachable"' "$tmp/u/summary.json"
ok unreachable_message grep -q 'netsolve: error: unreachable: ' "$tmp/stderr_u"
ok unreachable_packing_written [ -s "$tmp/u/packing.csv" ]
# refusals: one line, exit 2, nothing written
check_bad green_needs_3d "--route green-body is 3D" pack --route green-body
check_bad green_width "--width is an option of the ballistic deposition" pack --dim 3 --route green-body --width 20
check_bad green_lateral "--lateral is an option of the ballistic" pack --dim 3 --route green-body --lateral periodic
check_bad ballistic_n "--n is an option of --route green-body" pack --dim 3 --n 100
check_bad green_long_n "pass --allow-long" pack --dim 3 --route green-body --n 10000000
check_bad green_long_spc "pass --allow-long" pack --dim 3 --route green-body --steps-per-contact 1e6
check_bad green_long_speed "pass --allow-long" pack --dim 3 --route green-body --wall-speed 1e-9
check_bad route_2d "--route is for --dim 3 only" pack --route ballistic
check_bad route_bad "--route" pack --dim 3 --route sideways
check_bad green_diameter "--diameter must be a positive" pack --dim 3 --route green-body --diameter -1
check_bad green_diameter_units "SI metres" pack --dim 3 --route green-body --diameter 50
check_bad green_target "target density must be in (0, 0.74]" pack --dim 3 --route green-body --target-density 0.9
check_bad green_dispersion "dispersion must be in" pack --dim 3 --route green-body --dispersion 1
check_bad green_restitution "restitution must be in (0, 1]" pack --dim 3 --route green-body --restitution 0
check_bad green_lamina "--lamina must be a positive" pack --dim 3 --route green-body --lamina 0
check_bad green_n_zero "number of spheres" pack --dim 3 --route green-body --n 0
# issue 27 item 8: refused at the door (exit 2, one line naming the option, no folder) instead of
# exit 1 after the folder exists with an internal quantity (gamma_0, random_fill_3d, laminar_density)
door() {  # NAME WORD ARGS...
  local name="$1" word="$2"
  shift 2
  "$tool" pack --dim 3 --route green-body --quiet "$@" --out "$tmp/$name" >/dev/null 2>"$tmp/stderr"
  local rc=$?
  if [ "$rc" -eq 2 ] && [ "$(grep -c . "$tmp/stderr")" -eq 1 ] && grep -qF -- "$word" "$tmp/stderr" && [ ! -e "$tmp/$name" ] &&
     ! grep -q "gamma_0\|random_fill_3d\|laminar_density" "$tmp/stderr"; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
    echo "FAIL $name: rc=$rc $(head -c 400 "$tmp/stderr")"
  fi
}
door green_gravity_1e300 "--gravity must be in [1e-6, 1e4]" --gravity 1e300
door green_lamina_1e-12 "--lamina 1e-12 m" --lamina 1e-12
door green_dispersion_0.999 "--dispersion 0.999" --dispersion 0.999
# a cloud that can be made, whose lightest pair gets fewer than 10 steps per contact (the solver's
# rule): exit 1 after the folder existed, "time step ... 0.28 steps per contact" (campaign27)
door green_dispersion_0.999_n30 "--dispersion 0.999 with --steps-per-contact 25: the lightest pair of the route's cloud gets 0.28 steps" \
  --n 30 --target-density 0.4 --dispersion 0.999
door green_dispersion_0.6 "--dispersion 0.6 with --steps-per-contact 25: the lightest pair of the route's cloud gets 7.41 steps" --n 30 --target-density 0.4 --dispersion 0.6
door green_n_1 "--n 1 " --n 1
# a body too small for its bulk window (100 spheres, 2 diameters from every wall) reports no bulk
# density rather than one from a window under one sphere (issue 27 item 9)
"$tool" pack --dim 3 --route green-body --quiet --n 100 --max-overlap 0.049 --out "$tmp/green100" >"$tmp/stdout" 2>"$tmp/stderr"
if grep -q '"bulk": null' "$tmp/green100/summary.json" && grep -q "bulk n/a" "$tmp/stdout"; then pass=$((pass + 1)); else
  fail=$((fail + 1)); echo "FAIL green_small_bulk: $(grep '"bulk"' "$tmp/green100/summary.json") $(cat "$tmp/stdout")"; fi
finish
