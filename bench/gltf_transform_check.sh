#!/usr/bin/env bash
# Real glTF-Transform outputs against their originals, in the same run: the
# shared samples rewritten by the tool people use to compress glTF (npm
# @gltf-transform/cli at a pinned version: meshopt geometry, quantized
# attributes, simplified meshes, lossy WebP or AVIF textures; GPU instancing;
# and KTX2 ETC1S and UASTC (Zstandard) textures from Basis Universal's encoder,
# npm ktx2-encoder through bench/ktx2_encode.mjs, since the CLI's etc1s and
# uastc need KTX-Software), each
# loaded by probebake and baked on the same grid as its original. The peer is
# the original file; the error is the probes' irradiance (DC, mean of RGB)
# relative to the original's: what compressing an asset costs the bake. Its
# floor is printed beside it: the original baked again with another seed
# (a compressed file may reorder triangles, which changes which emitter a
# random number draws, so its paths decorrelate from the original's).
#
#   bench/gltf_transform_check.sh [--probebake P] [--out DIR] [--cases REGEX]
#
# --cases runs only the cases whose name matches (grep -E), into
# gltf_transform_check-cases.{json,csv} beside the full run's.
#
# Needs npm and the npm registry (the tool and its sharp/libvips come from
# there), and ../shared/scenes. Not part of the test suite: CI has neither
# the tool nor, by rule, a network step in its tests. Prints a table, writes
# CSV and JSON into bench/results/gltf_transform/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pb=$root/build/probebake
out=$root/bench/results/gltf_transform
version=4.5.1
only=
while [ $# -gt 0 ]; do
    case $1 in
        --probebake) pb=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        --cases) only=$2; shift 2 ;;
        *) echo "gltf_transform_check: unknown option $1" >&2; exit 2 ;;
    esac
