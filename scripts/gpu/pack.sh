#!/usr/bin/env bash
# Packs what the lent NVIDIA machine (the `device` tool) lacks, beside the
# working tree and ignored by git: .gl/ (Debian's Vulkan loader and GL
# dispatch, unpacked there into /) and .dev/ (our build, the libraries it
# links, the validation layer, the shared scenes the benches and tests read).
# That machine runs another distribution and fetches nothing. Usage, from the
# repository root after a Release build: bash scripts/gpu/pack.sh
# Then: device run, carry [".gl", ".dev"], command `bash scripts/gpu/check.sh`.
# --lavapipe also packs Mesa's lavapipe and the libraries it links
# (.dev/lvp.tar.xz, about 33 MB) for check.sh's `lavapipe` step, which runs
# the CPU benches on two of that machine's host cores; the scenes are then only
# the two that step reads and the validation layer stays behind, to stay
# within the 64 MiB a call carries (working tree included). Only that step
# then works there.
set -eu
lavapipe=0
[ "${1:-}" = --lavapipe ] && lavapipe=1
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
if [ $lavapipe = 0 ]; then # the benches there run without it
    cp -L /usr/lib/x86_64-linux-gnu/libVkLayer_khronos_validation.so "$stage/lib/"
    sed 's#"library_path": *"[^"]*"#"library_path": "./libVkLayer_khronos_validation.so"#' "$layer" >"$stage/lib/VkLayer_khronos_validation.json"
fi
tar -C "$stage" -cJf .dev/libs.tar.xz lib
pwd >.dev/srcdir
tar --exclude=CMakeFiles --exclude=Testing -cJf .dev/build.tar.xz build
s=$(cd "$shared" && pwd)
b=$(basename "$s")
scenes="$b/scenes/cornell $b/scenes/openarena/oacmpdm1.glb $b/scenes/MANIFEST.md"
[ $lavapipe = 1 ] || scenes="$scenes $b/scenes/openarena/am_underworks2.glb $b/scenes/env $b/scenes/samples"
tar -C "$(dirname "$s")" -cJf .dev/scenes.tar.xz $scenes
if [ $lavapipe = 1 ]; then
    # lavapipe and its libraries, glibc's own left to that machine's glibc
    lvp=/usr/lib/x86_64-linux-gnu/libvulkan_lvp.so
    rm -rf "$stage/lib" && mkdir -p "$stage/lib"
    for l in $lvp $(ldd $lvp | awk '$3 ~ /^\// {print $3}' | sort -u); do
        case $(basename "$l") in libc.so*|libm.so*|libgcc_s*|libstdc++*|libpthread*|libdl.so*|librt.so*) continue ;; esac
        cp -L "$l" "$stage/lib/"
    done
    # ICU's 31 MB data table made an empty one: LLVM links libxml2, which links ICU,
    # but lavapipe calls neither; this keeps the call within its 64 MiB
    echo 'const unsigned char icudt72_dat[16] = {0};' | cc -shared -fPIC -x c - \
        -Wl,-soname,libicudata.so.72 -o "$stage/lib/libicudata.so.72"
    tar -C "$stage" -cf - lib | xz -T0 -9e >.dev/lvp.tar.xz
fi
du -sh .gl .dev
