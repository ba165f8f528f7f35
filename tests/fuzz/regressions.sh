#!/usr/bin/env bash
# Every input the fuzzers found a bug with (tests/fuzz/regressions/), run as `ssgi run` runs a
# frame: it must end with a status of its own (0, or a refusal: 3 or 4), never a crash, and
# under tests/sanitize.sh without a sanitizer report. Usage: regressions.sh SSGI
set -euo pipefail
ssgi=${1:?the ssgi binary}
dir="$(cd "$(dirname "$0")" && pwd)/regressions"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
status=0
for f in "$dir"/*.exr; do
  for fov in "" "--fov 50"; do
    # shellcheck disable=SC2086
    rc=0; "$ssgi" run "$f" -o "$out/o.exr" -q --preset draft $fov || rc=$?
    case $rc in 0|3|4) ;; *) echo "$(basename "$f") $fov: exit $rc"; status=1 ;; esac
  done
done
exit $status
