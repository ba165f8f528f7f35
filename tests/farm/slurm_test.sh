#!/usr/bin/env bash
# Runs ssgi under a real Slurm scheduler on this one machine and checks that a job array of
# frame chunks writes the same pixels, bit for bit, as one process over the whole shot.
#
#   tests/farm/slurm_test.sh [path/to/ssgi]      (default: build/bin/ssgi)
#   cmake --build build --target slurm_test      (the same, with the built binary)
#
# It starts its own munged, slurmctld and slurmd in a private temporary directory (own key,
# sockets, ports, spool, state and logs; nothing under /etc or /run is used or changed),
# submits tests/farm/ssgi_array.sbatch as an array over testdata/moving in chunks of 4 frames,
# runs the same frames in one process, compares every frame with idiff -fail 0 -warn 0 (every
# channel of every pixel), and stops exactly the daemons it started, also on failure.
# Exit status: 0 all frames identical, 1 a failure, 77 skipped because Slurm, MUNGE or OIIO's
# tools are not installed (Debian: slurm-wlm munge openimageio-tools). Run it as root, so that
# slurmd can start the jobs; SLURM_TEST_KEEP=1 keeps the temporary directory for a post-mortem.
# Not part of the default ctest run: it starts daemons, takes 10-40 s and needs those packages.
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
ssgi=${1:-"$root/build/bin/ssgi"}
say() { echo "slurm_test: [${SECONDS} s] $*"; }
die() {
  echo "slurm_test: FAIL: $*" >&2
  exit 1
}

# Which Debian package provides each program the test needs.
declare -A package_of=(
  [munged]=munge [munge]=munge [slurmctld]=slurmctld [slurmd]=slurmd
  [sbatch]=slurm-client [squeue]=slurm-client [sinfo]=slurm-client [scontrol]=slurm-client
  [scancel]=slurm-client [idiff]=openimageio-tools [oiiotool]=openimageio-tools
)
missing=()
for program in "${!package_of[@]}"; do
  command -v "$program" >/dev/null || missing+=("${package_of[$program]}")
