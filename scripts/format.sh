#!/usr/bin/env bash
# Formats SoftKin's C++ sources with clang-format (style: .clang-format), or checks that they are.
set -euo pipefail

usage() {
  cat <<'USAGE'
Usage: bash scripts/format.sh [--check] [--help]

  Runs clang-format (Debian package clang-format, installed with apt-get if missing) over every
  tracked *.cpp and *.hpp file.
  --check   change nothing; list the files that are not formatted and exit 1 if there are any
            (CI runs this).
USAGE
}

check=0
case "${1:-}" in
  -h|--help) usage; exit 0 ;;
  --check) check=1 ;;
  "") ;;
  *) echo "format.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
esac

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

if ! command -v clang-format >/dev/null 2>&1; then
  SUDO=()
  [[ "$(id -u)" -ne 0 ]] && SUDO=(sudo)
  echo "[format] installing clang-format: ${SUDO[*]:+${SUDO[*]} }apt-get install -y clang-format"
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends clang-format
fi

mapfile -t files < <(git ls-files '*.cpp' '*.hpp')
if ((check)); then
  bad=()
  for f in "${files[@]}"; do
    clang-format --dry-run -Werror "$f" >/dev/null 2>&1 || bad+=("$f")
  done
  if ((${#bad[@]})); then
    echo "[format] not formatted (run: bash scripts/format.sh): ${bad[*]}" >&2
    exit 1
  fi
  echo "[format] all ${#files[@]} C++ files are formatted ($(clang-format --version))"
else
  # Twice: clang-format 14 can need a second pass where it breaks a long string literal.
  clang-format -i "${files[@]}"
  clang-format -i "${files[@]}"
  echo "[format] formatted ${#files[@]} C++ files"
fi
