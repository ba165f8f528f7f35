#!/usr/bin/env bash
# The README's accuracy table: runs ssgi on the Cycles sample sequences in ../shared/data and
# prints, per scene and setting, the relative RMSE (RMSE / mean of the truth over surface
# pixels, all channels, averaged over frames) of `indirect` against the path-traced DiffInd and
# of the composite against (DiffDir + DiffInd) x DiffCol + Emit, with the wall time of one
# `ssgi run` over the six-frame sequence divided by six. Usage: tests/accuracy/accuracy.sh [BUILD_DIR] [-- extra ssgi options]
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
shift || true
[ "${1:-}" = "--" ] && shift
extra=("$@")
data=../shared/data
ssgi=$build/bin/ssgi
truth=$build/bin/truth_error
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

settings=(
  "no GI|"
  "env black, 1 bounce|--miss env --bounces 1 --temporal none"
  "env black, 8 bounces|--miss env --temporal none"
  "frame estimate, 8 bounces|--miss frame --temporal none"
  "edge extension, 8 bounces (march)|--miss extend --temporal none --tracer march --max-steps 64"
  "auto, 8 bounces, no temporal|--temporal none"
  "march (the previous default: 8 rays, 64 steps)|--tracer march --max-steps 64"
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
    read -r ind comp <<< "$(for f in "${frames[@]}"; do
      n=${f##*.0}
      "$truth" "$f" "$out/o.0$n"
    done | awk -v nogi="$([ "$name" = "no GI" ] && echo 1 || echo 0)" \
      '{ if (nogi) { i += $1; c += $3 } else { i += $2; c += $4 }; n++ }
       END { printf "%.3f %.3f", i / n, c / n }')"
    printf '| %s | %s | %s | %s | %s |\n' "$scene" "$name" "$ind" "$comp" "$seconds"
  done
done
