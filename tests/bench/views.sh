#!/usr/bin/env bash
# The views table of tests/bench/README.md: what views (--view, --latlong-view) cost the GI of a
# rendered 1080p shot, and what --multiframe on costs. The shot is a training scene
# (tests/accuracy/training/scenes.py) rendered by Blender at 1920x1080, six frames at few
# samples, as tests/bench/rendered.sh renders it (the same cache); its views are rendered by
# tests/blender/render_views.py from the same scene saved as a .blend: six 128x128 cube faces
# and a 512x256 lat-long per frame, 16 samples. Runs interleaved round by round, each with
# --stats, their gi_ms the median over every frame of every round:
#   - --temporal none --frames-in-flight 1 --no-passthrough: without views, with the six faces,
#     with the lat-long (the GI of a frame and nothing else);
#   - the default (window +-2) --frames-in-flight 1 --no-passthrough, without and with
#     --multiframe on.
# Prints a markdown table of the medians and their ratios to the run without views (or without
# multiframe), each round's ratio, and the load average before and after (other work on the
# machine slows the runs: compare the ratios, measured in one run).
# Usage:
#   tests/bench/views.sh [BUILD_DIR] [ROUNDS]     (default: build 3)
# Environment: SSGI_BENCH_CACHE (default ~/.cache/ssgi/bench), SSGI_BENCH_SCENE (default loft),
# SSGI_BENCH_SAMPLES (default 4), BLENDER (default blender).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
rounds=${2:-3}
cache=${SSGI_BENCH_CACHE:-$HOME/.cache/ssgi/bench}
scene=${SSGI_BENCH_SCENE:-loft}
blender=${BLENDER:-blender}
res=1920x1080
ssgi=$build/bin/ssgi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

SSGI_TRAINING_CACHE=$cache/$res SSGI_TRAINING_RESOLUTION=$res SSGI_TRAINING_FRAMES=6 \
  SSGI_TRAINING_SAMPLES=${SSGI_BENCH_SAMPLES:-4} tests/accuracy/training/render.sh "$scene" \
  > /dev/null
shot=$cache/$res/$scene/$scene.####.exr
views=$cache/$res/$scene.views
if [[ ! -f $views/done ]]; then
  rm -rf "$views"
  mkdir -p "$views"
  "$blender" -b --factory-startup --python-exit-code 1 -P tests/accuracy/training/scenes.py -- \
    --scene "$scene" --out "$views/scene" --frames 6 --resolution $res --no-render \
    --save "$views/$scene.blend" > "$views/blender.log" 2>&1
  "$blender" -b "$views/$scene.blend" --python-exit-code 1 --python \
    tests/blender/render_views.py -- --out "$views" --name "$scene" --frames 1-6 \
    --face-size 128 --latlong-width 512 --samples 16 >> "$views/blender.log" 2>&1
  touch "$views/done"
fi
faces=()
for f in px nx py ny pz nz; do faces+=(--view "$views/$scene.$f.####.exr"); done

names=("none" "faces" "latlong" "window" "window_multiframe")
config() {
  local base=(--no-passthrough --frames-in-flight 1)
  case $1 in
    none) echo "--temporal none ${base[*]}" ;;
    faces) echo "--temporal none ${base[*]} ${faces[*]}" ;;
    latlong) echo "--temporal none ${base[*]} --latlong-view $views/$scene.latlong.####.exr" ;;
    window) echo "${base[*]}" ;;
    window_multiframe) echo "${base[*]} --multiframe on" ;;
  esac
}
cut -d' ' -f1-3 /proc/loadavg > "$out/load"
for ((r = 0; r < rounds; ++r)); do
  for name in "${names[@]}"; do
    read -r -a args <<< "$(config "$name")"
    "$ssgi" run "$shot" -o "$out/frames/o.####.exr" -q --stats "$out/$name.$r.json" "${args[@]}" \
      || exit 1
    rm -rf "$out/frames"
  done
done
cut -d' ' -f1-3 /proc/loadavg >> "$out/load"

python3 - "$out" "$rounds" "$scene" <<'PY'
import json, statistics, sys
out, rounds, scene = sys.argv[1], int(sys.argv[2]), sys.argv[3]


def gi(name, r=None):
    rs = range(rounds) if r is None else [r]
    return [f["gi_ms"] for i in rs for f in json.load(open(f"{out}/{name}.{i}.json"))["frames"]]


rows = [("none", "none", "--temporal none, no views"),
        ("faces", "none", "--temporal none, six 128x128 faces (--view x 6)"),
        ("latlong", "none", "--temporal none, a 512x256 lat-long (--latlong-view)"),
        ("window", "window", "window +-2 (the default)"),
        ("window_multiframe", "window", "window +-2, --multiframe on")]
print(f"| {scene} 1920x1080, 6 frames, {rounds} rounds, --no-passthrough --frames-in-flight 1 "
      "| gi_ms, median | against | each round's |")
print("|---|---|---|---|")
for name, base, what in rows:
    m = statistics.median(gi(name))
    each = ", ".join(f"{statistics.median(gi(name, r)) / statistics.median(gi(base, r)):.2f}"
                     for r in range(rounds))
    ratio = "" if name == base else f"**{m / statistics.median(gi(base)):.2f}x**"
    print(f"| {what} | {m:.0f} | {ratio} | {each if name != base else ''} |")
before, after = open(f"{out}/load").read().splitlines()
print(f"\nload average (1, 5, 15 min) before: {before}; after: {after}")
PY
