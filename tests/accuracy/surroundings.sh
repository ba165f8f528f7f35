#!/usr/bin/env bash
# The miss model against the true surroundings: how much of each scene's error is the
# miss model's guess at what the frame does not show. For each procedural scene of the training
# set, renders once into the training cache what surrounds the camera at one frame (scenes.py
# --panorama: lat-long maps from the camera's position and from the mean position of the
# surfaces it sees, 256 samples times the scene's SAMPLES_FACTOR), takes the light their
# surfaces send (Combined - Env - Emit: no sky and no emitter's own emission, which Cycles puts
# in the direct pass and ssgi's misses leave out), and runs ssgi on that frame without the
# temporal stage three times: with its miss model, and with every miss looking either map up in
# its direction (--miss env --env MAP --env-up z). A map is what one point sees, not what the
# surface a ray leaves would see (parallax: a wall near the camera fills half the camera's map
# and a small part of what the room's other surfaces see), so those columns say how well the
# surroundings known from one point would do, not what perfect knowledge would. Prints a
# markdown table, a row per scene (the oracle ambient, ssgi's relRMSE -- RMSE of `indirect`
# against DiffInd divided by the truth's mean, over surface pixels and all channels -- and level
# with its miss model, and with each map: truth_error's columns for that frame) and their means. Not run by ctest: needs blender and
# the training cache (training/render.sh).
# Usage: tests/accuracy/surroundings.sh [BUILD_DIR] [-- extra ssgi options]
# Environment: SSGI_SURROUNDINGS_FRAME (default 4), and training.sh's SSGI_TRAINING_SCENES,
# SSGI_TRAINING_CACHE, BLENDER.
set -euo pipefail
source "$(dirname "$0")/common.sh"

frame=${SSGI_SURROUNDINGS_FRAME:-4}
blender=${BLENDER:-blender}
mapfile -t scenes < <(training_scenes)
[ ${#scenes[@]} -gt 0 ] || { echo "surroundings.sh: no scenes" >&2; exit 1; }
cache=$(tests/accuracy/training/render.sh "${scenes[@]}" | tail -n 1)
f=$(printf '%04d' "$frame")

printf '| scene | frame | oracle ambient | ssgi | level | surroundings from the camera | level | from the surfaces | level |\n'
printf '|---|---|---|---|---|---|---|---|---|\n'
# run SCENE [ssgi options]: truth_error's columns for the frame.
run() {
  local scene=$1
  shift
  rm -f "$out"/o.*.exr
  "$ssgi" run "$cache/$scene/$scene.####.exr" --frames "$frame" --temporal none \
    -o "$out/o.####.exr" -q --no-passthrough "${extra[@]}" "$@"
  "$truth" "$cache/$scene/$scene.$f.exr" "$out/o.$f.exr"
}
rows=()
for scene in "${scenes[@]}"; do
  row=$(run "$scene")
  for at in camera surfaces; do
    panorama=$cache/$scene/${scene}_panorama_$at.$f.exr
    if ! iinfo --stats "$panorama" > /dev/null 2>&1; then
      rm -f "$panorama"
      "$blender" -b --factory-startup --python-exit-code 1 \
        -P tests/accuracy/training/scenes.py -- --scene "$scene" --out "$out/render" \
        --panorama "$frame" --panorama-at "$at" > "$out/blender.log" 2>&1 ||
        { cat "$out/blender.log" >&2; exit 1; }
      mv "$out/render/${scene}_panorama_$at.$f.exr" "$panorama"
    fi
    v=ViewLayer
    oiiotool "$panorama" --ch "$v.Combined.R,$v.Combined.G,$v.Combined.B" \
      "$panorama" --ch "$v.Env.R,$v.Env.G,$v.Env.B" --sub \
      "$panorama" --ch "$v.Emit.R,$v.Emit.G,$v.Emit.B" --sub \
      --chnames R,G,B -d float -o "$out/surroundings.exr"
    row+=" $(run "$scene" --miss env --env "$out/surroundings.exr" --env-up z)"
  done
  read -r -a c <<< "$row"
  # truth_error: 7 columns per run; [1] relRMSE of indirect, [4] oracle ambient, [5] level.
  printf '| %s | %s | %.3f | %.3f | %.2f | %.3f | %.2f | %.3f | %.2f |\n' "$scene" "$frame" \
    "${c[4]}" "${c[1]}" "${c[5]}" "${c[8]}" "${c[12]}" "${c[15]}" "${c[19]}"
  rows+=("${c[4]} ${c[1]} ${c[8]} ${c[15]}")
done
printf '%s\n' "${rows[@]}" | awk '{ o += $1; i += $2; a += $3; b += $4; n++ }
  END { printf "| **mean** | %d scenes | %.3f | %.3f | | %.3f | | %.3f | |\n",
    n, o / n, i / n, a / n, b / n }'
