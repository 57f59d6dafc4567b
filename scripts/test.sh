#!/usr/bin/env bash
# Installs dependencies, builds, and runs every test: the full suite on the
# Vulkan device (lavapipe unless PB_TEST_DEVICE / VK_DRIVER_FILES say
# otherwise), then the CPU-side tests again under ASan + UBSan.
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

cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPB_SANITIZE=ON -DPB_BUILD_BENCH=OFF >/dev/null
cmake --build build-asan -j"$jobs"
echo "== CPU-side tests under AddressSanitizer + UndefinedBehaviorSanitizer (PB_TEST_QUICK: a tenth of the rays)"
PB_TEST_QUICK=1 ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-asan -L cpu --output-on-failure

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$jobs"
echo "== full suite (validation layer on)"
ctest --test-dir build --output-on-failure
