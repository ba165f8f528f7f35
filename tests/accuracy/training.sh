#!/usr/bin/env bash
# Accuracy over every scene: the two Cycles sample scenes in ../shared/data and the
# training set of tests/accuracy/training (rendered with Blender into a cache on first use, see
# training/render.sh: the first run takes hours). Prints a markdown table, one row per scene,
# of the relative RMSE of `indirect` against the path-traced DiffInd over surface pixels (RMSE
# / mean of the truth, all channels, averaged over frames; truth_error) for no GI, for the
# oracle ambient (the truth's own mean DiffInd per channel and frame as a constant) and for
# ssgi with the given options (its default settings when none), ssgi's level (the mean of its
# indirect over the truth's: below 1 too dark overall, above 1 too bright), ssgi's error at the
# truth's level (its indirect scaled per channel and frame to the truth's mean: the error left
# when the overall level is right), with ssgi's wall time per frame, and a last row of the
# means over all scenes. Not run by ctest: too slow, and needs
# blender.
# Usage: tests/accuracy/training.sh [BUILD_DIR] [-- extra ssgi options]
# Environment: SSGI_TRAINING_SCENES (training scenes to measure, space-separated, " " for
# none; default all that training/scenes.py lists), render.sh's SSGI_TRAINING_CACHE, BLENDER.
set -euo pipefail
source "$(dirname "$0")/common.sh"

declare -A what=(
  [room]="interior, sun through a window; camera pans (sample data)"
  [stage]="blocks under a spot light, a rolling ball; static camera (sample data)"
)
if [ -n "${SSGI_TRAINING_SCENES:-}" ]; then
  read -r -a training <<< "$SSGI_TRAINING_SCENES"
else
  training=()
fi
while IFS=$'\t' read -r tag name description; do
  [ "$tag" = "SCENE" ] || continue
  what[$name]=$description
  [ -n "${SSGI_TRAINING_SCENES:-}" ] || training+=("$name")
done < <("${BLENDER:-blender}" -b --factory-startup --python-exit-code 1 \
  -P tests/accuracy/training/scenes.py -- --list 2> /dev/null)
cache=
[ ${#training[@]} -eq 0 ] || cache=$(tests/accuracy/training/render.sh "${training[@]}" | tail -n 1)

printf '| scene | what it exercises | no GI | oracle ambient | ssgi | ssgi level | ssgi at the truth'"'"'s level | s/frame |\n'
printf '|---|---|---|---|---|---|---|---|\n'
rows=()
for scene in room stage "${training[@]}"; do
  case $scene in
    room | stage) dir=$data/$scene ;;
    *) dir=$cache/$scene ;;
  esac
  frames=("$dir/$scene".*.exr)
  rm -f "$out"/o.*.exr
  start=$(date +%s.%N)
  "$ssgi" run "$dir/$scene.####.exr" -o "$out/o.####.exr" -q --no-passthrough "${extra[@]}"
  end=$(date +%s.%N)
  seconds=$(echo "($end - $start) / ${#frames[@]}" | bc -l | xargs printf '%.2f')
  read -r nogi ind _ _ oracle level leveled <<< "$(truth_means "$dir" "$scene")"
  printf '| %s | %s | %s | %s | %s | %s | %s | %s |\n' "$scene" "${what[$scene]:-}" "$nogi" \
    "$oracle" "$ind" "$level" "$leveled" "$seconds"
  rows+=("$nogi $oracle $ind $level $leveled $seconds")
done
printf '%s\n' "${rows[@]}" | awk '{ z += $1; o += $2; i += $3; l += $4; e += $5; s += $6; n++ }
  END { printf "| **mean** | %d scenes | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f |\n",
    n, z / n, o / n, i / n, l / n, e / n, s / n }'
