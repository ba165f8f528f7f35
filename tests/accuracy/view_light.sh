#!/usr/bin/env bash
# How right the light ssgi computes for the views is: a continued ray brings the light of the
# view surface it meets (what it reflects plus its albedo times the indirect light ssgi gives the
# view), so a view lit too dark or too bright moves every frame it serves. For each training
# scene, renders once the six 128x128 cube faces at the shot camera of one frame with their
# path-traced diffuse indirect light (tests/blender/render_views.py --with-indirect, SSGI_VIEWS_
# SAMPLES samples, default 64), then runs ssgi on each face as a frame (--temporal none),
# alone and with the other five as its views (--view x 5: how the views light one another in a
# run), and measures its indirect against the face's DiffInd (truth_error, as training.sh).
# Prints a markdown table, a row per scene: how many faces show a surface (the others have no
# truth to measure against), the relative RMSE and level (the mean of the indirect over the
# truth's), the median over those faces, alone and with the others, and the lowest and highest
# face level with the others; and the means of the medians. Not run by ctest: it renders
# with Blender.
# Usage: tests/accuracy/view_light.sh [BUILD_DIR] [-- extra ssgi options]
# Environment: SSGI_VIEW_LIGHT_FRAME (default 4), SSGI_VIEWS_SAMPLES, and render.sh's
# SSGI_TRAINING_SCENES, SSGI_TRAINING_CACHE, SSGI_TRAINING_SAMPLES, SSGI_TRAINING_RESOLUTION,
# SSGI_TRAINING_FRAMES, BLENDER.
set -euo pipefail
source "$(dirname "$0")/common.sh"
blender=${BLENDER:-blender}
mapfile -t scenes < <(training_scenes)
[ ${#scenes[@]} -gt 0 ] || { echo "view_light.sh: no scenes" >&2; exit 1; }
cache=$(tests/accuracy/training/render.sh "${scenes[@]}" | tail -n 1)
frame=${SSGI_VIEW_LIGHT_FRAME:-4}
samples=${SSGI_VIEWS_SAMPLES:-64}
frames=${SSGI_TRAINING_FRAMES:-8}
resolution=${SSGI_TRAINING_RESOLUTION:-320x180}
faces=(px nx py ny pz nz)

# render_faces SCENE: the faces of frame $frame with DiffInd in $cache/SCENE.view_light, once
# (a "done" file marks them whole).
render_faces() {
  local dir=$cache/$1.view_light
  [ -f "$dir/done.$frame" ] && return 0
  mkdir -p "$dir"
  save_scene_blend "$1" "$dir" "$frames" "$resolution"
  "$blender" -b "$dir/$1.blend" --python-exit-code 1 --python tests/blender/render_views.py \
    -- --out "$dir" --name "$1" --frames "$frame" --face-size 128 --samples "$samples" \
    --faces-only --with-indirect >> "$dir/blender.log" 2>&1
  touch "$dir/done.$frame"
}

printf '| scene | faces | alone | level | with the other faces | level | face levels with them |\n'
printf '|---|---|---|---|---|---|---|\n'
rows=()
for scene in "${scenes[@]}"; do
  render_faces "$scene"
  dir=$cache/$scene.view_light
  f=$(printf '%04d' "$frame")
  for face in "${faces[@]}"; do
    others=()
    for g in "${faces[@]}"; do
      [ "$g" = "$face" ] || others+=(--view "$dir/$scene.$g.####.exr")
    done
    for kind in alone views; do
      with=()
      [ $kind = views ] && with=("${others[@]}")
      "$ssgi" run "$dir/$scene.$face.####.exr" --frames "$frame" -o "$out/$kind.####.exr" -q \
        --temporal none --no-passthrough "${with[@]}" "${extra[@]}"
      read -r _ ind _ _ _ level _ <<< "$("$truth" "$dir/$scene.$face.$f.exr" "$out/$kind.$f.exr")"
      printf '%s %s ' "$ind" "$level"
    done
    printf '\n'
  done > "$out/faces"
  # A face that shows no surface (the sky above an exterior) has no truth to measure against;
  # one that shows a sliver has a tiny one, so a scene's faces are summed up by their median.
  row=$(python3 - "$out/faces" <<'PY'
import statistics, sys
rows = [list(map(float, line.split())) for line in open(sys.argv[1]) if "nan" not in line]
med = [statistics.median(r[c] for r in rows) for c in range(4)]
levels = [r[3] for r in rows]
print("%.3f %.2f %.3f %.2f %.2f %.2f %d" % (*med, min(levels), max(levels), len(rows)))
PY
  )
  read -r a al v vl lo hi n <<< "$row"
  printf '| %s | %s | %s | %s | %s | %s | %s-%s |\n' "$scene" "$n" "$a" "$al" "$v" "$vl" "$lo" "$hi"
  rows+=("$row")
done
printf '%s\n' "${rows[@]}" | awk '{ for (c = 1; c <= 4; ++c) s[c] += $c; n++ }
  END { printf "| **mean**, %d scenes | | %.3f | %.2f | %.3f | %.2f | |\n",
    n, s[1] / n, s[2] / n, s[3] / n, s[4] / n }'
