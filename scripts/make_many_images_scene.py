#!/usr/bin/env python3
"""A scene of many large textures for the loader's benches: COPIES side-by-side
instances of a glTF's meshes, each instance with its own materials and its own
copies of the image files, so a load decodes COPIES times the images (a
workstation's many-core decoding has work to share; bench/RESULTS.md, "Images
decoded ahead"). Geometry and buffers are shared.

    scripts/make_many_images_scene.py SRC.gltf COPIES OUT_DIR

Writes OUT_DIR/NAME.gltf (NAME: OUT_DIR's own name) beside the copied images
and buffers. Only .gltf
files whose images and buffers are separate files (uri) are taken."""
import copy
import json
import os
import shutil
import sys


def main():
    if len(sys.argv) != 4:
        sys.exit("usage: make_many_images_scene.py SRC.gltf COPIES OUT_DIR")
    src, copies, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    if copies < 1:
        sys.exit(f"{src}: COPIES must be 1 or more")
    with open(src) as f:
        g = json.load(f)
    base = os.path.dirname(os.path.abspath(src))
    os.makedirs(out, exist_ok=True)
    for b in g.get("buffers", []):
        if "uri" not in b or b["uri"].startswith("data:"):
            sys.exit(f"{src}: a buffer without a file uri")
        shutil.copy(os.path.join(base, b["uri"]), os.path.join(out, os.path.basename(b["uri"])))
        b["uri"] = os.path.basename(b["uri"])
    images, textures, materials, meshes = g.get("images", []), g.get("textures", []), g.get("materials", []), g["meshes"]
    for im in images:
        if "uri" not in im or im["uri"].startswith("data:"):
            sys.exit(f"{src}: an image without a file uri")
    n_img, n_tex, n_mat, n_mesh = len(images), len(textures), len(materials), len(meshes)
    uris = [im["uri"] for im in images]
    roots = g["scenes"][g.get("scene", 0)]["nodes"]
    new_roots = []
    for k in range(copies):
        # this instance's images (its own files), textures, materials and meshes
        for i, uri in enumerate(uris):
            name = f"copy{k}_{os.path.basename(uri)}"
            shutil.copy(os.path.join(base, uri), os.path.join(out, name))
            if k:
                images.append({**images[i], "uri": name})
            else:
                images[i]["uri"] = name
        if k == 0:
            continue
        for t in textures[:n_tex]:
            textures.append({**t, "source": t["source"] + k * n_img})

        def shift(obj):
            """texture indices of a material, moved to instance k's"""
            if isinstance(obj, dict):
                for key, v in obj.items():
                    if key == "index" and isinstance(v, int):
                        obj[key] = v + k * n_tex
                    else:
                        shift(v)
            elif isinstance(obj, list):
                for v in obj:
                    shift(v)

        for m in materials[:n_mat]:
            m2 = copy.deepcopy(m)
            shift(m2)
            materials.append(m2)
        for me in meshes[:n_mesh]:
            me2 = copy.deepcopy(me)
            for p in me2["primitives"]:
                if "material" in p:
                    p["material"] += k * n_mat
            meshes.append(me2)
    # one parent node per instance, side by side along x, over copies of the roots
    nodes = g["nodes"]
    n_nodes = len(nodes)
    for k in range(copies):
        ids = {}
        for i in range(n_nodes):
            ids[i] = i if k == 0 else len(nodes) + i
        if k:
            for i in range(n_nodes):
                nd = copy.deepcopy(nodes[i])
                if "mesh" in nd:
                    nd["mesh"] += k * n_mesh
                if "children" in nd:
                    nd["children"] = [ids[c] for c in nd["children"]]
                nd.pop("camera", None)
                nodes.append(nd)
        nodes.append({"name": f"instance {k}", "translation": [2.5 * k, 0.0, 0.0], "children": [ids[r] for r in roots]})
        new_roots.append(len(nodes) - 1)
    g["scenes"] = [{"name": f"{copies} instances", "nodes": new_roots}]
    g["scene"] = 0
    path = os.path.join(out, os.path.basename(os.path.normpath(out)) + ".gltf")
    with open(path, "w") as f:
        json.dump(g, f)
    print(f"{path}: {copies} instances, {len(images)} images")


if __name__ == "__main__":
    main()
