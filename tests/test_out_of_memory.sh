#!/usr/bin/env bash
# Out of host memory at every allocation: each host-only command (info,
# inspect, merge, export) is run once per heap allocation it makes, with that
# one allocation failing (tests/fail_alloc.c, LD_PRELOAD), and a sparse bake
# and a render (--pfm: two images) at a sample of their own allocations. Each run
# must either succeed or exit 1 with exactly one error line, never end on a
# signal, and never leave its output, or any other file, behind when it
# fails. Commands that make more than PB_OOM_RUNS (80) allocations are
# sampled evenly, their last three allocations always.
# Usage: test_out_of_memory.sh PROBEBAKE SOURCE_DIR FAIL_ALLOC_SO
set -u
shopt -s nullglob dotglob
pb=$1
src=$2
shim=$3
demo=$src/tests/scenes/demo.gltf
max_runs=${PB_OOM_RUNS:-80}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0
failed=0

# allocations NAME OUT -- command...: the command's allocation count
allocations() {
    shift 3
    rm -rf "$tmp/out"/*
    env LD_PRELOAD="$shim" PB_FAIL_ALLOC_OURS="${OURS:-0}" PB_FAIL_ALLOC_COUNT="$tmp/count" "$@" >/dev/null 2>&1 ||
        return 1
    rm -rf "$tmp/out"/*
    cat "$tmp/count"
}

# each_allocation_fails NAME OUT -- command...: OUT (a file or folder, or -)
# is what the command writes, in $tmp/out (emptied before each run)
each_allocation_fails() {
    local t0=$SECONDS
    local name=$1 out=$2
    shift 3
    local total
    if ! total=$(allocations "$name" "$out" -- "$@"); then
        failed=$((failed + 1))
        echo "[ FAIL ] $name: the command fails with no allocation failing"
        return
    fi
    local most=${RUNS:-$max_runs}
    local step=$(((total + most - 1) / most)) runs=0 ok=0 refused=0 bad=0 n rc why line lines
    local after
    # evenly, and the last three always (outputs are written last)
    local sample=() last=0
    for ((n = 1; n <= total; n += step)); do
        sample+=($n) last=$n
    done
    for ((n = total - 2 > last ? total - 2 : last + 1; n <= total; ++n)); do
        sample+=($n)
    done
    for n in "${sample[@]}"; do
        rm -rf "$tmp/out"/*
        env LD_PRELOAD="$shim" PB_FAIL_ALLOC_OURS="${OURS:-0}" PB_FAIL_ALLOC=$n "$@" >/dev/null 2>"$tmp/err"
        rc=$?
        runs=$((runs + 1))
        if [ $rc -eq 0 ]; then
            ok=$((ok + 1))
            continue
        fi
        lines=0 # bash builtins only: this loop runs hundreds of times
        while IFS= read -r line; do
            [[ $line == *error:* ]] && lines=$((lines + 1))
        done <"$tmp/err"
        why=""
        [ $rc -ne 1 ] && why="exit $rc"
        [ $rc -eq 1 ] && [ $lines -ne 1 ] && why="$lines error lines"
        [ "$out" != - ] && [ -e "$out" ] && why="$why, left $out"
        after=("$tmp/out"/*)
        [ ${#after[@]} -ne 0 ] && why="$why, left files: ${after[*]}"
        if [ -n "$why" ]; then
            bad=$((bad + 1))
            [ $bad -le 5 ] && echo "    allocation $n of $total: ${why#, }: $(head -c 300 "$tmp/err" | tr '\n' ' ')"
        else
            refused=$((refused + 1))
        fi
    done
    rm -rf "$tmp/out"/*
    if [ $bad -eq 0 ] && [ $refused -gt 0 ]; then
        passed=$((passed + 1))
        echo "[  OK  ] $name: $runs of $total allocations failed in turn: $refused one-line errors, $ok survived ($((SECONDS - t0)) s)"
    else
        failed=$((failed + 1))
        echo "[ FAIL ] $name: $runs of $total allocations failed in turn: $bad runs crashed, printed other than" \
             "one error line, or left files; $refused one-line errors, $ok survived"
    fi
}

mkdir "$tmp/in" "$tmp/out"
# inputs: a grid bake in 3 parts, a sparse bake in 2 (these need the device)
for i in 0 1 2; do
    "$pb" bake "$demo" --counts 6,5,7 --rays 16 --passes 1 --octmap-res 4 --quiet --shard "$i/3" \
        -o "$tmp/in/g$i.probes" >/dev/null || { echo "[ FAIL ] could not bake the parts"; exit 1; }
done
for i in 0 1; do
    "$pb" bake "$demo" --layout sparse --max-level 1 --spacing 0.3 --rays 16 --passes 1 --octmap-res 4 --quiet \
        --shard "$i/2" -o "$tmp/in/s$i.probes" >/dev/null || { echo "[ FAIL ] could not bake the parts"; exit 1; }
done
"$pb" merge "$tmp/in/g.probes" "$tmp/in"/g[012].probes >/dev/null
"$pb" merge "$tmp/in/s.probes" "$tmp/in"/s[01].probes >/dev/null

each_allocation_fails info - -- "$pb" info "$demo"
# a primitive without a material takes the default one, which the loader
# adds after the file's: when that addition fails, the primitive must not
# read a material that is not there (it did: a crash). Small, so every
# allocation fails in turn.
printf '%s' '{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}],"bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]}' \
    >"$tmp/in/nomat.gltf"
RUNS=100000 each_allocation_fails info-no-material - -- "$pb" info "$tmp/in/nomat.gltf"
# a material whose normal map is decoded (a 2 x 1 PNG) beside its colour texture, its primitive's
# TANGENT read: every allocation
printf '%s' '{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1,"TANGENT":2},"material":0}]}],"materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0},"metallicFactor":0},"normalTexture":{"index":1,"scale":0.5}}],"textures":[{"source":0},{"source":0}],"images":[{"uri":"data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAIAAAABCAYAAAD0In+KAAAAEUlEQVR4nGNoOPH/P1fDr/8AGREFyoKwXaYAAAAASUVORK5CYII="}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"},{"bufferView":2,"componentType":5126,"count":3,"type":"VEC4"}],"bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":24},{"buffer":0,"byteOffset":60,"byteLength":48}],"buffers":[{"byteLength":108,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AACAPwAAAAAAAAAAAACAPwAAgD8AAAAAAAAAAAAAgD8AAIA/AAAAAAAAAAAAAIA/"}]}' \
    >"$tmp/in/normalmap.gltf"
RUNS=100000 each_allocation_fails info-normal-map - -- "$pb" info "$tmp/in/normalmap.gltf"
# the same material with its colour and normal map read from two PNG files of noise (1.3 MB:
# past the 1 MiB under which nothing is decoded ahead), decoded ahead on the host's threads
# (prefetch_images) where there are two cores, so allocations fail on a worker as well as on
# the loader's thread
python3 - "$tmp/in" <<'EOF_PNG'
import struct, sys, zlib
def png(path, w, h, seed):
    raw, x = bytearray(), seed
    for _ in range(h):
        raw.append(0)
        for _ in range(4 * w):
            x = (x * 1664525 + 1013904223) & 0xffffffff
            raw.append(x >> 24)
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    open(path, "wb").write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)) +
                           chunk(b"IDAT", zlib.compress(bytes(raw), 1)) + chunk(b"IEND", b""))
png(sys.argv[1] + "/noise0.png", 400, 400, 1)
png(sys.argv[1] + "/noise1.png", 400, 400, 2)
EOF_PNG
sed 's/"textures":\[{"source":0},{"source":0}\]/"textures":[{"source":0},{"source":1}]/; s/"images":\[{"uri":"[^"]*"}\]/"images":[{"uri":"noise0.png"},{"uri":"noise1.png"}]/' \
    "$tmp/in/normalmap.gltf" >"$tmp/in/twoimages.gltf"
grep -q 'noise1.png' "$tmp/in/twoimages.gltf" || { echo "[ FAIL ] could not write twoimages.gltf"; failed=$((failed + 1)); }
RUNS=100000 each_allocation_fails info-two-images - -- "$pb" info "$tmp/in/twoimages.gltf"
# an ETC1S KTX2 texture with an alpha slice (KHR_texture_basisu required, the image in a
# bufferView): the container, the codebooks and the slices' allocations, every one
RUNS=100000 each_allocation_fails info-ktx2 - -- "$pb" info "$src/tests/fuzz/corpus/ktx2-etc1s_gradient_alpha.glb"
# a UASTC one, Zstandard supercompressed: the decompressor's context and its buffers, every one
RUNS=100000 each_allocation_fails info-ktx2-uastc - -- "$pb" info "$src/tests/fuzz/corpus/ktx2-uastc_gradient.glb"
each_allocation_fails inspect - -- "$pb" inspect "$tmp/in/s.probes"
each_allocation_fails inspect-json - -- "$pb" inspect "$tmp/in/g.probes" --json
# the two debug images (PNG over zlib, which reports a failed allocation)
each_allocation_fails inspect-images "$tmp/out/a.png" -- "$pb" inspect "$tmp/in/g.probes" --atlas "$tmp/out/a.png" \
    --sh-view "$tmp/out/s.png"
each_allocation_fails merge-grid "$tmp/out/g.probes" -- "$pb" merge "$tmp/out/g.probes" "$tmp/in"/g[012].probes
each_allocation_fails merge-sparse "$tmp/out/s.probes" -- "$pb" merge "$tmp/out/s.probes" "$tmp/in"/s[01].probes
each_allocation_fails export "$tmp/out/tex" -- "$pb" export "$tmp/in/s.probes" --textures "$tmp/out/tex"
# a bake: only probebake's own allocations fail (OURS), not the Vulkan
# driver's, which no program can answer; the driver's threads and the light
# cells' worker make the order vary from run to run, so each run may meet
# another allocation, and each must end as cleanly
OURS=1 RUNS=${PB_OOM_BAKE_RUNS:-12} each_allocation_fails bake-sparse "$tmp/out/b.probes" -- \
    "$pb" bake "$demo" --layout sparse --max-level 1 --spacing 0.5 --rays 16 --passes 1 --octmap-res 4 --quiet \
    -o "$tmp/out/b.probes"
OURS=1 RUNS=${PB_OOM_BAKE_RUNS:-12} each_allocation_fails render "$tmp/out/r.png" -- \
    "$pb" render "$demo" --volume "$tmp/in/s.probes" --mode diff --spp 1 --size 32x24 --pfm --quiet -o "$tmp/out/r.png"
duck=$src/../shared/scenes/samples/Duck/Duck.gltf
if [ -f "$duck" ]; then # an external buffer, a PNG texture
    each_allocation_fails info-textured - -- "$pb" info "$duck"
else
    echo "skip info-textured: $duck absent"
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
