#!/usr/bin/env bash
# Installs dependencies, builds, and runs the main job on the bundled demo
# scene (tests/scenes/demo.gltf).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
lvp=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
if [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ] && ! ls /usr/share/vulkan/icd.d/ 2>/dev/null | grep -qv lvp; then
    export VK_DRIVER_FILES=$lvp VK_ICD_FILENAMES=$lvp # only lavapipe here anyway
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target demo
