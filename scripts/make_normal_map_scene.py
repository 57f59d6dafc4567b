#!/usr/bin/env python3
"""Writes tests/scenes/bumps.gltf: a normal-mapped scene small enough to bundle.

bumps.gltf  a 4 x 4 m grey floor facing +Y whose normal map (256 x 256, an
            embedded PNG) holds an 8 x 8 grid of round domes (slopes up to 50
            degrees), lit by one directional light of intensity 3 from +Z at 30
            degrees elevation, seen by a camera from (0, 1.6, 3). Texture
            coordinates run u along +X and v along +Z, so the map's +Y (up the
            image) is -Z: the domes' far flanks face away from the light and go
            dark where they lean more than 30 degrees (docs/bake.md, "Normal
            maps", shows it with and without `--normal-maps off`).

Only the Python standard library is used. Run: python3 scripts/make_normal_map_scene.py
"""
import base64, math, os, struct, zlib

from gltf_scene import Scene, material, scenes_dir


def png_rgb(width, height, rows):
    """An 8-bit RGB PNG of `rows` (bytes of 3 x width each)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff)
    raw = b"".join(b"\x00" + r for r in rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def domes(size=256, grid=8, radius=0.4, slope=1.2):
    """Tangent-space normals (glTF: +X right, +Y up the image) of round domes:
    within `radius` of each cell's centre the normal leans outward by
    atan(slope sin(pi r / radius))."""
    rows = []
    for y in range(size):
        row = bytearray()
        for x in range(size):
            cx = (x + 0.5) / size * grid % 1 - 0.5  # right of the cell's centre
            cy = (y + 0.5) / size * grid % 1 - 0.5  # below it (image rows run down)
            r = math.hypot(cx, cy)
            s = slope * math.sin(math.pi * r / radius) if 0 < r < radius else 0.0
            n = (s * cx / r if r else 0.0, -s * cy / r if r else 0.0, 1.0)  # outward; below is -Y
            length = math.sqrt(sum(c * c for c in n))
            row += bytes(int(round((c / length + 1) * 127.5)) for c in n)
        rows.append(bytes(row))
    return png_rgb(size, size, rows)


def main():
    s = Scene()
    # counter-clockwise from +Y; quad() gives p0 (0, 1), p1 (1, 1), p2 (1, 0), p3 (0, 0)
    s.add("floor", 0, lambda: s.quad((-2, 0, 2), (2, 0, 2), (2, 0, -2), (-2, 0, -2), (0, 1, 0)))
    png = "data:image/png;base64," + base64.b64encode(domes()).decode()
    half = math.radians(-30) / 2  # the light's -Z turned 30 degrees down about X: from +Z, 30 degrees up
    look = math.atan2(1.6, 3) / 2  # the camera's -Z turned down toward the origin
    gltf = {
        "asset": {"version": "2.0", "generator": "probebake scripts/make_normal_map_scene.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"name": "sun", "type": "directional",
                                                           "intensity": 3.0}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"name": "floor", "mesh": 0},
                  {"name": "sun", "rotation": [math.sin(half), 0, 0, math.cos(half)],
                   "extensions": {"KHR_lights_punctual": {"light": 0}}},
                  {"name": "camera", "camera": 0, "translation": [0, 1.6, 3],
                   "rotation": [-math.sin(look), 0, 0, math.cos(look)]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05, "zfar": 50}}],
        "materials": [material("bumps", [0.8, 0.8, 0.8], normalTexture={"index": 0})],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}],
        "images": [{"uri": png}],
    }
    s.write(os.path.join(scenes_dir(), "bumps.gltf"), gltf)


if __name__ == "__main__":
    main()
