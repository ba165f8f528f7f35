#!/usr/bin/env bash
# Region renders: a shot cropped to a data window inside the display window (as a
# renderer's region render or a compositor's bounding box writes it), against the light the
# full frame gets over the same pixels. Per scene and region (a quarter of the display window
# at its centre and at its four corners, a strip along its bottom and one along its left side,
# a small region at its centre and a large one inside its edges), the mean of `indirect` over
# the region in a run on the cropped shot over the mean over the same pixels in a run on the
# whole shot, all frames, per channel; 1 is the same light. The crop alone (the largest and the
# smallest channel's ratio: at most 1.1, ssgi-run(1), --context), and the crop with the whole
# shot as its --context (the largest channel's). The background has no indirect light, so the
# means over the region are the means over its surfaces, scaled alike. Prints a markdown table.
# Not run by ctest.
# Usage: tests/accuracy/region.sh [BUILD_DIR] [-- extra ssgi options]
# Environment: SSGI_REGION_SCENES (directories holding SCENE/SCENE.####.exr, default the two
# sample scenes of ../shared/data; e.g. "$HOME/.cache/ssgi/training/plaza" adds a training scene).
set -euo pipefail
source "$(dirname "$0")/common.sh"

read -r -a scenes <<< "${SSGI_REGION_SCENES:-$data/room $data/stage}"
# mean_indirect FILE...: the means of indirect.R, G and B over the files' data windows.
mean_indirect() {
  local f
  for f in "$@"; do
    oiiotool "$f" --ch indirect.R,indirect.G,indirect.B --printstats 2> /dev/null |
      sed -n 's/^ *Stats Avg: *//p' | head -n 1
  done | awk '{ for (c = 1; c <= 3; ++c) s[c] += $c; n++ }
    END { printf "%.8f %.8f %.8f", s[1] / n, s[2] / n, s[3] / n }'
}
# ratios "R G B" "R G B": the largest and the smallest channel's ratio of the first to the second.
ratios() {
  echo "$1 $2" | awk '{ hi = 0; lo = 1e30
    for (c = 1; c <= 3; ++c) { r = $c / $(c + 3); if (r > hi) hi = r; if (r < lo) lo = r }
    printf "%.3f %.3f\n", hi, lo }'
}

printf '| scene | region | alone / whole frame, largest channel | smallest | with --context |\n'
printf '|---|---|---|---|---|\n'
for dir in "${scenes[@]}"; do
  scene=$(basename "$dir")
  frames=("$dir/$scene".*.exr)
  read -r w h < <(oiiotool --info "${frames[0]}" |
    sed -n 's/.*: *\([0-9]*\) x *\([0-9]*\),.*/\1 \2/p')
  "$ssgi" run "$dir/$scene.####.exr" -o "$out/whole.####.exr" -q --no-passthrough "${extra[@]}"
  hw=$((w / 2)) hh=$((h / 2))
  sw=$((w / 8)) sh=$((h / 6)) lw=$((w * 7 / 8)) lh=$((h * 7 / 8))
  for region in "centre ${hw}x${hh}+$((w / 4))+$((h / 4))" "top-left ${hw}x${hh}+0+0" \
    "top-right ${hw}x${hh}+$((w - hw))+0" "bottom-left ${hw}x${hh}+0+$((h - hh))" \
    "bottom-right ${hw}x${hh}+$((w - hw))+$((h - hh))" \
    "bottom-strip ${w}x$((h / 4))+0+$((h - h / 4))" "left-strip $((w / 5))x${h}+0+0" \
    "small ${sw}x${sh}+$(((w - sw) / 2))+$(((h - sh) / 2))" \
    "large ${lw}x${lh}+$(((w - lw) / 2))+$(((h - lh) / 2))"; do
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
    "$ssgi" run "$out/crop.####.exr" -o "$out/region.####.exr" -q --no-passthrough "${extra[@]}"
    read -r alone_hi alone_lo < <(ratios "$(mean_indirect "$out"/region.*.exr)" "$whole")
    "$ssgi" run "$out/crop.####.exr" -o "$out/region.####.exr" -q --no-passthrough \
      --context "$dir/$scene.####.exr" "${extra[@]}"
    read -r context_hi _ < <(ratios "$(mean_indirect "$out"/region.*.exr)" "$whole")
    printf '| %s | %s (%s) | %s | %s | %s |\n' "$scene" "$name" "$geom" "$alone_hi" "$alone_lo" \
      "$context_hi"
  done
done
