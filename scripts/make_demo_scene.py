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
import base64, math, os, struct, zlib

from gltf_scene import Scene, material as mat, scenes_dir

scene = Scene()
quad, add = scene.quad, scene.add


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
    {"name": "room", "mesh": scene.mesh_index("room"), "children": [1, 2, 5, 6, 7]},
    {"name": "panel", "mesh": scene.mesh_index("panel")},
    {"name": "boxes", "translation": [0.0, 0.0, -0.5], "children": [3, 4]},
    {"name": "tall box", "mesh": scene.mesh_index("box"), "translation": [-0.7, 0.9, -0.6], "rotation": yrot(20),
     "scale": [0.8, 1.8, 0.8]},
    {"name": "short box", "mesh": scene.mesh_index("box"), "translation": [0.75, 0.45, 0.5], "rotation": yrot(-18),
     "scale": [0.9, 0.9, 0.9]},
    {"name": "lattice", "mesh": scene.mesh_index("lattice"), "translation": [-1.2, 1.0, 1.2], "rotation": yrot(60)},
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
    "meshes": None,  # filled by Scene.write, keeping this key order
    "materials": materials,
    "textures": [{"source": 0, "sampler": 0}],
    "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497}],
    "images": [{"name": "lattice", "uri": "data:image/png;base64," + base64.b64encode(lattice_png).decode()}],
    "cameras": [{"name": "view", "type": "perspective",
                 "perspective": {"yfov": 1.0, "aspectRatio": 1.333, "znear": 0.05, "zfar": 50.0}}],
}
scene.write(os.path.join(scenes_dir(), "demo.gltf"), gltf)
