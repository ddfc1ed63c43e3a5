#!/usr/bin/env bash
# Set up and build SoftKin, then run every registered test with CTest.
set -euo pipefail

usage() {
  cat <<'USAGE'
Usage: bash scripts/test.sh [--help] [extra ctest options...]

  1. bash scripts/setup.sh   (missing Debian packages, Release build in build/)
  2. ctest --test-dir build --output-on-failure -j2 [extra options]

Extra options go to ctest, e.g. `-R cmake_package_consumer` or `-L solver`.
The exit code is ctest's.
USAGE
}

for arg in "$@"; do
  case "$arg" in
    -h|--help) usage; exit 0 ;;
  esac
done

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
BUILD_DIR="${SOFTKIN_BUILD_DIR:-build}"

bash scripts/setup.sh

echo "[test] running: ctest --test-dir $BUILD_DIR --output-on-failure -j2 $*"
# exec: ctest's summary line is the last thing printed and its exit code is ours.
exec ctest --test-dir "$BUILD_DIR" --output-on-failure -j2 "$@"
