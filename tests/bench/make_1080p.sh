#!/usr/bin/env bash
# Makes a 1920x1080 shot from a sample sequence for the speed benchmarks: every channel point
# sampled (no filtering, so depth and normals stay values the renderer wrote), motion vectors
# (pixels) scaled by the resize factor.
#   tests/bench/make_1080p.sh ../shared/data/room/room /tmp/ssgi1080/room
# writes /tmp/ssgi1080/room.0001.exr ... from ../shared/data/room/room.0001.exr ...
set -euo pipefail
src=${1:?source prefix, e.g. ../shared/data/room/room}
dst=${2:?destination prefix, e.g. /tmp/ssgi1080/room}
mkdir -p "$(dirname "$dst")"
for f in "$src".[0-9][0-9][0-9][0-9].exr; do
  frame=${f%.exr}; frame=${frame##*.}
  w=$(oiiotool --info "$f" | sed -n 's/.*: *\([0-9]*\) x *\([0-9]*\),.*/\1/p')
  scale=$(echo "1920 / $w" | bc -l)
  # One factor per channel: the resize factor for Vector's, 1 for the others.
  factors=$(oiiotool --info -v "$f" | sed -n 's/^ *channel list: //p' | tr ',' '\n' |
            sed 's/^ *//' | while read -r c; do
              case "$c" in *Vector.*) echo "$scale";; *) echo 1;; esac
            done | paste -sd, -)
  oiiotool "$f" --resample:interp=0 1920x1080 --mulc "$factors" -o "$dst.$frame.exr"
done
