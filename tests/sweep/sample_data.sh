#!/usr/bin/env bash
# Makes the sweep tables and plots of tests/sweep/README.md: `ssgi sweep` over each sample scene
# (every preset and the grid, against the 256-ray reference and Cycles' DiffInd, five rounds of
# timing), written here as SCENE.csv, SCENE.json and SCENE.png. relRMSE is the RMSE of
# `indirect` divided by the mean of what it is measured against (the reference or DiffInd), over
# surface pixels and all channels, averaged over frames. It builds nothing: run .ci/setup first.
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
