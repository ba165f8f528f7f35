#!/usr/bin/env bash
# What a guide (--guide) costs ssgi on a rendered 1080p shot: the median gi_ms (from --stats:
# lighting a frame, the guide's share of it included; reading the guide counts in read_ms) and
# the median wall time of the whole run, without and with a guide, in the default settings with
# one frame in flight and --no-passthrough, the two interleaved round by round so that a noisy
# machine weighs on both alike; with the guide's own render time per frame (Blender, from the
# guide cache's render.txt) beside it, which is not counted in the ratio.
# The shot is tests/bench/views.sh's (loft at 1920x1080, 4 samples, six frames, rendered by
# tests/accuracy/training/render.sh into SSGI_BENCH_CACHE); the guide is the same shot rendered as
# a guide (SSGI_TRAINING_GUIDE: 4 samples, a seed of its own per frame) into SSGI_GUIDE_CACHE.
# Both are rendered on first use (about 15 minutes each on 2 cores).
# Usage: tests/bench/guide.sh [BUILD_DIR] [ROUNDS]
# Environment: SSGI_BENCH_CACHE (default ~/.cache/ssgi/bench), SSGI_GUIDE_CACHE (default
# ~/.cache/ssgi/bench-guide), SSGI_GUIDE_SAMPLES (default 4), BLENDER.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
rounds=${2:-3}
ssgi=$build/bin/ssgi
res=1920x1080
cache=${SSGI_BENCH_CACHE:-$HOME/.cache/ssgi/bench}
guides=${SSGI_GUIDE_CACHE:-$HOME/.cache/ssgi/bench-guide}
SSGI_TRAINING_CACHE=$cache/$res SSGI_TRAINING_RESOLUTION=$res SSGI_TRAINING_FRAMES=6 \
  SSGI_TRAINING_SAMPLES=4 tests/accuracy/training/render.sh loft > /dev/null
SSGI_TRAINING_CACHE=$guides/$res SSGI_TRAINING_RESOLUTION=$res SSGI_TRAINING_FRAMES=6 \
  SSGI_TRAINING_GUIDE=1 SSGI_TRAINING_SAMPLES=${SSGI_GUIDE_SAMPLES:-4} SSGI_TRAINING_SEED=2 \
  tests/accuracy/training/render.sh loft > /dev/null
shot=$cache/$res/loft/loft.####.exr
guide=$guides/$res/loft/loft.####.exr
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# median FILE: the median of the numbers in FILE, one a line.
median() { sort -g "$1" | awk '{ v[NR] = $1 } END { print (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2) }'; }

for ((r = 0; r < rounds; ++r)); do
  for config in alone guided; do
    args=()
    [ "$config" = guided ] && args=(--guide "$guide")
    rm -f "$out"/o.*.exr
    start=$(date +%s.%N)
    "$ssgi" run "$shot" -o "$out/o.####.exr" -q --no-passthrough --frames-in-flight 1 \
      --stats "$out/stats.json" "${args[@]}"
    end=$(date +%s.%N)
    echo "$end - $start" | bc -l >> "$out/$config.wall"
    python3 -c 'import json, sys
for f in json.load(open(sys.argv[1]))["frames"]: print(f["gi_ms"])' "$out/stats.json" \
      >> "$out/$config.gi"
  done
done
alone_gi=$(median "$out/alone.gi")
guided_gi=$(median "$out/guided.gi")
alone_wall=$(median "$out/alone.wall")
guided_wall=$(median "$out/guided.wall")
render=$(sed -n 's/.*, \([0-9]*\) s\/frame.*/\1/p' "$guides/$res/loft/render.txt")
printf '| | gi_ms (median) | run wall s (median of %d) |\n|---|---|---|\n' "$rounds"
printf '| ssgi alone | %.0f | %.1f |\n' "$alone_gi" "$alone_wall"
printf '| with the guide | %.0f | %.1f |\n' "$guided_gi" "$guided_wall"
printf '| ratio | %.2f | %.2f |\n' "$(echo "$guided_gi / $alone_gi" | bc -l)" \
  "$(echo "$guided_wall / $alone_wall" | bc -l)"
printf 'the guide'"'"'s render: %s s/frame (Blender, %s samples, 2 cores)\n' "$render" \
  "${SSGI_GUIDE_SAMPLES:-4}"