done
shared=$root/../shared/scenes
[ -d "$shared/samples" ] || { echo "gltf_transform_check: $shared/samples absent" >&2; exit 1; }
command -v npm >/dev/null || { echo "gltf_transform_check: npm not found" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "gltf_transform_check: installing @gltf-transform/cli@$version into $work"
npm install --prefix "$work" --no-audit --no-fund "@gltf-transform/cli@$version" "@gltf-transform/core@$version" \
    "@gltf-transform/extensions@$version" ktx2-encoder@0.6.0 pngjs@7.0.0 jpeg-js@0.4.4 >"$work/npm.log" 2>&1 ||
    { tail -5 "$work/npm.log"; echo "gltf_transform_check: npm install failed" >&2; exit 1; }
gt=$work/node_modules/.bin/gltf-transform
cp "$root/bench/ktx2_encode.mjs" "$work/" # its imports resolve beside it
mkdir -p "$out"

# name | source under shared/scenes | gltf-transform command and options
cases=(
    "helmet-optimize|samples/DamagedHelmet/DamagedHelmet.gltf|optimize --texture-compress webp"
    "helmet-optimize-avif|samples/DamagedHelmet/DamagedHelmet.gltf|optimize --texture-compress avif"
    "duck-optimize|samples/Duck/Duck.gltf|optimize --texture-compress webp"
    "alpha-blend-optimize|samples/AlphaBlendModeTest/AlphaBlendModeTest.gltf|optimize --texture-compress webp"
    "texture-transform-instance|samples/TextureTransformTest/TextureTransformTest.gltf|instance --min 2"
    "crypt-optimize|openarena/oacmpdm1.glb|optimize"
    "crypt-draco-no-simplify|openarena/oacmpdm1.glb|optimize --compress draco --simplify false"
    "helmet-ktx2-etc1s|samples/DamagedHelmet/DamagedHelmet.gltf|ktx2 etc1s"
    "duck-ktx2-etc1s|samples/Duck/Duck.gltf|ktx2 etc1s"
    "alpha-blend-ktx2-etc1s|samples/AlphaBlendModeTest/AlphaBlendModeTest.gltf|ktx2 etc1s"
    "texture-transform-ktx2-etc1s|samples/TextureTransformTest/TextureTransformTest.gltf|ktx2 etc1s"
    "helmet-ktx2-uastc|samples/DamagedHelmet/DamagedHelmet.gltf|ktx2 uastc"
    "duck-ktx2-uastc|samples/Duck/Duck.gltf|ktx2 uastc"
    "alpha-blend-ktx2-uastc|samples/AlphaBlendModeTest/AlphaBlendModeTest.gltf|ktx2 uastc"
    "texture-transform-ktx2-uastc|samples/TextureTransformTest/TextureTransformTest.gltf|ktx2 uastc"
)
bake() { # scene bounds output [options]
    "$pb" bake "$1" --sky 1,1,1 --counts 8,8,8 --rays 512 --passes 4 --bounds "$2" --quiet -o "$3" "${@:4}" >/dev/null
}
rows="$work/rows.jsonl"
: >"$rows"
for c in "${cases[@]}"; do
    IFS='|' read -r name src cmd <<<"$c"
    orig=$shared/$src
    [ -z "$only" ] || grep -Eq "$only" <<<"$name" || continue
    [ -f "$orig" ] || { echo "skip $name: $orig absent"; continue; }
    t0=$(date +%s.%N)
    if [ "${cmd%% *}" = ktx2 ]; then
        node "$work/ktx2_encode.mjs" "$orig" "$work/$name.glb" "${cmd#ktx2 }" >"$work/$name.log" 2>&1 ||
            { tail -3 "$work/$name.log"; echo "gltf_transform_check: $name: ktx2_encode failed" >&2; exit 1; }
    else
        # shellcheck disable=SC2086 # the command's words
        "$gt" $cmd "$orig" "$work/$name.glb" >"$work/$name.log" 2>&1 ||
            { tail -3 "$work/$name.log"; echo "gltf_transform_check: $name: gltf-transform failed" >&2; exit 1; }
    fi
    echo "  $name: written in $(echo "$(date +%s.%N) - $t0" | bc | xargs printf '%.1f') s"
    bounds=$("$pb" info "$orig" --json | python3 -c \
        'import json,sys; d=json.load(sys.stdin); o=d["origin"]
print(",".join("%.6g" % (o[k % 3] + v) for k, v in enumerate(d["bounds_min"] + d["bounds_max"])))')
    bake "$orig" "$bounds" "$work/$name-orig.probes"
    bake "$work/$name.glb" "$bounds" "$work/$name.probes"
    bake "$orig" "$bounds" "$work/$name-seed2.probes" --seed 2
    "$pb" inspect "$work/$name-orig.probes" --json >"$work/a.json"
    "$pb" inspect "$work/$name.probes" --json >"$work/b.json"
    "$pb" inspect "$work/$name-seed2.probes" --json >"$work/c.json"
    "$pb" info "$work/$name.glb" --json >"$work/info.json"
    "$pb" info "$orig" --json >"$work/info0.json"
    # the load's wall time (info: read, decode, build the triangles), fastest of 3 alternating pairs
    load0=9e9 load1=9e9
    least() { awk -v a="$1" -v b="$2" 'BEGIN { print (a + 0 < b + 0) ? a : b }'; }
    for _ in 1 2 3; do
        /usr/bin/time -f %e -o "$work/t" "$pb" info "$orig" >/dev/null 2>&1 && load0=$(least "$(cat "$work/t")" "$load0")
        /usr/bin/time -f %e -o "$work/t" "$pb" info "$work/$name.glb" >/dev/null 2>&1 &&
            load1=$(least "$(cat "$work/t")" "$load1")
    done
    python3 - "$name" "$cmd" "$orig" "$work" "$(stat -c %s "$work/$name.glb")" "$load0" "$load1" >>"$rows" <<'EOF'
import json, sys
name, cmd, orig, work, size = sys.argv[1:6]
load0, load1 = float(sys.argv[6]), float(sys.argv[7])
a = json.load(open(work + "/a.json"))["probe_list"]
b = json.load(open(work + "/b.json"))["probe_list"]
c = json.load(open(work + "/c.json"))["probe_list"]
i0, i1 = json.load(open(work + "/info0.json")), json.load(open(work + "/info.json"))
def diffs(p, q):
    out = []
    for x, y in zip(p, q):
        lx, ly = sum(x["sh"][0:3]) / 3, sum(y["sh"][0:3]) / 3
        if lx > 0:
            out.append(abs(ly - lx) / lx)
    return sorted(out)
rel, floor = diffs(a, b), diffs(a, c)
def pick(v, q):
    return v[min(len(v) - 1, int(q * len(v)))] if v else float("nan")
print(json.dumps({"case": name, "command": ("node bench/ktx2_encode.mjs " + cmd[5:]) if cmd.startswith("ktx2 ")
                  else "gltf-transform " + cmd, "source": orig.split("/scenes/")[-1],
                  "triangles_original": i0["triangles"], "triangles": i1["triangles"],
                  "extensions_applied": i1["extensions_applied"], "bytes": int(size), "probes": len(rel),
                  "load_s_original": load0, "load_s": load1,
                  "rel_dc_median": pick(rel, 0.5), "rel_dc_p95": pick(rel, 0.95), "rel_dc_max": rel[-1] if rel else None,
                  "seed_floor_median": pick(floor, 0.5), "seed_floor_p95": pick(floor, 0.95)}))
EOF
done
python3 - "$rows" "$out" "$version" "$("$pb" --version | head -1)" "${only:+-cases}" <<'EOF'
import json, sys
rows_path, out, version, pbv, suffix = sys.argv[1:6]
rows = [json.loads(l) for l in open(rows_path) if l.strip()]
print("glTF-Transform %s outputs against their originals (%s); sky 1, 8x8x8 probes over the original's bounds,"
      " 512 rays x 4 passes; |irradiance DC difference| / original" % (version, pbv))
print("%-28s %10s %10s %9s %9s %9s %11s %9s %7s %7s  %s" % ("case", "tris orig", "tris", "median", "p95", "max",
      "seed median", "seed p95", "load0 s", "load s", "extensions applied"))
for r in rows:
    print("%-28s %10d %10d %9.4f %9.4f %9.4f %11.4f %9.4f %7.2f %7.2f  %s" % (r["case"], r["triangles_original"],
          r["triangles"], r["rel_dc_median"], r["rel_dc_p95"], r["rel_dc_max"], r["seed_floor_median"],
          r["seed_floor_p95"], r["load_s_original"], r["load_s"], ", ".join(r["extensions_applied"])))
json.dump({"gltf_transform": version, "probebake": pbv, "rows": rows}, open(out + "/gltf_transform_check%s.json" % suffix, "w"),
          indent=1)
with open(out + "/gltf_transform_check%s.csv" % suffix, "w") as f:
    f.write("case,command,triangles_original,triangles,rel_dc_median,rel_dc_p95,rel_dc_max,seed_floor_median,"
            "seed_floor_p95,load_s_original,load_s,extensions_applied\n")
    for r in rows:
        f.write('%s,"%s",%d,%d,%.6f,%.6f,%.6f,%.6f,%.6f,%.3f,%.3f,"%s"\n' % (r["case"], r["command"],
                r["triangles_original"], r["triangles"], r["rel_dc_median"], r["rel_dc_p95"], r["rel_dc_max"],
                r["seed_floor_median"], r["seed_floor_p95"], r["load_s_original"], r["load_s"],
                " ".join(r["extensions_applied"])))
print("wrote %s/gltf_transform_check%s.{json,csv}" % (out, suffix))
EOF
