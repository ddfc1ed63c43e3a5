#!/usr/bin/env bash
# Packaging test (ctest: cmake_package_consumer). Installs a SoftKin build tree into a temporary
# prefix, then configures, builds and runs tests/cmake/consumer against that prefix only.
#
# Usage: bash tests/cmake/run_consumer.sh BUILD_DIR SOURCE_DIR
set -euo pipefail

if [[ $# -ne 2 ]]; then
  echo "usage: $0 BUILD_DIR SOURCE_DIR" >&2
  exit 2
fi
BUILD_DIR="$(cd "$1" && pwd)"
SOURCE_DIR="$(cd "$2" && pwd)"

WORK="$(mktemp -d "${TMPDIR:-/tmp}/softkin_consumer.XXXXXX")"
cleanup() { rm -rf "$WORK"; }
trap cleanup EXIT
PREFIX="$WORK/prefix"

# Use the compiler and build type the SoftKin build used, so the static library links cleanly.
cache_value() {
  sed -n "s/^$1:[A-Z]*=//p" "$BUILD_DIR/CMakeCache.txt" | head -n1
}
CXX_COMPILER="$(cache_value CMAKE_CXX_COMPILER)"
BUILD_TYPE="$(cache_value CMAKE_BUILD_TYPE)"
BUILD_TYPE="${BUILD_TYPE:-Release}"
# Sanitizer builds (CMakePresets "asan") need the same flags on the consumer side.
CXX_FLAGS="$(cache_value CMAKE_CXX_FLAGS)"
EXE_LINKER_FLAGS="$(cache_value CMAKE_EXE_LINKER_FLAGS)"

echo "== install $BUILD_DIR -> $PREFIX"
cmake --install "$BUILD_DIR" --prefix "$PREFIX" --config "$BUILD_TYPE" >"$WORK/install.log" || {
  cat "$WORK/install.log"; echo "cmake --install failed" >&2; exit 1; }
config="$(find "$PREFIX" -name softkinConfig.cmake -print -quit)"
if [[ -z "$config" ]]; then
  echo "no softkinConfig.cmake under $PREFIX" >&2
  exit 1
fi
echo "   found $config"

echo "== configure consumer"
# CMAKE_FIND_USE_PACKAGE_REGISTRY=OFF and only PREFIX on the prefix path: the package must come
# from the install, never from the build tree.
cmake -S "$SOURCE_DIR/tests/cmake/consumer" -B "$WORK/build" \
  -DCMAKE_BUILD_TYPE="$BUILD_TYPE" \
  ${CXX_COMPILER:+-DCMAKE_CXX_COMPILER="$CXX_COMPILER"} \
  -DCMAKE_CXX_FLAGS="$CXX_FLAGS" \
  -DCMAKE_EXE_LINKER_FLAGS="$EXE_LINKER_FLAGS" \
  -DCMAKE_PREFIX_PATH="$PREFIX" \
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
  -Dsoftkin_DIR="$(dirname "$config")"

echo "== build consumer"
cmake --build "$WORK/build" -j2

echo "== run consumer"
out="$("$WORK/build/softkin_consumer")"
echo "$out"
if ! grep -Eq '^three_chamber res 3: [1-9][0-9]* tets' <<<"$out"; then
  echo "unexpected consumer output" >&2
  exit 1
fi
echo "== run the core-only consumer"
core_out="$("$WORK/build/softkin_core_consumer")" || { echo "$core_out"; echo "core consumer failed" >&2; exit 1; }
echo "$core_out"
# The core library must not pull in CGAL, Ceres or Ipopt.
if ldd "$WORK/build/softkin_core_consumer" | grep -Eiq 'ceres|ipopt|gmp|mpfr'; then
  echo "softkin::core links a library it should not need:" >&2
  ldd "$WORK/build/softkin_core_consumer" >&2
  exit 1
fi
echo "cmake_package_consumer: OK"
