#!/usr/bin/env bash
# A real scheduler, not a simulation of one: brings up a one-node Slurm
# cluster (munged, slurmctld, slurmd) in a scratch directory, submits
# experiments/slurm/run-spec.sbatch over the quick spec as a 4-task array,
# merges the shard stores and checks that they equal one unsharded run of the
# same spec with the same options. Every daemon and job it started is gone
# when it exits, pass or fail.
#
#   tests/slurm/slurm_cluster_test.sh path/to/shimmer
#
# Exit 77 (skipped) when slurmctld, slurmd or munged is not installed
# (Debian: apt-get install slurm-wlm munge) or when not run as root (slurmd
# starts each job as the user who submitted it); anything else that goes
# wrong fails with one line, and the scratch directory is kept for its logs.
set -euo pipefail

shimmer=${1:?usage: slurm_cluster_test.sh SHIMMER_EXE}
shimmer=$(realpath "$shimmer")
root=$(cd "$(dirname "$0")/../.." && pwd)
spec=$root/experiments/specs/quick.json
shards=4
# The timing renders and the doubled-sample reference checks are most of the
# quick spec's cost, and neither is what sharding can get wrong: jobs are.
options=(--no-benchmark --no-check)
# Deadlines well inside ctest's TIMEOUT, so that a hang ends in this script's
# cleanup and not in a SIGKILL that would strand the daemons.
node_deadline_s=60
array_deadline_s=600
run_deadline_s=300

# Debian puts the daemons in sbin, which a non-login PATH may lack.
PATH=$PATH:/usr/sbin:/sbin
for daemon in slurmctld slurmd munged; do
  if ! command -v "$daemon" >/dev/null; then
    echo "slurm_cluster_test: SKIP: $daemon not installed (apt-get install slurm-wlm munge)"
    exit 77
  fi
done

scratch=""
failed=""
fail() {
  failed=1
  echo "slurm_cluster_test: FAIL: $*${scratch:+ (logs in $scratch)}" >&2
  exit 1
}
if [ "$(id -u)" -ne 0 ]; then
  # slurmd starts each job as the user who submitted it, which only root can.
  echo "slurm_cluster_test: SKIP: needs root to run slurmd (run the test suite as root, as CI does)"
  exit 77
fi
for tool in mungekey munge sbatch squeue sinfo scontrol scancel sqlite3; do
  command -v "$tool" >/dev/null || fail "$tool not found (apt-get install slurm-wlm munge sqlite3)"
done

scratch=$(mktemp -d -t shimmer-slurm.XXXXXX)
conf=$scratch/slurm.conf
socket=$scratch/munge/munge.socket
pids=()
job=""

# Slurm's client commands find this cluster through SLURM_CONF. It is never
# exported from this shell, so that a process carrying it in its environment
# is one this test started (the daemons, slurmstepd, the job's shimmer).
slurm() { env SLURM_CONF="$conf" "$@"; }

# The pids of the processes that carry our SLURM_CONF.
ours() {
  local env pid
  for env in /proc/[0-9]*/environ; do
    pid=${env#/proc/}
    pid=${pid%/environ}
    if grep -qzxF "SLURM_CONF=$conf" "$env" 2>/dev/null; then echo "$pid"; fi
  done
}

steps_running() {
  local socket
  for socket in "$scratch"/spool/*; do [ -S "$socket" ] && return 0; done
  return 1
}

# An exited slurmstepd (it is reparented to init) stays a zombie until init
# reaps it; its environment is gone by then, so only its name tells.
orphaned_steps() {
  local stat comm state ppid
  for stat in /proc/[0-9]*/stat; do
    read -r _ comm state ppid _ 2>/dev/null <"$stat" || continue
    [ "$comm $state $ppid" = "(slurmstepd) Z 1" ] && return 0
  done
  return 1
}

alive() {
  local pid
  for pid in "$@"; do [ -e "/proc/$pid" ] && return 0; done
  return 1
}

cleanup() {
  local rc=$? seen=() pid
  set +e
  if [ -n "$job" ]; then
    slurm scancel "$job" 2>/dev/null
    for _ in $(seq 30); do
      [ -z "$(slurm squeue -h -j "$job" -o %i 2>/dev/null)" ] && break
      sleep 1
    done
    # A finished job's slurmstepd lingers a moment; its socket in the spool
    # goes last.
    for _ in $(seq 50); do
      steps_running || break
      sleep 0.2
    done
  fi
  mapfile -t seen < <(ours)
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[i]}" 2>/dev/null; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null; done
  # slurmstepd outlives slurmd by design: a step the cancel did not reach
  # ends here, and the test returns once every such process is gone.
  for pid in $(ours); do kill -9 "$pid" 2>/dev/null; done
  for _ in $(seq 50); do
    alive "${seen[@]}" || orphaned_steps || break
    sleep 0.2
  done
  if [ "$rc" -eq 0 ]; then
    rm -rf "$scratch"
  elif [ -z "$failed" ]; then
    echo "slurm_cluster_test: FAIL: exit $rc at an unexpected error (logs in $scratch)" >&2
  fi
}
trap cleanup EXIT
trap 'fail "stopped by a signal"' INT TERM HUP

