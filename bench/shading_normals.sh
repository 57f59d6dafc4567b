#!/usr/bin/env bash
# What shading normals, or normal maps, cost and change: each scene baked
# with the feature (the default) and without it, alternately, same seed, in
# the same run. Shading normals: the file's vertex normals against face
# normals (--shading-normals face, the peer: what every bake did before
# vertex normals were read). Normal maps (--feature normal-maps): with the
# materials' normal maps against without (--normal-maps off).
#   time     GPU trace ms of each bake; the ratio with / without is the median
#            of the pairs' ratios (lavapipe drifts within minutes: pairs, not means)
#   change   relative RMS difference of the probes' DC irradiance (luminance)
#            between the two bakes, over probes valid in both
#   noise    the same between two bakes with the feature and seeds 1 and 2: a
#            change far below it is invisible at this bake's quality
# Prints a table, writes CSV and JSON.
#
#   bench/shading_normals.sh [--feature shading-normals|normal-maps] [--probebake P] [--pairs N] [--out DIR]
#                            [SCENE ...]
#
# Each bake has the scene's lights, and a white sky where it has none (for normal maps, where it
# has no punctual light).
# Default: shading normals on The Crypt, the Cornell box and the glTF Duck, normal maps on
# DamagedHelmet and AlphaBlendModeTest, from ../shared/scenes (skipped when absent), 256 rays
# x 4 passes, 5 pairs, into bench/results/shading_normals/ or bench/results/normal_maps/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pb=$root/build/probebake
pairs=5
feature=shading-normals
out=
while [ $# -gt 0 ]; do
    case $1 in
        --feature) feature=$2; shift 2 ;;
        --probebake) pb=$2; shift 2 ;;
        --pairs) pairs=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        *) break ;;
    esac
done
# per feature: its bake options with and without, the column names, what info counts of it
case $feature in
    shading-normals)
        with=(--shading-normals vertex) without=(--shading-normals face) on=vertex off=face count=smooth_triangles
        defaults=(openarena/oacmpdm1.glb cornell/cornellBox.gltf samples/Duck/Duck.gltf) ;;
    normal-maps)
        with=(--normal-maps on) without=(--normal-maps off) on=mapped off=unmapped count=normal_mapped_materials
        defaults=(samples/DamagedHelmet/DamagedHelmet.gltf samples/AlphaBlendModeTest/AlphaBlendModeTest.gltf) ;;
    *) echo "shading_normals: --feature takes shading-normals or normal-maps"; exit 2 ;;
esac
out=${out:-$root/bench/results/${feature/-/_}}
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
    for s in "${defaults[@]}"; do
        f=$root/../shared/scenes/$s
        if [ -f "$f" ]; then scenes+=("$f"); else echo "skip $s: absent"; fi
    done
fi
[ ${#scenes[@]} -gt 0 ] || { echo "shading_normals: no scene"; exit 1; }
mkdir -p "$out"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# the scene's bake: lights of its own where it has them, else a white sky
bake() { # scene with|without seed out
    local sky=() opts=("${with[@]}")
    [ "$2" = with ] || opts=("${without[@]}")
    # (normal maps: a white sky wherever there is no punctual light: DamagedHelmet's own light is its emission,
    # too little to see its maps by at preview quality)
    { [ "$feature" = normal-maps ] || "$pb" info "$1" --json | grep -q '"emissive_materials": 0,'; } &&
        "$pb" info "$1" --json | grep -q '"lights": \[\]' && sky=(--sky 1,1,1)
    "$pb" bake "$1" --quality preview --rays 256 --passes 4 "${sky[@]}" "${opts[@]}" --seed "$3" -o "$4" 2>&1 |
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
stem=${feature/-/_}
echo "$stem: $(nproc) cores; device: $device; $pairs pairs; preview, 256 rays x 4 passes"
printf '%-28s %8s %10s %10s %10s %9s %9s\n' scene "${count%%_*}" "$on ms" "$off ms" "ratio" change noise
csv=$out/$stem.csv
echo "scene,$count,triangles,${on}_ms,${off}_ms,ratio,change,noise" >"$csv"
json="["
for s in "${scenes[@]}"; do
    name=$(basename "$s")
    counted=$("$pb" info "$s" --json | sed -n "s/.*\"$count\": \([0-9]*\).*/\1/p")
    tris=$("$pb" info "$s" --json | sed -n 's/^  "triangles": \([0-9]*\).*/\1/p')
    bake "$s" with 1 "$tmp/w.probes" >/dev/null # warm-up: pipelines, caches
    ratios=() vs=() fs=()
    for ((i = 0; i < pairs; ++i)); do
        v=$(bake "$s" with 1 "$tmp/v.probes")
        f=$(bake "$s" without 1 "$tmp/f.probes")
        vs+=("$v") fs+=("$f") ratios+=("$(echo "$v / $f" | bc -l)")
    done
    median() { printf '%s\n' "$@" | sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
    bake "$s" with 2 "$tmp/v2.probes" >/dev/null
    ch=$(change "$tmp/v.probes" "$tmp/f.probes")
    no=$(change "$tmp/v.probes" "$tmp/v2.probes")
    mv=$(median "${vs[@]}") mf=$(median "${fs[@]}") mr=$(median "${ratios[@]}")
    printf '%-28s %8s %10.0f %10.0f %10.3f %9.4f %9.4f\n' "$name" "$counted" "$mv" "$mf" "$mr" "$ch" "$no"
    echo "$name,$counted,$tris,$mv,$mf,$mr,$ch,$no" >>"$csv"
    json+="$([ "$json" = "[" ] || echo ,){\"scene\": \"$name\", \"$count\": $counted, \"triangles\": $tris, \"${on}_ms\": [$(IFS=,; echo "${vs[*]}")], \"${off}_ms\": [$(IFS=,; echo "${fs[*]}")], \"ratio_median\": $mr, \"change\": $ch, \"noise\": $no}"
done
echo "$json]" >"$out/$stem.json"
echo "wrote $csv and $out/$stem.json"
