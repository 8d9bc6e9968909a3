#!/usr/bin/env bash
# Command-line checks of `netsolve sinter` (docs/staggered.md "netsolve sinter"): a 3x3x3 cubic
# lattice of spheres of radius 25e-6 m (spacing 0.999 of a diameter, so that every neighbour pair
# is an initial contact; the lower corner of the spheres at the origin, on the boundary planes)
# sintered for 100 s writes the documented files and headers, finite rows with t increasing,
# equal shrinkage along x, y and z, the same history.csv twice, and a run to t1 = 50 s continued
# from its state.txt to 100 s ends on the last row of an uninterrupted run whose steps end at t1
# (--checkpoints 50), bit for bit. Bad input gives
# one line on stderr, exit 2 and no output folder.
# usage: test_netsolve_sinter.sh PATH/TO/netsolve
set -u
tool="$1"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
ok() {  # name condition-command...
  local name="$1"
  shift
  if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL $name"; fi
}

# the lattice: centres at 25e-6 + k * 49.95e-6, k = 0, 1, 2
lat="$tmp/lattice.csv"
awk 'BEGIN {
  s = 49.95e-6; r = 25e-6; L = 2 * r + 2 * s
  printf "# box 0 0 0 %.17g %.17g %.17g\n# dim 3\n# seed 7\nid,x,y,z,r\n", L, L, L
  n = 0
  for (i = 0; i < 3; i++) for (j = 0; j < 3; j++) for (k = 0; k < 3; k++)
    printf "%d,%.17g,%.17g,%.17g,%.17g\n", n++, r + i * s, r + j * s, r + k * s, r
}' >"$lat"

# ---- refusals: one line naming the problem, exit 2, no folder
check_bad_rc() {  # like check_bad, and the exit status must be 2
  local name="$1"
  check_bad "$@"
  "$tool" "${@:3}" --out "$tmp/$name" >/dev/null 2>&1
  local rc=$?
  if [ "$rc" -ne 2 ]; then fail=$((fail + 1)); echo "FAIL $name: exit $rc, not 2"; fi
  rm -rf "${tmp:?}/$name"
}
check_bad_rc sn_missing_packing "no_such.csv" sinter --packing "$tmp/no_such.csv" --time 100 --quiet
check_bad_rc sn_negative_time "time" sinter --packing "$lat" --time -5 --quiet
check_bad_rc sn_strategy "strategy" sinter --packing "$lat" --time 100 --strategy 3 --quiet
check_bad_rc sn_time_beyond_max_steps "--max-steps: the run of 1e+12 s needs at least 1e+11 steps" sinter --packing "$lat" --time 1e12 --quiet
# issue 27: each breakpoint of a profile ends a step: 2000 rows within 100 s are at least 2000 steps
# (the estimate --time / --dt-max alone is 10)
awk 'BEGIN { print "time,T"; for (k = 0; k < 2000; k++) printf "%.17g,1293\n", 0.05 * k }' >"$tmp/dense_profile.csv"
check_bad_rc sn_profile_breakpoints "--max-steps: the run of 100 s needs at least 2e+03 steps .*each of the 1999 breakpoints" \
  sinter --packing "$lat" --time 100 --profile "$tmp/dense_profile.csv" --max-steps 500 --quiet
# issue 27: a profile of more than 1e4 breakpoints within the run is refused at the door unless
# --allow-long (1e5 rows within 100 s: 1e5 forced steps, 12-20 s on this lattice under the default
# --max-steps before the limit), in well under a second; the limit counts the run's breakpoints only
awk 'BEGIN { print "time,T"; for (k = 0; k < 100000; k++) printf "%.17g,1293\n", 0.001 * k }' >"$tmp/profile_1e5.csv"
start=$SECONDS
check_bad_rc sn_profile_1e5_rows "--profile '.*profile_1e5.csv': 99999 breakpoints of the temperature profile within the run (0 to 100 s), more than 10000; each ends a step: pass --allow-long" \
  sinter --packing "$lat" --time 100 --profile "$tmp/profile_1e5.csv" --quiet
