#!/usr/bin/env python3
"""The bake's normal-map frames against a file's own TANGENT.

    python3 tangent_frames.py FILE.gltf

For every primitive that has TANGENT, TEXCOORD_0 and NORMAL and whose
material has a normalTexture, each corner's frame as the bake makes it
(shaders/include/normal_map.glsl: T = dp/du of the triangle made orthogonal
to the corner's normal, B = n x T turned against dp/dv) against the file's
tangent (xyz) and handedness (w): the angle between the two T, and whether
the handedness agrees. A plain re-statement of the kernel's arithmetic in
double, independent of probebake's code; .gltf files with float accessors
and external buffers only. Standard library only.
"""
import json, math, os, struct, sys


def accessor(g, bufs, i):
    a = g['accessors'][i]
    v = g['bufferViews'][a['bufferView']]
    n = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4}[a['type']]
    fmt = {5126: 'f', 5121: 'B', 5123: 'H', 5125: 'I'}[a['componentType']]
    size = struct.calcsize(fmt)
    stride = v.get('byteStride', size * n)
    off = v.get('byteOffset', 0) + a.get('byteOffset', 0)
    return [struct.unpack_from('<' + fmt * n, bufs[v['buffer']], off + k * stride) for k in range(a['count'])]


def main(path):
    g = json.load(open(path))
    base = os.path.dirname(path)
    bufs = [open(os.path.join(base, b['uri']), 'rb').read() for b in g['buffers']]
    for m in g['meshes']:
        for p in m['primitives']:
            at = p['attributes']
            mat = g['materials'][p['material']] if 'material' in p else {}
            if not all(k in at for k in ('TANGENT', 'NORMAL', 'TEXCOORD_0')) or 'normalTexture' not in mat:
                continue
            P, N, T, UV = (accessor(g, bufs, at[k]) for k in ('POSITION', 'NORMAL', 'TANGENT', 'TEXCOORD_0'))
            idx = [x[0] for x in accessor(g, bufs, p['indices'])] if 'indices' in p else list(range(len(P)))
            angles, agree, degenerate, untangent = [], 0, 0, 0
            for t in range(len(idx) // 3):
                a, b, c = idx[3 * t:3 * t + 3]
                e1 = [P[b][k] - P[a][k] for k in range(3)]
                e2 = [P[c][k] - P[a][k] for k in range(3)]
                du1, dv1 = UV[b][0] - UV[a][0], UV[b][1] - UV[a][1]
                du2, dv2 = UV[c][0] - UV[a][0], UV[c][1] - UV[a][1]
                det = du1 * dv2 - du2 * dv1
                if det == 0:
                    degenerate += 1
                    continue
                s = 1 if det > 0 else -1
                dpdu = [(dv2 * e1[k] - dv1 * e2[k]) * s for k in range(3)]
                dpdv = [(du1 * e2[k] - du2 * e1[k]) * s for k in range(3)]
                for v in (a, b, c):
                    n = N[v]
                    d = sum(dpdu[k] * n[k] for k in range(3))
                    tu = [dpdu[k] - d * n[k] for k in range(3)]
                    l = math.sqrt(sum(x * x for x in tu))
                    tf = T[v][:3]
                    tl = math.sqrt(sum(x * x for x in tf))
                    if l == 0 or tl == 0:  # no frame here, or the file's tangent is zero
                        untangent += 1
                        continue
                    tu = [x / l for x in tu]
                    B = [n[1] * tu[2] - n[2] * tu[1], n[2] * tu[0] - n[0] * tu[2], n[0] * tu[1] - n[1] * tu[0]]
                    w = -1 if sum(B[k] * dpdv[k] for k in range(3)) > 0 else 1
                    cos = sum(tu[k] * tf[k] for k in range(3)) / tl
                    angles.append(math.degrees(math.acos(max(-1.0, min(1.0, cos)))))
                    agree += w == (1 if T[v][3] > 0 else -1)
            if not angles:
                continue
            angles.sort()
            print('%s / %s: %d triangles (%d without a frame), %d corners (%d more without a frame or a tangent): '
                  'angle to TANGENT median %.2f, p95 %.2f, max %.2f degrees; handedness agrees at %d' %
                  (m.get('name', '?'), mat.get('name', '?'), len(idx) // 3, degenerate, len(angles), untangent,
                   angles[len(angles) // 2], angles[int(0.95 * (len(angles) - 1))], angles[-1], agree))


if __name__ == '__main__':
    main(sys.argv[1])