# A port nothing answers on, so that a stale daemon of another run cannot
# take this cluster's messages.
free_port() {
  local port
  for _ in $(seq 50); do
    port=$((20000 + RANDOM % 30000))
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
      echo "$port"
      return
    fi
  done
  return 1
}

elapsed() { echo $((SECONDS - $1)); }

# --- munge, with its own key and socket ---
# munged wants every directory above its socket searchable by all users.
chmod 711 "$scratch"
mkdir -m 711 "$scratch/munge"
mungekey --create --keyfile="$scratch/munge/munge.key" 2>"$scratch/munge/mungekey.err" ||
  fail "mungekey: $(tail -n 1 "$scratch/munge/mungekey.err")"
munged --foreground --socket="$socket" --key-file="$scratch/munge/munge.key" \
  --pid-file="$scratch/munge/munged.pid" --log-file="$scratch/munge/munged.log" \
  --seed-file="$scratch/munge/munged.seed" 2>"$scratch/munge/munged.err" &
pids+=($!)
for _ in $(seq 50); do
  munge -n -S "$socket" >/dev/null 2>&1 && break
  kill -0 "${pids[0]}" 2>/dev/null || fail "munged exited: $(tail -n 1 "$scratch/munge/munged.err")"
  sleep 0.2
done
munge -n -S "$socket" >/dev/null 2>&1 || fail "munged does not answer on its socket"

# --- slurm.conf for this one node ---
host=$(hostname -s)
cpus=$(nproc)
# A little below what slurmd measures, or the node is drained as "Low RealMemory".
memory=$(($(free -m | awk '/^Mem:/ {print $2}') * 9 / 10))
ctld_port=$(free_port) || fail "no free TCP port found"
slurmd_port=$(free_port) || fail "no free TCP port found"
[ "$ctld_port" != "$slurmd_port" ] || slurmd_port=$((ctld_port + 1))
mkdir -p "$scratch/state" "$scratch/spool" "$scratch/log" "$scratch/tmp" "$scratch/runs"
cat >"$conf" <<EOF
ClusterName=shimmer-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
MpiDefault=none
# No cgroup plugin at all, so no cgroup.conf: a container without systemd
# may not delegate a cgroup hierarchy, and one task at a time needs none.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MailProg=/bin/true
# The next task starts when one ends, not at backfill's next pass.
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
# The node is idle as soon as slurmd registers, not down until resumed.
ReturnToService=2
# Finished tasks stay known until the test reads how each ended: the tasks
# run one after another, and on a busy machine the first ended more than the
# default 300 s before the last (seen: 3 of 4 tasks reported).
MinJobAge=3600
StateSaveLocation=$scratch/state
SlurmdSpoolDir=$scratch/spool
SlurmctldPidFile=$scratch/slurmctld.pid
SlurmdPidFile=$scratch/slurmd.pid
SlurmctldLogFile=$scratch/log/slurmctld.log
SlurmdLogFile=$scratch/log/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

# --- the daemons, in the foreground of background jobs so their pids are ours ---
start=$SECONDS
SLURM_CONF=$conf slurmctld -D -i -f "$conf" >"$scratch/log/slurmctld.out" 2>&1 &
pids+=($!)
SLURM_CONF=$conf slurmd -D -N "$host" -f "$conf" >"$scratch/log/slurmd.out" 2>&1 &
pids+=($!)
state=""
for _ in $(seq $((node_deadline_s * 2))); do
  kill -0 "${pids[1]}" 2>/dev/null || fail "slurmctld exited: $(tail -n 1 "$scratch/log/slurmctld.log")"
  kill -0 "${pids[2]}" 2>/dev/null || fail "slurmd exited: $(tail -n 1 "$scratch/log/slurmd.log")"
  state=$(slurm sinfo -h -n "$host" -o %t 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "$state" = idle ] || fail "node $host is '${state:-unknown}' after ${node_deadline_s} s, not idle"
echo "slurm_cluster_test: one-node cluster up ($host, $cpus CPUs, ${memory} MiB) in $(elapsed "$start") s"

