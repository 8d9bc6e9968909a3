#!/usr/bin/env bash
# Builds netdem and runs the whole test suite (README command 2).
#   bash apps/scripts/run-tests.sh              Release build with -Werror, all tests
#   bash apps/scripts/run-tests.sh --sanitize   the same under AddressSanitizer + UBSan
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
mode=release
if [ "${1:-}" = "--sanitize" ]; then mode=sanitize; fi
bash "$root/apps/scripts/install-deps.sh"
jobs=$(nproc)
if [ "$mode" = sanitize ]; then
  build="$root/build-asan"
  # -O1 -g1, as the AddressSanitizer documentation recommends: line tables are enough for the
  # reports' stack traces, and the heaviest test file compiles in 111 s instead of 203 s at -O2 -g
  # (docs/performance.md, "CI time"), which keeps .ci/run inside its 45 minutes on two cores.
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNETDEM_WERROR=ON \
        "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
        -DNETDEM_SANITIZE=ON -DNETDEM_BUILD_BENCH=OFF >/dev/null
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  export NETDEM_TEST_SCALE=small   # heavy tests use smaller systems under the sanitizers
else
  build="$root/build"
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DNETDEM_WERROR=ON >/dev/null
fi
cmake --build "$build" -j "$jobs"
ctest --test-dir "$build" --output-on-failure -j "$jobs"
