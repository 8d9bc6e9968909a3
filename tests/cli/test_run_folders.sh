#!/usr/bin/env bash
# Run folders held by a live run (issue 27, items 1-2; README.md "Run folders"): a folder whose
# .incomplete names a process that is still running is refused, with or without --overwrite, with
# its pid (exit 2, nothing touched); once that process is gone (killed), --overwrite takes the
# folder and removes only what the old run wrote, keeping the user's files, and lists what it
# removed (one line on stderr). netsolve and demsolve use the same functions.
# usage: test_run_folders.sh PATH/TO/netsolve PATH/TO/demsolve
set -u
ns="$(readlink -f "$1")"
ds="$(readlink -f "$2")"
tool="$ns"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
ok() { pass=$((pass + 1)); }
ko() { fail=$((fail + 1)); echo "FAIL $1: $(head -c 600 "$tmp/stderr" 2>/dev/null)"; }
# the marker and command.txt of a live run (which may add files of its own while it runs)
held() { (cd "$1" && sha256sum .incomplete command.txt && ls -A); }
# still_held DIR BEFORE: the marker and command.txt unchanged, no file of BEFORE removed
still_held() {
  local now n
  now=$(held "$1")
  [ "$(echo "$2" | head -2)" = "$(echo "$now" | head -2)" ] || return 1
  for n in $(echo "$2" | tail -n +3); do [ -e "$1/$n" ] || return 1; done
}

# start_long NAME CMD...: starts CMD in the background (its pid in $bg) and waits until its
# .incomplete exists (at most 60 s), so that the folder is held by a live run
start_long() {
  local dir="$1"
  shift
  "$@" >/dev/null 2>&1 &
  bg=$!
  for _ in $(seq 1200); do [ -s "$dir/.incomplete" ] && [ -s "$dir/command.txt" ] && return 0; sleep 0.05; done
  echo "FAIL: $* did not open $dir"
  return 1
}
stop_long() { kill -KILL "$bg" 2>/dev/null; wait "$bg" 2>/dev/null; }

# held_refused TOOL DIR ARGS...: TOOL ARGS --out DIR, with and without --overwrite, exits 2 with one
# line naming the live run's pid and how to tell it is gone, and touches nothing
held_refused() {
  local t="$1" dir="$2" name="$3"
  shift 3
  local before
  before=$(held "$dir")
  for ow in "" "--overwrite"; do
    # shellcheck disable=SC2086
    "$t" "$@" $ow --out "$dir" >/dev/null 2>"$tmp/stderr"
    local rc=$?
    if [ "$rc" -eq 2 ] && [ "$(grep -c . "$tmp/stderr")" -eq 1 ] && grep -q "pid $bg" "$tmp/stderr" &&
       grep -q "still running" "$tmp/stderr" && grep -q "ps -p $bg" "$tmp/stderr" && still_held "$dir" "$before"; then
      ok
    else
      ko "$name${ow:+ $ow} rc=$rc"
    fi
  done
}

# ---- netsolve: the issue's reproducer (sinter --generate cu --time 1000, then a second run; here
# --time 1e5, which runs for minutes, so that the first run is surely alive until it is killed)
f="$tmp/F"
if start_long "$f" "$ns" sinter --generate cu --time 1e5 --quiet --out "$f"; then
  held_refused "$ns" "$f" netsolve_live pack --width 20
  held_refused "$ns" "$f" netsolve_live_sinter sinter --generate cu --time 100 --quiet
  [ -e "$f/.incomplete" ] && grep -q "sinter --generate cu --time 1e5" "$f/command.txt" && ok || ko live_untouched
  stop_long
  # the run is gone (killed): its marker is stale; the user adds a note and a file of the run's kind
  printf 'my notes\n' >"$f/notes.txt"
  printf 'old state\n' >"$f/state.txt"
  "$ns" pack --width 20 --overwrite --out "$f" >/dev/null 2>"$tmp/stderr"
  rc=$?
  if [ "$rc" -eq 0 ] && [ "$(cat "$f/notes.txt")" = "my notes" ] && [ ! -e "$f/state.txt" ] && [ ! -e "$f/.incomplete" ] &&
     grep -q "pack --width 20" "$f/command.txt" && [ "$(grep -c . "$tmp/stderr")" -eq 1 ] &&
     grep -q "removed" "$tmp/stderr" && grep -q "command.txt" "$tmp/stderr" && grep -q "state.txt" "$tmp/stderr" &&
     grep -q "kept 1 other: notes.txt" "$tmp/stderr" && ! grep -q "removed.*notes.txt.*;" "$tmp/stderr"; then
    ok
  else
    ko "netsolve_stale_overwrite rc=$rc"
  fi
else
  fail=$((fail + 1))
fi

