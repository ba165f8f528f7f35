#!/usr/bin/env bash
# Builds the libFuzzer targets with clang, AddressSanitizer and UndefinedBehaviorSanitizer into
# build-fuzz/ (SSGI_FUZZ=ON), writes the seed corpus from the fixtures, and runs each target
# for SECONDS (default 600) with what it finds kept in build-fuzz/corpus/<target>/ and crashes
# in build-fuzz/findings/. Not part of the default test run.
# Usage: tests/fuzz/run.sh [SECONDS] [TARGET...]   (targets: exr camera pattern)
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
seconds="${1:-600}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(exr camera pattern)
build="${SSGI_FUZZ_BUILD:-$root/build-fuzz}"

CC=clang CXX=clang++ cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DSSGI_FUZZ=ON ${SSGI_CMAKE_ARGS:-} > /dev/null
cmake --build "$build" --target $(printf 'fuzz_%s ' "${targets[@]}")

seeds="$build/seeds"
[ -d "$seeds/exr" ] || "$root/tests/fuzz/make_corpus.sh" "$seeds"
mkdir -p "$build/findings"
# Leaks are findings; OIIO's and OpenEXR's thread pools are not torn down before exit.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
status=0
for t in "${targets[@]}"; do
  corpus="$build/corpus/$t"
  mkdir -p "$corpus"
  echo "fuzz_$t: ${seconds}s"
  # -rss_limit_mb: a header may declare a huge image; ssgi must refuse it before allocating.
  "$build/bin/fuzz_$t" "$corpus" "$seeds/$t" -max_total_time="$seconds" \
    -rss_limit_mb=2048 -timeout=30 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$build/findings/${t}_" 2>&1 | tail -n 25 || status=1
done
exit $status
