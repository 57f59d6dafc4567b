#!/usr/bin/env bash
# Installs dependencies, builds, and runs the main job on the bundled demo
# scene (tests/scenes/demo.gltf).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# The best Vulkan device is used (a GPU if there is one, else lavapipe);
# `--device` or VK_DRIVER_FILES choose another.
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target demo
