"""A tiny glTF 2.0 writer shared by the scene generators in scripts/.

Geometry is collected as quads into named meshes (one primitive per material),
packed into one embedded buffer (positions, normals, UVs, uint16 indices), and
written with the caller's materials, nodes and extensions. Only the Python
standard library is used.
"""
import base64, json, os, struct


class Scene:
    def __init__(self):
        self.positions, self.normals, self.uvs, self.indices = [], [], [], []
        self.primitives = {}  # mesh name -> list of (first index, count, material)

    def quad(self, p0, p1, p2, p3, n, uv_scale=1.0):
        """Quad p0..p3 counter-clockwise seen from the side `n` points to."""
        base = len(self.positions)
        for p, uv in zip((p0, p1, p2, p3), ((0, 1), (1, 1), (1, 0), (0, 0))):
            self.positions.append(p)
            self.normals.append(n)
            self.uvs.append((uv[0] * uv_scale, uv[1] * uv_scale))
        self.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3])

    def box(self, lo=(-0.5, -0.5, -0.5), hi=(0.5, 0.5, 0.5), inward=False):
        """Axis-aligned box lo..hi, faces outward (or inward: a room)."""
        (x0, y0, z0), (x1, y1, z1) = lo, hi
        faces = [  # outward: +z, -z, +x, -x, +y, -y
            (((x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)), (0, 0, 1)),
            (((x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0)), (0, 0, -1)),
            (((x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1)), (1, 0, 0)),
            (((x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)), (-1, 0, 0)),
            (((x0, y1, z1), (x1, y1, z1), (x1, y1, z0), (x0, y1, z0)), (0, 1, 0)),
            (((x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)), (0, -1, 0)),
        ]
        for (p0, p1, p2, p3), n in faces:
            if inward:
                self.quad(p3, p2, p1, p0, tuple(-c for c in n))
            else:
                self.quad(p0, p1, p2, p3, n)

    def add(self, mesh, material, fn):
        """Geometry that fn() emits becomes one primitive of `mesh`."""
        first = len(self.indices)
        fn()
        self.primitives.setdefault(mesh, []).append((first, len(self.indices) - first, material))

    def write(self, out, gltf):
        """Completes `gltf` (a dict with materials, nodes, ...) with meshes,
        accessors, buffer views and the embedded buffer, and writes it."""
        blob = bytearray()

        def append(data, align=4):
            while len(blob) % align:
                blob.append(0)
            off = len(blob)
            blob.extend(data)
            return off

        pos, nv = self.positions, len(self.positions)
        pos_off = append(b"".join(struct.pack("<3f", *p) for p in pos))
        nrm_off = append(b"".join(struct.pack("<3f", *n) for n in self.normals))
        uv_off = append(b"".join(struct.pack("<2f", *t) for t in self.uvs))
        idx_off = append(b"".join(struct.pack("<H", i) for i in self.indices))
        buffer_views = [
            {"buffer": 0, "byteOffset": pos_off, "byteLength": 12 * nv, "target": 34962},
            {"buffer": 0, "byteOffset": nrm_off, "byteLength": 12 * nv, "target": 34962},
            {"buffer": 0, "byteOffset": uv_off, "byteLength": 8 * nv, "target": 34962},
            {"buffer": 0, "byteOffset": idx_off, "byteLength": 2 * len(self.indices), "target": 34963},
        ]
        lo = [min(p[k] for p in pos) for k in range(3)]
        hi = [max(p[k] for p in pos) for k in range(3)]
        accessors = [
            {"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5126, "count": nv, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": nv, "type": "VEC2"},
        ]
        meshes = []
        for name, prims in self.primitives.items():
            mesh = {"name": name, "primitives": []}
            for first, count, material in prims:
                accessors.append({"bufferView": 3, "byteOffset": 2 * first, "componentType": 5123, "count": count,
                                  "type": "SCALAR"})
                mesh["primitives"].append({"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                           "indices": len(accessors) - 1, "material": material, "mode": 4})
            meshes.append(mesh)
        gltf["meshes"] = meshes
        gltf["accessors"] = accessors
        gltf["bufferViews"] = buffer_views
        gltf["buffers"] = [{"byteLength": len(blob),
                            "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}]
        with open(out, "w") as f:
            json.dump(gltf, f, indent=1)
            f.write("\n")
        print("wrote", os.path.normpath(out), len(self.indices) // 3, "triangles")

    def mesh_index(self, name):
        return list(self.primitives).index(name)


def material(name, color, **kw):
    """A rough dielectric (Lambertian for the bake) of base colour `color`."""
    m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": color + [1.0], "metallicFactor": 0.0,
                                                "roughnessFactor": 1.0}}
    m.update(kw)
    return m


def scenes_dir():
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "scenes")
