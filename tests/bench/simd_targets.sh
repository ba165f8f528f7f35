#!/usr/bin/env bash
# The table of SIMD targets in tests/bench/README.md: median gi_ms (from --stats) of the default preset with
# each target `ssgi info` lists (--simd), interleaved round by round so that a noisy machine
# weighs on all alike, and whether each target's frames are the same bits as the first's
# (ssgi compare -fail 0 -warn 0: every channel of every pixel). Usage:
#   tests/bench/simd_targets.sh [BUILD_DIR] [PATTERN] [FRAMES] [ROUNDS]
# PATTERN defaults to /tmp/ssgi1080/room.####.exr (tests/bench/make_1080p.sh makes it).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
pattern=${2:-/tmp/ssgi1080/room.####.exr}
frames=${3:-1-2}
rounds=${4:-3}
ssgi=$build/bin/ssgi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

first=${pattern//####/0001}
mapfile -t targets < <("$ssgi" info "$first" --json |
  python3 -c 'import json,sys; print("\n".join(t for t in json.load(sys.stdin)["simd"]["available"] if t != "auto"))')
for ((r = 0; r < rounds; ++r)); do
  for t in "${targets[@]}"; do
    mkdir -p "$out/$t"
    "$ssgi" run "$pattern" --frames "$frames" -o "$out/$t/o.####.exr" -q --no-passthrough \
      --temporal none --simd "$t" --stats "$out/stats.$t.$r.json"
  done
done
printf '| --simd | gi_ms (median of frames %s x %s rounds) | same bits as %s |\n|---|---|---|\n' \
  "$frames" "$rounds" "${targets[0]}"
for t in "${targets[@]}"; do
  same=yes
  "$ssgi" compare -q -fail 0 -warn 0 "$out/${targets[0]}/o.####.exr" "$out/$t/o.####.exr" \
    --frames "$frames" >/dev/null 2>&1 || same=NO
  python3 - "$t" "$same" "$out"/stats."$t".*.json <<'PY'
import json, statistics, sys
ms = [f["gi_ms"] for path in sys.argv[3:] for f in json.load(open(path))["frames"]]
print(f"| {sys.argv[1]} | {statistics.median(ms):.0f} | {sys.argv[2]} |")
PY
done
