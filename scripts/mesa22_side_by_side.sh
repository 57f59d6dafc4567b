#!/bin/bash
# Runs a bench against Debian 12's own lavapipe (Mesa 22.3, suite bookworm)
# beside the installed one (Mesa 25 from bookworm-backports), without
# installing it: the package is unpacked into a temporary directory and its
# ICD is named through VK_DRIVER_FILES. For bench/RESULTS.md's driver table.
#
#   scripts/mesa22_side_by_side.sh BENCH [ARGS...]
#   e.g. scripts/mesa22_side_by_side.sh build/bench/trace_bench --json bench/results/trace-lavapipe-mesa22.json
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 BENCH [ARGS...]" >&2; exit 2; }
version=$(apt-cache policy mesa-vulkan-drivers | awk '{v = $1 == "***" ? $2 : $1} v ~ /^[0-9]+\.[0-9]+\./ && v !~ /bpo/ {print v; exit}')
[ -n "$version" ] || { echo "$0: no bookworm version of mesa-vulkan-drivers in apt's lists" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && apt-get download "mesa-vulkan-drivers=$version" >/dev/null 2>&1) ||
    { echo "$0: cannot download mesa-vulkan-drivers=$version" >&2; exit 1; }
dpkg-deb -x "$tmp"/mesa-vulkan-drivers_*.deb "$tmp/root"
lib=$(find "$tmp/root" -name libvulkan_lvp.so | head -1)
cat > "$tmp/lvp.json" <<JSON
{"file_format_version": "1.0.0", "ICD": {"library_path": "$lib", "api_version": "1.3.0"}}
JSON
echo "$0: lavapipe from mesa-vulkan-drivers $version ($lib)" >&2
VK_DRIVER_FILES="$tmp/lvp.json" "$@"
