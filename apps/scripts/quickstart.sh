#!/usr/bin/env bash
# README command 1: install what is missing, build in Release, run netsolve on the embedded
# default scene (polydisperse ballistic packing W = 80R, hydrostatic die compaction, sticking
# friction, to D = 0.85) and write results plus a short report to results/default/.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out="${1:-$root/results/default}"
bash "$root/apps/scripts/install-deps.sh"
cmake -S "$root" -B "$root/build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$root/build" -j "$(nproc)" --target netsolve
# --overwrite: a second quickstart replaces the first one's results (README.md "Run folders")
"$root/build/apps/netsolve" compact --overwrite --out "$out"
/usr/bin/python3 "$root/apps/scripts/plot_run.py" "$out"
echo "results and report: $out/report.md"
