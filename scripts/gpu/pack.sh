#!/usr/bin/env bash
# Packs what the lent NVIDIA machine (the `device` tool) lacks, beside the
# working tree and ignored by git: .gl/ (Debian's Vulkan loader and GL
# dispatch, unpacked there into /) and .dev/ (our build, the libraries it
# links, the validation layer, the shared scenes the benches and tests read).
# That machine runs another distribution and fetches nothing. Usage, from the
# repository root after a Release build: bash scripts/gpu/pack.sh
# Then: device run, carry [".gl", ".dev"], command `bash scripts/gpu/check.sh`.
set -eu
[ -x build/probebake ] || { echo "pack.sh: no build/probebake (build first)" >&2; exit 1; }
shared=${PB_SHARED:-../shared}
grep -qx '/.gl/' .git/info/exclude 2>/dev/null || echo /.gl/ >>.git/info/exclude
grep -qx '/.dev/' .git/info/exclude 2>/dev/null || echo /.dev/ >>.git/info/exclude
rm -rf .gl .dev
mkdir -p .gl .dev /tmp/pb-amd64/partial
o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/pb-amd64'
apt-get $o update >/dev/null
(cd .gl && apt-get $o download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2 >/dev/null)
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/lib"
# every shared library our programs link that is not in a bare glibc/libstdc++ system
for l in $(ldd build/probebake build/bench/trace_bench build/tests/test_bake | awk '$3 ~ /^\// {print $3}' | sort -u); do
    case $(basename "$l") in libc.so*|libm.so*|libgcc_s*|libstdc++*) continue ;; esac
    cp -L "$l" "$stage/lib/"
done
# TBB loads its allocator at run time (ldd does not list it)
cp -L /usr/lib/x86_64-linux-gnu/libtbbmalloc.so.2 "$stage/lib/" 2>/dev/null || true
layer=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json
cp -L /usr/lib/x86_64-linux-gnu/libVkLayer_khronos_validation.so "$stage/lib/"
sed 's#"library_path": *"[^"]*"#"library_path": "./libVkLayer_khronos_validation.so"#' "$layer" >"$stage/lib/VkLayer_khronos_validation.json"
tar -C "$stage" -cJf .dev/libs.tar.xz lib
pwd >.dev/srcdir
tar --exclude=CMakeFiles --exclude=Testing -cJf .dev/build.tar.xz build
s=$(cd "$shared" && pwd)
tar -C "$(dirname "$s")" -cf .dev/scenes.tar \
    "$(basename "$s")/scenes/cornell" "$(basename "$s")/scenes/openarena/oacmpdm1.glb" \
    "$(basename "$s")/scenes/openarena/am_underworks2.glb" "$(basename "$s")/scenes/env" \
    "$(basename "$s")/scenes/samples" "$(basename "$s")/scenes/MANIFEST.md"
du -sh .gl .dev
