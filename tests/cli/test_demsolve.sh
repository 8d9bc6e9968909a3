#!/usr/bin/env bash
# Command-line checks of demsolve prepare: bad input gives one clear line on stderr, a non-zero
# exit and no output folder; a short good run writes every documented file and is deterministic.
# usage: test_demsolve.sh PATH/TO/demsolve
set -u
ds="$1"
tool="$1"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
check_bad unknown_option "bogus" prepare --bogus
check_bad negative_pressure "pressure" prepare --pressure -1
check_bad nan_pressure "pressure" prepare --pressure nan
check_bad zero_n "--n" prepare --n 0
check_bad zero_time "--time" prepare --time 0
files_ok() {  # out-dir
  local f
  for f in command.txt timeseries.csv summary.json particles_initial.vtp particles_final.vtp state.txt; do
    [ -s "$1/$f" ] || return 1
  done
}
good() {  # out-dir
  "$ds" prepare --n 30 --time 0.003 --seed 7 --quiet --out "$1" >/dev/null 2>"$tmp/stderr"
}
if good "$tmp/a" && good "$tmp/b" &&
   files_ok "$tmp/a" &&
   head -1 "$tmp/a/timeseries.csv" | grep -q "^t,nu,C,sxx,szz" && grep -q '"seed": 7' "$tmp/a/summary.json" &&
   cmp -s "$tmp/a/state.txt" "$tmp/b/state.txt"; then
  pass=$((pass + 1))
else
  fail=$((fail + 1))
  echo "FAIL good_run (files, header, seed, determinism): $(cat "$tmp/stderr")"
fi
finish
