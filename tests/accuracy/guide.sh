#!/usr/bin/env bash
# What a guide (--guide) does to ssgi's accuracy on the training set (training/scenes.py): each
# scene's shot as training/render.sh renders it (the truth), and a guide of it rendered by
# render.sh as well (SSGI_TRAINING_GUIDE: SSGI_GUIDE_SAMPLES samples, default 4, a seed of its own
# per frame, seed 2, at 1 / SSGI_GUIDE_FRACTION of the shot's resolution, default 1) into
# SSGI_GUIDE_CACHE. Prints a markdown table, one row per scene, of the relative RMSE of
# `indirect` against the path-traced DiffInd (truth_error, as training.sh) for ssgi alone, for
# the guide blurred alone (blurred_guide: three passes of a box of radius 4 over the surface
# pixels) and for ssgi with the guide, each with its level (the mean of its indirect over the
# truth's); the change of ssgi with the guide against the guide blurred alone; the guide's
# render time and ssgi's wall time per frame without and with it; and the means.
# With SSGI_TRUTH_SECOND (a cache folder), every shot is rendered there again with seed 1
# (render.sh, SSGI_TRAINING_SEED), and each error is measured against the two renders' mean with
# the truth's own noise taken out (truth_error --second), as views.sh does.
# Not run by ctest: it renders with Blender.
# Usage: tests/accuracy/guide.sh [BUILD_DIR] [-- extra ssgi options]
# Environment: SSGI_TRAINING_SCENES (space-separated; default every training scene), render.sh's
# SSGI_TRAINING_CACHE, SSGI_TRAINING_SAMPLES, SSGI_TRAINING_RESOLUTION, SSGI_TRAINING_FRAMES;
# SSGI_GUIDE_SAMPLES, SSGI_GUIDE_FRACTION, SSGI_GUIDE_CACHE (default
# ~/.cache/ssgi/guide<samples>, with "f<fraction>" after it for a fraction), SSGI_TRUTH_SECOND,
# BLENDER.
set -euo pipefail
source "$(dirname "$0")/common.sh"
mapfile -t scenes < <(training_scenes)
cache=$(tests/accuracy/training/render.sh "${scenes[@]}" | tail -n 1)
resolution=${SSGI_TRAINING_RESOLUTION:-320x180}
guide_samples=${SSGI_GUIDE_SAMPLES:-4}
fraction=${SSGI_GUIDE_FRACTION:-1}
default_guides=$HOME/.cache/ssgi/guide$guide_samples
[ "$fraction" = 1 ] || default_guides+=f$fraction
guides=${SSGI_GUIDE_CACHE:-$default_guides}
width=${resolution%x*}
height=${resolution#*x}
if (( width % fraction || height % fraction )); then
  echo "guide.sh: $resolution is not divisible by SSGI_GUIDE_FRACTION=$fraction" >&2
  exit 2
fi
SSGI_TRAINING_CACHE=$guides SSGI_TRAINING_GUIDE=1 SSGI_TRAINING_SAMPLES=$guide_samples \
  SSGI_TRAINING_SEED=2 SSGI_TRAINING_RESOLUTION=$((width / fraction))x$((height / fraction)) \
  tests/accuracy/training/render.sh "${scenes[@]}" > /dev/null
second=${SSGI_TRUTH_SECOND:-}
if [ -n "$second" ]; then
  SSGI_TRAINING_CACHE=$second SSGI_TRAINING_SEED=1 tests/accuracy/training/render.sh \
    "${scenes[@]}" > /dev/null
fi
blur=$build/bin/blurred_guide

# run NAME [ssgi options]: ssgi over the scene's shot into $out/o.*.exr; prints s/frame.
run() {
  local name=$1 frames start end
  shift
  frames=("$cache/$name/$name".*.exr)
  rm -f "$out"/o.*.exr
  start=$(date +%s.%N)
  "$ssgi" run "$cache/$name/$name.####.exr" -o "$out/o.####.exr" -q --no-passthrough \
    "${extra[@]}" "$@"
  end=$(date +%s.%N)
  echo "($end - $start) / ${#frames[@]}" | bc -l | xargs printf '%.2f'
}

# measure NAME: truth_means' relRMSE and level of $out/o.*.exr, as "relRMSE level".
measure() {
  local columns
  read -r -a columns <<< "$(truth_means "$cache/$1" "$1" "$second")"
  echo "${columns[1]} ${columns[5]}"
}

printf '| scene | ssgi | level | guide blurred | level | ssgi + guide | level | against blurred |'
printf ' guide render s/frame | ssgi s/frame | with guide |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|\n'
rows=()
for scene in "${scenes[@]}"; do
  alone_s=$(run "$scene")
  read -r alone alone_level <<< "$(measure "$scene")"
  rm -f "$out"/o.*.exr
  for f in "$cache/$scene/$scene".*.exr; do
    n=${f%.exr}
    "$blur" "$f" "$guides/$scene/${f##*/}" "$out/o.${n##*.}.exr"
  done
  read -r blurred blurred_level <<< "$(measure "$scene")"
  guided_s=$(run "$scene" --guide "$guides/$scene/$scene.####.exr")
  read -r guided guided_level <<< "$(measure "$scene")"
  render_s=$(sed -n 's/.*, \([0-9]*\) s\/frame.*/\1/p' "$guides/$scene/render.txt")
  change=$(echo "100 * ($guided - $blurred) / $blurred" | bc -l | xargs printf '%+.0f%%')
  printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$scene" "$alone" \
    "$alone_level" "$blurred" "$blurred_level" "$guided" "$guided_level" "$change" "$render_s" \
    "$alone_s" "$guided_s"
  rows+=("$alone $alone_level $blurred $blurred_level $guided $guided_level $render_s $alone_s $guided_s")
done
printf '%s\n' "${rows[@]}" | awk '{ for (c = 1; c <= NF; ++c) s[c] += $c; n++ }
  END { printf "| **mean** | %.3f | %.2f | %.3f | %.2f | %.3f | %.2f | %+.0f%% | %.0f | %.2f | %.2f |\n",
    s[1] / n, s[2] / n, s[3] / n, s[4] / n, s[5] / n, s[6] / n, 100 * (s[5] - s[3]) / s[3],
    s[7] / n, s[8] / n, s[9] / n }'
