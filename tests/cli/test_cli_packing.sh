#!/usr/bin/env bash
# Command-line reproducers of issue 13 for the packing reader (netsolve compact --packing): each
# gives one clear line on stderr, a non-zero exit and no output folder, quickly.
# W20 = a packing from `netsolve pack --width 20`.
# usage: test_cli_packing.sh PATH/TO/netsolve
set -u
ns="$1"
tool="$1"
# shellcheck source=cli_lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/cli_lib.sh"
"$ns" pack --width 20 --out "$tmp/p" >/dev/null 2>&1 || { echo "FAIL: netsolve pack --width 20"; exit 1; }
w20="$tmp/p/packing.csv"
# every radius 1e-300 (was: SIGSEGV in the neighbour build)
awk -F, 'BEGIN { OFS = "," } /^[0-9]/ { $4 = "1e-300" } { print }' "$w20" >"$tmp/r300.csv"
check_bad radii_1e-300 "r = 1e-300" compact --packing "$tmp/r300.csv" --increments 10
# box 0 0 2e300 2e300, coordinates scaled by 1e299 (was: SIGSEGV)
awk -F, 'BEGIN { OFS = "," } /^# box/ { print "# box 0 0 2e300 2e300"; next }
         /^[0-9]/ { $2 = sprintf("%.17g", $2 * 1e299); $3 = sprintf("%.17g", $3 * 1e299) } { print }' "$w20" >"$tmp/big.csv"
check_bad box_2e300 "box x_max = 2e+300 is outside" compact --packing "$tmp/big.csv" --increments 10
# one radius 4.9e-324 (was: endless loop in peripheral_layer)
awk -F, 'BEGIN { OFS = "," } /^5,/ { $4 = "4.9e-324" } { print }' "$w20" >"$tmp/denorm.csv"
check_bad radius_4.9e-324 "r = 5e-324" compact --packing "$tmp/denorm.csv" --increments 10
# 10^5 disks within 1e-10 of each other (was: quadratic duplicate search, a hang)
awk 'BEGIN { print "# box 0 0 1 1"; print "id,x,y,r"
             for (i = 0; i < 100000; i++) printf "%d,%.17g,%.17g,0.01\n", i, 0.5 + (i % 317) * 3e-13, 0.5 + int(i / 317) * 3e-13 }' \
  >"$tmp/neardup.csv"
start=$(date +%s)
check_bad near_duplicates "too close" compact --packing "$tmp/neardup.csv" --to-density 40
if [ $(( $(date +%s) - start )) -gt 10 ]; then
  fail=$((fail + 1)); echo "FAIL near_duplicates: took more than 10 s"
fi
# a directory (was: "read error")
mkdir -p "$tmp/adir"
check_bad packing_dir "is a \\(directory\\|folder\\)" compact --packing "$tmp/adir"
# a binary first line of 5 MB (was: echoed whole to stderr)
{ head -c 5000000 /dev/urandom | tr -d '\n'; printf '\n'; } >"$tmp/binary.csv"
check_bad binary_first_line "control character" compact --packing "$tmp/binary.csv"
if [ "$(wc -c <"$tmp/stderr")" -gt 300 ]; then
  fail=$((fail + 1)); echo "FAIL binary_first_line: $(wc -c <"$tmp/stderr") bytes on stderr"
fi
# a printable 5 MB first line: at most 80 characters of it are quoted
{ head -c 5000000 /dev/zero | tr '\0' 'x'; printf '\n'; } >"$tmp/long.csv"
check_bad long_first_line "bad header 'xxxx" compact --packing "$tmp/long.csv"
if [ "$(wc -c <"$tmp/stderr")" -gt 300 ]; then
  fail=$((fail + 1)); echo "FAIL long_first_line: $(wc -c <"$tmp/stderr") bytes on stderr"
fi
# radius ratio above 100 and a pair closer than the larger radius, naming the line
printf '# box 0 0 10 10\nid,x,y,r\n0,5,5,1\n1,2,2,0.005\n' >"$tmp/ratio.csv"
check_bad radius_ratio "ratio.csv:3: r_max / r_min" compact --packing "$tmp/ratio.csv"
printf '# box 0 0 10 10\nid,x,y,r\n0,5,5,1\n1,5.5,5,1\n' >"$tmp/close.csv"
check_bad close_pair "close.csv:4: disk id 1 and disk id 0 (line 3) are too close" compact --packing "$tmp/close.csv"
finish
