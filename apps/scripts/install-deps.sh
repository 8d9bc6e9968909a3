#!/usr/bin/env bash
# Installs the Debian 12 packages netdem needs (only the missing ones). Needs root or sudo.
set -euo pipefail
pkgs=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libsuitesparse-dev libsundials-dev libgtest-dev libfmt-dev
  libcli11-dev nlohmann-json3-dev libbenchmark-dev
  libboost-dev                       # Boost.Math (Carlson's elliptic integrals), header-only
  libopenblas0-serial                # optimised serial BLAS for CHOLMOD's supernodal factorisation
  clang libclang-rt-14-dev           # the sanitizer build with the fuzz targets (run-tests.sh --sanitize,
                                     # tests/fuzz, .ci/run): libFuzzer + ASan/UBSan runtimes;
                                     # libclang-rt-14-dev is only a Recommends of clang-14, hence listed
  libomp-dev                         # clang's OpenMP runtime: find_package(OpenMP) of the clang sanitizer
                                     # build (clang does not depend on it)
  python3 python3-numpy python3-matplotlib
  pybind11-dev python3-dev python3-pytest   # the Python module netdem (python/) and its tests (tests/python)
)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#pkgs[@]} packages present" >&2
  exit 0
fi
echo "install-deps: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if ! command -v sudo >/dev/null 2>&1; then
    echo "install-deps: error: missing packages (${missing[*]}) and neither root nor sudo to install them" >&2
    exit 1
  fi
  SUDO="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
