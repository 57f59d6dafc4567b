#!/usr/bin/env bash
# The shipped WebGL2 sampler: runtime/probe_sample.glsl is what
# scripts/make_runtime_glsl.sh generates from the shared GLSL (so the web
# and Vulkan samplers cannot drift apart), and runtime/example.frag with it
# pasted in compiles as a GLSL ES 3.00 fragment shader.
# Usage: test_runtime.sh SOURCE_DIR GLSLANG
set -u
src=$1
glslang=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failed=0
bash "$src/scripts/make_runtime_glsl.sh" "$tmp/probe_sample.glsl" "$tmp/probe_sample_glsl.js"
for f in probe_sample.glsl js/probe_sample_glsl.js; do
    if cmp -s "$tmp/$(basename "$f")" "$src/runtime/$f"; then
        echo "[  OK  ] runtime/$f is up to date"
    else
        echo "[ FAIL ] runtime/$f differs from scripts/make_runtime_glsl.sh's output: run it"
        failed=1
    fi
done
# as pasted for a grid volume, and for a sparse one (#define PB_SPARSE first)
for variant in grid sparse; do
    define=""
    [ "$variant" = sparse ] && define="#define PB_SPARSE"
    awk -v f="$src/runtime/probe_sample.glsl" -v d="$define" \
        '/@PROBE_SAMPLE@/ { if (d != "") print d; while ((getline l < f) > 0) print l; next } { print }' \
        "$src/runtime/example.frag" >"$tmp/example-$variant.frag"
    if out=$("$glslang" "$tmp/example-$variant.frag" 2>&1); then
        echo "[  OK  ] runtime/example.frag with the sampler compiles as GLSL ES 3.00 ($variant volume)"
    else
        echo "[ FAIL ] GLSL ES 3.00 compile ($variant volume):"
        sed 's/^/    /' <<<"$out" | head -20
        failed=1
    fi
done
[ "$failed" -eq 0 ]