ok sn_profile_1e5_rows_seconds [ $((SECONDS - start)) -le 4 ]
awk 'BEGIN { print "time,T"; for (k = 0; k <= 10001; k++) printf "%.17g,1293\n", 0.01 * k }' >"$tmp/profile_1e4.csv"
check_bad_rc sn_profile_10001 "10001 breakpoints of the temperature profile within the run (0 to 100.02 s), more than 10000" sinter --packing "$lat" --time 100.02 --profile "$tmp/profile_1e4.csv" --quiet
"$tool" sinter --packing "$lat" --time 100 --profile "$tmp/profile_1e4.csv" --quiet --out "$tmp/sn_profile_9999" >/dev/null 2>&1
ok sn_profile_9999_runs [ $? -eq 0 -a "$(grep -c . "$tmp/sn_profile_9999/history.csv")" -gt 10000 ]
"$tool" sinter --packing "$lat" --time 100.02 --profile "$tmp/profile_1e4.csv" --allow-long --quiet --out "$tmp/sn_profile_long" >/dev/null 2>&1
ok sn_profile_allow_long [ $? -eq 0 -a "$(grep -c '"status": "ok"' "$tmp/sn_profile_long/summary.json")" -eq 1 ]
# issue 27: the work at the door, spheres x the least number of global steps, above 1e8 is refused
# unless --allow-long: --time 1e8 on the lattice is 1e7 steps (within --max-steps) of 27 spheres,
# 2.7e8 sphere-steps, about 25 minutes; refused in well under a second (timeout: before, it ran)
start=$SECONDS
timeout 20 "$tool" sinter --packing "$lat" --time 1e8 --quiet --out "$tmp/sn_work" >/dev/null 2>"$tmp/stderr"
rc=$?
ok sn_work_refused [ $rc -eq 2 -a $((SECONDS - start)) -le 3 -a "$(grep -c . "$tmp/stderr")" -eq 1 -a ! -e "$tmp/sn_work" ]
ok sn_work_message grep -q -- "--time 1e+08: the run needs at least 2.7e+08 sphere-steps (27 spheres x 1e+07 global steps of at most 10 s), more than 1e+08, hours of one core: pass --allow-long" "$tmp/stderr"
# with --allow-long the run starts (stopped here after 2 s: it holds its folder)
timeout 2 "$tool" sinter --packing "$lat" --time 1e8 --allow-long --quiet --out "$tmp/sn_work_long" >/dev/null 2>&1
ok sn_work_allow_long [ $? -eq 124 -a -e "$tmp/sn_work_long/.incomplete" ]
check_bad_rc sn_restart_beyond_max_steps "more than the step limit 5" sinter --packing "$lat" --time 100 --dt-max 1 --max-steps 5 --quiet
# the library checks the options once (StaggeredOptions, StaggeredRunOptions) and names the
# quantity; the message names the option (netdem::FieldError, the field renamed where it differs)
check_bad_rc sn_x0_range "--x0: the initial neck x0 / R_min must be in (0.0001, 0.5), got 0.7" sinter --packing "$lat" --time 100 --x0 0.7 --quiet
check_bad_rc sn_x0_vanished "--x0: the initial neck" sinter --packing "$lat" --time 100 --x0 5e-5 --quiet
check_bad_rc sn_x_max "--x-max: the freeze limit" sinter --packing "$lat" --time 100 --x0 0.05 --x-max 0.04 --quiet
check_bad_rc sn_dt_initial "--dt-initial: the first global step" sinter --packing "$lat" --time 100 --dt-initial 1e-12 --quiet
check_bad_rc sn_nu "--nu: the bonds' Poisson's ratio" sinter --packing "$lat" --time 100 --nu -0.2 --quiet
check_bad_rc sn_checkpoints_twice "--checkpoints: the checkpoint times must increase: 50 s after 50 s" sinter --packing "$lat" --time 100 --checkpoints 50,50 --quiet
check_bad_rc sn_checkpoints_order "--checkpoints: the checkpoint times must increase: 50 s after 80 s" sinter --packing "$lat" --time 100 --checkpoints 80,50 --quiet
check_bad_rc sn_checkpoints_item "--checkpoints: '5x' is not a number" sinter --packing "$lat" --time 100 --checkpoints 20,5x --quiet
check_bad_rc sn_checkpoints_range "--checkpoints: 150 s is not between" sinter --packing "$lat" --time 100 --checkpoints 150 --quiet
check_bad_rc sn_nan_temperature "temperature" sinter --packing "$lat" --time 100 --temperature nan --quiet
check_bad_rc sn_material "material" sinter --packing "$lat" --material unobtainium --quiet
check_bad_rc sn_new_contacts "new-contacts" sinter --packing "$lat" --new-contacts maybe --quiet
check_bad_rc sn_both "excludes" sinter --packing "$lat" --generate cu --quiet
check_bad_rc sn_restart_missing "no_state.txt" sinter --restart "$tmp/no_state.txt" --quiet
printf 'id,x,y,r\n' >"$tmp/flat.csv"
check_bad_rc sn_2d_packing "flat.csv" sinter --packing "$tmp/flat.csv" --quiet

