#!/usr/bin/env bash
# One prepared pass on the lent NVIDIA machine (see scripts/gpu/pack.sh):
# unpack the carried loader, libraries, build and scenes at the paths the
# build was made at, then the benches and the GPU tests, each step under its
# own time limit so one hang cannot eat the lease. Everything lands in $OUT
# (at most 8 files come back): log.txt, clocks.csv (the GPU's clocks every
# 250 ms), ctest.log, bake_portable.log, json.tar.
# Usage there, from the repository root: bash scripts/gpu/check.sh [STEPS]
# STEPS: any of compile bake bakeab blocks bench clocks decode large lavapipe loads peer schedules sweep test_bake
# test_trace traceab tests vsbake wavefront (default: compile bake wavefront vsbake peer bench clocks loads tests,
# in that order). PB_GPU_TEST_LIMIT: seconds for each test program in the tests step (default 300).
set -u
out=${OUT:?OUT must name the folder that comes back}
steps=${*:-compile bake wavefront vsbake peer bench clocks loads tests}
log=$out/log.txt
say() { echo "== $(date +%T) $*" | tee -a "$log"; }
run() { local limit=$1; shift; say "$*"; timeout "$limit" "$@" >>"$log" 2>&1; local rc=$?; [ $rc = 0 ] || say "rc $rc"; }
keep() { [ -f "$1" ] && tar -C "$(dirname "$1")" -rf "$out/json.tar" "$(basename "$1")"; }

src=$(cat .dev/srcdir)
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
mkdir -p /opt/pb && tar -C /opt/pb -xJf .dev/libs.tar.xz
export LD_LIBRARY_PATH=/opt/pb/lib VK_LAYER_PATH=/opt/pb/lib
# PB_GPU_ICD and PB_TEST_DEVICE let the script be tried here on lavapipe first
export VK_DRIVER_FILES=${PB_GPU_ICD:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}
export PB_TEST_DEVICE=${PB_TEST_DEVICE:-NVIDIA}
if [ "$PWD" != "$src" ]; then
    [ -e "$src" ] && { say "$src exists and is not this checkout"; exit 1; }
    mkdir -p "$(dirname "$src")" && ln -s "$PWD" "$src"
fi
[ -d "$(dirname "$src")/shared/scenes" ] || tar -C "$(dirname "$src")" -xJf .dev/scenes.tar.xz
tar -xJf .dev/build.tar.xz
[ -f .dev/probebake-before.xz ] && xz -dc .dev/probebake-before.xz >.dev/probebake-before && chmod +x .dev/probebake-before
cd "$src" || exit 1
say "setup done in $PWD: $(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null)"
run 60 build/probebake devices || exit 1
# the clocks beside every step: a short dispatch may run before the GPU has left its idle clocks
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,utilization.gpu,power.draw --format=csv -lms 250 \
    >"$out/clocks.csv" 2>&1 &
sampler=$!
trap 'kill $sampler 2>/dev/null' EXIT