# --- the array ---
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$scratch/tmp}
start=$SECONDS
submitted=$(cd "$scratch" && SLURM_CONF=$conf SHIMMER_EXE=$shimmer SHIMMER_RUNS=$scratch/runs TMPDIR=$scratch/tmp \
  sbatch --array=0-$((shards - 1)) "$root/experiments/slurm/run-spec.sbatch" "$spec" "${options[@]}" \
  2>"$scratch/sbatch.err") || fail "sbatch: $(tail -n 1 "$scratch/sbatch.err")"
echo "$submitted"
job=${submitted##* }
[[ "$job" =~ ^[0-9]+$ ]] || fail "no job id in sbatch's answer: $submitted"
while [ -n "$(slurm squeue -h -j "$job" -o %i)" ]; do
  if [ "$(elapsed "$start")" -ge "$array_deadline_s" ]; then
    fail "job $job not done after $array_deadline_s s: $(slurm squeue -h -j "$job" -o '%i %T %r' | tr '\n' ';')"
  fi
  sleep 2
done
# Finished tasks stay known to slurmctld for MinJobAge (3600 s, slurm.conf
# above), long enough to read how each ended.
slurm scontrol -o show job "$job" >"$scratch/tasks.txt" || fail "scontrol cannot show job $job"
completed=0
while read -r task state exit_code; do
  [ "$state" = COMPLETED ] || fail "array task $task ended $state (exit $exit_code), see shimmer-$task.log"
  completed=$((completed + 1))
done < <(sed -nE 's/.* ArrayJobId=([0-9]+) ArrayTaskId=([0-9]+) .* JobState=([A-Z_]+) .* ExitCode=([0-9:]+).*/\1_\2 \3 \4/p' \
  "$scratch/tasks.txt")
[ "$completed" -eq "$shards" ] || fail "$completed of $shards array tasks reported COMPLETED (tasks.txt)"
echo "slurm_cluster_test: $shards array tasks completed in $(elapsed "$start") s"

for ((i = 0; i < shards; i++)); do
  [ -s "$scratch/runs/quick/shard-$i.db" ] || fail "task $i wrote no store runs/quick/shard-$i.db"
done
(cd "$scratch/runs/quick" && "$shimmer" merge shard-*.db -o merged.db) || fail "shimmer merge failed"

# --- the same spec, unsharded, with the same options ---
start=$SECONDS
timeout "$run_deadline_s" "$shimmer" run "$spec" --db "$scratch/full.db" --work "$scratch/frames" "${options[@]}" \
  >"$scratch/full.log" 2>&1 || fail "unsharded shimmer run failed: $(tail -n 1 "$scratch/full.log")"
echo "slurm_cluster_test: unsharded run in $(elapsed "$start") s"

# --- the stores must agree on everything that is not a timing or a path ---
# jobs: every key and metric column, and the full metrics JSON less the two
# frame paths (each run renders into its own frame cache). gpu_ms_per_frame,
# wall_s and finished_at are timings. shots and benchmarks: their keys and
# the verdict (their JSON and medians hold timings); with --no-check and
# --no-benchmark both tables are empty in both stores.
rows() {
  sqlite3 -bail "$1" "
    SELECT id, reference_id, scene, material, camera, variant, params, derivatives, width, height, frames, fps,
           reference_spp, reference_tolerance, tv_ratio, tv_err, energy_bias, temporal_diff_err, relmse,
           flicker_index, json_remove(metrics, '$.reference', '$.test'), job, revision, core_version, device, driver
      FROM jobs ORDER BY id;
    SELECT 'shot', reference_id, scene, material, camera, converged FROM shots ORDER BY reference_id;
    SELECT 'benchmark', scene, derivatives, variant, params, width, height, device
      FROM benchmarks ORDER BY scene, derivatives, variant, params, width, height, device;"
}
rows "$scratch/full.db" >"$scratch/full.rows" || fail "sqlite3 cannot read full.db"
rows "$scratch/runs/quick/merged.db" >"$scratch/merged.rows" || fail "sqlite3 cannot read runs/quick/merged.db"
jobs=$(sqlite3 "$scratch/full.db" "SELECT count(*) FROM jobs")
[ "$jobs" -gt 0 ] || fail "the unsharded run stored no jobs"
if ! diff "$scratch/full.rows" "$scratch/merged.rows" >"$scratch/rows.diff"; then
  first=$(grep -m 1 '^[<>]' "$scratch/rows.diff" | cut -d '|' -f 1)
  fail "merged store differs from the unsharded run in $(grep -c '^[<>]' "$scratch/rows.diff") lines (first: $first; rows.diff)"
fi
echo "slurm_cluster_test: PASS: $shards shards merged = unsharded run ($jobs jobs, options ${options[*]})"