done
if [ ${#missing[@]} -gt 0 ]; then
  say "skipped: missing Debian packages: $(printf '%s\n' "${missing[@]}" | sort -u | tr '\n' ' ')(apt-get install slurm-wlm munge openimageio-tools)"
  exit 77
fi
[ -x "$ssgi" ] || die "$ssgi is not an executable (build first: .ci/setup)"
ssgi=$(cd "$(dirname "$ssgi")" && pwd)/$(basename "$ssgi")

shot=$root/testdata/moving/moving.####.exr
first=1
last=6
chunk=4
for ((f = first; f <= last; f++)); do
  [ -f "$(printf "$root/testdata/moving/moving.%04d.exr" "$f")" ] ||
    die "testdata/moving lacks frame $f (the test needs frames $first-$last)"
done
tasks=$(((last - first + chunk) / chunk))

tmp=$(mktemp -d "${TMPDIR:-/tmp}/ssgi-slurm.XXXXXX")
# munged refuses a socket whose directories are not searchable by all.
chmod 711 "$tmp"
mkdir -m 711 "$tmp/run"
mkdir "$tmp/log" "$tmp/state" "$tmp/spool" "$tmp/array" "$tmp/single"

munged_pid=""
slurmctld_pid=""
slurmd_pid=""
job=""

# Stops a daemon this script started: SIGTERM, then SIGKILL after 15 s.
stop() {
  local pid=$1
  [ -n "$pid" ] || return 0
  kill -TERM "$pid" 2>/dev/null || return 0
  for _ in $(seq 150); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  kill -KILL "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
}

cleanup() {
  local status=$?
  set +e
  if [ -n "$job" ] && [ -n "$slurmctld_pid" ] && [ -n "$(squeue -h -j "$job" -o %i 2>/dev/null)" ]; then
    scancel "$job"
    for _ in $(seq 100); do
      [ -z "$(squeue -h -j "$job" -o %i 2>/dev/null)" ] && break
      sleep 0.2
    done
  fi
  stop "$slurmd_pid"
  stop "$slurmctld_pid"
  stop "$munged_pid"
  if [ "$status" -ne 0 ]; then
    for f in "$tmp"/log/*; do
      [ -s "$f" ] || continue
      echo "--- $f (last 15 lines)" >&2
      tail -n 15 "$f" >&2
    done
  fi
  if [ "${SLURM_TEST_KEEP:-0}" = 1 ]; then
    say "kept $tmp"
  else
    rm -rf "$tmp"
  fi
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# Waits up to $1 seconds for the command after it to succeed.
wait_for() {
  local seconds=$1
  shift
  local deadline=$((SECONDS + seconds))
  until "$@"; do
    [ "$SECONDS" -lt "$deadline" ] || return 1
    sleep 0.5
  done
}

# A TCP port nothing listens on, not among the arguments.
free_port() {
  local port
  while true; do
    port=$((20000 + RANDOM % 40000))
    [[ " $* " == *" $port "* ]] && continue
    (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null || break
  done
  echo "$port"
}

# MUNGE, with its own key and socket.
head -c 1024 /dev/urandom >"$tmp/munge.key"
chmod 600 "$tmp/munge.key"
socket=$tmp/run/munge.socket
munged --foreground --socket="$socket" --key-file="$tmp/munge.key" \
  --pid-file="$tmp/run/munged.pid" --log-file="$tmp/log/munged.log" \
  --seed-file="$tmp/munged.seed" >"$tmp/log/munged.out" 2>&1 &
munged_pid=$!
wait_for 10 test -S "$socket" || die "munged did not create its socket"
munge -S "$socket" -n | unmunge -S "$socket" >/dev/null || die "munge cannot encode and decode"

# Slurm: one node (this machine) with all its CPUs, one partition.
node=$(hostname -s)
ctld_port=$(free_port)
slurmd_port=$(free_port "$ctld_port")
cpus=$(nproc)
user=$(id -un)
touch "$tmp/plugstack.conf"
cat >"$tmp/slurm.conf" <<EOF
ClusterName=ssgitest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/run/slurmctld.pid
SlurmdPidFile=$tmp/run/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
PlugStackConfig=$tmp/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
MinJobAge=600
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=ssgitest Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$tmp/slurm.conf
slurmctld -D >"$tmp/log/slurmctld.out" 2>&1 &
slurmctld_pid=$!
slurmd -D -N "$node" >"$tmp/log/slurmd.out" 2>&1 &
slurmd_pid=$!
node_idle() { [ "$(sinfo -h -N -n "$node" -o %T 2>/dev/null)" = idle ]; }
wait_for 60 node_idle || die "node $node did not become idle within 60 s"
say "slurmctld (port $ctld_port) and slurmd (port $slurmd_port) up; node $node idle with $cpus CPUs"

# The array: one CPU per task, so that tasks run side by side on this machine. Submits it with
# log files under $tmp/log/$1-task-N.out, waits, and checks each task's final state and exit
# code in slurmctld's record of the job.
run_array() {
  local label=$1 job records record id state code
  job=$(SSGI=$ssgi sbatch --parsable --array=0-$((tasks - 1)) --cpus-per-task=1 \
    --chdir="$tmp" --output="$tmp/log/$label-task-%a.out" \
    "$root/tests/farm/ssgi_array.sbatch" "$shot" "$tmp/array/moving.####.exr" \
    "$first-$last" "$chunk")
  job=${job%%;*}
  say "$label: submitted job $job: $tasks array tasks over frames $first-$last in chunks of $chunk"
  job_gone() { [ -z "$(squeue -h -j "$job" -o %i)" ]; }
  wait_for 300 job_gone || die "job $job still queued or running after 300 s"
  say "$label: job $job left the queue"
  mapfile -t records < <(scontrol -o show job "$job")
  [ ${#records[@]} -eq "$tasks" ] || die "scontrol shows ${#records[@]} tasks of job $job, expected $tasks"
  for record in "${records[@]}"; do
    [[ $record =~ ArrayTaskId=([0-9]+) ]] || die "no ArrayTaskId in: $record"
    id=${BASH_REMATCH[1]}
    [[ $record =~ JobState=([A-Z_]+) ]] || die "no JobState in: $record"
    state=${BASH_REMATCH[1]}
    [[ $record =~ ExitCode=([0-9]+:[0-9]+) ]] || die "no ExitCode in: $record"
    code=${BASH_REMATCH[1]}
    [ "$state" = COMPLETED ] && [ "$code" = 0:0 ] || die "task $id: $state, exit code $code"
    say "$label: task $id: $state, exit code $code: $(grep -m1 '^ssgi_array:' "$tmp/log/$label-task-$id.out" || true)"
  done
}
run_array first

# The same frames in one process, with this machine's default thread count.
"$ssgi" run "$shot" -o "$tmp/single/moving.####.exr" --frames "$first-$last" -q ||
  die "the single run failed"
say "single run of frames $first-$last done"

# Exactly the frames asked for, and no temporary file left behind.
expected=$(for ((f = first; f <= last; f++)); do printf 'moving.%04d.exr\n' "$f"; done)
[ "$(ls -A "$tmp/array")" = "$expected" ] ||
  die "the array wrote $(ls -A "$tmp/array" | tr '\n' ' '), expected $(echo $expected)"

# The comparison can fail: one float ulp in a copy of a frame must be caught.
oiiotool "$tmp/single/moving.0001.exr" --mulc 1.0000001 -o "$tmp/nudged.exr"
if idiff -fail 0 -warn 0 "$tmp/single/moving.0001.exr" "$tmp/nudged.exr" >"$tmp/log/idiff-nudged.out"; then
  die "idiff -fail 0 did not notice a one-ulp change"
fi

for ((f = first; f <= last; f++)); do
  name=$(printf 'moving.%04d.exr' "$f")
  idiff -fail 0 -warn 0 "$tmp/array/$name" "$tmp/single/$name" >"$tmp/log/idiff-$f.out" ||
    die "frame $f: the array's pixels differ from the single run's:$(grep -m1 -i 'max error' "$tmp/log/idiff-$f.out" | sed 's/ *values are.*//')"
done
say "frames $first-$last from $tasks array tasks are identical to one run, every channel of every pixel"

# A resubmission after damage, as a wrangler retries a shot: one frame cut short (a half-copied
# file), one gone. The tasks keep the frames that are whole (--skip-existing in the batch
# script), make the two again, and the shot is again identical to the single run.
damaged=$((first + 1))
gone=$last
damaged_name=$(printf 'moving.%04d.exr' "$damaged")
gone_name=$(printf 'moving.%04d.exr' "$gone")
mkdir -p "$tmp/kept"
for ((f = first; f <= last; f++)); do
  name=$(printf 'moving.%04d.exr' "$f")
  [ "$f" -eq "$damaged" ] || [ "$f" -eq "$gone" ] || cp -p "$tmp/array/$name" "$tmp/kept/$name"
done
size=$(stat -c %s "$tmp/array/$damaged_name")
truncate -s $((size / 2)) "$tmp/array/$damaged_name"
rm "$tmp/array/$gone_name"
run_array resubmitted
for name in $(ls "$tmp/kept"); do
  cmp -s "$tmp/kept/$name" "$tmp/array/$name" || die "$name was written again, though it was whole"
done
made=$(cat "$tmp"/log/resubmitted-task-*.out | grep -c ' frames written, ' || true)
[ "$made" -eq "$tasks" ] || die "expected a summary line from each of the $tasks tasks, found $made"
skipped=$(sed -n 's/.* frames written, \([0-9]*\) skipped.*/\1/p' "$tmp"/log/resubmitted-task-*.out |
  paste -sd+ | bc)
[ "$skipped" -eq $((last - first - 1)) ] ||
  die "the resubmission skipped $skipped frames, expected $((last - first - 1))"
for name in "$damaged_name" "$gone_name"; do
  idiff -fail 0 -warn 0 "$tmp/array/$name" "$tmp/single/$name" >"$tmp/log/idiff-again.out" ||
    die "$name, made again, differs from the single run"
done
[ "$(ls -A "$tmp/array")" = "$expected" ] || die "the resubmission left $(ls -A "$tmp/array" | tr '\n' ' ')"
say "resubmitted: $skipped whole frames kept as they were, frames $damaged (cut short) and $gone (gone) made again, identical to one run"
say "PASS"
