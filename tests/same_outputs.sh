#!/usr/bin/env bash
# The outputs of the same commands from two builds of ssgi, compared pixel for pixel: the check
# that a change meant to keep every output exactly as it was does. Each command of the list below
# runs once with each build; every EXR it writes is compared with `idiff -fail 0` (every channel,
# no difference allowed), and the one line per case says which differ.
#
# The list covers the fixtures (testdata/: every temporal mode, bounces, tracers, presets, views,
# lat-long views, --multiframe, a region with its context frames, chunked frames), the sample data
# (../shared/data: room and stage with and without their cube faces, with --multiframe) and,
# when SSGI_TRAINING_CACHE names it, the training set as tests/accuracy/views.sh renders it
# (each scene's shot without views, with its six faces, with its lat-long, with --multiframe).
#
# Usage: tests/same_outputs.sh BASE NEW
#   BASE, NEW   a build directory (holding bin/ssgi) or a git revision of this repository, which
#               is built once into $SSGI_SAME_CACHE/<commit> (default /tmp/ssgi-same) and kept
# Environment:
#   SSGI_SAME_DATA       the sample data (default ../shared/data; skipped when absent)
#   SSGI_TRAINING_CACHE  the training set's cache (tests/accuracy/training/render.sh); optional
#   SSGI_SAME_ONLY       a regular expression: only the cases whose names match it
#   SSGI_SAME_KEEP       a folder to keep both builds' outputs in (default: removed at the end)
# Exit status: 0 when every output is the same, 1 when one differs or a command's exit status
# does, 2 on a usage error.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ $# -ne 2 ]; then
  sed -n '/^# Usage/,/^# Exit/p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
cache=${SSGI_SAME_CACHE:-/tmp/ssgi-same}
data=${SSGI_SAME_DATA:-../shared/data}
training=${SSGI_TRAINING_CACHE:-}
only=${SSGI_SAME_ONLY:-}
keep=${SSGI_SAME_KEEP:-}

# ssgi_of BUILD_OR_REVISION: the path of its ssgi binary, building a revision first.
ssgi_of() {
  if [ -x "$1/bin/ssgi" ]; then
    echo "$1/bin/ssgi"
    return
  fi
  local commit
  commit=$(git rev-parse --verify --quiet "$1^{commit}") ||
    { echo "same_outputs.sh: $1: neither a build directory nor a revision" >&2; exit 2; }
  local dir=$cache/$commit
  if [ ! -x "$dir/build/bin/ssgi" ]; then
    mkdir -p "$cache"
    rm -rf "$dir"
    git worktree add --detach "$dir" "$commit" > /dev/null 2>&1
    launcher=()
    if command -v ccache > /dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
    cmake -S "$dir" -B "$dir/build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" \
      > "$dir.configure.log" 2>&1 || { cat "$dir.configure.log" >&2; exit 1; }
    cmake --build "$dir/build" --target ssgi_cli > "$dir.build.log" 2>&1 ||
      cmake --build "$dir/build" > "$dir.build.log" 2>&1 ||
      { tail -n 30 "$dir.build.log" >&2; exit 1; }
  fi
  echo "$dir/build/bin/ssgi"
}

base=$(ssgi_of "$1")
new=$(ssgi_of "$2")
work=$(mktemp -d)
if [ -n "$keep" ]; then
  mkdir -p "$keep"
  work=$keep
else
  trap 'rm -rf "$work"' EXIT
fi

# The cases: a name, then `ssgi run`'s input and options (`ssgi reference`'s for a name that
# starts with "reference."; the output is added). Paths with spaces are not supported.
cases=()
add() { cases+=("$*"); }

t=testdata
faces() {  # faces PREFIX SUFFIX: the six --view options of a cube
  local f
  for f in px nx py ny pz nz; do printf -- '--view %s.%s%s ' "$1" "$f" "$2"; done
}
add sample.default $t/sample/sample.####.exr
add sample.none $t/sample/sample.####.exr --temporal none
add sample.ema $t/sample/sample.####.exr --temporal ema
add sample.bounces1 $t/sample/sample.####.exr --bounces 1
add sample.bounces3 $t/sample/sample.####.exr --bounces 3
add sample.draft $t/sample/sample.####.exr --preset draft
add sample.final $t/sample/sample.####.exr --preset final
add sample.march $t/sample/sample.####.exr --tracer march
add sample.chunk $t/sample/sample.####.exr --frames 3-4
add sample.multiframe $t/sample/sample.####.exr --multiframe on
add sample.multiframe.none $t/sample/sample.####.exr --multiframe on --temporal none
add pan.default $t/pan/pan.####.exr
add pan.multiframe $t/pan/pan.####.exr --multiframe on
add pan.multiframe.bounces1 $t/pan/pan.####.exr --multiframe on --bounces 1
add pan.faces $t/pan/pan.####.exr $(faces $t/views/pan .####.exr)
add pan.faces.none $t/pan/pan.####.exr --temporal none $(faces $t/views/pan .####.exr)
add pan.faces.ema $t/pan/pan.####.exr --temporal ema $(faces $t/views/pan .####.exr)
add pan.faces.bounces1 $t/pan/pan.####.exr --bounces 1 $(faces $t/views/pan .####.exr)
add pan.faces.multiframe $t/pan/pan.####.exr --multiframe on $(faces $t/views/pan .####.exr)
add pan.latlong $t/pan/pan.####.exr --latlong-view $t/views/pan.latlong.####.exr
add static.faces $t/static/static.####.exr $(faces $t/views/static .exr)
add static.latlong $t/static/static.####.exr --latlong-view $t/views/static.latlong.exr
add moving.default $t/moving/moving.####.exr
add moving.multiframe $t/moving/moving.####.exr --multiframe on
add moving.ema $t/moving/moving.####.exr --temporal ema
add blender.default $t/blender/corner.####.exr
add blender.multiframe $t/blender/corner.####.exr --multiframe on
add crop.default $t/crop/crop.0001.exr
add overscan.default $t/overscan/overscan.0001.exr
add furnace.default $t/furnace/furnace.0001.exr
add plane.default $t/plane/plane.0001.exr
add symmetric.default $t/symmetric/symmetric.0001.exr
add region.context $t/crop/crop.0001.exr --context $t/sample/sample.####.exr
add region.context.multiframe $t/crop/crop.0001.exr --context $t/sample/sample.####.exr \
  --multiframe on
