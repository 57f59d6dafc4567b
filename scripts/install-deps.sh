#!/usr/bin/env bash
# Installs probebake's build, test and bench dependencies from Debian's packages.
# Non-interactive and idempotent: packages already present are not fetched again.
set -euo pipefail

pkgs=(
  build-essential cmake pkg-config
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers
  glslang-tools spirv-tools
  libtinygltf-dev nlohmann-json3-dev libstb-dev
  libvulkan-volk-dev
  libembree-dev
  gnuplot-nox
)

missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
