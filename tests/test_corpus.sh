#!/usr/bin/env bash
# scripts/corpus.py over the repository's scenes and ../shared/scenes (when
# present): every file loads or is refused with a one-line reason, none
# crashes, every volume is finite; the files expected to load do, and the
# shared corpus's three expected refusals are the only ones.
# The repository's scenes also go in compressed, as tests/gltf_compress
# writes them (Draco, meshopt, quantized; issue 15), and the demo scene with
# legacy materials: each must load and bake.
# Usage: test_corpus.sh SOURCE_DIR PROBEBAKE GLTF_COMPRESS
set -u
src=$1
pb=$2
compress=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for f in "$src"/tests/scenes/*.gltf; do
    for mode in draco meshopt quantize; do
        "$compress" "$mode" "$f" "$tmp/$(basename "$f" .gltf)_$mode.glb" || { echo "[ FAIL ] gltf_compress $mode $f"; exit 1; }
    done
done
# ... and as legacy files: the demo scene's materials rewritten as
# KHR_materials_pbrSpecularGlossiness (diffuse = base colour), one of them
# KHR_materials_unlit, its texture through KHR_texture_transform, all three
# required, in .gltf and (compressed) .glb
python3 - "$src/tests/scenes/demo.gltf" "$tmp/legacy_demo.gltf" <<'PY' || { echo "[ FAIL ] legacy sample"; exit 1; }
import json, sys
g = json.load(open(sys.argv[1]))
for i, m in enumerate(g["materials"]):
    pbr = m.pop("pbrMetallicRoughness", {})
    sg = {"diffuseFactor": pbr.get("baseColorFactor", [1, 1, 1, 1]), "glossinessFactor": 0.2}
    if "baseColorTexture" in pbr:
        sg["diffuseTexture"] = dict(pbr["baseColorTexture"],
                                    extensions={"KHR_texture_transform": {"offset": [0.25, 0], "scale": [2, 2]}})
    m.setdefault("extensions", {})["KHR_materials_pbrSpecularGlossiness"] = sg
    if i == len(g["materials"]) - 1:
        m["extensions"]["KHR_materials_unlit"] = {}
ext = ["KHR_materials_pbrSpecularGlossiness", "KHR_materials_unlit", "KHR_texture_transform"]
g["extensionsUsed"] = sorted(set(g.get("extensionsUsed", []) + ext))
g["extensionsRequired"] = sorted(set(g.get("extensionsRequired", []) + ext))
json.dump(g, open(sys.argv[2], "w"))
PY
"$compress" draco "$tmp/legacy_demo.gltf" "$tmp/legacy_demo_draco.glb" || { echo "[ FAIL ] gltf_compress legacy"; exit 1; }
dirs=("$src/tests/scenes" "$tmp")
shared="$src/../shared/scenes"
[ -d "$shared" ] && dirs+=("$shared") || echo "  SKIP part: $shared not present"
out=$(python3 "$src/scripts/corpus.py" --probebake "$pb" "${dirs[@]}")
rc=$?
echo "$out" | python3 -c '
import json, sys
d = json.load(sys.stdin)
print("  %(files)d files: %(loaded)d loaded, %(baked)d baked, %(refused)d refused, %(crashed)d crashed, %(nan)d NaN" % d)
for r in d["refusals"]:
    print("  refused: " + r["reason"])
bad = d["crashed"] or d["nan"]
expected = {"Empty.gltf", "OnlyAccessors.gltf", "EmbedBufferInvalid.gltf"}  # no triangles; an invalid data URI
unexpected = [r["file"] for r in d["refusals"] if r["file"].rsplit("/", 1)[-1] not in expected]
if unexpected:
    print("  unexpected refusals: %s" % unexpected)
compressed = [f for f in d["baked_files"] if "_draco." in f or "_meshopt." in f or "_quantize." in f]
legacy = [f for f in d["baked_files"] if "legacy_demo" in f]
print("  %d compressed files and %d legacy ones loaded and baked" % (len(compressed), len(legacy)))
sys.exit(1 if bad or unexpected or d["files"] < 4 or len(compressed) < 12 or len(legacy) < 2 else 0)
'
check=$?
if [ "$rc" -eq 0 ] && [ "$check" -eq 0 ]; then
    echo "[  OK  ] corpus"
else
    echo "[ FAIL ] corpus (corpus.py exit $rc)"
    exit 1
fi
