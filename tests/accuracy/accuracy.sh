#!/usr/bin/env bash
# The README's accuracy table: runs ssgi on the Cycles sample sequences in ../shared/data and
# prints, per scene and setting, the relative RMSE (RMSE / mean of the truth over surface
# pixels, all channels, averaged over frames) of `indirect` against the path-traced DiffInd and
# of the composite against (DiffDir + DiffInd) x DiffCol + Emit, with the median wall time per
# frame. Usage: tests/accuracy/accuracy.sh [BUILD_DIR] [-- extra ssgi options]
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
shift || true
[ "${1:-}" = "--" ] && shift
extra=("$@")
data=../shared/data
ssgi=$build/bin/ssgi
truth=$build/bin/truth_error
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

settings=(
  "no GI|"
  "env black, 1 bounce|--miss env --bounces 1"
  "env black, 8 bounces|--miss env"
  "frame estimate, 8 bounces|--miss frame"
  "edge extension, 8 bounces|--miss extend"
  "default (auto, 8 rays, 8 bounces)|"
)
printf '| scene | setting | relRMSE indirect | relRMSE composite | s/frame |\n'
printf '|---|---|---|---|---|\n'
for scene in room stage; do
  frames=("$data/$scene/$scene".*.exr)
  for entry in "${settings[@]}"; do
    name=${entry%%|*}
    read -r -a opts <<< "${entry#*|}"
    times=()
    if [ "$name" != "no GI" ]; then
      for f in "${frames[@]}"; do
        n=$(basename "$f")
        start=$(date +%s.%N)
        "$ssgi" run "$f" -o "$out/$n" -q --no-passthrough "${opts[@]}" "${extra[@]}"
        end=$(date +%s.%N)
        times+=("$(echo "$end - $start" | bc)")
      done
    fi
    sums=$(for f in "${frames[@]}"; do
      n=$(basename "$f")
      [ "$name" = "no GI" ] && "$ssgi" run "$f" -o "$out/$n" -q --no-passthrough >/dev/null
      "$truth" "$f" "$out/$n"
    done | awk -v nogi="$([ "$name" = "no GI" ] && echo 1 || echo 0)" \
      '{ if (nogi) { i += $1; c += $3 } else { i += $2; c += $4 }; n++ }
       END { printf "%.3f %.3f", i / n, c / n }')
    median="-"
    if [ ${#times[@]} -gt 0 ]; then
      median=$(printf '%s\n' "${times[@]}" | sort -g | awk '{ a[NR] = $1 } END { printf "%.2f", a[int((NR + 1) / 2)] }')
    fi
    read -r ind comp <<< "$sums"
    printf '| %s | %s | %s | %s | %s |\n' "$scene" "$name" "$ind" "$comp" "$median"
  done
done
