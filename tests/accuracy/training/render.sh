#!/usr/bin/env bash
# Renders the accuracy training set (scenes.py) with Blender into a cache outside the
# repository, once: a scene whose frames are all there and readable, with camera attributes in
# their headers, is skipped. Each scene renders into a temporary folder beside its final one and
# is moved into place only when complete, so an interrupted run leaves no half scene.
# Stock Blender does not write worldToCamera/worldToNDC; they are added here from the
# camera.json the script writes (oiiotool keeps channels, float type and ZIP compression).
# Prints the cache folder on the last line of stdout. A second run on the same cache waits for
# the first (flock).
# A scene already in the cache at another resolution, frame count or seed is an error, not
# replaced: give such renders their own SSGI_TRAINING_CACHE (tests/bench/rendered.sh does).
# Usage: tests/accuracy/training/render.sh [SCENE...]   (default: every scene of scenes.py)
# Environment: SSGI_TRAINING_CACHE (default ~/.cache/ssgi/training), SSGI_TRAINING_SAMPLES
# (default 256), SSGI_TRAINING_RESOLUTION (WxH, default 320x180), SSGI_TRAINING_FRAMES
# (default 8), SSGI_TRAINING_SEED (Cycles' sampling seed, default 0: another seed renders the same
# frames with independent noise, into its own cache), SSGI_TRAINING_GUIDE (1: render the frames
# as a guide for ssgi --guide, scenes.py --guide: the samples as given, a seed per frame; into a
# cache of its own), BLENDER (default blender). Needs
# blender 3.4, oiiotool, python3.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cache=${SSGI_TRAINING_CACHE:-$HOME/.cache/ssgi/training}
samples=${SSGI_TRAINING_SAMPLES:-256}
blender=${BLENDER:-blender}
resolution=${SSGI_TRAINING_RESOLUTION:-320x180}
frames=${SSGI_TRAINING_FRAMES:-8}
seed=${SSGI_TRAINING_SEED:-0}
guide=()
kind=
if [ "${SSGI_TRAINING_GUIDE:-0}" = 1 ]; then
  guide=(--guide)
  kind=" guide"
fi
blender_run() {
  "$blender" -b --factory-startup --python-exit-code 1 -P "$here/scenes.py" -- "$@"
}

# rendered_as DIR: the resolution, frame count and seed DIR/camera.json says, as "WxH N seed S",
# with " guide" after it for a guide's frames (seed 0 where it names none).
rendered_as() {
  python3 -c 'import json, sys; c = json.load(open(sys.argv[1]))
print("%dx%d %d seed %d%s" % (c["width"], c["height"], len(c["frames"]), c.get("seed", 0),
                              " guide" if c.get("animated_seed") else ""))' "$1/camera.json"
}

# complete DIR NAME: every frame present, readable to the last pixel, with its camera.
complete() {
  local dir=$1 name=$2 f
  [ -f "$dir/camera.json" ] || return 1
  [ "$(rendered_as "$dir")" = "$resolution $frames seed $seed$kind" ] || return 1
  for f in $(seq -f "$dir/$name.%04g.exr" 1 "$frames"); do
    [ -f "$f" ] || return 1
    iinfo --stats "$f" > /dev/null 2>&1 || return 1
    iinfo -v "$f" 2>/dev/null | grep -q "worldToNDC" || return 1
  done
}

# add_cameras DIR NAME: worldToCamera and worldToNDC from DIR/camera.json into each header.
add_cameras() {
  local dir=$1 name=$2 frame w2c ndc
  while read -r frame w2c ndc; do
    local f
    f=$(printf '%s/%s.%04d.exr' "$dir" "$name" "$frame")
    oiiotool --nosoftwareattrib "$f" --attrib:type=matrix worldToCamera "$w2c" \
      --attrib:type=matrix worldToNDC "$ndc" -o "$f.tmp.exr"
    mv "$f.tmp.exr" "$f"
  done < <(python3 -c '
import json, sys
for f in json.load(open(sys.argv[1]))["frames"]:
    print(f["frame"], ",".join(repr(v) for v in f["worldToCamera"]),
          ",".join(repr(v) for v in f["worldToNDC"]))' "$dir/camera.json")
}

if [ $# -gt 0 ]; then
  scenes=("$@")
else
  mapfile -t scenes < <(blender_run --list 2> /dev/null | awk -F'\t' '$1 == "SCENE" { print $2 }')
fi
[ ${#scenes[@]} -gt 0 ] || { echo "render.sh: $blender lists no scenes" >&2; exit 1; }
mkdir -p "$cache"
# One render at a time per cache: a second run waits, then finds the scenes done.
exec 9> "$cache/.lock"
flock 9
for name in "${scenes[@]}"; do
  if complete "$cache/$name" "$name"; then
    echo "$name: rendered already" >&2
    continue
  fi
  if [ -f "$cache/$name/camera.json" ]; then
    held=$(rendered_as "$cache/$name")
    [ "$held" = "$resolution $frames seed $seed$kind" ] || {
      echo "render.sh: $cache/$name holds $held frames, not $resolution $frames seed $seed$kind:" \
        "set SSGI_TRAINING_CACHE to another folder" >&2
      exit 1
    }
  fi
  tmp=$(mktemp -d "$cache/.$name.XXXXXX")
  echo "$name: rendering $frames frames of $resolution at $samples samples or more" \
    "(log: $tmp/blender.log)" >&2
  start=$(date +%s)
  blender_run --scene "$name" --out "$tmp" --samples "$samples" --frames "$frames" \
    --resolution "$resolution" --seed "$seed" "${guide[@]}" > "$tmp/blender.log" 2>&1 || {
    echo "render.sh: $name failed, see $tmp/blender.log" >&2
    exit 1
  }
  add_cameras "$tmp" "$name"
  complete "$tmp" "$name" || { echo "render.sh: $name: incomplete output in $tmp" >&2; exit 1; }
  # The samples as rendered (scenes.py raises them for scenes whose truth needs more).
  spp=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["spp"])' "$tmp/camera.json")
  echo "$spp samples, seed $seed, $resolution, $(( ($(date +%s) - start) / frames )) s/frame" \
    > "$tmp/render.txt"
  echo "$name: $(cat "$tmp/render.txt")" >&2
  rm -f "$tmp/blender.log"
  chmod 755 "$tmp"
  rm -rf "$cache/$name"
  mv "$tmp" "$cache/$name"
done
echo "$cache"
