#!/usr/bin/env bash
# Builds the glTF loader's libFuzzer harness with clang (ASan + UBSan) and
# runs it on tests/fuzz/corpus, adding what it finds there; crashes land in
# tests/fuzz/crashers (each then becomes a regression input of
# test_fuzz_corpus). Usage: scripts/fuzz.sh [SECONDS] (default 1800).
# scripts/fuzz.sh SECONDS volume: the volume reader instead (fuzz_volume_read,
# tests/fuzz/volume_corpus, crashes saved there as crash-*); SECONDS ktx2: the
# KTX2 reader and its ETC1S and UASTC decoders (fuzz_ktx2_decode,
# tests/fuzz/ktx2_corpus).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-1800}
CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPB_FUZZ=ON -DPB_BUILD_BENCH=OFF >/dev/null
if [ "${2:-scene}" = volume ]; then
    cmake --build build-fuzz -j"$(nproc)" --target fuzz_volume_read
    ASAN_OPTIONS=detect_leaks=1 exec build-fuzz/tests/fuzz_volume_read -max_total_time="$seconds" -max_len=131072 \
        -timeout=10 -rss_limit_mb=2048 -artifact_prefix=tests/fuzz/volume_corpus/crash- tests/fuzz/volume_corpus
fi
if [ "${2:-scene}" = ktx2 ]; then
    cmake --build build-fuzz -j"$(nproc)" --target fuzz_ktx2_decode
    ASAN_OPTIONS=detect_leaks=1 exec build-fuzz/tests/fuzz_ktx2_decode -max_total_time="$seconds" -max_len=65536 \
        -timeout=10 -rss_limit_mb=2048 -artifact_prefix=tests/fuzz/ktx2_corpus/crash- tests/fuzz/ktx2_corpus
fi
cmake --build build-fuzz -j"$(nproc)" --target fuzz_scene_load
mkdir -p tests/fuzz/corpus tests/fuzz/crashers
ASAN_OPTIONS=detect_leaks=1 build-fuzz/tests/fuzz_scene_load -max_total_time="$seconds" -max_len=65536 \
    -timeout=10 -rss_limit_mb=2048 -artifact_prefix=tests/fuzz/crashers/ tests/fuzz/corpus
