#!/usr/bin/env python3
"""Writes tests/scenes/demo.gltf: probebake's bundled demo scene.

A closed Cornell-style room (4 x 3 x 5 m, walls facing inward): white floor,
ceiling and end walls, red left wall, green right wall; an emissive ceiling
panel (KHR_materials_emissive_strength); a KHR_lights_punctual point light;
two boxes instancing one mesh through TRS nodes under a parent; an
alpha-masked, double-sided lattice screen (RGBA texture, data URI); a camera.
Everything is embedded (base64 data URIs), so the file stands alone.
Only the Python standard library is used. Run: python3 scripts/make_demo_scene.py
"""
import base64, json, math, os, struct, zlib

positions, normals, uvs, indices = [], [], [], []
primitives = {}  # mesh name -> list of (first index, count, material)


def quad(p0, p1, p2, p3, n, uv_scale=1.0):
    """Quad p0..p3 counter-clockwise seen from the side `n` points to."""
    base = len(positions)
    for p, uv in zip((p0, p1, p2, p3), ((0, 1), (1, 1), (1, 0), (0, 0))):
        positions.append(p)
        normals.append(n)
        uvs.append((uv[0] * uv_scale, uv[1] * uv_scale))
    indices.extend([base, base + 1, base + 2, base, base + 2, base + 3])


def add(mesh, material, fn):
    first = len(indices)
    fn()
    primitives.setdefault(mesh, []).append((first, len(indices) - first, material))


X, Y, Z = 2.0, 3.0, 2.5
WHITE, RED, GREEN, LIGHT, BOX, LATTICE = range(6)
# room: every face looks inward
add("room", WHITE, lambda: quad((-X, 0, Z), (X, 0, Z), (X, 0, -Z), (-X, 0, -Z), (0, 1, 0)))         # floor
add("room", WHITE, lambda: quad((-X, Y, -Z), (X, Y, -Z), (X, Y, Z), (-X, Y, Z), (0, -1, 0)))        # ceiling
add("room", WHITE, lambda: quad((-X, 0, -Z), (X, 0, -Z), (X, Y, -Z), (-X, Y, -Z), (0, 0, 1)))       # back
add("room", WHITE, lambda: quad((X, 0, Z), (-X, 0, Z), (-X, Y, Z), (X, Y, Z), (0, 0, -1)))          # front
add("room", RED, lambda: quad((-X, 0, Z), (-X, 0, -Z), (-X, Y, -Z), (-X, Y, Z), (1, 0, 0)))         # left
add("room", GREEN, lambda: quad((X, 0, -Z), (X, 0, Z), (X, Y, Z), (X, Y, -Z), (-1, 0, 0)))          # right
# ceiling panel, 1 m^2, 1 cm below the ceiling, facing down
h = Y - 0.01
add("panel", LIGHT, lambda: quad((-0.5, h, -0.5), (0.5, h, -0.5), (0.5, h, 0.5), (-0.5, h, 0.5), (0, -1, 0)))


def box():  # unit cube [-0.5,0.5]^3 with outward faces
    s = 0.5
    quad((-s, -s, s), (s, -s, s), (s, s, s), (-s, s, s), (0, 0, 1))
    quad((s, -s, -s), (-s, -s, -s), (-s, s, -s), (s, s, -s), (0, 0, -1))
    quad((s, -s, s), (s, -s, -s), (s, s, -s), (s, s, s), (1, 0, 0))
    quad((-s, -s, -s), (-s, -s, s), (-s, s, s), (-s, s, -s), (-1, 0, 0))
    quad((-s, s, s), (s, s, s), (s, s, -s), (-s, s, -s), (0, 1, 0))
    quad((-s, -s, -s), (s, -s, -s), (s, -s, s), (-s, -s, s), (0, -1, 0))


add("box", BOX, box)
# lattice screen 1.6 x 1.6 m, in the local XY plane (node places it)
add("lattice", LATTICE, lambda: quad((-0.8, -0.8, 0), (0.8, -0.8, 0), (0.8, 0.8, 0), (-0.8, 0.8, 0), (0, 0, 1), 4.0))


def png_rgba(w, h, pixel):
    raw = b"".join(b"\0" + b"".join(bytes(pixel(x, y)) for x in range(w)) for y in range(h))
    def chunk(tag, data):
        c = tag + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xffffffff)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


# 16x16 lattice: opaque bars 4 texels wide around 12x12 holes... here: bars on
# rows/columns 0-3 of each 8-texel cell, so a quarter of each cell is a hole
lattice_png = png_rgba(16, 16, lambda x, y: (200, 170, 120, 255 if (x % 8 < 3 or y % 8 < 3) else 0))

# ---- buffer: positions, normals, uvs, indices (uint16)
blob = bytearray()
def append(data, align=4):
    while len(blob) % align:
        blob.append(0)
    off = len(blob)
    blob.extend(data)
    return off

