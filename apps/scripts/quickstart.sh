#!/usr/bin/env bash
# README command 1: install what is missing, build in Release, run netsolve on the embedded
# default scene (polydisperse ballistic packing W = 80R, hydrostatic die compaction, sticking
# friction, to D = 0.85) and write results plus a short report to results/default/; then build the
# Python module netdem and make it importable by Debian's python3.
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
# The Python module (README "From Python"), after the results: built for Debian's /usr/bin/python3
# and registered with it through a netdem.pth in the user's site-packages, so that
# `python3 -c "import netdem"` works (delete that file to undo; NETDEM_NO_PYTHON=1 skips this step).
if [ "${NETDEM_NO_PYTHON:-0}" != 1 ] && [ -f "$root/build/python/netdem/__init__.py" ]; then
  cmake --build "$root/build" -j "$(nproc)" --target _netdem
  site=$(/usr/bin/python3 -m site --user-site)
  mkdir -p "$site"
  echo "$root/build/python" > "$site/netdem.pth"
  /usr/bin/python3 -c "import netdem" && echo "python: import netdem works (module in $root/build/python, listed in $site/netdem.pth)"
fi
