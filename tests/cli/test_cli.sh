#!/usr/bin/env bash
# Command-line checks of netsolve: bad input gives one clear line on stderr, a non-zero exit and
# no output folder; a small good run writes every documented file.
# usage: test_cli.sh PATH/TO/netsolve
set -u
ns="$1"
tool="$1"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
check_bad unknown_option "bogus" compact --bogus
check_bad negative_friction "friction" compact --friction -1
check_bad nan_friction "friction" compact --friction nan
check_bad bad_path "strain path" compact --path 1,foo,0
check_bad dilatant_path "impossible target" compact --path 1,1,0
check_bad low_target "impossible target" compact --to-density 0.5
check_bad missing_packing "cannot open" compact --packing "$tmp/does_not_exist.csv"
printf '# box 0 0 10 10\nid,x,y,r\n0,5,5,-1\n' >"$tmp/negr.csv"
check_bad negative_radius "r <= 0" compact --packing "$tmp/negr.csv"
check_bad bad_lid "lid" pack --lid foo
check_bad negative_width "width" pack --width -3
check_bad zero_increments "increments" compact --increments 0
check_bad bad_unloading "normal-unloading" compact --normal-unloading plastic
# a good small run writes every documented file (W = 16 with 40 increments converges: exit 0;
# W = 12 with 5 does not, exit 3, see test_status.sh)
good="$tmp/good"
if "$ns" compact --width 16 --increments 40 --to-density 0.83 --quiet --out "$good" >/dev/null 2>"$tmp/stderr" &&
   [ -s "$good/history.csv" ] && [ -s "$good/summary.json" ] && [ -s "$good/command.txt" ] && [ -s "$good/packing.csv" ] &&
   [ -s "$good/particles_final.vtp" ] && [ -s "$good/contacts_final.vtp" ] &&
   head -1 "$good/history.csv" | grep -q "D,S11,S22,S12" && grep -q '"seed"' "$good/summary.json" &&
   grep -q '"centres_outside_box": 0' "$good/summary.json" &&
   [ "$(find "$good" -name '.*tmp*' | wc -l)" -eq 0 ]; then
  pass=$((pass + 1))
else
  fail=$((fail + 1))
  echo "FAIL good_run: $(cat "$tmp/stderr")"
fi
finish
