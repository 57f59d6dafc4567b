#!/usr/bin/env bash
# What shading normals cost and change: each scene baked with its vertex
# normals (the default) and with face normals (--shading-normals face, the
# peer: what every bake did before vertex normals were read), alternately,
# same seed, in the same run:
#   time     GPU trace ms of each bake; the ratio vertex / face is the median
#            of the pairs' ratios (lavapipe drifts within minutes: pairs, not means)
#   change   relative RMS difference of the probes' DC irradiance (luminance)
#            between the two bakes, over probes valid in both
#   noise    the same between two vertex-normal bakes with seeds 1 and 2: a
#            change far below it is invisible at this bake's quality
# Prints a table, writes CSV and JSON.
#
#   bench/shading_normals.sh [--probebake P] [--pairs N] [--out DIR] [SCENE ...]
#
# Default: The Crypt, the Cornell box and the glTF Duck from ../shared/scenes (skipped when
# absent), 256 rays x 4 passes, 5 pairs, into bench/results/shading_normals/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pb=$root/build/probebake
pairs=5
out=$root/bench/results/shading_normals
while [ $# -gt 0 ]; do
    case $1 in
        --probebake) pb=$2; shift 2 ;;
        --pairs) pairs=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        *) break ;;
    esac
done
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
    for s in openarena/oacmpdm1.glb cornell/cornellBox.gltf samples/Duck/Duck.gltf; do
        f=$root/../shared/scenes/$s
        if [ -f "$f" ]; then scenes+=("$f"); else echo "skip $s: absent"; fi
    done
fi
[ ${#scenes[@]} -gt 0 ] || { echo "shading_normals: no scene"; exit 1; }
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# the scene's bake: lights of its own where it has them, else a white sky
bake() { # scene normals seed out
    local sky=()
    "$pb" info "$1" --json | grep -q '"emissive_materials": 0,' && "$pb" info "$1" --json | grep -q '"lights": \[\]' &&
        sky=(--sky 1,1,1)
    "$pb" bake "$1" --quality preview --rays 256 --passes 4 "${sky[@]}" --shading-normals "$2" --seed "$3" -o "$4" 2>&1 |
        sed -n 's/^time: .*GPU trace \([0-9.]*\) ms.*/\1/p'
}
change() { # a.probes b.probes: relative RMS difference of DC luminance over probes valid in both
    "$pb" inspect "$1" --json >"$tmp/a.json"
    "$pb" inspect "$2" --json >"$tmp/b.json"
    python3 - "$tmp/a.json" "$tmp/b.json" <<'EOF'
import json, math, sys
a, b = (json.load(open(f))["probe_list"] for f in sys.argv[1:3])
lum = lambda sh: 0.2126 * sh[0] + 0.7152 * sh[1] + 0.0722 * sh[2]  # DC: coefficient-major RGB
d = [(lum(p["sh"]), lum(q["sh"])) for p, q in zip(a, b) if "valid" in p["flags"] and "valid" in q["flags"]]
print("%.5f" % (math.sqrt(sum((x - y) ** 2 for x, y in d) / len(d)) / (sum(x for x, _ in d) / len(d))))
EOF
}

device=$("$pb" devices --json | sed -n 's/.*"index": 0, "name": "\([^"]*\)".*/\1/p' | head -n 1)
echo "shading_normals: $(nproc) cores; device: $device; $pairs pairs; preview, 256 rays x 4 passes"
printf '%-16s %8s %10s %10s %10s %9s %9s\n' scene smooth "vertex ms" "face ms" "ratio" change noise
csv=$out/shading_normals.csv
echo "scene,smooth_triangles,triangles,vertex_ms,face_ms,ratio,change,noise" >"$csv"
json="["
for s in "${scenes[@]}"; do
    name=$(basename "$s")
    smooth=$("$pb" info "$s" --json | sed -n 's/.*"smooth_triangles": \([0-9]*\).*/\1/p')
    tris=$("$pb" info "$s" --json | sed -n 's/^  "triangles": \([0-9]*\).*/\1/p')
    bake "$s" vertex 1 "$tmp/w.probes" >/dev/null # warm-up: pipelines, caches
    ratios=() vs=() fs=()
    for ((i = 0; i < pairs; ++i)); do
        v=$(bake "$s" vertex 1 "$tmp/v.probes")
        f=$(bake "$s" face 1 "$tmp/f.probes")
        vs+=("$v") fs+=("$f") ratios+=("$(echo "$v / $f" | bc -l)")
    done
    median() { printf '%s\n' "$@" | sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
    bake "$s" vertex 2 "$tmp/v2.probes" >/dev/null
    ch=$(change "$tmp/v.probes" "$tmp/f.probes")
    no=$(change "$tmp/v.probes" "$tmp/v2.probes")
    mv=$(median "${vs[@]}") mf=$(median "${fs[@]}") mr=$(median "${ratios[@]}")
    printf '%-16s %8s %10.0f %10.0f %10.3f %9.4f %9.4f\n' "$name" "$smooth" "$mv" "$mf" "$mr" "$ch" "$no"
    echo "$name,$smooth,$tris,$mv,$mf,$mr,$ch,$no" >>"$csv"
    json+="$([ "$json" = "[" ] || echo ,){\"scene\": \"$name\", \"smooth_triangles\": $smooth, \"triangles\": $tris, \"vertex_ms\": [$(IFS=,; echo "${vs[*]}")], \"face_ms\": [$(IFS=,; echo "${fs[*]}")], \"ratio_median\": $mr, \"change\": $ch, \"noise\": $no}"
done
echo "$json]" >"$out/shading_normals.json"
echo "wrote $csv and $out/shading_normals.json"
