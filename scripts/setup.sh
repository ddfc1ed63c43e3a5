#!/usr/bin/env bash
# Installs the Debian packages SoftKin needs (only those that are missing) and builds the
# project in Release mode into build/. Safe to run again: it skips what is already done.
set -euo pipefail

usage() {
  cat <<'USAGE'
Usage: bash scripts/setup.sh [--help]

  1. Checks with dpkg-query which of SoftKin's Debian packages are missing and, only if some
     are, runs `apt-get update` and `apt-get install -y --no-install-recommends` for those
     (through sudo when not root).
  2. Configures and builds:  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
                             cmake --build build -j$(nproc)
     Binaries land in build/bin/ (softkin, test_solver, test_experiments, bench_fk).

Environment:
  SOFTKIN_BUILD_DIR   build folder (default: build)
  SOFTKIN_JOBS        parallel build jobs (default: nproc)
  SOFTKIN_WERROR      ON: treat compiler warnings as errors (CI sets it; default OFF)
USAGE
}

case "${1:-}" in
  -h|--help) usage; exit 0 ;;
  "") ;;
  *) echo "setup.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
esac

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
BUILD_DIR="${SOFTKIN_BUILD_DIR:-build}"
JOBS="${SOFTKIN_JOBS:-$(nproc)}"
WERROR="${SOFTKIN_WERROR:-OFF}"

# Debian packages. The compiler, CMake, GoogleTest and Google Benchmark are expected to be
# present already; everything else comes from here. Ceres, Ipopt, NLopt and CGAL are listed
# for the solvers and tools that later parts of SoftKin use.
PACKAGES=(
  libeigen3-dev
  libsuitesparse-dev
  libopenblas-dev
  nlohmann-json3-dev
  libcli11-dev
  python3-matplotlib
  python3-numpy
  libceres-dev
  coinor-libipopt-dev
  libnlopt-cxx-dev
  libcgal-dev
  pkg-config
  calculix-ccx
  python3-dev
  pybind11-dev
  python3-pytest
  python3-meshio
  libopenmpi-dev
  openmpi-bin
  slurmctld
  slurmd
  slurm-client
  munge
)

log() { echo "[setup] $*"; }

missing=()
for pkg in "${PACKAGES[@]}"; do
  status="$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)"
  if [[ "$status" != "install ok installed" ]]; then
    missing+=("$pkg")
  fi
done

if ((${#missing[@]} == 0)); then
  log "all ${#PACKAGES[@]} Debian packages are installed"
else
  log "missing Debian packages: ${missing[*]}"
  SUDO=()
  if [[ "$(id -u)" -ne 0 ]]; then
    if command -v sudo >/dev/null 2>&1; then
      SUDO=(sudo)
    else
      echo "setup.sh: not root and sudo is not available; install as root: apt-get install ${missing[*]}" >&2
      exit 1
    fi
  fi
  export DEBIAN_FRONTEND=noninteractive
  prefix="${SUDO[*]:+${SUDO[*]} }"
  log "running: ${prefix}apt-get update"
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
  log "running: ${prefix}apt-get install -y --no-install-recommends ${missing[*]}"
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y --no-install-recommends "${missing[@]}"
fi

for tool in cmake c++; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "setup.sh: '$tool' not found; SoftKin needs a C++17 compiler and CMake >= 3.20" >&2
    exit 1
  fi
done

log "configuring: cmake -S . -B $BUILD_DIR -DCMAKE_BUILD_TYPE=Release -DSOFTKIN_WERROR=$WERROR"
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSOFTKIN_WERROR="$WERROR"
log "building: cmake --build $BUILD_DIR -j$JOBS"
cmake --build "$BUILD_DIR" -j"$JOBS"
log "done: binaries are in $ROOT/$BUILD_DIR/bin"
