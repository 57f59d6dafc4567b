#!/usr/bin/env bash
# What sharding costs: wall time of a bake split into N parts against the
# same bake in one process, in the same run, on this machine:
#   one process      probebake bake (the peer every ratio is against)
#   N in sequence    N processes one after another, then probebake merge:
#                    the total work a farm pays (each part loads the scene,
#                    builds the BVH, creates the device and its pipelines)
#   N, J at a time   the same N processes, J running at once
#   N devices        bake --devices with N logical devices of device 0, one
#                    process (a thread per part), merged in memory
#   a farm of W      what W machines would take for the N parts, from the
#                    parts' measured times: each part goes, in index order,
#                    to the first machine free (a Slurm job array limited to
#                    W tasks at a time, --array=0-(N-1)%W), then the merge;
#                    against the one-process bake split perfectly over W
#                    machines (peer / W). Uneven parts (probes in rock
#                    stop early, converged probes drop out at their own
#                    pass) show here as a farm slower than peer / W.
# Every merged file must equal the one-process file outside the timings
# block (it is checked and reported: sharding costs no error). Prints a
# table, writes CSV and JSON.
#
#   bench/shard_bench.sh [--probebake P] [--parts N] [--jobs J] [--workers W] [--out DIR]
#                        [SCENE [bake options...]]
#
# Default: the demo scene at --quality production with 2,048 probes, 4 parts,
# 2 at a time, a farm of 4, into bench/results/shard_bench/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pb=$root/build/probebake
n=4
jobs=2
workers=4
out=$root/bench/results/shard_bench
while [ $# -gt 0 ]; do
    case $1 in
        --probebake) pb=$2; shift 2 ;;
        --parts) n=$2; shift 2 ;;
        --jobs) jobs=$2; shift 2 ;;
        --workers) workers=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        *) break ;;
    esac
