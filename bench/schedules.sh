#!/usr/bin/env bash
# The bake's schedules (--schedule: docs/bake.md, "Schedules") against one
# another on the same scenes: rounds of one bake per schedule, the order turned
# each round so that a slow phase of the machine falls on every schedule.
# Reads each bake's GPU time of its passes (the stage the schedule changes;
# relocation runs one path per invocation in all) from `--verbose`, and checks
# that every schedule wrote the first one's volume, byte for byte outside the
# file's timings: the schedules differ in speed only, so the error a faster
# one costs is zero, and the bench fails if it is not. Prints a table of
# medians and their ratio to the first schedule (the peer), writes every bake
# to CSV and the medians to JSON.
#
#   bench/schedules.sh [--rounds N] [--out DIR] [--probebake BIN] [--schedules "S1 S2 ..."] SCENE... [-- ARGS]
#   bench/schedules.sh --report DIR     # the table again from DIR/schedules.csv (e.g. one from a GPU lease)
#
# Defaults: 5 rounds, `build/probebake`, "megakernel restart:8 restart:32",
# ARGS `--counts 16,8,16 --rays 256 --passes 1 --bounces 3`, into
# bench/results/schedules/. Each schedule bakes each scene once untimed first:
# llvmpipe compiles a kernel at its first dispatch.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
rounds=5
out=$root/bench/results/schedules
bin=$root/build/probebake
schedules="megakernel restart:8 restart:32"
report=0
while [ $# -gt 0 ]; do
    case $1 in
        --report) report=1 out=$2; shift 2 ;;
        --rounds) rounds=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        --probebake) bin=$2; shift 2 ;;
        --schedules) schedules=$2; shift 2 ;;
        -*) echo "schedules: unknown option $1" >&2; exit 2 ;;
        *) break ;;
    esac
done
csv=$out/schedules.csv
args=()
if [ $report = 1 ]; then
    [ -f "$csv" ] || { echo "schedules: $csv: no such file" >&2; exit 1; }
    args=("$(sed -n 's/^# args: //p' "$csv")")
fi
scenes=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do scenes+=("$1"); shift; done
[ $# -gt 0 ] && shift
args=("$@")
[ ${#args[@]} -gt 0 ] || args=(--counts 16,8,16 --rays 256 --passes 1 --bounces 3)
if [ $report = 0 ] && [ ${#scenes[@]} = 0 ]; then
    echo "usage: schedules.sh [--rounds N] [--out DIR] [--probebake BIN] [--schedules LIST] SCENE... [-- ARGS]" >&2
    exit 2
fi
[ -x "$bin" ] || { echo "schedules: $bin: not an executable" >&2; exit 1; }
read -r -a sched <<<"$schedules"
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ $report = 0 ]; then
    echo "# args: ${args[*]}" >"$csv"
    echo "scene,schedule,round,passes_gpu_ms,passes_wall_ms,relocate_gpu_ms,traversals_per_s,same_bytes" >>"$csv"
else
    scenes=()
fi
bake() { # $1 scene, $2 schedule, $3 volume: the stages' line and the summary
    "$bin" bake "$1" "${args[@]}" --schedule "$2" --verbose -o "$3" 2>&1 | grep -E "bake stages|^time" || {
        echo "schedules: $1 --schedule $2: the bake failed" >&2
        exit 1
    }
}
for scene in "${scenes[@]}"; do
    name=$(basename "$scene")
    for s in "${sched[@]}"; do bake "$scene" "$s" "$tmp/$s.probes" >/dev/null; done
    for ((r = 0; r < rounds; ++r)); do
        n=${#sched[@]}
        for ((k = 0; k < n; ++k)); do
            s=${sched[$(((k + r) % n))]}
            log=$(bake "$scene" "$s" "$tmp/$s.probes")
            same=yes
            if [ "$s" != "${sched[0]}" ] && [ -f "$tmp/${sched[0]}.probes" ]; then
                [ "$(cmp -l "$tmp/${sched[0]}.probes" "$tmp/$s.probes" | awk '$1 < 185 || $1 > 248' | wc -l)" = 0 ] ||
                    same=no
            fi
            echo "$log" | python3 -c '
import re, sys
t = sys.stdin.read()
passes = re.search(r"passes ([0-9.]+) \(GPU ([0-9.]+)\)", t)
reloc = re.search(r"relocate [0-9.]+ \(GPU ([0-9.]+)\)", t)
trav = re.search(r"([0-9.]+) M traversals/s", t)
print(",".join(sys.argv[1:4] + [passes.group(2), passes.group(1), reloc.group(1), trav.group(1), sys.argv[4]]))
' "$name" "$s" "$r" "$same" >>"$csv"
        done
    done
done
python3 - "$csv" "$out/schedules.json" "${args[*]}" <<'EOF'
import csv, json, statistics, sys
rows = list(csv.DictReader(line for line in open(sys.argv[1]) if not line.startswith("#")))
scenes = list(dict.fromkeys(r["scene"] for r in rows))
sched = list(dict.fromkeys(r["schedule"] for r in rows))
out, bad = [], 0
print(f"probebake bake {sys.argv[3]}: the passes' GPU ms, median (range) of {len(rows) // (len(scenes) * len(sched))} "
      f"rounds; ratio: the first schedule's median time over each one's (> 1: faster); paired: the median (and\n"
      f"quartiles) of that ratio within each round, which a drift of the machine between rounds leaves alone; "
      f"same: its volume's bytes are the first's")
print(f"{'scene':20} {'schedule':14} {'passes GPU ms':>26} {'ratio':>7} {'paired (quartiles)':>24} {'same':>5}")
for sc in scenes:
    at = lambda s: {r["round"]: float(r["passes_gpu_ms"]) for r in rows if r["scene"] == sc and r["schedule"] == s}
    peer_t = at(sched[0])
    peer = statistics.median(peer_t.values())
    for s in sched:
        t = at(s)
        paired = sorted(peer_t[k] / t[k] for k in t)
        q = statistics.quantiles(paired, n=4) if len(paired) > 1 else [paired[0]] * 3
        same = all(r["same_bytes"] == "yes" for r in rows if r["scene"] == sc and r["schedule"] == s)
        bad += not same
        m = statistics.median(t.values())
        print(f"{sc[:20]:20} {s:14} {m:10.1f} ({min(t.values()):.1f}-{max(t.values()):.1f}){'':3} {peer / m:7.3f} "
              f"{q[1]:9.3f} ({q[0]:.3f}-{q[2]:.3f}) {'yes' if same else 'NO':>5}")
        out.append({"scene": sc, "schedule": s, "passes_gpu_ms": m, "runs": list(t.values()), "ratio": peer / m,
                    "paired_ratio": q[1], "paired_quartiles": [q[0], q[2]], "same_bytes": same})
json.dump({"args": sys.argv[3], "peer": sched[0], "rows": out}, open(sys.argv[2], "w"), indent=1)
print(f"wrote {sys.argv[1]} and {sys.argv[2]}")
if bad:
    sys.exit("schedules: a schedule wrote other bytes than " + sched[0])
EOF
