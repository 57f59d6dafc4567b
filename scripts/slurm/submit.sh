#!/usr/bin/env bash
# Bakes SCENE on a Slurm cluster in N parts: a job array of N tasks (one
# part each, bake.sbatch) and a merge job (merge.sbatch) that waits for all
# of them (--dependency=afterok) and writes OUT. Prints the two job ids.
#
#   scripts/slurm/submit.sh [--probebake PATH] [--parts DIR] [--at-once K] SCENE OUT.probes N [bake options...]
#
# --at-once K: at most K parts run at a time (--array=0-(N-1)%K), so a bake
# in more parts than the slots it should hold (GPUs, licences) leaves the
# rest of the cluster free; each task that ends frees its slot for the next.
# A grid's parts are dealt (probes I, I + N, ...) and take about equal
# times, so N = the machines you have is the usual choice.
#
# Every task must see SCENE, probebake and DIR (default OUT.parts/) at the
# same paths: a shared file system. sbatch's own environment variables
# choose the rest (SBATCH_PARTITION, SBATCH_TIMELIMIT, SBATCH_GRES=gpu:1 for
# one GPU per part, ...). Parts and logs stay for inspection.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
pb=$(command -v probebake || true)
parts=""
at_once=""
while [ $# -gt 0 ]; do
    case $1 in
        --probebake) pb=$2; shift 2 ;;
        --parts) parts=$2; shift 2 ;;
        --at-once) at_once=$2; shift 2 ;;
        *) break ;;
    esac
done
if [ $# -lt 3 ]; then
    echo "usage: $0 [--probebake PATH] [--parts DIR] [--at-once K] SCENE OUT.probes N [bake options...]" >&2
    exit 2
fi
scene=$(realpath "$1") out=$(realpath -m "$2") n=$3
shift 3
case $n in ''|*[!0-9]*|0) echo "submit.sh: N '$n' is not a positive number of parts" >&2; exit 2 ;; esac
throttle=""
if [ -n "$at_once" ]; then
    case $at_once in *[!0-9]*|0) echo "submit.sh: --at-once '$at_once' is not a positive number of parts" >&2; exit 2 ;; esac
    throttle=%$at_once
fi
[ -n "$pb" ] && [ -x "$pb" ] || { echo "submit.sh: no probebake: give --probebake PATH" >&2; exit 2; }
pb=$(realpath "$pb")
parts=$(realpath -m "${parts:-$out.parts}")
mkdir -p "$parts"
array=$(sbatch --parsable --chdir="$parts" --array=0-$((n - 1))$throttle "$here/bake.sbatch" "$pb" "$scene" "$parts" "$n" "$@")
array=${array%%;*}
merge=$(sbatch --parsable --chdir="$parts" --dependency=afterok:"$array" "$here/merge.sbatch" "$pb" "$out" "$parts" "$n")
merge=${merge%%;*}
echo "parts: job array $array ($n tasks${at_once:+, $at_once at a time}) -> $parts; merge: job $merge -> $out"
