#!/usr/bin/env bash
# The temporal table of tests/accuracy/README.md: per Cycles sample scene and --temporal mode,
# the relative RMSE of `indirect` against DiffInd (RMSE / mean of the truth over surface pixels,
# all channels, averaged over frames) and the temporal stability (mean absolute
# frame-to-frame change of `indirect` on static surfaces, relative to its mean; the truth's own
# change beside it). Usage: tests/accuracy/temporal.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
data=../shared/data
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
printf '| scene | --temporal | relRMSE indirect | relRMSE composite | frame-to-frame change | truth'"'"'s change |\n'
printf '|---|---|---|---|---|---|\n'
for scene in stage room; do
  static_camera=$([ "$scene" = stage ] && echo 1 || echo 0)
  for mode in none ema window; do
    "$build/bin/ssgi" run "$data/$scene/$scene.####.exr" -o "$out/o.####.exr" -q --temporal "$mode"
    read -r ind comp <<< "$(for f in "$data/$scene/$scene".*.exr; do
      n=${f##*.0}; "$build/bin/truth_error" "$f" "$out/o.0${n}"
    done | awk '{ i += $2; c += $4; n++ } END { printf "%.3f %.3f", i / n, c / n }')"
    read -r ours truth _ <<< "$("$build/bin/temporal_stability" "$data/$scene/$scene.####.exr" \
      "$out/o.####.exr" 1 6 "$static_camera")"
    printf '| %s | %s | %s | %s | %.1f%% | %.1f%% |\n' "$scene" "$mode" "$ind" "$comp" \
      "$(echo "$ours * 100" | bc -l)" "$(echo "$truth * 100" | bc -l)"
  done
done
