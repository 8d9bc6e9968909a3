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
finish() {
  echo "cli: $pass passed, $fail failed"
  [ "$fail" -eq 0 ]
}
