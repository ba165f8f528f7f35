#!/usr/bin/env bash
# The end-to-end table of tests/bench/README.md: a whole `ssgi run` against the I/O floor, and
# its peak memory. Per frame, the floor is oiiotool reading the passes ssgi needs and writing ten
# channels (one process per frame, as a farm task would); against it `ssgi run` over the shot
# without and with its input's channels passed through, each with the default plan (no limit:
# the least memory, one frame in flight, the window's frames read twice) and with
# --frames-in-flight 2 (the fastest: two frames in flight, the window's frames kept). The five
# run interleaved, round by round, so that a noisy machine weighs on all alike; each row is the
# median over rounds of seconds per frame, and the largest peak resident size (/usr/bin/time)
# of its runs.
#   tests/bench/end_to_end.sh [BUILD_DIR] [PREFIX] [FRAMES] [ROUNDS]
# PREFIX defaults to /tmp/ssgi1080/room (tests/bench/make_1080p.sh makes it); FRAMES 1-6.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
prefix=${2:-/tmp/ssgi1080/room}
frames=${3:-1-6}
rounds=${4:-3}
ssgi=$build/bin/ssgi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
first=${frames%-*}
last=${frames#*-}
count=$((last - first + 1))
# The passes the default plan reads (ssgi info lists them), as oiiotool --ch names them.
channels=$(
  "$ssgi" info "$prefix.####.exr" --json |
    python3 -c '
import json, sys
info = json.load(sys.stdin)
roles = info["layout"]["channels"]
print(",".join(c for role in ("depth", "normal", "albedo", "direct") for c in roles[role]))'
)

# wall seconds and peak KB of a command, appended to $out/NAME.
measure() {
  local name=$1
  shift
  /usr/bin/time -f '%e %M' -o "$out/time" "$@" > /dev/null
  cat "$out/time" >> "$out/$name"
}
floor() {
  local f
  for f in $(seq "$first" "$last"); do
    oiiotool "$(printf '%s.%04d.exr' "$prefix" "$f")" --ch "$channels" -o "$out/floor.exr"
  done
}
for ((r = 0; r < rounds; ++r)); do
  /usr/bin/time -f '%e %M' -o "$out/time" bash -c "$(declare -f floor); prefix=$prefix \
    first=$first last=$last channels=$channels out=$out floor" > /dev/null
  cat "$out/time" >> "$out/floor"
  measure run "$ssgi" run "$prefix.####.exr" --frames "$frames" -o "$out/run.####.exr" -q \
    --no-passthrough
  measure run_fast "$ssgi" run "$prefix.####.exr" --frames "$frames" -o "$out/run.####.exr" -q \
    --no-passthrough --frames-in-flight 2
  measure passthrough "$ssgi" run "$prefix.####.exr" --frames "$frames" -o "$out/pass.####.exr" \
    -q
  measure passthrough_fast "$ssgi" run "$prefix.####.exr" --frames "$frames" \
    -o "$out/pass.####.exr" -q --frames-in-flight 2
done
printf '| %s, %s frames x %s rounds | s/frame (median) | x floor | peak RSS MB |\n' \
  "$prefix" "$count" "$rounds"
printf '|---|---|---|---|\n'
python3 - "$out" "$count" <<'EOF'
import statistics, sys
out, count = sys.argv[1], int(sys.argv[2])
rows = {}
for name in ("floor", "run", "run_fast", "passthrough", "passthrough_fast"):
    runs = [line.split() for line in open(f"{out}/{name}")]
    rows[name] = (statistics.median(float(t) for t, _ in runs) / count,
                  max(int(k) for _, k in runs) / 1024)
labels = {"floor": "oiiotool: read the passes, write 10 channels (a process per frame)",
          "run": "ssgi run --no-passthrough (the least memory: read twice)",
          "run_fast": "ssgi run --no-passthrough --frames-in-flight 2",
          "passthrough": "ssgi run (every channel passed; the least memory)",
          "passthrough_fast": "ssgi run --frames-in-flight 2 (every channel passed)"}
for name, (s, mb) in rows.items():
    print(f"| {labels[name]} | {s:.2f} | {s / rows['floor'][0]:.2f} | {mb:.0f} |")
EOF
