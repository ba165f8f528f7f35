#!/usr/bin/env bash
# Region renders: a shot cropped to a data window inside the display window (as a
# renderer's region render or a compositor's bounding box writes it) must get the light the
# full frame gets over the same pixels. Per scene and region (each a quarter of the display
# window: its centre and its four corner quadrants), the mean of `indirect` over the region in
# a run on the cropped shot over the mean over the same pixels in a run on the whole shot, all
# frames; 1 is the same light: the crop alone, and the crop with the whole shot as its
# --context. Prints a markdown table. Not run by ctest.
# Usage: tests/accuracy/region.sh [BUILD_DIR] [-- extra ssgi options]
# Environment: SSGI_REGION_SCENES (directories holding SCENE/SCENE.####.exr, default the two
# sample scenes of ../shared/data; e.g. "$HOME/.cache/ssgi/training/plaza" adds a training scene).
set -euo pipefail
source "$(dirname "$0")/common.sh"

read -r -a scenes <<< "${SSGI_REGION_SCENES:-$data/room $data/stage}"
# mean_indirect FILE...: the mean of indirect.{R,G,B} over the files' data windows.
mean_indirect() {
  local f
  for f in "$@"; do
    oiiotool "$f" --ch indirect.R,indirect.G,indirect.B --printstats 2> /dev/null |
      sed -n 's/^ *Stats Avg: *//p' | head -n 1
  done | awk '{ s += ($1 + $2 + $3) / 3; n++ } END { printf "%.6f", s / n }'
}

printf '| scene | region | mean indirect, region render / whole frame | with --context |\n'
printf '|---|---|---|---|\n'
for dir in "${scenes[@]}"; do
  scene=$(basename "$dir")
  frames=("$dir/$scene".*.exr)
  read -r w h < <(oiiotool --info "${frames[0]}" |
    sed -n 's/.*: *\([0-9]*\) x *\([0-9]*\),.*/\1 \2/p')
  "$ssgi" run "$dir/$scene.####.exr" -o "$out/whole.####.exr" -q --no-passthrough "${extra[@]}"
  hw=$((w / 2)) hh=$((h / 2))
  for region in "centre ${hw}x${hh}+$((w / 4))+$((h / 4))" "top-left ${hw}x${hh}+0+0" \
    "top-right ${hw}x${hh}+$((w - hw))+0" "bottom-left ${hw}x${hh}+0+$((h - hh))" \
    "bottom-right ${hw}x${hh}+$((w - hw))+$((h - hh))"; do
    read -r name geom <<< "$region"
    rm -f "$out"/crop.*.exr "$out"/region.*.exr "$out"/part.*.exr
    for f in "${frames[@]}"; do
      n=${f%.exr}
      n=${n##*.}
      # --crop keeps the display window and shrinks the data window to the region.
      oiiotool "$f" --crop "$geom" -o "$out/crop.$n.exr"
      oiiotool "$out/whole.$n.exr" --crop "$geom" -o "$out/part.$n.exr"
    done
    whole=$(mean_indirect "$out"/part.*.exr)
    ratios=()
    for context in "" "$dir/$scene.####.exr"; do
      "$ssgi" run "$out/crop.####.exr" -o "$out/region.####.exr" -q --no-passthrough \
        ${context:+--context "$context"} "${extra[@]}"
      ratios+=("$(echo "$(mean_indirect "$out"/region.*.exr) / $whole" | bc -l)")
    done
    printf '| %s | %s (%s) | %.3f | %.3f |\n' "$scene" "$name" "$geom" "${ratios[@]}"
  done
done