add reference.sample $t/sample/sample.0001.exr --spp 16
if [ -d "$data/room" ]; then
  for scene in room stage; do
    add "$scene.default" "$data/$scene/$scene.####.exr"
    add "$scene.multiframe" "$data/$scene/$scene.####.exr" --multiframe on
    add "$scene.faces" "$data/$scene/$scene.####.exr" $(faces "$data/$scene/views/$scene" .####.exr)
    add "$scene.faces.multiframe" "$data/$scene/$scene.####.exr" --multiframe on \
      $(faces "$data/$scene/views/$scene" .####.exr)
  done
fi
if [ -n "$training" ]; then
  for dir in "$training"/*/; do
    scene=$(basename "$dir")
    case $scene in *.views) continue ;; esac
    [ -n "$(ls "$dir" | grep -E "^$scene\.[0-9]+\.exr$" || true)" ] || continue
    shot=$dir$scene.####.exr
    views=$training/$scene.views/$scene
    add "training.$scene" "$shot"
    add "training.$scene.multiframe" "$shot" --multiframe on
    if [ -f "$training/$scene.views/done" ]; then
      add "training.$scene.faces" "$shot" $(faces "$views" .####.exr)
      add "training.$scene.latlong" "$shot" --latlong-view "$views.latlong.####.exr"
      add "training.$scene.faces.multiframe" "$shot" --multiframe on \
        $(faces "$views" .####.exr)
    fi
  done
fi

# run_case BINARY DIR COMMAND ARGS...: ssgi COMMAND ARGS -o DIR/o.####.exr; its exit status.
run_case() {
  local bin=$1 dir=$2 command=$3
  shift 3
  mkdir -p "$dir"
  local rc=0
  "$bin" "$command" "$@" -o "$dir/o.####.exr" -q > "$dir/log" 2>&1 || rc=$?
  echo "$rc"
}

failed=0 ran=0
for c in "${cases[@]}"; do
  read -r -a words <<< "$c"
  name=${words[0]}
  args=("${words[@]:1}")
  if [ -n "$only" ] && ! [[ $name =~ $only ]]; then continue; fi
  ran=$((ran + 1))
  command=run
  case $name in reference.*) command=reference ;; esac
  rc_base=$(run_case "$base" "$work/base/$name" "$command" "${args[@]}")
  rc_new=$(run_case "$new" "$work/new/$name" "$command" "${args[@]}")
  verdict=same
  if [ "$rc_base" != "$rc_new" ]; then
    verdict="exit status $rc_base -> $rc_new"
  else
    mapfile -t outputs < <(cd "$work/base/$name" && ls -- *.exr 2> /dev/null || true)
    mapfile -t outputs_new < <(cd "$work/new/$name" && ls -- *.exr 2> /dev/null || true)
    if [ "${outputs[*]}" != "${outputs_new[*]}" ]; then
      verdict="other files: ${outputs[*]} -> ${outputs_new[*]}"
    elif [ ${#outputs[@]} -eq 0 ]; then
      verdict="no output (exit status $rc_base)"
    else
      differ=()
      for o in "${outputs[@]}"; do
        idiff -q -fail 0 -warn 0 "$work/base/$name/$o" "$work/new/$name/$o" > /dev/null 2>&1 ||
          differ+=("$o")
      done
      if [ ${#differ[@]} -gt 0 ]; then verdict="differ: ${differ[*]}"; fi
    fi
  fi
  [ "$verdict" = same ] || failed=$((failed + 1))
  printf '%-36s %s (%d EXRs)\n' "$name" "$verdict" \
    "$(ls "$work/new/$name" | grep -c '\.exr$' || true)"
done
echo "$ran cases, $failed differ"
[ "$failed" -eq 0 ]
