# odd large scenes for the loader's exactness check: non-finite and degenerate triangles spread over
# many blocks, -0.0 coordinates, huge coordinates, vertex colours on a later primitive, zero normals,
# a mirrored node, strips and fans
import array, json, math, random, struct, sys
def glb(path, prims, nodes):
    buf = bytearray(); views = []; accs = []; meshes = []
    def add(data, comp, typ, count, target=None):
        while len(buf) % 4: buf.append(0)
        views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(data)})
        buf.extend(data)
        a = {"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": typ}
        accs.append(a); return len(accs) - 1
    for p in prims:
        attrs = {"POSITION": add(p["pos"].tobytes(), 5126, "VEC3", len(p["pos"]) // 3)}
        if "nrm" in p: attrs["NORMAL"] = add(p["nrm"].tobytes(), 5126, "VEC3", len(p["nrm"]) // 3)
        if "col" in p: attrs["COLOR_0"] = add(p["col"].tobytes(), 5126, "VEC4", len(p["col"]) // 4)
        if "uv" in p: attrs["TEXCOORD_0"] = add(p["uv"].tobytes(), 5126, "VEC2", len(p["uv"]) // 2)
        prim = {"attributes": attrs, "mode": p.get("mode", 4)}
        if "idx" in p: prim["indices"] = add(p["idx"].tobytes(), 5125, "SCALAR", len(p["idx"]))
        meshes.append({"primitives": [prim]})
    js = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}],
          "nodes": nodes, "meshes": meshes, "accessors": accs, "bufferViews": views,
          "buffers": [{"byteLength": len(buf)}]}
    j = json.dumps(js).encode(); j += b" " * (-len(j) % 4); buf += b"\0" * (-len(buf) % 4)
    out = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(j) + 8 + len(buf)) + struct.pack("<II", len(j), 0x4E4F534A) + j + struct.pack("<II", len(buf), 0x004E4942) + buf
    open(path, "wb").write(out)
def soup(n, seed, kinds):
    r = random.Random(seed); pos = array.array('f'); nrm = array.array('f'); col = array.array('f'); uv = array.array('f')
    for t in range(n):
        base = [r.uniform(-50, 50) for _ in range(3)]
        v = [[base[k] + r.uniform(-1, 1) for k in range(3)] for _ in range(3)]
        x = r.random()
        if "nan" in kinds and x < 0.002: v[r.randrange(3)][r.randrange(3)] = float("nan")
        elif "inf" in kinds and x < 0.004: v[r.randrange(3)][r.randrange(3)] = float("inf")
        elif "deg" in kinds and x < 0.008: v[2] = list(v[0])
        elif "negzero" in kinds and x < 0.05: v[r.randrange(3)][r.randrange(3)] = -0.0
        elif "huge" in kinds and x < 0.0005: v[0][0] = 3e38
        for c in v: pos.extend(c)
        for c in v:
            if "zeronormal" in kinds and r.random() < 0.01: nrm.extend((0.0, 0.0, 0.0))
            else: nrm.extend((r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1)))
            col.extend((r.random(), r.random() * 1.5 - 0.2, r.random(), 1.0)); uv.extend((r.random(), r.random()))
    return pos, nrm, col, uv
out = sys.argv[1]
p1, n1, c1, u1 = soup(60000, 1, {"nan", "inf", "deg", "negzero"})
p2, n2, c2, u2 = soup(50000, 2, {"deg", "zeronormal", "negzero"})
p3, n3, c3, u3 = soup(40000, 3, {"huge", "nan"})
glb(out + "/odd_mix.glb", [{"pos": p1}, {"pos": p2, "nrm": n2, "col": c2, "uv": u2}, {"pos": p3, "nrm": n3}],
    [{"mesh": 0}, {"mesh": 1, "scale": [1, -1, 1]}, {"mesh": 2, "translation": [1e7, 0, -1e7]}])
# colours first, then none; strips and fans of 40k vertices
p4, n4, c4, u4 = soup(30000, 4, {"deg"})
glb(out + "/odd_colfirst.glb", [{"pos": p4, "col": c4}, {"pos": p1}], [{"mesh": 0}, {"mesh": 1, "rotation": [0, 0.7071, 0, 0.7071]}])
idx = array.array('I', range(len(p2) // 3))
glb(out + "/odd_strip.glb", [{"pos": p2, "nrm": n2, "idx": idx, "mode": 5}, {"pos": p3, "idx": idx[:len(p3) // 3], "mode": 6}], [{"mesh": 0}, {"mesh": 1}])
# every coordinate -0 or +0 on the box's bounds, many blocks
pz = array.array('f')
r = random.Random(9)
for t in range(70000):
    for k in range(3): pz.extend((r.choice([0.0, -0.0, 1.0]), r.choice([0.0, -0.0, 2.0]), r.choice([0.0, -0.0, -1.0])))
glb(out + "/odd_zeros.glb", [{"pos": pz}], [{"mesh": 0}])
print("ok")
