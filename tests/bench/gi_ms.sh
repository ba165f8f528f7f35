#!/usr/bin/env bash
# The GI table of tests/bench/README.md: median gi_ms (from --stats) per preset, thread count and temporal
# mode on a 1080p shot, the configurations interleaved round by round so that a noisy machine
# weighs on all of them alike. One frame in flight: the GI's own time, not shared with the
# decoding and encoding of the frames around it (tests/bench/end_to_end.sh times the whole).
# Usage:
#   tests/bench/gi_ms.sh [BUILD_DIR] [PATTERN] [FRAMES] [ROUNDS]
# PATTERN defaults to /tmp/ssgi1080/room.####.exr (tests/bench/make_1080p.sh makes it).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
pattern=${2:-/tmp/ssgi1080/room.####.exr}
frames=${3:-1-4}
rounds=${4:-3}
ssgi=$build/bin/ssgi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

configs=(
  "draft|--preset draft --temporal none"
  "default|--temporal none"
  "final|--preset final --temporal none"
  "default, 1 thread|--temporal none --threads 1"
  "default, window ±2|"
  "default, window ±2, --multiframe on|--multiframe on"
  "final (window ±2, multiframe on)|--preset final"
  "default, SSGI_SIMD=scalar|--temporal none|scalar"
)
for ((r = 0; r < rounds; ++r)); do
  for i in "${!configs[@]}"; do
    IFS='|' read -r name opts simd <<< "${configs[$i]}"
    read -r -a args <<< "$opts"
    SSGI_SIMD=${simd:-} "$ssgi" run "$pattern" --frames "$frames" -o "$out/o.####.exr" -q \
      --no-passthrough --frames-in-flight 1 --stats "$out/stats.$i.$r.json" "${args[@]}"
  done
done
printf '| configuration | gi_ms (median of %s frames x %s rounds) |\n' "$frames" "$rounds"
printf '|---|---|\n'
for i in "${!configs[@]}"; do
  name=${configs[$i]%%|*}
  python3 - "$name" "$out"/stats."$i".*.json <<'EOF'
import json, statistics, sys
ms = [f["gi_ms"] for path in sys.argv[2:] for f in json.load(open(path))["frames"]]
print(f"| {sys.argv[1]} | {statistics.median(ms):.0f} |")
EOF
done
