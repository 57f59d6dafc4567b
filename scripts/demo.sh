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
# The viewer page for the demo (runtime/web: three.js lit by the volume); ES
# modules need HTTP, so it is served from the repository root.
url="runtime/web/index.html?scene=/tests/scenes/demo.gltf&probes=/build/demo.probes"
printf '<!doctype html><meta http-equiv="refresh" content="0; url=/%s">\n' "$url" >build/demo-viewer.html
echo
echo "The demo in the browser (three.js lit by build/demo.probes): serve the repository root,"
echo "  python3 -m http.server 8000 --bind 127.0.0.1 --directory \"$PWD\""
echo "then open http://127.0.0.1:8000/$url"
echo "(or http://127.0.0.1:8000/build/demo-viewer.html; textures for other engines: build/demo-textures/)"
