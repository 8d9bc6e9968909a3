# Shared helpers of the command-line tests (sourced, not run).
# check_bad NAME WORD ARGS...: the tool ($tool) called with ARGS and --out must exit non-zero,
# print exactly one line on stderr containing WORD, and leave no output folder.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0
fail=0
check_bad() {
  local name="$1" word="$2"
  shift 2
  local out="$tmp/$name"
  "$tool" "$@" --out "$out" >"$tmp/stdout" 2>"$tmp/stderr"
  local rc=$?
  local lines
  lines=$(grep -c . "$tmp/stderr")
  if [ "$rc" -ne 0 ] && [ "$lines" -eq 1 ] && grep -qi -- "$word" "$tmp/stderr" && [ ! -e "$out" ]; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
    echo "FAIL $name: rc=$rc lines=$lines out-exists=$([ -e "$out" ] && echo yes || echo no) stderr: $(cat "$tmp/stderr")"
  fi
}
# result NAME RC: counts a check that passed (RC 0) or failed (its stderr's first 2000 bytes
# printed); a test file may define its own.
result() {  # name ok?
  if [ "$2" -eq 0 ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL $1: $(head -c 2000 "$tmp/stderr")"; fi
}
finish() {
  echo "cli: $pass passed, $fail failed"
  [ "$fail" -eq 0 ]
}
# check_pvd NAME DIR KIND,KIND,... [tests/pvd_check.py options]: DIR's snapshots.pvd is the
# ParaView collection of its KIND_*.vtp snapshots (tests/pvd_check.py) and its .netdem-files lists
# it (--overwrite removes it).
pvd_check="$(dirname "${BASH_SOURCE[0]}")/../pvd_check.py"
check_pvd() {
  local name="$1" dir="$2"
  shift 2
  if /usr/bin/python3 "$pvd_check" "$dir" "$@" 2>"$tmp/pvd_stderr" && grep -qx snapshots.pvd "$dir/.netdem-files"; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
    echo "FAIL $name: $(head -3 "$tmp/pvd_stderr")$(grep -qx snapshots.pvd "$dir/.netdem-files" 2>/dev/null || echo " (.netdem-files does not list snapshots.pvd)")"
  fi
}
