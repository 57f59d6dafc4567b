#!/bin/bash
# Where a kernel spends its time on lavapipe, instruction by instruction.
# llvmpipe JIT-compiles each pipeline to x86 code in anonymous memory, which
# perf samples but cannot name. This runs a command, samples it with perf
# while the kernel runs, copies the hottest JIT code out of the live process
# with gdb, disassembles it and prints each loop's share of the samples and
# the hottest instructions (bench/RESULTS.md, "Where the trace kernel's time
# goes"). Needs perf (package linux-perf) and gdb.
#
#   scripts/profile_lavapipe.sh [-w SECONDS] [-s SECONDS] COMMAND [ARGS...]
#   e.g. scripts/profile_lavapipe.sh build/bench/trace_bench --repeat 60 \
#            ../shared/scenes/openarena/oacmpdm1.glb
#
# -w: seconds to wait before sampling (past scene load and BVH build), default 4
# -s: seconds to sample, default 4. The command must still be running then.
# Writes the annotated disassembly to profile-lavapipe.s in the current directory.
set -euo pipefail
wait_s=4
sample_s=4
while getopts "w:s:" opt; do
    case $opt in
    w) wait_s=$OPTARG ;;
    s) sample_s=$OPTARG ;;
    *) exit 2 ;;
    esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || { echo "usage: $0 [-w SECONDS] [-s SECONDS] COMMAND [ARGS...]" >&2; exit 2; }
for tool in perf gdb objdump python3; do
    command -v "$tool" >/dev/null || { echo "$0: $tool not found (perf: apt-get install linux-perf)" >&2; exit 1; }
done
tmp=$(mktemp -d)
"$@" >"$tmp/stdout" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null || true; rm -rf "$tmp"' EXIT
sleep "$wait_s"
kill -0 $pid 2>/dev/null || { echo "$0: the command ended within $wait_s s; give it more work" >&2; exit 1; }
# stopped by SIGINT after the sampling time: `perf record -p PID -- sleep N`
# got SIGTERM on some kernels (the Zen 5 VM, 2026-11-27) and wrote nothing
timeout -s INT "$sample_s" perf record -q -o "$tmp/perf.data" -F 4000 -p $pid >/dev/null 2>&1 || true
# samples in anonymous (JIT) memory: perf names them after /tmp/perf-PID.map
perf script -i "$tmp/perf.data" -F ip,dso 2>/dev/null | awk '$2 ~ /perf-[0-9]+\.map/ {print $1}' >"$tmp/ips"
total=$(perf script -i "$tmp/perf.data" -F ip 2>/dev/null | wc -l)
[ -s "$tmp/ips" ] || { echo "$0: no samples in JIT code (was the kernel running?)" >&2; exit 1; }
# the densest run of pages: the kernel's code
range=$(python3 - "$tmp/ips" <<'PY'
import collections, sys
pages = collections.Counter(int(l, 16) >> 12 for l in open(sys.argv[1]))
top = max(pages, key=pages.get)
lo = hi = top
while pages.get(lo - 1): lo -= 1
while pages.get(hi + 1): hi += 1
print(hex(lo << 12), hex((hi + 1) << 12))
PY
)
set -- $range
gdb -p $pid -batch -ex "dump memory $tmp/jit.bin $1 $2" >/dev/null 2>&1 ||
    { echo "$0: gdb could not read the process (ptrace permission?)" >&2; exit 1; }
objdump -D -b binary -m i386:x86-64 --adjust-vma="$1" "$tmp/jit.bin" >"$tmp/jit.s"
python3 - "$tmp/ips" "$tmp/jit.s" "$total" <<'PY'
import collections, re, sys
ips = collections.Counter(int(l, 16) for l in open(sys.argv[1]))
total = int(sys.argv[3])
rows = []
for line in open(sys.argv[2]):
    m = re.match(r'^\s*([0-9a-f]+):\t[0-9a-f ]+\t(.*)$', line)
    if m:
        a = int(m.group(1), 16)
        rows.append((a, ips.get(a, 0), m.group(2).strip()))
base = rows[0][0]
hot = sum(n for _, n, _ in rows)
print(f"samples: {total} in the process, {hot} ({100 * hot / max(total, 1):.1f} %) in the kernel's JIT code")
print("loops (backward jumps), outermost last, share of the kernel's samples:")
for a, n, ins in rows:
    m = re.match(r'(j\w+)\s+0x([0-9a-f]+)', ins)
    if m and int(m.group(2), 16) < a:
        t = int(m.group(2), 16)
        s = sum(k for aa, k, _ in rows if t <= aa <= a)
        if s * 20 >= hot:
            print(f"  +{t - base:#07x} .. +{a - base:#07x}  {100 * s / hot:5.1f} %  ({a - t} bytes of code)")
gathers = [(a, n) for a, n, ins in rows if 'gather' in ins]
after = 0
for i, (a, n, ins) in enumerate(rows):
    if 'gather' in ins and i + 1 < len(rows):
        after += rows[i + 1][1]
print(f"gathers: {len(gathers)} in the code; the instruction after each holds {100 * after / hot:.1f} % of the samples (waiting on them)")
print("hottest instructions:")
for a, n, ins in sorted(rows, key=lambda r: -r[1])[:12]:
    print(f"  +{a - base:#07x} {100 * n / hot:5.1f} %  {ins}")
with open("profile-lavapipe.s", "w") as f:
    for a, n, ins in rows:
        f.write(f"{n:6d}  +{a - base:#07x}  {ins}\n")
PY
echo "annotated disassembly: profile-lavapipe.s (samples, offset, instruction)"