crypt=../shared/scenes/openarena/oacmpdm1.glb
cornell=../shared/scenes/cornell/cornellBox.gltf
for s in $steps; do
    case $s in
    bench)
        run 240 build/bench/trace_bench --probes 65536 --rays 1024 --repeat 5 --json /tmp/trace-probe.json
        keep /tmp/trace-probe.json
        run 120 build/bench/trace_bench --probes 65536 --rays 1024 --repeat 5 --portable --json /tmp/trace-probe-portable.json $crypt
        keep /tmp/trace-probe-portable.json ;;
    compile) # the driver's compile time for each kernel set, with an empty shader cache each
        for k in "" --portable-kernels; do
            say "pipelines ${k:-native64}, cold cache"
            __GL_SHADER_DISK_CACHE_PATH=$(mktemp -d) timeout 240 build/probebake bake tests/scenes/demo.gltf \
                --counts 2,2,2 --rays 64 --passes 1 --verbose $k -o /tmp/compile.probes 2>&1 | grep -E "pipeline|kernels" >>"$log"
        done ;;
    clocks) # the same Crypt rays at two probe counts, interleaved, clocks sampled beside: the long
        # host-fed run lets the driver drop the SM clock (2026-11-26: 2,072 against 519-744 Mrays/s)
        for p in 16384 65536 16384 65536; do
            run 90 build/bench/trace_bench --probes $p --rays 1024 --repeat 3 --json /tmp/trace-clocks-$p-$SECONDS.json $crypt
            keep /tmp/trace-clocks-$p-*.json
            rm -f /tmp/trace-clocks-*.json
        done ;;
    loads) # the BVH read as texels (lavapipe's default since 2026-11-26) against addresses (the GPU
        # default), interleaved: the trace kernel on The Crypt, then the issue's bake with each
        for l in address texel address texel; do
            run 90 build/bench/trace_bench --probes 16384 --rays 1024 --repeat 3 --scene-loads $l \
                --json /tmp/trace-loads-$l-$SECONDS.json $crypt
            keep /tmp/trace-loads-$l-*.json
            rm -f /tmp/trace-loads-*.json
        done
        for l in address texel; do
            say "bake, $l loads"
            timeout 120 build/probebake bake $crypt --counts 32,16,32 --rays 256 --passes 1 --bounces 3 \
                --scene-loads $l --verbose -o /tmp/c16k.probes 2>&1 | grep -E "scene loads|^time" >>"$log"
        done ;;
    sweep) # leaf size and SAH step cost: the defaults (8, 2) were tuned for llvmpipe
        for lt in "8 2" "4 1" "4 2" "2 1" "8 1"; do
            set -- $lt
            run 90 build/bench/trace_bench --probes 16384 --rays 1024 --repeat 3 --leaf $1 --tc $2 \
                --json /tmp/trace-leaf$1-tc$2.json $crypt
            keep /tmp/trace-leaf$1-tc$2.json
        done ;;
    decode) # the loader's images decoded ahead on the host's 16 cores against decoded in turn, alternately
        # (bench/decode_bench), on eight instances of two samples, each with its own image files
        # (scripts/make_many_images_scene.py: 32 and 40 large textures read) and on the samples alone
        sm=../shared/scenes/samples
        run 60 python3 scripts/make_many_images_scene.py $sm/DamagedHelmet/DamagedHelmet.gltf 8 /tmp/helmet8
        run 60 python3 scripts/make_many_images_scene.py $sm/AlphaBlendModeTest/AlphaBlendModeTest.gltf 8 /tmp/alpha8
        run 180 build/bench/decode_bench --runs 7 --json /tmp/decode.json /tmp/helmet8/helmet8.gltf \
            /tmp/alpha8/alpha8.gltf $sm/DamagedHelmet/DamagedHelmet.gltf $sm/AlphaBlendModeTest/AlphaBlendModeTest.gltf
        keep /tmp/decode.json ;;
    large) # the host's share of a large scene's bake on a workstation's cores (bench/RESULTS.md,
        # "The BVH build, and a large scene's load"): the 4.2M-triangle terrain (75 MB, made
        # here: too big to carry), its BVH build against Embree's on all host cores, then the
        # issue's bake size on it twice (load, BVH, stages and GPU times)
        run 120 python3 scripts/make_large_scene.py /tmp/terrain.glb
        [ -s /tmp/terrain.glb ] || continue
        run 180 build/bench/trace_bench --probes 4096 --rays 256 --repeat 3 --json /tmp/trace-terrain.json \
            /tmp/terrain.glb
        keep /tmp/trace-terrain.json
        for i in 1 2; do
            say "terrain bake $i"
            timeout 180 build/probebake bake /tmp/terrain.glb --counts 32,16,32 --rays 256 --passes 1 --bounces 3 \
                --verbose -o /tmp/terrain.probes 2>&1 | grep -E "loaded|BVH|stages|^time" >>"$log"
        done ;;
    bake) # issue 11's GPU figure: 16k probes x 256 rays x 3 bounces on The Crypt
        for i in 1 2; do
            say "bake $i"
            start=$(date +%s%N)
            timeout 120 build/probebake bake $crypt --counts 32,16,32 --rays 256 --passes 1 --bounces 3 \
                --verbose -o /tmp/c16k.probes >>"$log" 2>&1
            say "rc $? wall $(( ($(date +%s%N) - start) / 1000000 )) ms"
        done ;;
    wavefront) # --schedule megakernel against wavefront (docs/bake.md, "Schedules"), alternately, on
        # the issue's bake and the Cornell box: the stages' times of each, and whether the volumes
        # are the same bytes outside the timings (bytes 185-248), as on lavapipe
        for sc in $crypt $cornell; do
            for sched in megakernel wavefront megakernel wavefront; do
                say "bake $(basename $sc), $sched"
                timeout 60 build/probebake bake $sc --counts 32,16,32 --rays 256 --passes 1 --bounces 3 \
                    --schedule $sched --verbose -o /tmp/sched-$sched.probes 2>&1 | grep -E "stages|^time" >>"$log"
            done
            say "volumes differ outside the timings in $(cmp -l /tmp/sched-megakernel.probes /tmp/sched-wavefront.probes \
                | awk '$1 < 185 || $1 > 248' | wc -l) bytes"
        done ;;
    schedules) # --schedule megakernel against restart:K (bench/schedules.sh: turned rounds, the passes' GPU
        # time, the volumes' bytes checked) on the issue's bake; the replay predicted restarts 1.15-1.25x here
        run 300 bash bench/schedules.sh --rounds 7 --out /tmp/schedules \
            --schedules "megakernel restart:2 restart:4 restart:8 restart:16" $crypt $cornell \
            -- --counts 32,16,32 --rays 256 --passes 1 --bounces 3
        keep /tmp/schedules/schedules.json
        keep /tmp/schedules/schedules.csv
        # and issue 11's ratio ("vs trc", as the vsbake step) with restarts
        run 240 build/bench/bake_bench --probes 16384 --reference-passes 8 --bounces 3 --repeat 3 --schedule restart:8 \
            --json /tmp/bake-vs-trace-16k-restart8.json $crypt $cornell
        keep /tmp/bake-vs-trace-16k-restart8.json ;;
    vsbake) # issue 11's bake ratio on the device, at a size that fills it: bake_bench's "vs trc"
        # (bake traversals per second of GPU time over the trace kernel's probe-ray rate on the same
        # grid, next to it in the same process) and "vs bnc", at 16k probes and 3 bounces. bake_bench's
        # default 240 probes leave an H100 idle (2026-11-24: "says nothing about the kernel there").
        run 240 build/bench/bake_bench --probes 16384 --reference-passes 8 --bounces 3 --repeat 3 \
            --json /tmp/bake-vs-trace-16k.json $crypt $cornell
        keep /tmp/bake-vs-trace-16k.json ;;
    peer) # the bake's paths against the same paths on the CPU path tracer with Embree on all host
        # cores (bench/peer_paths), at a size that fills the GPU; PB_PEER_ARGS: more options
        # (e.g. --restart 8:1, whose recording runs on one CPU; --methods plain,nee,cells,guide,all: what each
        # estimator's shading costs)
        run 300 build/bench/peer_paths --probes 16384 --repeat 3 ${PB_PEER_ARGS:-} --out /tmp/peer $crypt $cornell
        keep /tmp/peer/peer_paths.json ;;
    bakeab) # the issue's bake by this build and by .dev/probebake-before (another build's
        # binary: scripts/gpu/variant.sh DIFF puts this commit with a kernel change there),
        # alternately: the stages' wall and GPU times of each
        for b in before after before after before after; do
            bin=build/probebake
            [ $b = before ] && bin=.dev/probebake-before
            [ -x $bin ] || continue
            say "bake, $b"
            timeout 60 $bin bake $crypt --counts 32,16,32 --rays 256 --passes 1 --bounces 3 \
                --verbose -o /tmp/c16k.probes 2>&1 | grep -E "stages|^time" >>"$log"
        done ;;
    traceab) # the trace kernel of this build and of .dev/trace_bench-before (another build's
        # binary, put there by hand), alternately, on The Crypt and the Cornell box
        for b in before after before after before after; do
            bin=build/bench/trace_bench
            [ $b = before ] && bin=.dev/trace_bench-before
            [ -x $bin ] || continue
            say "trace, $b"
            timeout 90 $bin --probes 16384 --rays 1024 --repeat 3 --json /tmp/traceab-$b-$SECONDS.json \
                $crypt $cornell 2>&1 | grep -E "^(oacmpdm1|cornellBox)" >>"$log"
            keep /tmp/traceab-$b-*.json
            rm -f /tmp/traceab-*.json
        done ;;
    blocks) # a bake whose depth sums pass NVIDIA's 4 GiB allocation limit: 2.3M probes at 16x16,
        # 4.4 GiB in two blocks (src/bake/depth_sums.h); one short pass, no bounces
        say "bake 160 x 90 x 160"
        start=$(date +%s%N)
        timeout 200 build/probebake bake $crypt --counts 160,90,160 --rays 32 --passes 1 --bounces 0 \
            --verbose -o /tmp/big.probes >>"$log" 2>&1
        say "rc $? wall $(( ($(date +%s%N) - start) / 1000000 )) ms, $(stat -c %s /tmp/big.probes 2>/dev/null) bytes"
        rm -f /tmp/big.probes ;;
    lavapipe) # the CPU benches through lavapipe on two of this machine's host cores (pack.sh
        # --lavapipe): the trace kernel against Embree in the same run, texel and address
        # loads alternately, bake_bench, bounce rays; each result in the log as it comes
        [ -f .dev/lvp.tar.xz ] || { say "no .dev/lvp.tar.xz: run pack.sh --lavapipe"; continue; }
        mkdir -p /opt/lvp && tar -C /opt/lvp -xJf .dev/lvp.tar.xz
        printf '{"file_format_version": "1.0.0", "ICD": {"library_path": "/opt/lvp/lib/libvulkan_lvp.so", "api_version": "1.4.305"}}\n' \
            >/opt/lvp/icd.json
        say "host: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; lavapipe pinned to cores ${PB_LVP_CORES:-2,3}"
        (
            export VK_DRIVER_FILES=/opt/lvp/icd.json LP_NUM_THREADS=2 LD_LIBRARY_PATH=/opt/pb/lib:/opt/lvp/lib
            two="taskset -c ${PB_LVP_CORES:-2,3}" # PB_LVP_CORES: to try it here first
            run 60 $two build/probebake devices
            pair() { # $1: a tag, the rest: trace_bench's options
                local tag=$1; shift
                for l in texel address; do
                    run 60 $two build/bench/trace_bench --probes 4096 --rays 256 --repeat 3 --scene-loads $l \
                        "$@" --json /tmp/lvp-$tag-$l-$SECONDS.json $cornell $crypt
                    keep /tmp/lvp-$tag-$l-*.json && rm -f /tmp/lvp-$tag-$l-*.json
                done
            }
            for i in 1 2 3; do pair probe; done
            run 90 $two build/bench/bake_bench --json /tmp/lvp-bake-1.json && keep /tmp/lvp-bake-1.json
            pair bounce --bounce
            for i in 4 5 6; do pair probe; done
            run 90 $two build/bench/bake_bench --json /tmp/lvp-bake-2.json && keep /tmp/lvp-bake-2.json
            pair bounce --bounce
        ) ;;
    test_bake) # the bake suite alone (native kernels)
        run 200 build/tests/test_bake ;;
    test_trace) # every trace kernel variant against the CPU reference, hit for hit
        run 200 build/tests/test_trace ;;
    tests)
        say "tests: ctest -L gpu (no browser, slurm, corpus, smoke) and test_bake_portable beside it"
        tl=${PB_GPU_TEST_LIMIT:-300}
        (cd build && timeout $((tl + 30)) ctest -L gpu -E "browser|slurm|corpus|smoke|test_bake_portable" -j6 \
            --timeout $tl --output-on-failure) >"$out/ctest.log" 2>&1 &
        ctest_pid=$!
        PB_TEST_PORTABLE_KERNELS=1 timeout $tl build/tests/test_bake >"$out/bake_portable.log" 2>&1 &
        # name the two: a bare `wait` also waits for the clock sampler, which never ends
        wait $ctest_pid $!
        say "tests finished"
        tail -25 "$out/ctest.log" >>"$log"
        tail -3 "$out/bake_portable.log" >>"$log" ;;
    *) say "unknown step $s" ;;
    esac
done
say "done"
