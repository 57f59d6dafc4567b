#!/usr/bin/env bash
# Two builds' trace kernels against each other on a machine whose lavapipe
# rate drifts (bench/RESULTS.md: by up to 25 % between minutes on the Intel
# machines, and bimodal per process on the AMD one, 2.1 or 3.2 Mrays/s on The
# Crypt). One run of each says nothing there; this runs N alternating pairs of
# short trace_bench runs per scene (A then B, same rays, same scene) and reads
# the median of the pairs' kernel-rate ratios B/A, with its spread. Each run's
# Embree ratio is kept too. Prints a table, writes CSV (every pair) and JSON
# (the summary).
#
#   bench/ab_kernel.sh [--pairs N] [--out DIR] [--bake] BUILD_A BUILD_B SCENE... [-- ARGS]
#
# BUILD_A, BUILD_B: build directories (each with bench/trace_bench), e.g. a
# worktree of the commit before a change. Defaults: 20 pairs, `--probes 1024
# --rays 256 --repeat 3`, into bench/results/ab_kernel/. The device is the
# one trace_bench picks (VK_DRIVER_FILES: lavapipe where set).
# --bake: the pairs are `probebake bake SCENE ARGS` instead (default ARGS
# `--counts 16,8,16 --rays 256 --passes 1 --bounces 3`), and the ratio is of
# the bake's GPU trace time (relocation and passes), B/A: below 1 is faster.
# No Embree peer there. Each build runs once per scene before the pairs,
# untimed: llvmpipe compiles a kernel at its first dispatch (cached on disk
# afterwards), and each scene's stack depth is a specialisation of its own.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pairs=20
out=$root/bench/results/ab_kernel
bake=0
while [ $# -gt 0 ]; do
    case $1 in
        --pairs) pairs=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        --bake) bake=1; shift ;;
        *) break ;;
    esac
done
[ $# -ge 3 ] || { echo "usage: $0 [--pairs N] [--out DIR] [--bake] BUILD_A BUILD_B SCENE... [-- ARGS]" >&2; exit 2; }
a=$1 b=$2
shift 2
scenes=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do scenes+=("$1"); shift; done
[ $# -gt 0 ] && shift
extra=("$@")
if [ $bake = 1 ]; then
    [ ${#extra[@]} -gt 0 ] || extra=(--counts 16,8,16 --rays 256 --passes 1 --bounces 3)
    tool=probebake
else
    [ ${#extra[@]} -gt 0 ] || extra=(--probes 1024 --rays 256 --repeat 3)
    tool=bench/trace_bench
fi
for bd in "$a" "$b"; do
    [ -x "$bd/$tool" ] || { echo "$0: $bd/$tool: not built" >&2; exit 1; }
done
[[ "$pairs" =~ ^[1-9][0-9]*$ ]] || { echo "$0: --pairs '$pairs' is not a positive integer" >&2; exit 2; }
for s in "${scenes[@]}"; do
    [ -f "$s" ] || { echo "$0: scene $s: no such file" >&2; exit 1; }
done
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

csv=$out/ab_kernel.csv
# one run: trace_bench's kernel Mrays/s and its Embree ratio, or (--bake) the
# bake's GPU trace ms and an empty peer column
if [ $bake = 1 ]; then
    echo "scene,pair,a_gpu_ms,b_gpu_ms,b_over_a,a_embree_ratio,b_embree_ratio" >"$csv"
else
    echo "scene,pair,a_mrays,b_mrays,b_over_a,a_embree_ratio,b_embree_ratio" >"$csv"
fi
run() {
    if [ $bake = 1 ]; then
        "$1/probebake" bake "$2" "${extra[@]}" -o "$tmp/v.probes" >"$tmp/log" 2>&1 ||
            { echo "$0: $1/probebake bake failed on $2:" >&2; tail -3 "$tmp/log" >&2; exit 1; }
        local ms
        ms=$(grep -oE 'GPU trace [0-9.]+ ms' "$tmp/log" | grep -oE '[0-9.]+') ||
            { echo "$0: no GPU trace time in $1/probebake's output" >&2; exit 1; }
        echo "$ms nan"
        return
    fi
    "$1/bench/trace_bench" "${extra[@]}" --json "$tmp/r.json" "$2" >"$tmp/log" 2>&1 ||
        { echo "$0: $1/bench/trace_bench failed on $2:" >&2; tail -3 "$tmp/log" >&2; exit 1; }
    python3 -c 'import json,sys; r=json.load(open(sys.argv[1]))["results"][0]; print(r["gpu_mrays_kernel"], r["ratio_gpu_kernel_to_embree"])' "$tmp/r.json"
}
for s in "${scenes[@]}"; do
    name=$(basename "$s")
    echo "ab_kernel: $name, $pairs pairs (A $a, B $b)" >&2
    # one untimed run of each build first: llvmpipe compiles each new
    # specialisation (a scene's stack depth) at its first dispatch
    run "$a" "$s" >/dev/null
    run "$b" "$s" >/dev/null
    for i in $(seq "$pairs"); do
        read -r ka ea < <(run "$a" "$s")
        read -r kb eb < <(run "$b" "$s")
        echo "$name,$i,$ka,$kb,$(python3 -c "print(round($kb / $ka, 4))"),$ea,$eb" >>"$csv"
    done
done

python3 - "$csv" "$out/ab_kernel.json" "$a" "$b" "$pairs" "$bake" <<'EOF'
import csv, json, statistics as st, sys
rows = list(csv.DictReader(open(sys.argv[1])))
bake = sys.argv[6] == "1"
ka, kb = ("a_gpu_ms", "b_gpu_ms") if bake else ("a_mrays", "b_mrays")
summary = []
unit = "ms" if bake else "Mr/s"
print(f"{'scene':24s} {'pairs':>5s} {'B/A median':>10s} {'min':>7s} {'max':>7s} {'A ' + unit:>7s} {'B ' + unit:>7s} {'A/Embree':>8s} {'B/Embree':>8s}")
for scene in dict.fromkeys(r["scene"] for r in rows):
    rs = [r for r in rows if r["scene"] == scene]
    ratio = [float(r["b_over_a"]) for r in rs]
    med = lambda k: round(st.median(float(r[k]) for r in rs), 4)
    s = {"scene": scene, "pairs": len(rs), "b_over_a_median": round(st.median(ratio), 4),
         "b_over_a_min": min(ratio), "b_over_a_max": max(ratio),
         ka + "_median": med(ka), kb + "_median": med(kb),
         "a_embree_ratio_median": med("a_embree_ratio"), "b_embree_ratio_median": med("b_embree_ratio")}
    summary.append(s)
    print(f"{scene:24s} {s['pairs']:5d} {s['b_over_a_median']:10.3f} {s['b_over_a_min']:7.3f} {s['b_over_a_max']:7.3f} "
          f"{s[ka + '_median']:7.2f} {s[kb + '_median']:7.2f} {s['a_embree_ratio_median']:8.3f} {s['b_embree_ratio_median']:8.3f}")
    if bake:  # no peer: null in the JSON
        s["a_embree_ratio_median"] = s["b_embree_ratio_median"] = None
json.dump({"bench": "ab_bake" if bake else "ab_kernel", "build_a": sys.argv[3], "build_b": sys.argv[4], "pairs": int(sys.argv[5]),
           "results": summary}, open(sys.argv[2], "w"), indent=2)
print(f"wrote {sys.argv[1]} and {sys.argv[2]}")
EOF
