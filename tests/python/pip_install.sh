#!/usr/bin/env bash
# `pip install --no-build-isolation .` into a fresh virtual environment (with Debian's packages
# visible), from a copy of the source tree, reusing the configured build tree BUILD_DIR for the
# compiled module; then `import softkin` from outside both trees. Usage: pip_install.sh SRC BUILD_DIR
set -euo pipefail
SRC="$1"
BUILD_DIR="$2"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
mkdir "$WORK/src"
# The sources without build trees or results.
tar -C "$SRC" --exclude='./build*' --exclude='./results' --exclude='./.git' \
  --exclude='*.egg-info' -cf - . | tar -C "$WORK/src" -xf -
/usr/bin/python3 -m venv --system-site-packages "$WORK/venv"
SOFTKIN_CMAKE_BUILD_DIR="$BUILD_DIR" "$WORK/venv/bin/python" -m pip install \
  --no-build-isolation --no-deps --no-index --quiet "$WORK/src"
cd "$WORK"
"$WORK/venv/bin/python" - <<'PY'
import os, sys
import softkin
here = os.path.dirname(softkin.__file__)
assert os.path.realpath(here).startswith(os.path.realpath(sys.prefix)), here
for f in ("__init__.pyi", "py.typed"):
    assert os.path.exists(os.path.join(here, f)), f
r = softkin.solve_fk(softkin.robot("three_chamber", res=3), [1.3, 1.0, 1.0])
assert r.converged, r.status
print("pip-installed softkin at", here, "solves:", r)
PY