done
scene=${1:-$root/tests/scenes/demo.gltf}
[ $# -gt 0 ] && shift
args=("$@")
[ ${#args[@]} -gt 0 ] || args=(--quality production --counts 16,8,16)
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

now_ms() { echo $(($(date +%s%N) / 1000000)); }
same() { # 1 when the two files agree outside the timings block (header bytes 184..247)
    cmp -s <(head -c 184 "$1") <(head -c 184 "$2") && cmp -s <(tail -c +249 "$1") <(tail -c +249 "$2") && echo yes || echo no
}
bake() { "$pb" bake "$scene" "${args[@]}" --quiet "$@" >/dev/null; }

device=$("$pb" devices --json | sed -n 's/.*"index": 0, "name": "\([^"]*\)".*/\1/p' | head -n 1)
echo "shard_bench: $scene ${args[*]}; $n parts; $(nproc) cores; device: $device"

t=$(now_ms); bake -o "$tmp/whole.probes"; whole=$(($(now_ms) - t))

parts_ms=()
t=$(now_ms)
for i in $(seq 0 $((n - 1))); do
    tp=$(now_ms)
    bake --shard "$i/$n" -o "$tmp/seq$i.probes"
    parts_ms+=($(($(now_ms) - tp)))
done
tm=$(now_ms)
"$pb" merge "$tmp/seq.probes" $(for i in $(seq 0 $((n - 1))); do echo "$tmp/seq$i.probes"; done) >/dev/null
merge=$(($(now_ms) - tm))
sequential=$(($(now_ms) - t))
seq_same=$(same "$tmp/whole.probes" "$tmp/seq.probes")
longest=0
for m in "${parts_ms[@]}"; do [ "$m" -gt "$longest" ] && longest=$m; done
# list schedule in index order over W machines, then the merge
farm=$(printf '%s\n' "${parts_ms[@]}" | awk -v w="$workers" -v merge="$merge" '
    BEGIN { for (i = 0; i < w; ++i) free[i] = 0 }
    { k = 0; for (i = 1; i < w; ++i) if (free[i] < free[k]) k = i; free[k] += $1 }
    END { m = 0; for (i = 0; i < w; ++i) if (free[i] > m) m = free[i]; print m + merge }')

t=$(now_ms)
for i in $(seq 0 $((n - 1))); do
    bake --shard "$i/$n" -o "$tmp/par$i.probes" &
    while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n; done
done
wait
"$pb" merge "$tmp/par.probes" $(for i in $(seq 0 $((n - 1))); do echo "$tmp/par$i.probes"; done) >/dev/null
parallel=$(($(now_ms) - t))
par_same=$(same "$tmp/whole.probes" "$tmp/par.probes")

list=$(for i in $(seq 1 "$n"); do printf '0,'; done)
t=$(now_ms); bake --devices "${list%,}" -o "$tmp/dev.probes"; devices=$(($(now_ms) - t))
dev_same=$(same "$tmp/whole.probes" "$tmp/dev.probes")

ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }
printf '\n%-34s %10s %9s %10s\n' "run" "wall ms" "vs one" "identical"
printf '%-34s %10d %9s %10s\n' "one process (peer)" "$whole" "1.00" "-"
printf '%-34s %10d %9s %10s\n' "$n parts in sequence + merge" "$sequential" "$(ratio "$sequential" "$whole")" "$seq_same"
printf '%-34s %10d %9s %10s\n' "  of which the longest part" "$longest" "$(ratio "$longest" "$whole")" ""
printf '%-34s %10d %9s %10s\n' "  of which merge" "$merge" "$(ratio "$merge" "$whole")" ""
printf '%-34s %10d %9s %10s\n' "$n parts, $jobs at a time + merge" "$parallel" "$(ratio "$parallel" "$whole")" "$par_same"
printf '%-34s %10d %9s %10s\n' "--devices: $n logical devices" "$devices" "$(ratio "$devices" "$whole")" "$dev_same"
ideal=$((whole / workers))
printf '%-34s %10d %9s %10s\n' "a farm of $workers: one process / $workers" "$ideal" "$(ratio "$ideal" "$whole")" "-"
printf '%-34s %10d %9s %10s\n' "a farm of $workers: $n parts + merge" "$farm" "$(ratio "$farm" "$whole")" "$seq_same"
printf '%-34s %10s %9s\n' "  farm / (one process / $workers)" "" "$(ratio "$farm" "$ideal")"

stem=$out/$(basename "$scene" | sed 's/\.[^.]*$//')-$n-parts
{
    echo "run,wall_ms,ratio_vs_one_process,identical"
    echo "one_process,$whole,1.00,"
    echo "parts_sequential_with_merge,$sequential,$(ratio "$sequential" "$whole"),$seq_same"
    echo "longest_part,$longest,$(ratio "$longest" "$whole"),"
    echo "merge,$merge,$(ratio "$merge" "$whole"),"
    echo "parts_${jobs}_at_a_time_with_merge,$parallel,$(ratio "$parallel" "$whole"),$par_same"
    echo "devices_${n}_logical,$devices,$(ratio "$devices" "$whole"),$dev_same"
    echo "farm_${workers}_ideal,$ideal,$(ratio "$ideal" "$whole"),"
    echo "farm_${workers}_parts_with_merge,$farm,$(ratio "$farm" "$whole"),$seq_same"
} >"$stem.csv"
cat >"$stem.json" <<EOF
{"scene": "$(basename "$scene")", "args": "${args[*]}", "parts": $n, "jobs": $jobs, "cores": $(nproc), "device": "$device",
 "one_process_ms": $whole, "parts_sequential_ms": $sequential, "part_ms": [$(IFS=,; echo "${parts_ms[*]}")],
 "merge_ms": $merge, "parts_parallel_ms": $parallel, "devices_ms": $devices,
 "workers": $workers, "farm_ms": $farm, "farm_ideal_ms": $ideal, "farm_vs_ideal": $(ratio "$farm" "$ideal"),
 "identical": {"sequential": "$seq_same", "parallel": "$par_same", "devices": "$dev_same"}}
EOF
echo
echo "wrote $stem.csv and $stem.json"
[ "$seq_same" = yes ] && [ "$par_same" = yes ] && [ "$dev_same" = yes ]
