#!/usr/bin/env bash
# Installs dependencies, builds, and runs every test: the full suite on the
# Vulkan device (lavapipe unless PB_TEST_DEVICE / VK_DRIVER_FILES say
# otherwise), then the CPU-side tests, the bake's and the command line's
# again under ASan + UBSan, then short fuzzing runs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
jobs=$(nproc)

# Default to Mesa's lavapipe so results do not depend on the machine's GPU.
# (Mesa 25 names its manifest lvp_icd.json, 22.3 lvp_icd.x86_64.json)
lvp=/usr/share/vulkan/icd.d/lvp_icd.json
[ -f "$lvp" ] || lvp=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
if [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ] && [ -f "$lvp" ]; then
    export VK_DRIVER_FILES=$lvp VK_ICD_FILENAMES=$lvp
fi

# The whole suite first: it also fills Mesa's shader cache (llvmpipe
# compiles each kernel variant at its first dispatch and keeps it on disk;
# the sanitizer build embeds the same SPIR-V), so the sanitizer runs below,
# where that compile runs under ASan's allocator at about half the speed,
# find the variants compiled (test_bake under ASan: 200 s with an empty
# cache, 127 s with a filled one).
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$jobs"
echo "== full suite (validation layer on) ($(date +%T))"
# two at a time: one test's host phases (CPU references, loading, BVH
# builds) overlap another's device work; test_cli_interrupt, which times
# Ctrl-C, runs alone (RUN_SERIAL)
ctest --test-dir build -j"$jobs" --output-on-failure

# One sanitizer build serves the tests and the fuzzers: clang, ASan + UBSan,
# and libFuzzer's coverage hooks (PB_FUZZ), so the fuzz targets need no second
# build of the core (clang also builds the whole tree faster than gcc here:
# 83 s against 113 s for gcc's sanitizer build and 46 s for the fuzz build).
# Line tables only: a sanitizer's report names file and line as with full
# debug information, and the build takes 74 s instead of 83.
san_flags="-O2 -gline-tables-only -DNDEBUG"
CC=clang CXX=clang++ cmake -S . -B build-san -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPB_SANITIZE=ON -DPB_FUZZ=ON \
    -DPB_BUILD_BENCH=OFF -DCMAKE_C_FLAGS_RELWITHDEBINFO="$san_flags" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$san_flags" \
    >/dev/null
cmake --build build-san -j"$jobs"
echo "== CPU-side tests under AddressSanitizer + UndefinedBehaviorSanitizer (PB_TEST_QUICK: a tenth of the rays) ($(date +%T))"
PB_TEST_QUICK=1 ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-san -j"$jobs" -L cpu --output-on-failure
# The bake's stages and the command line's error paths (fault injection,
# Ctrl-C) under the same sanitizers, on the Vulkan device: host code that only
# runs beside a device (pipelines, staging, the stages) is not in the CPU
# tests. Leak checks off here: Mesa's llvmpipe keeps JIT and LLVM allocations
# to the end of the process, which LeakSanitizer reports without a usable
# stack; leaks in our code are the CPU run's to find. A 16 MB quarantine
# instead of 256: Mesa's compiler frees a few hundred MB through ASan for each
# pipeline it makes, so the default quarantine holds mostly Mesa's memory and
# each bake process faults in fresh pages for it (a tiny bake 1.44-1.53 ->
# 1.06-1.09 s, 360 -> 203 MB; this stage 221 -> 194 s); a use after free in
# our code is still caught until 16 MB more have been freed.
echo "== test_bake and test_cli under AddressSanitizer + UndefinedBehaviorSanitizer on the device ($(date +%T))"
PB_TEST_QUICK=1 ASAN_OPTIONS=detect_leaks=0:quarantine_size_mb=16 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-san -j"$jobs" -R '^(test_bake|test_cli|test_cli_interrupt)$' --output-on-failure

# Short libFuzzer runs of the glTF loader (scripts/fuzz.sh is the long one)
# and of the volume reader (the sparse layout's tables index each other),
# side by side: each is one process on one core. From the committed corpus
# into a scratch folder, so the repository does not change; a crash, leak or
# sanitizer report fails the suite and leaves the input in
# tests/fuzz/crashers or tests/fuzz/volume_corpus/crash-* (which
# test_fuzz_corpus reads).
echo "== fuzzing, side by side: the glTF loader ${PB_FUZZ_SECONDS:-30} s from tests/fuzz/corpus, the volume reader" \
    "${PB_FUZZ_VOLUME_SECONDS:-15} s from tests/fuzz/volume_corpus ($(date +%T))"
scene_dir=$(mktemp -d) volume_dir=$(mktemp -d)
ASAN_OPTIONS=detect_leaks=1 build-san/tests/fuzz_scene_load -max_total_time="${PB_FUZZ_SECONDS:-30}" \
    -max_len=65536 -timeout=10 -rss_limit_mb=2048 -artifact_prefix=tests/fuzz/crashers/ "$scene_dir" tests/fuzz/corpus \
    >"$scene_dir.log" 2>&1 &
scene_pid=$!
ASAN_OPTIONS=detect_leaks=1 build-san/tests/fuzz_volume_read -max_total_time="${PB_FUZZ_VOLUME_SECONDS:-15}" \
    -max_len=131072 -timeout=10 -rss_limit_mb=2048 -artifact_prefix=tests/fuzz/volume_corpus/crash- "$volume_dir" \
    tests/fuzz/volume_corpus >"$volume_dir.log" 2>&1 &
volume_pid=$!
scene_rc=0 volume_rc=0
wait "$scene_pid" || scene_rc=$?
wait "$volume_pid" || volume_rc=$?
echo "glTF loader: $(grep -E "^(Done|#[0-9]+ +DONE)" "$scene_dir.log" | tail -n 1)"
echo "volume reader: $(grep -E "^(Done|#[0-9]+ +DONE)" "$volume_dir.log" | tail -n 1)"
if [ "$scene_rc" != 0 ]; then
    tail -n 40 "$scene_dir.log"; echo "fuzzing found a crash: tests/fuzz/crashers"; exit 1
fi
if [ "$volume_rc" != 0 ]; then
    tail -n 40 "$volume_dir.log"; echo "fuzzing found a crash: tests/fuzz/volume_corpus/crash-*"; exit 1
fi
rm -rf "$scene_dir" "$scene_dir.log" "$volume_dir" "$volume_dir.log"
