#!/usr/bin/env bash
# A scene's load (read, decode, build: `probebake info`) timed for two builds
# side by side: runs alternate between them, so a slow phase of the machine
# falls on both. Prints a table of medians and their ratio, writes every run
# to CSV and the medians to JSON.
#
#   bench/load_bench.sh [--runs N] [--out DIR] BEFORE_PROBEBAKE AFTER_PROBEBAKE SCENE...
#
# The peer is the other build, on the same files in the same run; what a
# change to the loader costs in error is checked elsewhere (the scene's bytes:
# test_scene), so this reports time only.
set -euo pipefail
runs=7
out=$(cd "$(dirname "$0")" && pwd)/results/load_bench
while [ $# -gt 0 ]; do
    case $1 in
        --runs) runs=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        -*) echo "load_bench: unknown option $1" >&2; exit 2 ;;
        *) break ;;
    esac
done
[ $# -ge 3 ] || { echo "usage: load_bench.sh [--runs N] [--out DIR] BEFORE AFTER SCENE..." >&2; exit 2; }
before=$1 after=$2
shift 2
for b in "$before" "$after"; do
    [ -x "$b" ] || { echo "load_bench: $b: not an executable" >&2; exit 1; }
done
mkdir -p "$out"
csv=$out/load_bench.csv
echo "scene,build,run,wall_ms" >"$csv"
for scene in "$@"; do
    "$after" info "$scene" >/dev/null 2>&1 || { echo "load_bench: $scene: probebake info fails" >&2; exit 1; }
    for ((i = 1; i <= runs; ++i)); do
        for build in before after; do
            bin=$before
            [ $build = after ] && bin=$after
            t0=$(date +%s%N)
            "$bin" info "$scene" >/dev/null 2>&1
            t1=$(date +%s%N)
            echo "$(basename "$scene"),$build,$i,$(((t1 - t0) / 1000000))" >>"$csv"
        done
    done
done
python3 - "$csv" "$out/load_bench.json" "$before" "$after" <<'EOF'
import csv, json, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
scenes = list(dict.fromkeys(r["scene"] for r in rows))
out = []
print(f"probebake info, {len(rows) // (2 * len(scenes))} alternating runs of each build; wall ms")
print(f"{'scene':34} {'before: median (range)':24} {'after: median (range)':24} {'before / after':>14}")
for s in scenes:
    t = {b: [int(r["wall_ms"]) for r in rows if r["scene"] == s and r["build"] == b] for b in ("before", "after")}
    mb, ma = statistics.median(t["before"]), statistics.median(t["after"])
    print(f"{s:34} {mb:7.0f} ({min(t['before'])}-{max(t['before'])}){'':8} {ma:7.0f} ({min(t['after'])}-{max(t['after'])}){'':8} {mb / ma:14.2f}")
    out.append({"scene": s, "before_ms": mb, "after_ms": ma, "ratio": mb / ma,
                "before_runs": t["before"], "after_runs": t["after"]})
json.dump({"before": sys.argv[3], "after": sys.argv[4], "scenes": out}, open(sys.argv[2], "w"), indent=1)
print(f"wrote {sys.argv[1]} and {sys.argv[2]}")
EOF
