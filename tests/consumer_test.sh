#!/usr/bin/env bash
# Installs the built ssgi into a temporary prefix, then configures, builds and runs
# tests/consumer against it with find_package(ssgi CONFIG).
# Usage: consumer_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1
build=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" > /dev/null
cmake -S "$src/tests/consumer" -B "$work/build" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" \
  > "$work/configure.log" || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/build" > "$work/build.log" || { cat "$work/build.log"; exit 1; }
"$work/build/consumer" "$src/testdata/sample/sample.1-2#.exr" "$work/out/o.####.exr"
test -f "$work/out/o.0001.exr" && test -f "$work/out/o.0002.exr"
test -f "$work/prefix/share/man/man1/ssgi.1"
test -x "$work/prefix/bin/ssgi"
