#!/usr/bin/env bash
# Regenerates every validation case's report (runs only the simulations that are missing or whose
# command changed). Usage: bash validation/run_all.sh [--quick] [--force] [--netsolve PATH] [--demsolve PATH] [--jobs N]
# Every argument is passed through to each case's run.py. Debian's python3 (numpy, matplotlib) is used.
# Run times per case and the total: validation/README.md. At the end, validation/status.py lists every report
# as current or stale; update README.md's block with validation/status.py --write-readme.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
py=/usr/bin/python3
[ -x "$py" ] || py=python3
status=0
for case_dir in "$here"/redanz_fleck_compaction "$here"/redanz_fleck_yield "$here"/luding_sintering "$here"/sintering_pair \
    "$here"/quasistatic_vs_dynamic "$here"/quasistatic_vs_dynamic_periodic "$here"/quasistatic_vs_dynamic_walls \
    "$here"/redanz_fleck_walls "$here"/compaction_3d "$here"/literature_3d "$here"/ivannikov_staggered; do
  echo "== $(basename "$case_dir")"
  "$py" "$case_dir/run.py" "$@" || status=1
done
"$py" "$here/status.py" || true   # which reports are current (a flag, not a failure)
exit $status
