#!/usr/bin/env bash
# The denormal benchmark of tests/bench/README.md: gi_ms (from --stats) of one 1080p frame against the same frame
# with its direct light (DiffDir) scaled by 1e-40, so that the light the pipeline carries, direct
# light times albedo and every bounce of it, is denormal, interleaved round by
# round; prints the medians and their ratio (the target: at most 1.1). Usage:
#   tests/bench/denormals.sh [BUILD_DIR] [FRAME] [ROUNDS]
# FRAME defaults to /tmp/ssgi1080/room.0001.exr (tests/bench/make_1080p.sh makes it); its
# channels must be Blender's 30 (DiffDir at indices 8-10).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
frame=${2:-/tmp/ssgi1080/room.0001.exr}
rounds=${3:-5}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

scale=$(python3 -c "print(','.join('1e-40' if 8 <= i <= 10 else '1' for i in range(30)))")
cp "$frame" "$out/normal.0001.exr"
oiiotool "$frame" --mulc "$scale" -o "$out/denormal.0001.exr"
for ((r = 0; r < rounds; ++r)); do
  for k in normal denormal; do
    "$build/bin/ssgi" run "$out/$k.0001.exr" -o "$out/o_$k.0001.exr" -q --no-passthrough \
      --stats "$out/$k.$r.json"
  done
done
python3 - "$out" "$rounds" <<'PY'
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
ms = {k: statistics.median(json.load(open(f"{out}/{k}.{r}.json"))["frames"][0]["gi_ms"]
                           for r in range(rounds)) for k in ("normal", "denormal")}
print(f"gi_ms median of {rounds}: normal {ms['normal']:.0f}, denormal {ms['denormal']:.0f}, "
      f"ratio {ms['denormal'] / ms['normal']:.2f}")
PY
