#!/usr/bin/env bash
# Builds ssgi with clang (CXX overrides it), AddressSanitizer and UndefinedBehaviorSanitizer
# (SSGI_SANITIZE=ON, any report fatal) into build-asan/ and runs the test suite there: the unit
# tests, the CLI tests and the property tests. The benchmarks and the accuracy tool are not run, and the tests that
# time or measure memory (they would measure the sanitizers) are left out. Not part of the
# README's test command; CI (.ci/run) runs it after that command.
# Usage: tests/sanitize.sh [ctest arguments...]     e.g. tests/sanitize.sh -R Cli
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${SSGI_ASAN_BUILD:-$root/build-asan}"
# clang and its sanitizer runtimes, from Debian's packages when missing.
"$root/.ci/install-packages" clang libclang-rt-dev
export CC="${CC:-clang}" CXX="${CXX:-clang++}"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSSGI_SANITIZE=ON \
  ${SSGI_CMAKE_ARGS:-} > /dev/null
cmake --build "$build"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
start=$(date +%s)
ctest --test-dir "$build" -j"$(nproc)" --output-on-failure -E "${SSGI_ASAN_EXCLUDE:-Memory.TheEstimateBoundsTheMeasuredPeak}" --timeout 1800 "$@"
echo "sanitized test run: $(( $(date +%s) - start )) s"