# ---- a run
hist_header="t,T,dt,shrink_x,shrink_y,shrink_z,density,neck_mean,neck_std,contacts,newton,substeps"
steps_header="step,t,dt,rejected,contacts_substepped,new_contacts,newly_frozen,gmres_iterations,refactorised,max_error,max_shrink_error"
run() {  # OUT ARGS...: a quiet run of the lattice
  local out="$1"
  shift
  "$tool" sinter --packing "$lat" --quiet --out "$out" "$@" >"$tmp/stdout" 2>"$tmp/stderr"
}
a="$tmp/a"
run "$a" --time 100
ok sn_exit [ $? -eq 0 ]
ok sn_quiet [ ! -s "$tmp/stderr" ]
for f in command.txt history.csv steps.csv dL_bar.csv state.txt summary.json report.md snapshots.pvd \
         particles_000.vtp bonds_000.vtp particles_005.vtp bonds_005.vtp; do
  ok "sn_file_$f" [ -s "$a/$f" ]
done
ok sn_no_marker [ ! -e "$a/.incomplete" ]
# snapshots.pvd (the shared writer of apps/common/output.hpp): the six snapshots by time t, the bonds as part 1
check_pvd sn_pvd "$a" particles,bonds --tags 000,001,002,003,004,005 --history history.csv:t
# the command draws nothing: report.md names the script that plots history.csv
ok sn_no_svg [ ! -e "$a/history.svg" ]
ok sn_report_names_plot grep -q "apps/scripts/plot_sinter.py" "$a/report.md"
ok sn_plot /usr/bin/python3 "$(dirname "${BASH_SOURCE[0]}")/../../apps/scripts/plot_sinter.py" "$a"
ok sn_plot_png [ -s "$a/history.png" ]
ok sn_history_header [ "$(head -1 "$a/history.csv")" = "$hist_header" ]
ok sn_steps_header [ "$(head -1 "$a/steps.csv")" = "$steps_header" ]
ok sn_dlbar_header [ "$(head -1 "$a/dL_bar.csv")" = "a,b,L0,dL_bar,dL_bar_over_L0,neck,t_created" ]
ok sn_status grep -q '"status": "ok"' "$a/summary.json"
ok sn_seed grep -q '"seed": 7' "$a/summary.json"
ok sn_no_nan bash -c "! grep -qi 'nan\|inf' '$a/history.csv' '$a/steps.csv' '$a/dL_bar.csv'"
# a row at t = 0, then one per step with t increasing to 100, 12 fields each, 54 initial contacts
ok sn_first_row awk -F, 'NR == 2 { exit !($1 == 0 && $10 == 54) }' "$a/history.csv"
ok sn_rows awk -F, 'NR > 1 { if (NF != 12) exit 1; if (NR > 2 && !($1 > t)) exit 1; t = $1 } END { exit !(NR > 3 && t == 100) }' "$a/history.csv"
ok sn_steps_rows [ "$(($(wc -l <"$a/history.csv") - 1))" -eq "$(wc -l <"$a/steps.csv")" ]
ok sn_dlbar_rows [ "$(($(wc -l <"$a/dL_bar.csv") - 1))" -eq "$(tail -1 "$a/history.csv" | cut -d, -f10)" ]
# the lattice shrinks, and alike along x, y and z
ok sn_shrinks awk -F, 'END { exit !($4 > 0 && $5 > 0 && $6 > 0) }' "$a/history.csv"
ok sn_isotropic awk -F, 'NR > 2 { d1 = $4 - $5; d2 = $4 - $6; if (d1 < 0) d1 = -d1; if (d2 < 0) d2 = -d2;
  if (d1 > 1e-6 * $4 + 1e-15 || d2 > 1e-6 * $4 + 1e-15) exit 1 }' "$a/history.csv"
