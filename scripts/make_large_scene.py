#!/usr/bin/env python3
"""Writes a large glTF scene for the host-side benches (load, BVH build):

    python3 scripts/make_large_scene.py OUT.glb [N]

A 40 x 40 m rolling terrain of N x N vertices (2 (N-1)^2 triangles; N = 1449,
the default, gives 4,193,410 triangles and a 75 MB file), lit by one 8 x 8 m
emissive panel 8 m above it. Positions only, uint32 indices, one .glb. The
shared scenes stop at 80k triangles (shared/scenes/MANIFEST.md); this is the
"large scene" a GPU workstation user bakes, where the host's load and BVH
build weigh most. Only the Python standard library is used.
"""
import array, json, math, struct, sys


def terrain(n, size=40.0):
    pos, idx = array.array('f'), array.array('I')
    for j in range(n):
        z = -size / 2 + size * j / (n - 1)
        for i in range(n):
            x = -size / 2 + size * i / (n - 1)
            y = 0.6 * math.sin(x * 0.7) * math.cos(z * 0.5) + 0.15 * math.sin(x * 3.1 + z * 2.3)
            pos.extend((x, y, z))
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            idx.extend((a, a + n, a + 1, a + 1, a + n, a + n + 1))
    return pos, idx


def main():
    out = sys.argv[1]
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 1449
    pos, idx = terrain(n)
    base = len(pos) // 3
    pos.extend((-4, 8, -4, 4, 8, -4, 4, 8, 4, -4, 8, 4))  # the panel, facing down (double-sided)
    lamp = array.array('I', (base, base + 1, base + 2, base, base + 2, base + 3))
    pb, ib, lb = pos.tobytes(), idx.tobytes(), lamp.tobytes()
    blob = pb + ib + lb
    views = [(0, len(pb)), (len(pb), len(ib)), (len(pb) + len(ib), len(lb))]
    lo = [min(pos[k::3]) for k in range(3)]
    hi = [max(pos[k::3]) for k in range(3)]
    gltf = {
        "asset": {"version": "2.0", "generator": "probebake scripts/make_large_scene.py"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.55, 0.5, 1], "metallicFactor": 0}},
            {"emissiveFactor": [1, 1, 1], "doubleSided": True,
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 20}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0},
                                   {"attributes": {"POSITION": 0}, "indices": 2, "material": 1}]}],
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": [{"buffer": 0, "byteOffset": o, "byteLength": l} for o, l in views],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(pos) // 3, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5125, "count": len(lamp), "type": "SCALAR"}],
    }
    js = json.dumps(gltf).encode()
    js += b' ' * (-len(js) % 4)
    blob += b'\0' * (-len(blob) % 4)
    with open(out, 'wb') as f:
        f.write(struct.pack('<III', 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(blob)))
        f.write(struct.pack('<II', len(js), 0x4E4F534A) + js)
        f.write(struct.pack('<II', len(blob), 0x004E4942) + blob)
    print(f"{out}: {len(idx) // 3 + 2} triangles")


if __name__ == '__main__':
    main()
