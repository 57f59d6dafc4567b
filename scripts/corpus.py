#!/usr/bin/env python3
"""Runs probebake over a corpus of glTF files, as a new user would: `info` on
every .gltf / .glb under the given directories, and for those that load a tiny
bake (2 x 2 x 2 probes, 16 rays, 1 pass) and `inspect --json` of its volume.
Prints one JSON object: loaded / refused (with each file's one-line reason) /
crashed (killed by a signal, or a multi-line error) / nan (a volume holding a
non-finite number) counts and lists. Exit status 0 unless something crashed or
baked to NaN. Python standard library only.

  python3 scripts/corpus.py [--probebake build/probebake] [--no-bake] DIR...
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile


def files_under(dirs):
    for d in dirs:
        if os.path.isfile(d):
            yield d
            continue
        for root, _, names in os.walk(d):
            for n in sorted(names):
                if n.lower().endswith((".gltf", ".glb")):
                    yield os.path.join(root, n)


def run(cmd, timeout):
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        return None, "", "timed out after %d s" % timeout


def error_line(stderr):
    lines = [l for l in stderr.splitlines() if "error:" in l]
    return lines, (lines[-1].split("error:", 1)[1].strip() if lines else stderr.strip()[-200:])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--probebake", default=os.path.join(os.path.dirname(__file__), "..", "build", "probebake"))
    ap.add_argument("--no-bake", action="store_true", help="only `info` (no Vulkan device needed)")
    ap.add_argument("--timeout", type=int, default=300)
    ap.add_argument("dirs", nargs="+")
    a = ap.parse_args()
    out = {"files": 0, "loaded": 0, "refused": 0, "crashed": 0, "nan": 0, "baked": 0,
           "refusals": [], "crashes": [], "nans": [], "baked_files": []}
    with tempfile.TemporaryDirectory() as tmp:
        for f in files_under(a.dirs):
            out["files"] += 1
            rc, _, err = run([a.probebake, "info", f, "--json", "--quiet"], a.timeout)
            lines, reason = error_line(err)
            if rc is None or rc < 0 or rc > 2 or len(lines) > 1:
                out["crashed"] += 1
                out["crashes"].append({"file": f, "status": rc, "stderr": err.strip()[-400:]})
                continue
            if rc != 0:
                out["refused"] += 1
                out["refusals"].append({"file": f, "reason": reason})
                continue
            out["loaded"] += 1
            if a.no_bake:
                continue
            vol = os.path.join(tmp, "v.probes")
            rc, _, err = run([a.probebake, "bake", f, "--counts", "2,2,2", "--rays", "16", "--passes", "1",
                              "--sky", "0.5,0.5,0.5", "--quiet", "-o", vol], a.timeout)
            if rc is None or rc < 0:
                out["crashed"] += 1
                out["crashes"].append({"file": f, "status": rc, "stderr": err.strip()[-400:]})
                continue
            if rc != 0:  # a bake may refuse what info accepts (no triangles at all): a refusal with its reason
                out["refused"] += 1
                out["refusals"].append({"file": f, "reason": "bake: " + error_line(err)[1]})
                continue
            out["baked"] += 1
            out["baked_files"].append(f)
            rc, js, err = run([a.probebake, "inspect", vol, "--json"], a.timeout)
            ok = rc == 0
            if ok:
                try:
                    v = json.loads(js)
                    ok = all(math.isfinite(c) for p in v["probe_list"] for c in p["sh"])
                except (ValueError, KeyError, TypeError):
                    ok = False
            if not ok:
                out["nan"] += 1
                out["nans"].append(f)
    json.dump(out, sys.stdout, indent=1)
    print()
    return 1 if out["crashed"] or out["nan"] else 0


if __name__ == "__main__":
    sys.exit(main())
