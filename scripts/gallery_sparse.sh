#!/usr/bin/env bash
# The README's sparse-vs-grid gallery (issue 14): the Cornell box from its
# glTF camera with a 0.5 m grid and a sparse layout of the same finest
# spacing (refine error 0.3, surface test), each drawn as probe spheres and as the error
# map of its probe-lit image against one path-traced reference (2,048 spp,
# shared by both). Writes docs/gallery/sparse-*.png; prints the metrics.
#   scripts/gallery_sparse.sh [--probebake P] [SCENE]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pb=$root/build/probebake
[ "${1:-}" = --probebake ] && { pb=$2; shift 2; }
scene=${1:-$root/../shared/scenes/cornell/cornellBox.gltf}
[ -f "$scene" ] || { echo "gallery_sparse.sh: $scene: not found (../shared/scenes)" >&2; exit 1; }
out=$root/docs/gallery
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
bake=(--rays 256 --passes 4 --quiet)
"$pb" bake "$scene" --spacing 0.5 "${bake[@]}" -o "$tmp/grid.probes" >"$tmp/grid.txt"
"$pb" bake "$scene" --spacing 0.5 --layout sparse --refine-error 0.3 "${bake[@]}" -o "$tmp/sparse.probes" >"$tmp/sparse.txt"
"$pb" render "$scene" --mode reference --spp 2048 --size 160x120 --pfm --quiet -o "$tmp/ref.png" >/dev/null
for v in grid sparse; do
    probes=$("$pb" inspect "$tmp/$v.probes" --json | sed -n 's/.*"probes": \([0-9]*\).*/\1/p' | head -n 1)
    "$pb" render "$scene" --volume "$tmp/$v.probes" --show-probes --size 320x240 --quiet -o "$out/sparse-$v-spheres.png" \
        >/dev/null
    m=$("$pb" render "$scene" --volume "$tmp/$v.probes" --mode diff --spp 64 --size 160x120 --reference "$tmp/ref.pfm" \
        --json --quiet -o "$out/sparse-$v-diff.png")
    echo "$v: $probes probes; $(sed 's/.*"relative_rmse_surfaces": \([0-9.]*\), "p95_relative_error": \([0-9.]*\).*/surface RMSE \1, p95 \2/' <<<"$m")"
done