# ---- --overwrite of a finished run keeps the user's files, removes the run's own, lists them
g="$tmp/G"
"$ns" pack --width 20 --out "$g" >/dev/null 2>&1
printf 'keep me\n' >"$g/notes.txt"
printf 'x\n' >"$g/mydata.csv"  # the user's, although of a kind a run writes
"$ns" pack --width 20 --seed 2 --overwrite --out "$g" >/dev/null 2>"$tmp/stderr"
rc=$?
if [ "$rc" -eq 0 ] && [ "$(cat "$g/notes.txt")" = "keep me" ] && [ "$(cat "$g/mydata.csv")" = "x" ] &&
   grep -q -- "--seed 2" "$g/command.txt" && [ -s "$g/packing.csv" ] && [ "$(grep -c . "$tmp/stderr")" -eq 1 ] &&
   grep -q "packing.csv" "$tmp/stderr" && grep -q "summary.json" "$tmp/stderr" && grep -q "kept 2 others" "$tmp/stderr"; then
  ok
else
  ko "overwrite_keeps_user_files rc=$rc"
fi
# a plain run into a folder of the user's files only keeps them and says nothing
h="$tmp/H"
mkdir -p "$h" && printf 'n\n' >"$h/notes.txt"
"$ns" pack --width 20 --out "$h" >/dev/null 2>"$tmp/stderr"
rc=$?
if [ "$rc" -eq 0 ] && [ -s "$h/notes.txt" ] && [ ! -s "$tmp/stderr" ]; then ok; else ko "plain_run_keeps rc=$rc"; fi
# ... and a later --overwrite keeps them too
"$ns" pack --width 20 --overwrite --out "$h" >/dev/null 2>"$tmp/stderr"
rc=$?
if [ "$rc" -eq 0 ] && [ -s "$h/notes.txt" ] && grep -q "kept 1 other: notes.txt" "$tmp/stderr"; then ok; else ko "overwrite_keeps_preexisting rc=$rc"; fi

# ---- demsolve uses the same functions
d="$tmp/D"
if start_long "$d" "$ds" prepare --dim 3 --n 300 --time 50 --quiet --out "$d"; then
  held_refused "$ds" "$d" demsolve_live prepare --n 20 --time 0.002 --quiet
  # a run killed after its first snapshot keeps a valid snapshots.pvd of it (rewritten with each)
  for _ in $(seq 1200); do [ -s "$d/snapshots.pvd" ] && break; sleep 0.05; done
  stop_long
  if /usr/bin/python3 "$pvd_check" "$d" particles,contacts 2>"$tmp/stderr" && [ -e "$d/.incomplete" ]; then
    ok
  else
    ko "demsolve_killed_pvd"
  fi
  printf 'my notes\n' >"$d/notes.txt"
  "$ds" prepare --n 20 --time 0.002 --quiet --overwrite --out "$d" >/dev/null 2>"$tmp/stderr"
  rc=$?
  if [ "$rc" -eq 0 ] && [ -s "$d/notes.txt" ] && [ ! -e "$d/.incomplete" ] && grep -q "prepare --n 20" "$d/command.txt" &&
     grep -q "removed" "$tmp/stderr"; then
    ok
  else
    ko "demsolve_stale_overwrite rc=$rc"
  fi
else
  fail=$((fail + 1))
fi

# ---- snapshots.pvd is the run's own: --overwrite removes it with the snapshots it names, and the
# new run's names only its own (issue 33)
c="$tmp/C"
"$ns" compact --width 16 --increments 40 --to-density 0.83 --snapshots 0.81,0.82 --quiet --out "$c" >/dev/null 2>"$tmp/stderr"
check_pvd compact_pvd "$c" particles,contacts --tags initial,D0.810,D0.820,final --history history.csv:D
"$ns" compact --width 16 --increments 40 --to-density 0.83 --snapshots '' --quiet --overwrite --out "$c" >/dev/null 2>"$tmp/stderr"
rc=$?
if [ "$rc" -eq 0 ] && [ ! -e "$c/particles_D0.810.vtp" ] && grep -q "removed" "$tmp/stderr"; then ok; else ko "overwrite_pvd rc=$rc"; fi
check_pvd overwritten_pvd "$c" particles,contacts --tags initial,final --history history.csv:D

# An empty file option is refused with one line naming it (it was read as "not given": the run
# went on from the defaults), and no folder is made.
tool="$ns"
check_bad empty_compact_state "--state" compact --state ''
check_bad empty_yield_from_state "--from-state" yield --from-state ''
check_bad empty_sinter_restart "--restart" sinter --restart ''
check_bad empty_sinter_packing "--packing" sinter --packing ''
check_bad empty_sinter_profile "--profile" sinter --profile ''
check_bad empty_pair_profile "--profile" sinter-pair --profile ''
tool="$ds"
check_bad empty_dem_compact_state "--state" compact --state ''
check_bad empty_dem_sinter_state "--state" sinter --state ''
check_bad empty_dem_compress_state "--state" compress --state ''
finish
