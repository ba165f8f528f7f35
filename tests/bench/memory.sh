#!/usr/bin/env bash
# The memory estimate (ssgi -v: "memory: estimated peak ...") against the peak resident size
# measured by /usr/bin/time (%M), for the sample room resampled to each WIDTH (27 channels,
# point sampled) over 5 frames, so that the temporal window holds what it holds in a shot:
# the slice tracer with and without passthrough and its window (the least memory, and two frames
# in flight with the window's frames kept), the march, and the reference
# keeping its hits or not. Prints one row per run: the estimate should be above the peak, and
# not by much. Usage:
#   tests/bench/memory.sh [BUILD_DIR] [THREADS] [WIDTH...]     (default: build 2 960 1920)
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
threads=${2:-2}
shift 2 || shift $#
widths=("$@")
[ ${#widths[@]} -gt 0 ] || widths=(960 1920)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ssgi="$build/bin/ssgi"

printf '%-6s %-52s %9s %9s %6s\n' width run "peak MiB" "est. MiB" ratio
for w in "${widths[@]}"; do
  for f in 1 2 3 4 5; do
    oiiotool "testdata/sample/sample.000$f.exr" --resample:interp=0 "${w}x$((w * 2 / 3))" \
      -o "$work/room_$w.000$f.exr"
  done
  in="$work/room_$w.####.exr"
  while IFS= read -r flags; do
    # shellcheck disable=SC2086
    /usr/bin/time -f %M -o "$work/rss" "$ssgi" $flags "$in" -o "$work/out/o.####.exr" \
      --threads "$threads" -v 2> "$work/err" > /dev/null || { cat "$work/err"; exit 1; }
    peak=$(( $(cat "$work/rss") / 1024 ))
    est=$(sed -n 's/.*memory: estimated peak \([0-9.]*\) \([KMG]\)iB.*/\1 \2/p' "$work/err" |
          awk '{ m = $2 == "G" ? 1024 : ($2 == "K" ? 1 / 1024 : 1); printf "%.0f", $1 * m }')
    printf '%-6s %-52s %9s %9s %6s\n' "$w" "$flags" "$peak" "$est" \
      "$(echo "scale=2; $est / $peak" | bc)"
    rm -rf "$work/out"
  done <<FLAGS
run
run --frames-in-flight 2
run --no-passthrough
run --temporal none --no-passthrough
run --tracer march --rays 8 --frames 1
reference --spp 16 --bounces 2 --frames 1
reference --spp 16 --bounces 2 --frames 1 --max-memory $((w * w / 1000 + 300))M
FLAGS
done
