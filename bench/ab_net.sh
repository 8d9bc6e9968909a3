#!/usr/bin/env bash
# (bench/ab_net.sh; docs/performance.md "Issue 11 refactor": old and new netsolve binaries, interleaved)
# Interleaved A/B of netsolve: OLD and NEW binaries, N rounds; prints "case variant round seconds".
# usage: ab_net.sh OLD NEW N
# A binary that exits 3 (e.g. W = 320: Eq 13 more than 2 % off the contact stress) is timed again
# with --allow-unconverged where it knows the option; see docs/performance.md.
OLD=$1; NEW=$2; N=$3
OLD=$(realpath "$OLD"); NEW=$(realpath "$NEW")
cd "$(mktemp -d)"  # scratch folder: run folders and time.txt
run() {  # label bin args...
  local label=$1 bin=$2; shift 2
  rm -rf out_ab
  local s
  /usr/bin/time -o time.txt -f %e "$bin" "$@" --out out_ab --quiet --allow-unconverged >/dev/null 2>/dev/null ||
    { rm -rf out_ab; /usr/bin/time -o time.txt -f %e "$bin" "$@" --out out_ab --quiet >/dev/null 2>/dev/null; }
  s=$(tail -1 time.txt)
  echo "$label $s"
}
for k in $(seq 1 "$N"); do
  for v in old new; do
    bin=$OLD; [ $v = new ] && bin=$NEW
    run "compact80 $v $k" $bin compact
    run "compact320 $v $k" $bin compact --width 320
    run "yield80 $v $k" $bin yield
    run "compact80_inline_off $v $k" env NETDEM_CHOLMOD_INLINE_OMP=0 $bin compact
  done
done
