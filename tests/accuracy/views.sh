#!/usr/bin/env bash
# What views (--view, --latlong-view) do to ssgi's accuracy on the training set
# (training/scenes.py): each scene's shot as training/render.sh renders it (the same cache), and
# per frame its views rendered by tests/blender/render_views.py from the scene saved as a .blend:
# six 128x128 cube faces and a 512x256 lat-long at the shot camera, SSGI_VIEWS_SAMPLES samples
# (default 64), kept beside the shot in the cache (SCENE.views/). Prints a markdown table, one
# row per scene, of the relative RMSE of `indirect` against the path-traced DiffInd (truth_error,
# as training.sh) for the oracle ambient, ssgi without views, with the six faces and with the
# lat-long, each with its level (the mean of its indirect over the truth's), and the means.
# The sample data's scenes (room, stage) have no .blend to render views from and are not in it.
# With SSGI_TRUTH_SECOND (a cache folder), every shot is rendered there again with seed 1
# (render.sh, SSGI_TRAINING_SEED), and each error is measured against the two renders' mean with
# the truth's own noise taken out (truth_error --second): an estimate of the error against the
# noise-free light; a last column gives one render's noise (its relative RMSE).
# Not run by ctest: it renders with Blender.
# Usage: tests/accuracy/views.sh [BUILD_DIR] [-- extra ssgi options]
# Environment: SSGI_TRAINING_SCENES (space-separated; default every training scene), render.sh's
# SSGI_TRAINING_CACHE, SSGI_TRAINING_SAMPLES, SSGI_TRAINING_RESOLUTION, SSGI_TRAINING_FRAMES;
# SSGI_VIEWS_SAMPLES, SSGI_TRUTH_SECOND, BLENDER.
set -euo pipefail
source "$(dirname "$0")/common.sh"
blender=${BLENDER:-blender}
mapfile -t scenes < <(training_scenes)
cache=$(tests/accuracy/training/render.sh "${scenes[@]}" | tail -n 1)
samples=${SSGI_VIEWS_SAMPLES:-64}
frames=${SSGI_TRAINING_FRAMES:-8}
resolution=${SSGI_TRAINING_RESOLUTION:-320x180}
second=${SSGI_TRUTH_SECOND:-}
if [ -n "$second" ]; then
  SSGI_TRAINING_CACHE=$second SSGI_TRAINING_SEED=1 tests/accuracy/training/render.sh \
    "${scenes[@]}" > /dev/null
fi

# render_views SCENE: its views in $cache/SCENE.views, once (a "done" file marks them whole).
render_views() {
  local views=$cache/$1.views
  [ -f "$views/done" ] && return 0
  rm -rf "$views"
  mkdir -p "$views"
  save_scene_blend "$1" "$views" "$frames" "$resolution"
  "$blender" -b "$views/$1.blend" --python-exit-code 1 --python tests/blender/render_views.py \
    -- --out "$views" --name "$1" --frames "1-$frames" --face-size 128 --latlong-width 512 \
    --samples "$samples" >> "$views/blender.log" 2>&1
  touch "$views/done"
}

head='| scene | oracle ambient | ssgi | level | six faces | level | lat-long | level |'
rule='|---|---|---|---|---|---|---|---|'
if [ -n "$second" ]; then head+=' truth noise |' rule+='---|'; fi
printf '%s\n%s\n' "$head" "$rule"
rows=()
for scene in "${scenes[@]}"; do
  render_views "$scene"
  views=$cache/$scene.views
  faces=()
  for f in px nx py ny pz nz; do faces+=(--view "$views/$scene.$f.####.exr"); done
  cells=()
  for kind in none faces latlong; do
    case $kind in
      none) with=() ;;
      faces) with=("${faces[@]}") ;;
      latlong) with=(--latlong-view "$views/$scene.latlong.####.exr") ;;
    esac
    rm -f "$out"/o.*.exr
    "$ssgi" run "$cache/$scene/$scene.####.exr" -o "$out/o.####.exr" -q --no-passthrough \
      "${with[@]}" "${extra[@]}"
    read -r _ ind _ _ oracle level _ noise <<< "$(truth_means "$cache/$scene" "$scene" "$second")"
    cells+=("$ind" "$level")
  done
  if [ -n "$second" ]; then cells+=("$noise"); fi
  line=$(printf '| %s ' "$scene" "$oracle" "${cells[@]}")
  printf '%s|\n' "$line"
  rows+=("$oracle ${cells[*]}")
done
printf '%s\n' "${rows[@]}" | awk '{ for (c = 1; c <= NF; ++c) s[c] += $c; n++; k = NF }
  END { printf "| **mean**, %d scenes | %.3f |", n, s[1] / n
    for (c = 2; c <= k; ++c) printf(c % 2 ? " %.2f |" : " %.3f |", s[c] / n)
    printf "\n" }'
