#!/usr/bin/env bash
# The main job: set up and build SoftKin, then bend the embedded pneumatic finger through its
# range (thesis Fig. 2.11 / Table 2.2) and plot the tip trajectory.
set -euo pipefail

CONFIG=experiments/configs/fig2_11_pneumatic_bending.json
NAME=fig2_11_pneumatic_bending

usage() {
  cat <<USAGE
Usage: bash scripts/main.sh [--help] [softkin run options...]

  1. bash scripts/setup.sh   (missing Debian packages, Release build in build/)
  2. build/bin/softkin run $CONFIG [options]

Options are passed to \`softkin run\` unchanged, for example:
  --quick           the config's small settings (a coarse mesh, few steps)
  --no-plot         skip the paper_figs plot script
  --results DIR     results root (default: results)

Output: results/$NAME/{summary.json, config.json, run.json, trajectory.csv, fem_trajectory.csv}
        and results/$NAME/$NAME.png
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

# Where the results will go: honour --results DIR / --results=DIR if given.
RESULTS_ROOT=results
prev=""
for arg in "$@"; do
  if [[ "$prev" == "--results" ]]; then RESULTS_ROOT="$arg"; fi
  case "$arg" in --results=*) RESULTS_ROOT="${arg#--results=}" ;; esac
  prev="$arg"
done

bash scripts/setup.sh

echo "[main] running: $BUILD_DIR/bin/softkin run $CONFIG $*"
"$BUILD_DIR/bin/softkin" run "$CONFIG" "$@"

OUT="$RESULTS_ROOT/$NAME"
[[ "$OUT" = /* ]] || OUT="$ROOT/$OUT"
echo "[main] results: $OUT/ (summary.json, trajectory.csv, fem_trajectory.csv, config.json, run.json)"
if [[ -f "$OUT/$NAME.png" ]]; then
  echo "[main] figure:  $OUT/$NAME.png"
else
  echo "[main] no figure was written (was --no-plot given?)"
fi
