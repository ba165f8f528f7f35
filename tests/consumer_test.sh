#!/usr/bin/env bash
# Installs the built ssgi into a temporary prefix, then configures and builds tests/consumer
# against it with find_package(ssgi CONFIG) and runs its programs, each of which checks its own
# result: a sequence run (every frame written), a frame lit from buffers (light on the floor),
# two outputs compared (the same frame passes at RMSE 0, two different frames fail).
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
"$work/build/run_sequence" "$src/testdata/sample/sample.1-2#.exr" "$work/out/o.####.exr"
test -f "$work/out/o.0001.exr" && test -f "$work/out/o.0002.exr"
"$work/build/light_frame"
"$work/build/compare_outputs" "$work/out/o.0001.exr" "$work/out/o.0001.exr" 0
status=0
"$work/build/compare_outputs" "$work/out/o.0002.exr" "$work/out/o.0001.exr" 0 || status=$?
if [ "$status" -ne 1 ]; then
  echo "consumer_test: compare_outputs of two different frames exited $status, not 1" >&2
  exit 1
fi
test -f "$work/prefix/share/man/man1/ssgi.1"
test -x "$work/prefix/bin/ssgi"
# The options library and the internal headers are not part of the package.
test ! -e "$work/prefix/include/ssgi/layout.h" && test ! -e "$work/prefix/lib/libssgi_options.a"
