#!/usr/bin/env bash
# A one-node Slurm cluster on localhost, from Debian's slurm-wlm and munge,
# every file in a temporary directory (keys, config, state, logs; nothing in
# /etc is touched): scripts/slurm/submit.sh bakes the demo scene in 3 parts
# as a job array, at most 2 at a time (--at-once 2, checked in the array's
# record), and merges them in a job that waits for the array; the
# merged file must equal a one-process bake's outside the timings block.
# When the sandbox cannot run the daemons, the test says why and skips.
# Usage: test_slurm.sh PROBEBAKE SOURCE_DIR
set -u
pb=$(realpath "$1")
src=$(realpath "$2")
demo=$src/tests/scenes/demo.gltf
skip() { echo "  SKIP: $*"; echo "[ SKIP ] slurm"; exit 0; }
fail() { echo "  FAIL: $*"; echo "[ FAIL ] slurm"; exit 1; }
for tool in munged slurmctld slurmd sbatch squeue scontrol; do
    command -v "$tool" >/dev/null || skip "$tool not found: scripts/install-deps.sh installs slurm-wlm and munge"
done

t=$(mktemp -d /tmp/pb-slurm-XXXXXX)
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
    sleep 0.5
    for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null; done
    rm -rf "$t"
}
trap cleanup EXIT
mkdir -p "$t/munge" "$t/state" "$t/spool" "$t/jobs"
chmod 700 "$t/munge"

# munge: its own key and socket
dd if=/dev/urandom of="$t/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$t/munge/munge.key"
munged --force --key-file="$t/munge/munge.key" --socket="$t/munge/munge.sock" --pid-file="$t/munge/munged.pid" \
    --log-file="$t/munge/munged.log" --seed-file="$t/munge/munged.seed" 2>"$t/munge/start.err" ||
    skip "munged does not start here: $(head -n 1 "$t/munge/start.err")"
sleep 0.5
[ -f "$t/munge/munged.pid" ] && pids+=("$(cat "$t/munge/munged.pid")")

# slurm: this host as controller and only node, free ports, root as SlurmUser
host=$(hostname -s)
cpus=$(nproc)
mem=$(awk '/MemTotal/ {print int($2 / 1024 / 2)}' /proc/meminfo)
port=$((20000 + RANDOM % 20000))
cat >"$t/slurm.conf" <<EOF
ClusterName=probebake-test
SlurmctldHost=$host
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$(id -un)
SlurmdUser=$(id -un)
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$t/munge/munge.sock
StateSaveLocation=$t/state
SlurmdSpoolDir=$t/spool
SlurmctldPidFile=$t/slurmctld.pid
SlurmdPidFile=$t/slurmd.pid
SlurmctldLogFile=$t/slurmctld.log
SlurmdLogFile=$t/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
SwitchType=switch/none
MaxArraySize=64
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=probebake Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$t/slurm.conf
slurmctld -D -f "$SLURM_CONF" >"$t/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" >"$t/slurmd.out" 2>&1 &
pids+=($!)
# both up and the node idle, within 30 s
up=0
for _ in $(seq 1 60); do
    if ! kill -0 "${pids[-2]}" 2>/dev/null || ! kill -0 "${pids[-1]}" 2>/dev/null; then
        break
    fi
    if scontrol show node "$host" 2>/dev/null | grep -Eq 'State=(IDLE|MIXED)'; then
        up=1
        break
    fi
    sleep 0.5
done
if [ "$up" != 1 ]; then
    why=$(cat "$t/slurmctld.out" "$t/slurmd.out" "$t/slurmctld.log" "$t/slurmd.log" 2>/dev/null |
          grep -iE 'error|fatal' | head -n 1)
    skip "slurmctld/slurmd did not bring the node up here: ${why:-no error logged}"
fi
echo "  one-node cluster up: $host, $cpus CPUs, ports $port/$((port + 1))"

# the bake, one process, then through Slurm in 3 parts
args=(--counts 6,5,7 --rays 32 --passes 6 --target-error 0.05 --octmap-res 4 --quiet)
"$pb" bake "$demo" "${args[@]}" -o "$t/whole.probes" >/dev/null || fail "one-process bake failed"
out=$(bash "$src/scripts/slurm/submit.sh" --probebake "$pb" --parts "$t/jobs" --at-once 2 "$demo" "$t/merged.probes" 3 \
    "${args[@]}") || fail "submit.sh: $out"
echo "  $out"
merge_job=$(sed -n 's/.*merge: job \([0-9]*\).*/\1/p' <<<"$out")
array_job=$(sed -n 's/.*job array \([0-9]*\).*/\1/p' <<<"$out")
# --at-once 2: Slurm holds the array to 2 running tasks (the %2 of --array)
scontrol show job "$array_job" 2>/dev/null | grep -q 'ArrayTaskThrottle=2' ||
    fail "--at-once 2 did not throttle the array: $(scontrol show job "$array_job" 2>&1 | grep -o 'ArrayTaskThrottle=[0-9]*' | head -n 1)"
# wait for the merge job to leave the queue, at most 240 s
for _ in $(seq 1 480); do
    [ -z "$(squeue -h -j "$merge_job" 2>/dev/null)" ] && break
    sleep 0.5
done
[ -z "$(squeue -h -j "$merge_job" 2>/dev/null)" ] || fail "the merge job is still queued after 240 s: $(squeue)"
[ -f "$t/merged.probes" ] || fail "no merged file; logs: $(cat "$t"/jobs/*.log 2>/dev/null | tail -n 5)"
for i in 0 1 2; do
    grep -q "wrote $t/jobs/part-$i.probes: part $i of 3" "$t"/jobs/probebake-part-*_"$i".log ||
        fail "part $i did not run as array task $i"
done
if cmp -s <(head -c 184 "$t/whole.probes") <(head -c 184 "$t/merged.probes") &&
   cmp -s <(tail -c +249 "$t/whole.probes") <(tail -c +249 "$t/merged.probes"); then
    echo "  merged file (3 array tasks + a dependent merge job) == one-process bake, timings aside"
    echo "[  OK  ] slurm"
else
    fail "the merged file differs from the one-process bake"
fi
