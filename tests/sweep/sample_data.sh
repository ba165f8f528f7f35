#!/usr/bin/env bash
# Makes the README's sweep tables and plots: `ssgi sweep` over each sample scene (every preset
# and the grid, against the 256-ray reference and Cycles' DiffInd, five rounds of timing),
# written here as SCENE.csv, SCENE.json and SCENE.png. It builds nothing: run .ci/setup first.
# Usage: tests/sweep/sample_data.sh [BUILD_DIR] [DATA_DIR]   (relative to the repository root;
# default: build ../shared/data)
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
data=${2:-../shared/data}
for scene in room stage; do
  "$build/bin/ssgi" sweep "$data/$scene/$scene.####.exr" --truth DiffInd --grid --repeat 5 \
    -o "tests/sweep/$scene.csv" --json "tests/sweep/$scene.json" --plot "tests/sweep/$scene.png"
done
