#!/usr/bin/env bash
# Installs probebake's build, test and bench dependencies from Debian's packages
# (nodejs, npm, chromium: the web runtime, runtime/, is tested with node's runner
# and in headless Chromium, and uses three.js from npm at a pinned version;
# clang: the glTF loader's libFuzzer harness; libdraco-dev and
# libmeshoptimizer-dev: compressed glTF geometry; libwebp-dev and libavif-dev:
# EXT_texture_webp and EXT_texture_avif textures; libopenexr-dev: OpenEXR
# environment maps, whose DWA and other codecs no single-header reader decodes;
# slurm-wlm and munge: the cluster path, tested on a one-node cluster the test
# starts itself).
# Everything comes from bookworm except Mesa's Vulkan drivers (lavapipe), which
# come from bookworm-backports at a pinned version: Mesa 25's llvmpipe runs our
# kernels several times faster than bookworm's 22.3 (bench/RESULTS.md) and has
# no 65,535-iteration loop cap. The backports suite is added from the mirror
# the machine's apt sources already use. Non-interactive and idempotent.
set -euo pipefail

MESA_SUITE=bookworm-backports
MESA_VERSION=25.0.7-2~bpo12+1

pkgs=(
  build-essential cmake pkg-config
  libvulkan-dev vulkan-validationlayers
  glslang-tools spirv-tools
  libtinygltf-dev nlohmann-json3-dev libstb-dev zlib1g-dev
  libdraco-dev libmeshoptimizer-dev
  libwebp-dev libavif-dev libopenexr-dev libzstd-dev
  clang
  slurm-wlm munge
  libvulkan-volk-dev
  libembree-dev
  gnuplot-nox
  nodejs chromium
  python3
)

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive

missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Debian's npm, unless the machine's nodejs already brings one (NodeSource's does)
command -v npm >/dev/null || missing+=(npm)
mesa_now=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
# three.js for the web runtime and its tests, from npm at the version
# runtime/package-lock.json pins (into runtime/node_modules, not committed)
npm_deps() {
  local runtime pinned have
  runtime="$(cd "$(dirname "$0")/.." && pwd)/runtime"
  pinned=$(grep -o '"three": "[0-9.]*"' "$runtime/package.json" | grep -o '[0-9.]*[0-9]')
  have=$(grep -o '"version": "[0-9.]*"' "$runtime/node_modules/three/package.json" 2>/dev/null | grep -o '[0-9.]*[0-9]' || true)
  if [ "$have" != "$pinned" ]; then
    echo "install-deps: three.js $pinned from npm into runtime/node_modules"
    (cd "$runtime" && npm ci --no-audit --no-fund --loglevel=error)
  fi
}

if [ ${#missing[@]} -eq 0 ] && [ "$mesa_now" = "$MESA_VERSION" ]; then
  echo "install-deps: all packages present (mesa-vulkan-drivers $MESA_VERSION)"
  npm_deps
  exit 0
fi

# The backports suite, on the mirror the existing sources name (deb822 or
# one-line format); no host name is written here.
if ! grep -rqs "$MESA_SUITE" /etc/apt/sources.list /etc/apt/sources.list.d/; then
  mirror=$(grep -hs '^URIs:' /etc/apt/sources.list.d/*.sources | awk '{print $2}' | grep -v -- '-security' | head -n 1 || true)
  [ -n "$mirror" ] || mirror=$(grep -hs '^deb ' /etc/apt/sources.list /etc/apt/sources.list.d/*.list |
                               awk '{print $2}' | grep -v -- '-security' | head -n 1 || true)
  if [ -z "$mirror" ]; then
    echo "install-deps: error: cannot find a Debian mirror in /etc/apt/sources.list*" >&2
    exit 1
  fi
  echo "install-deps: adding $MESA_SUITE from $mirror"
  printf 'Types: deb\nURIs: %s\nSuites: %s\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
    "$mirror" "$MESA_SUITE" | $SUDO tee /etc/apt/sources.list.d/probebake-backports.sources >/dev/null
fi

echo "install-deps: installing ${missing[*]} mesa-vulkan-drivers=$MESA_VERSION"
$SUDO apt-get update -qq
[ ${#missing[@]} -eq 0 ] || $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
# -t lets the driver's own dependencies (libdrm) come from backports too
$SUDO apt-get install -y -qq --no-install-recommends -t "$MESA_SUITE" "mesa-vulkan-drivers=$MESA_VERSION"
npm_deps
