#!/usr/bin/env bash
# Writes the seed corpora of the fuzz targets into DIR (default build-fuzz/corpus) from the
# fixtures: every small fixture frame and layout file as it is, the sample room resampled to 16 x 11
# in each encoding OpenEXR has (tiled, MIP-mapped, every compression, half floats, a data
# window of its own) and truncated; camera sidecars and header cameras; sequence patterns.
# Usage: tests/fuzz/make_corpus.sh [DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
dir="${1:-$root/build-fuzz/corpus}"
rm -rf "$dir"
mkdir -p "$dir/exr" "$dir/camera" "$dir/pattern"
td="$root/testdata"

n=0
for f in "$td"/layouts/*.exr "$td"/bad/*.exr "$td"/crop/*.exr "$td"/overscan/*.exr \
         "$td"/plane/*.0001.exr "$td"/furnace/*.exr "$td"/custom/*.exr; do
  [ -f "$f" ] && cp "$f" "$dir/exr/fixture_$((n++)).exr"
done
small="$dir/exr/room_small.exr"
oiiotool "$td/sample/sample.0001.exr" --resample:interp=0 16x11 -o "$small"
for c in none rle zips zip piz pxr24 b44 b44a dwaa dwab; do
  oiiotool "$small" --compression "$c" -o "$dir/exr/room_$c.exr"
done
oiiotool "$small" --tile 8 8 -o "$dir/exr/room_tiled.exr"
oiiotool "$small" -otex "$dir/exr/room_mipmap.exr"
oiiotool "$small" -d half -o "$dir/exr/room_half.exr"
oiiotool "$small" --crop 10x7+3+2 -o "$dir/exr/room_crop.exr"
oiiotool "$small" --origin -4-3 -o "$dir/exr/room_negative_origin.exr"
head -c 600 "$small" > "$dir/exr/room_truncated.exr"

# The camera target's first byte picks the parser: even, a sidecar.
sidecar() { { printf '\x00'; printf '%s' "$2"; } > "$dir/camera/$1"; }
sidecar static.json '{"hfov_deg": 40}'
sidecar aspect.json '{"hfov_deg": 40, "pixel_aspect": 2}'
sidecar frames.json '{"frames": [{"frame": 1, "hfov_deg": 30}, {"frame": 1001, "worldToCamera": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,-5,1], "hfov_deg": 60}]}'
sidecar matrices.json '{"frames": [{"frame": 1, "worldToCamera": [[1,0,0,0],[0,1,0,0],[0,0,-1,0],[0,0,5,1]], "worldToNDC": [[1.2,0,0,0],[0,-1.6,0,0],[-0.5,-0.5,-1,-1],[2.5,2.5,5,5]]}]}'
sidecar singular.json '{"worldToCamera": [0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,0], "worldToNDC": [0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,0]}'
# Odd: header attributes: width, height and which attributes (32-bit integers), then floats.
python3 - "$dir/camera" <<'PY'
import struct, sys
d = sys.argv[1]
def header(name, present, values):
    with open(f"{d}/{name}", "wb") as f:
        f.write(b"\x01" + struct.pack("<3I", 64, 48, present) + struct.pack(f"<{len(values)}f", *values))
identity = [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]
ndc = [1.2,0,0,0, 0,-1.6,0,0, -0.5,-0.5,-1,-1, 2.5,2.5,5,5]
header("matrices.bin", 3, identity + ndc)
header("screen.bin", 1 | 4 | 8 | 16 | 32, identity + identity + [0, 0, 2, 1])
header("vray.bin", 64 | 128, identity + [45])
header("arnold.bin", 1 | 512 | 1024, identity + [35, 36])
PY

printf 'shot.####.exr\n1-10' > "$dir/pattern/hashes"
printf 'shot.%%04d.exr\n1,4,7-9' > "$dir/pattern/printf"
printf 'shot.1-50x2####.exr\n10-1' > "$dir/pattern/range_in_name"
printf 'dir@host/take#2/shot.-5--1#.exr\n-3-2' > "$dir/pattern/negative"
printf 'shot.#@@.exr\n1-20y3' > "$dir/pattern/mixed"
echo "corpus: $(find "$dir" -type f | wc -l) files in $dir"
