# Sourced by the accuracy scripts (accuracy.sh, training.sh) with their arguments
# [BUILD_DIR] [-- extra ssgi options]: moves to the repository and sets build, extra (the ssgi
# options), data (the sample scenes), ssgi, truth (truth_error) and out (a temporary folder,
# removed on exit).
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
build=${1:-build}
shift || true
[ "${1:-}" = "--" ] && shift
extra=("$@")
data=../shared/data
ssgi=$build/bin/ssgi
truth=$build/bin/truth_error
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# training_scenes: the training scenes to measure, one a line: SSGI_TRAINING_SCENES
# (space-separated), else every scene training/scenes.py lists (BLENDER runs it).
training_scenes() {
  if [ -n "${SSGI_TRAINING_SCENES:-}" ]; then
    printf '%s\n' $SSGI_TRAINING_SCENES
  else
    "${BLENDER:-blender}" -b --factory-startup --python-exit-code 1 \
      -P tests/accuracy/training/scenes.py -- --list 2> /dev/null |
      awk -F'\t' '$1 == "SCENE" { print $2 }'
  fi
}

# truth_means DIR SCENE [SECOND]: truth_error's seven columns, each averaged over the frames
# DIR/SCENE.*.exr, against ssgi's output $out/o.<frame>.exr; with SECOND (a cache of the same
# frames rendered with another seed), truth_error --second's eight, the truth's noise taken out.
truth_means() {
  local f n second=()
  for f in "$1/$2".*.exr; do
    n=${f%.exr}
    if [ -n "${3:-}" ]; then second=(--second "$3/$2/${f##*/}"); fi
    "$truth" "${second[@]}" "$f" "$out/o.${n##*.}.exr"
  done | awk '{ for (c = 1; c <= NF; ++c) s[c] += $c; n++; k = NF }
    END { for (c = 1; c <= k; ++c) printf "%.3f%s", s[c] / n, c < k ? " " : "\n" }'
}

# save_scene_blend SCENE DIR FRAMES RESOLUTION: training scene SCENE built by scenes.py as the
# cache renders it (FRAMES frames at WxH RESOLUTION), saved as DIR/SCENE.blend unrendered, for
# render_views.py to render its views from; Blender's output to DIR/blender.log.
save_scene_blend() {
  "${BLENDER:-blender}" -b --factory-startup --python-exit-code 1 \
    -P tests/accuracy/training/scenes.py -- --scene "$1" --out "$2/scene" --frames "$3" \
    --resolution "$4" --no-render --save "$2/$1.blend" > "$2/blender.log" 2>&1
}
