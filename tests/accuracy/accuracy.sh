#!/usr/bin/env bash
# The accuracy table of README.md and tests/accuracy/README.md: runs ssgi on the Cycles sample
# sequences in ../shared/data and prints, per scene and setting, the relative RMSE (RMSE / mean
# of the truth over surface pixels, all channels, averaged over frames) of `indirect` against
# the path-traced DiffInd and of the composite against (DiffDir + DiffInd) x DiffCol + Emit,
# with the wall time of one `ssgi run` over the six-frame sequence divided by six.
# Usage: tests/accuracy/accuracy.sh [BUILD_DIR] [-- extra ssgi options]
set -euo pipefail
source "$(dirname "$0")/common.sh"

settings=(
  "no GI|"
  "env black, 1 bounce|--miss env --bounces 1 --temporal none"
  "env black, 8 bounces|--miss env --temporal none"
  "frame estimate, 8 bounces|--miss frame --temporal none"
  "edge extension, 8 bounces (march)|--miss extend --temporal none --tracer march --max-steps 64"
  "auto, 8 bounces, no temporal|--temporal none"
  "march (8 rays, 64 steps)|--tracer march --max-steps 64"
  "preset draft|--preset draft"
  "default (slices 2x28, auto, 8 bounces, window ±2)|"
  "preset final|--preset final"
)
printf '| scene | setting | relRMSE indirect | relRMSE composite | s/frame |\n'
printf '|---|---|---|---|---|\n'
for scene in room stage; do
  frames=("$data/$scene/$scene".*.exr)
  for entry in "${settings[@]}"; do
    name=${entry%%|*}
    read -r -a opts <<< "${entry#*|}"
    seconds="-"
    if [ "$name" != "no GI" ]; then
      start=$(date +%s.%N)
      "$ssgi" run "$data/$scene/$scene.####.exr" -o "$out/o.####.exr" -q --no-passthrough \
        "${opts[@]}" "${extra[@]}"
      end=$(date +%s.%N)
      seconds=$(echo "($end - $start) / ${#frames[@]}" | bc -l | xargs printf '%.2f')
    else
      "$ssgi" run "$data/$scene/$scene.####.exr" -o "$out/o.####.exr" -q --no-passthrough \
        --rays 1 --bounces 1 --temporal none
    fi
    read -r ind0 ind comp0 comp _ <<< "$(truth_means "$data/$scene" "$scene")"
    [ "$name" != "no GI" ] || { ind=$ind0; comp=$comp0; }
    printf '| %s | %s | %s | %s | %s |\n' "$scene" "$name" "$ind" "$comp" "$seconds"
  done
done