nv = len(positions)
pos_off = append(b"".join(struct.pack("<3f", *p) for p in positions))
nrm_off = append(b"".join(struct.pack("<3f", *n) for n in normals))
uv_off = append(b"".join(struct.pack("<2f", *t) for t in uvs))
idx_off = append(b"".join(struct.pack("<H", i) for i in indices))

buffer_views = [
    {"buffer": 0, "byteOffset": pos_off, "byteLength": 12 * nv, "target": 34962},
    {"buffer": 0, "byteOffset": nrm_off, "byteLength": 12 * nv, "target": 34962},
    {"buffer": 0, "byteOffset": uv_off, "byteLength": 8 * nv, "target": 34962},
    {"buffer": 0, "byteOffset": idx_off, "byteLength": 2 * len(indices), "target": 34963},
]
lo = [min(p[k] for p in positions) for k in range(3)]
hi = [max(p[k] for p in positions) for k in range(3)]
accessors = [
    {"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3", "min": lo, "max": hi},
    {"bufferView": 1, "componentType": 5126, "count": nv, "type": "VEC3"},
    {"bufferView": 2, "componentType": 5126, "count": nv, "type": "VEC2"},
]
meshes = []
for name, prims in primitives.items():
    mesh = {"name": name, "primitives": []}
    for first, count, material in prims:
        accessors.append({"bufferView": 3, "byteOffset": 2 * first, "componentType": 5123, "count": count,
                          "type": "SCALAR"})
        mesh["primitives"].append({"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                   "indices": len(accessors) - 1, "material": material, "mode": 4})
    meshes.append(mesh)
mesh_index = {m["name"]: i for i, m in enumerate(meshes)}

def mat(name, color, **kw):
    m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": color + [1.0], "metallicFactor": 0.0,
                                                "roughnessFactor": 1.0}}
    m.update(kw)
    return m

materials = [
    mat("white", [0.73, 0.73, 0.73]),
    mat("red", [0.65, 0.05, 0.05]),
    mat("green", [0.12, 0.45, 0.15]),
    mat("light", [0.78, 0.78, 0.78], emissiveFactor=[1.0, 0.85, 0.6],
        extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 8.0}}),
    mat("box", [0.6, 0.6, 0.65]),
    {"name": "lattice", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True,
     "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "baseColorTexture": {"index": 0},
                              "metallicFactor": 0.0, "roughnessFactor": 1.0}},
]

def yrot(deg):
    a = math.radians(deg) / 2
    return [0.0, math.sin(a), 0.0, math.cos(a)]

nodes = [
    {"name": "room", "mesh": mesh_index["room"], "children": [1, 2, 5, 6, 7]},
    {"name": "panel", "mesh": mesh_index["panel"]},
    {"name": "boxes", "translation": [0.0, 0.0, -0.5], "children": [3, 4]},
    {"name": "tall box", "mesh": mesh_index["box"], "translation": [-0.7, 0.9, -0.6], "rotation": yrot(20),
     "scale": [0.8, 1.8, 0.8]},
    {"name": "short box", "mesh": mesh_index["box"], "translation": [0.75, 0.45, 0.5], "rotation": yrot(-18),
     "scale": [0.9, 0.9, 0.9]},
    {"name": "lattice", "mesh": mesh_index["lattice"], "translation": [-1.2, 1.0, 1.2], "rotation": yrot(60)},
    {"name": "lamp", "translation": [0.6, 2.4, 1.2], "extensions": {"KHR_lights_punctual": {"light": 0}}},
    {"name": "camera", "camera": 0, "translation": [0.0, 1.5, 2.4]},
]

gltf = {
    "asset": {"version": "2.0", "generator": "probebake scripts/make_demo_scene.py"},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "lamp", "type": "point", "color": [1.0, 0.9, 0.8], "intensity": 15.0}]}},
    "scene": 0,
    "scenes": [{"name": "demo", "nodes": [0]}],
    "nodes": nodes,
    "meshes": meshes,
    "materials": materials,
    "textures": [{"source": 0, "sampler": 0}],
    "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497}],
    "images": [{"name": "lattice", "uri": "data:image/png;base64," + base64.b64encode(lattice_png).decode()}],
    "cameras": [{"name": "view", "type": "perspective",
                 "perspective": {"yfov": 1.0, "aspectRatio": 1.333, "znear": 0.05, "zfar": 50.0}}],
    "accessors": accessors,
    "bufferViews": buffer_views,
    "buffers": [{"byteLength": len(blob),
                 "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
}
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "scenes", "demo.gltf")
with open(out, "w") as f:
    json.dump(gltf, f, indent=1)
    f.write("\n")
print("wrote", os.path.normpath(out), len(indices) // 3, "triangles")
