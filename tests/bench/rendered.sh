#!/usr/bin/env bash
# The rendered 1080p and 4K tables of tests/bench/README.md: peak memory and GI time of ssgi on
# a training scene (tests/accuracy/training/scenes.py) rendered by Blender at each resolution,
# six frames at few samples (the passes' size and the GI's cost do not depend on the sample
# count), with the training set's 30 float channels, ZIP, cameras in the headers. Per
# resolution, the runs interleaved round by round so that a noisy machine weighs on all alike:
#   - `ssgi run SHOT -o OUT` with default settings (passthrough, window +-2, no limit: the
#     least memory), with --frames-in-flight 2 (the fastest) and under a farm slot
#     sized for the resolution: peak resident size (/usr/bin/time %M) against the estimate `-v`
#     prints ("memory: estimated peak", as `ssgi info` prints it);
#   - --no-passthrough --frames-in-flight 1 at --threads 1 and 2: gi_ms from --stats, the median
#     over every frame of every round, and the ratio of the medians (and of each round's).
# Prints two markdown tables, each configuration's estimate in parts, and the load average
# before and after (other work on the machine slows the runs and takes the second thread's
# core: s/frame is wall time, with the CPU time of ssgi's own beside it). The first run renders
# the shots (tests/accuracy/training/render.sh; 11 minutes at 1080p and 46 to 70 at 4K on the
# two shared cores) into the cache, a folder per resolution; later runs find them there.
# Usage:
#   tests/bench/rendered.sh [BUILD_DIR] [ROUNDS]     (default: build 3)
# Environment: SSGI_BENCH_CACHE (default ~/.cache/ssgi/bench), SSGI_BENCH_SCENE (default loft),
# SSGI_BENCH_RESOLUTIONS (default "1920x1080 3840x2160"), SSGI_BENCH_SAMPLES (default 4),
# BLENDER (default blender).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
rounds=${2:-3}
cache=${SSGI_BENCH_CACHE:-$HOME/.cache/ssgi/bench}
scene=${SSGI_BENCH_SCENE:-loft}
read -r -a resolutions <<< "${SSGI_BENCH_RESOLUTIONS:-1920x1080 3840x2160}"
ssgi=$build/bin/ssgi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

for res in "${resolutions[@]}"; do
  SSGI_TRAINING_CACHE=$cache/$res SSGI_TRAINING_RESOLUTION=$res SSGI_TRAINING_FRAMES=6 \
    SSGI_TRAINING_SAMPLES=${SSGI_BENCH_SAMPLES:-4} tests/accuracy/training/render.sh "$scene" \
    > /dev/null
done

# The runs of a round: `ssgi run`'s options. The default takes the least memory (no limit here);
# --frames-in-flight 2 the most (two frames in flight, the window's frames kept, the allocator
# keeping what it frees); LIMIT is a farm slot sized for the resolution (500 MB at 1080p, 1.6 GB
# at 4K, in bytes; none at other sizes); the last two give the GI's time on 1 and 2 threads.
configs=(
  ""
  "--frames-in-flight 2"
  "--max-memory LIMIT"
  "--no-passthrough --frames-in-flight 1 --threads 1"
  "--no-passthrough --frames-in-flight 1 --threads 2"
)
slot() {
  case $1 in
    1920x1080) echo 500000000 ;;
    3840x2160) echo 1600000000 ;;
  esac
}
cut -d' ' -f1-3 /proc/loadavg > "$out/load"
for ((r = 0; r < rounds; ++r)); do
  for res in "${resolutions[@]}"; do
    for i in "${!configs[@]}"; do
      limit=$(slot "$res")
      config=${configs[$i]}
      [[ -n $limit ]] && config=${config/LIMIT/$limit} || config=${config/--max-memory LIMIT/}
      read -r -a args <<< "$config"
      tag=$out/$res.$i.$r
      /usr/bin/time -f '%e %U %S %M' -o "$tag.time" "$ssgi" run \
        "$cache/$res/$scene/$scene.####.exr" -o "$out/frames/o.####.exr" -v --stats "$tag.json" \
        "${args[@]}" > /dev/null 2> "$tag.log" || { cat "$tag.log" >&2; exit 1; }
      rm -rf "$out/frames"
    done
  done
done
cut -d' ' -f1-3 /proc/loadavg >> "$out/load"

python3 - "$out" "$rounds" "$scene" "${resolutions[@]}" -- "${configs[@]}" <<'PY'
import json, re, statistics, sys
args = sys.argv[1:]
out, rounds, scene = args[0], int(args[1]), args[2]
resolutions = args[3:args.index("--")]
configs = args[args.index("--") + 1:]
mib = {"KiB": 1 / 1024, "MiB": 1, "GiB": 1024}


def run(res, i, r):
    """One run's wall and CPU seconds, peak MiB, frames' stats and -v's estimate."""
    tag = f"{out}/{res}.{i}.{r}"
    wall, user, system, kb = open(f"{tag}.time").read().split()[-4:]
    estimate = re.search(r"memory: estimated peak ([0-9.]+) (\w+) \((.*?)\);",
                         open(f"{tag}.log").read())
    return {"wall": float(wall), "cpu": float(user) + float(system), "peak": int(kb) / 1024,
            "frames": json.load(open(f"{tag}.json"))["frames"],
            "estimate": float(estimate[1]) * mib[estimate[2]], "parts": estimate[3]}


runs = {(res, i): [run(res, i, r) for r in range(rounds)]
        for res in resolutions for i in range(len(configs))}
slots = {"1920x1080": "500000000", "3840x2160": "1600000000"}
print(f"| {scene}, 6 frames, {rounds} rounds | `ssgi run` options | peak RSS MiB, median (min-max)"
      " | estimate MiB (-v) | estimate / peak | s/frame, wall (CPU) |")
print("|---|---|---|---|---|---|")
for (res, i), rs in runs.items():
    peaks = [x["peak"] for x in rs]
    peak, estimate, frames = statistics.median(peaks), rs[0]["estimate"], len(rs[0]["frames"])
    wall, cpu = (statistics.median(x[k] for x in rs) / frames for k in ("wall", "cpu"))
    config = configs[i].replace("LIMIT", slots.get(res, "none"))
    print(f"| {res} | {config or '(default)'} | **{peak:.0f}** ({min(peaks):.0f}-"
          f"{max(peaks):.0f}) | {estimate:.0f} | {estimate / peak:.2f} | {wall:.1f} ({cpu:.1f}) |")

print(f"\n| {scene}, --no-passthrough --frames-in-flight 1 | gi_ms 1 thread | gi_ms 2 threads"
      " | 2 threads faster by | each round's |")
print("|---|---|---|---|---|")
for res in resolutions:
    one, two = ([[f["gi_ms"] for f in x["frames"]] for x in runs[res, i]]
                for i in (len(configs) - 2, len(configs) - 1))
    median_one, median_two = statistics.median(sum(one, [])), statistics.median(sum(two, []))
    each = ", ".join(f"{statistics.median(a) / statistics.median(b):.2f}" for a, b in zip(one, two))
    print(f"| {res}, median of {len(sum(one, []))} frames | {median_one:.0f} | {median_two:.0f} | "
          f"**{median_one / median_two:.2f}x** | {each} |")

print()
for (res, i), rs in runs.items():
    print(f"{res} {configs[i].replace('LIMIT', slots.get(res, 'none')) or '(default)'}: "
          f"{rs[0]['parts']}")
before, after = open(f"{out}/load").read().splitlines()
print(f"\nload average (1, 5, 15 min) before: {before}; after: {after}")
PY
