#!/usr/bin/env bash
# Frames as Blender writes them: every scene of training.sh (the two Cycles sample scenes and the
# training set) with the camera attributes removed from its headers (worldToCamera, worldToNDC,
# screenWindowCenter, screenWindowWidth), run with no camera option, so that ssgi fits the camera
# to the Position pass, against the same frames with their true camera in the header. Prints a
# markdown table, one row per scene: the true horizontal fov (info on the frame with its header
# camera) and the fitted one (info on the stripped frame, first frame; the largest difference
# over the frames is the next column), the fit's residual in pixels, the relative RMSE of
# `indirect` against the path-traced DiffInd (RMSE / mean of the truth over surface pixels, all
# channels, averaged over frames; truth_error) with the true camera and with the fitted one, and
# their ratio. Exits 1 when a scene's fov is off by more than 0.2 degrees or its error with the
# fitted camera is more than 2% above the error with the true one. Not run by ctest: needs the
# renders (training/render.sh) and takes minutes.
# Usage: tests/accuracy/as_rendered.sh [BUILD_DIR] [-- extra ssgi options]
# Environment: as training.sh (SSGI_TRAINING_SCENES, SSGI_TRAINING_CACHE, BLENDER).
set -euo pipefail
source "$(dirname "$0")/common.sh"

mapfile -t training < <(training_scenes)
cache=
[ ${#training[@]} -eq 0 ] || cache=$(tests/accuracy/training/render.sh "${training[@]}" | tail -n 1)

# info_fovs FILE...: "fov residual" per file, from info --json (residual 0 without a fit).
info_fovs() {
  "$ssgi" info "$@" --json | python3 -c '
import json, sys
for c in json.load(sys.stdin)["cameras"]:
    print(c["hfov_deg"], c.get("fit_residual_px", 0))'
}

# relrmse DIR SCENE: truth_error's relative RMSE of indirect, averaged over the frames
# DIR/SCENE.*.exr, against $out/o.<frame>.exr.
relrmse() {
  local f n
  for f in "$1/$2".*.exr; do
    n=${f%.exr}
    "$truth" "$f" "$out/o.${n##*.}.exr"
  done | awk '{ s += $2; n++ } END { printf "%.5f\n", s / n }'
}

printf '| scene | true fov | fitted fov | largest fov difference | fit residual px | relRMSE true camera | relRMSE fitted | ratio |\n'
printf '|---|---|---|---|---|---|---|---|\n'
failed=0
for scene in room stage "${training[@]}"; do
  case $scene in
    room | stage) dir=$data/$scene ;;
    *) dir=$cache/$scene ;;
  esac
  stripped=$out/stripped
  rm -rf "$stripped" && mkdir -p "$stripped"
  for f in "$dir/$scene".*.exr; do
    oiiotool --nosoftwareattrib "$f" --eraseattrib worldToCamera --eraseattrib worldToNDC \
      --eraseattrib screenWindowCenter --eraseattrib screenWindowWidth -o "$stripped/$(basename "$f")"
  done
  if "$ssgi" info "$stripped/$scene.0001.exr" 2>&1 | grep 'worldToCamera' > /dev/null; then
    echo "as_rendered.sh: $scene: the camera attributes were not removed" >&2
    exit 1
  fi
  mapfile -t truth_cams < <(info_fovs "$dir/$scene.####.exr")
  mapfile -t fit_cams < <(info_fovs "$stripped/$scene.####.exr")
  read -r true_fov _ <<< "${truth_cams[0]}"
  read -r fit_fov residual <<< "${fit_cams[0]}"
  worst=$(paste -d' ' <(printf '%s\n' "${truth_cams[@]}") <(printf '%s\n' "${fit_cams[@]}") |
    awk '{ d = $1 - $3; if (d < 0) d = -d; if (d > w) w = d; if ($4 > r) r = $4 }
      END { printf "%.5f %.2g\n", w, r }')
  read -r worst_fov worst_residual <<< "$worst"
  rm -f "$out"/o.*.exr
  "$ssgi" run "$dir/$scene.####.exr" -o "$out/o.####.exr" -q --no-passthrough "${extra[@]}"
  with_true=$(relrmse "$dir" "$scene")
  rm -f "$out"/o.*.exr
  "$ssgi" run "$stripped/$scene.####.exr" -o "$out/o.####.exr" -q --no-passthrough "${extra[@]}"
  with_fit=$(relrmse "$dir" "$scene")
  ratio=$(echo "$with_fit / $with_true" | bc -l | xargs printf '%.4f')
  printf '| %s | %.4f | %.4f | %s | %s | %s | %s | %s |\n' "$scene" "$true_fov" "$fit_fov" \
    "$worst_fov" "$worst_residual" "$with_true" "$with_fit" "$ratio"
  if awk -v w="$worst_fov" -v r="$ratio" 'BEGIN { exit !(w > 0.2 || r > 1.02) }'; then
    echo "as_rendered.sh: $scene: fov off by $worst_fov degrees, error ratio $ratio" >&2
    failed=1
  fi
done
exit $failed
