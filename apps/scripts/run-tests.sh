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
  # clang (in install-deps.sh for libFuzzer): the same build also makes the fuzz targets that
  # .ci/run runs (NETDEM_FUZZ, coverage only in the readers they drive), so CI compiles the
  # libraries twice, not three times. A build directory left by another compiler starts afresh.
  if [ -f "$build/CMakeCache.txt" ] && ! grep -q '^CMAKE_CXX_COMPILER:[A-Z]*=.*clang++' "$build/CMakeCache.txt"; then
    rm -rf "$build"
  fi
  # The libraries at -O2 -g1: clang at -O1 with the sanitizers leaves Eigen's element accessors as
  # calls (the periodic DEM yield test took 248 s of its 300 s); line tables are enough for the
  # reports' stack traces. The command lines and the test files compile at -O0 (apps/ and tests/
  # CMakeLists.txt), which keeps .ci/run inside its 45 minutes on two cores (docs/performance.md,
  # "CI time").
  CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNETDEM_WERROR=ON \
        "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" \
        -DNETDEM_SANITIZE=ON -DNETDEM_FUZZ=ON -DNETDEM_BUILD_BENCH=OFF >/dev/null
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  export NETDEM_TEST_SCALE=small   # heavy tests use smaller systems under the sanitizers
else
  build="$root/build"
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DNETDEM_WERROR=ON >/dev/null
fi
cmake --build "$build" -j "$jobs"
ctest --test-dir "$build" --output-on-failure -j "$jobs"