# deterministic
b="$tmp/b"
run "$b" --time 100
ok sn_deterministic cmp -s "$a/history.csv" "$b/history.csv"
# restart: an uninterrupted run to 100 s whose steps end at t1 = 50 s (--checkpoints 50, which
# also writes state_1.txt there), against a run to t1 continued from its state.txt to 100 s
c="$tmp/c"
run "$c" --time 100 --checkpoints 50
ok sn_checkpoint_exit [ $? -eq 0 ]
ok sn_checkpoint_file [ -s "$c/state_1.txt" ]
ok sn_checkpoint_row grep -q '^50,' "$c/history.csv"
run "$tmp/r1" --time 50
ok sn_restart_first [ $? -eq 0 ]
ok sn_restart_t1 [ "$(tail -1 "$tmp/r1/history.csv")" = "$(grep '^50,' "$c/history.csv")" ]
"$tool" sinter --restart "$tmp/r1/state.txt" --time 100 --quiet --out "$tmp/r2" >/dev/null 2>"$tmp/stderr"
ok sn_restart_exit [ $? -eq 0 ]
ok sn_restart_last [ "$(tail -1 "$tmp/r2/history.csv")" = "$(tail -1 "$c/history.csv")" ]
ok sn_restart_rows [ "$(awk -F, 'NR > 2' "$tmp/r2/history.csv")" = "$(awk -F, 'NR > 1 && $1 > 50' "$c/history.csv")" ]
ok sn_restart_start awk -F, 'NR == 2 { exit !($1 == 50) }' "$tmp/r2/history.csv"
ok sn_restart_seed grep -q '"seed": 7' "$tmp/r2/summary.json"
# the record of origin is in the state itself: a state without its summary.json beside it keeps the seed
mkdir -p "$tmp/lone" && cp "$tmp/r1/state.txt" "$tmp/lone/state.txt"
"$tool" sinter --restart "$tmp/lone/state.txt" --time 100 --quiet --out "$tmp/r4" >/dev/null 2>"$tmp/stderr"
ok sn_restart_origin_in_state grep -q '"seed": 7' "$tmp/r4/summary.json"
ok sn_restart_origin_packing grep -q '"source": ".*lattice.csv"' "$tmp/r4/summary.json"
# a record of origin that does not describe the state is refused (campaign of issue 27: a seed of -1 or
# 1e300 was dropped to null, a packing of 100 particles was recorded for a 27-sphere state)
sed 's/"particles":27,/"particles":100,/' "$tmp/lone/state.txt" >"$tmp/lone/count.txt"
check_bad_rc sn_restart_origin_count "/origin/packing/particles: expected 27" sinter --restart "$tmp/lone/count.txt" --time 100 --quiet
sed 's/"seed":7}/"seed":-1}/' "$tmp/lone/state.txt" >"$tmp/lone/seed.txt"
check_bad_rc sn_restart_origin_seed "/origin/seed: expected a whole number" sinter --restart "$tmp/lone/seed.txt" --time 100 --quiet
sed 's/"seed":7}/"seed":1e300}/' "$tmp/lone/state.txt" >"$tmp/lone/seed2.txt"
check_bad_rc sn_restart_origin_seed_float "/origin/seed" sinter --restart "$tmp/lone/seed2.txt" --time 100 --quiet
# issue 27 item 8: a NaN clock in a restart state is named by its field, not blamed on --time
sed -E 's/"t":50.0}/"t":"nan"}/' "$tmp/lone/state.txt" >"$tmp/lone/nan_clock.txt"
check_bad_rc sn_restart_nan_clock "nan_clock.txt: /clock/t: expected a number" sinter --restart "$tmp/lone/nan_clock.txt" --time 100 --quiet
"$tool" sinter --restart "$tmp/lone/nan_clock.txt" --time 100 --quiet --out "$tmp/nan_clock" >/dev/null 2>"$tmp/stderr"
ok sn_restart_nan_clock_not_time [ "$(grep -c -- "--time" "$tmp/stderr")" -eq 0 ]
ok sn_restart_old_untouched [ "$(tail -1 "$tmp/r1/history.csv")" = "$(grep '^50,' "$c/history.csv")" ]
# the same from the checkpoint's state
"$tool" sinter --restart "$c/state_1.txt" --time 100 --quiet --out "$tmp/r3" >/dev/null 2>&1
ok sn_restart_checkpoint [ "$(tail -1 "$tmp/r3/history.csv")" = "$(tail -1 "$c/history.csv")" ]
# the state fixes the options: one given with --restart is refused
check_bad_rc sn_restart_option "strategy" sinter --restart "$tmp/r1/state.txt" --strategy 1 --quiet
check_bad_rc sn_restart_time "time" sinter --restart "$tmp/r1/state.txt" --time 1 --quiet
# a folder that holds a run is refused
cp "$a/history.csv" "$tmp/a_history.csv"
"$tool" sinter --packing "$lat" --time 100 --quiet --out "$a" >/dev/null 2>"$tmp/stderr"
rc=$?
ok sn_foreign_out bash -c "[ $rc -eq 2 ] && [ \$(grep -c . '$tmp/stderr') -eq 1 ] && grep -q 'holds the files of' '$tmp/stderr'"
ok sn_foreign_out_untouched cmp -s "$a/history.csv" "$tmp/a_history.csv"
finish
