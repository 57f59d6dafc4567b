#!/usr/bin/env python3
"""Random bake / render / info command lines on normal-mapped, tangent, glass and
plain scenes, for a sanitizer build: each must succeed, or fail with exit 1 or 2,
exactly one `error:` line and no file left; no sanitizer report either way.

    python3 random_commands.py SEED RUNS PROBEBAKE SCENE...

(2026-11-29: build-san's probebake, seeds 1 and 2, 40 and 150 runs, on
DamagedHelmet with MikkTSpace tangents, AlphaBlendModeTest, tests/scenes/demo.gltf
and skylight.gltf, and test_out_of_memory.sh's normal-mapped file.)
"""
import random, subprocess, os, sys, tempfile
random.seed(int(sys.argv[1]))
pb = sys.argv[3]
scenes = sys.argv[4:]
here = os.path.dirname(os.path.abspath(__file__))
env_map = os.path.join(here, '..', '..', '..', '..', 'shared', 'scenes', 'env', 'courtyard.hdr')
tmp = tempfile.mkdtemp()
opts = [['--normal-maps', 'on'], ['--normal-maps', 'off'], ['--normal-maps', 'x'], ['--shading-normals', 'face'],
        ['--schedule', 'wavefront'], ['--layout', 'sparse', '--max-level', '1'], ['--shard', '1/2'], ['--indirect', 'volume'],
        ['--sky', '1,1,1'], ['--env', env_map], ['--bounces', '0'], ['--bounces', '3'],
        ['--rays', '32'], ['--rays', '0'], ['--passes', '2'], ['--octmap-res', '4'], ['--guide', 'on'], ['--light-cells', 'off'],
        ['--emitter-sampling', 'area'], ['--spacing', '0.5'], ['--counts', '3,2,3'], ['--seed', '7'], ['--quality', 'preview']]
bad = 0
okc = 0
N = int(sys.argv[2])
for i in range(N):
    sc = random.choice(scenes)
    cmd = [pb, random.choice(['bake', 'bake', 'render', 'info']), sc]
    for o in random.sample(opts, random.randint(1, 5)):
        cmd += o
    out = os.path.join(tmp, 'out.%d' % i)
    if cmd[1] == 'bake':
        cmd += ['--rays', '16', '--passes', '1', '-o', out + '.probes', '--quiet']
    elif cmd[1] == 'render':
        cmd = [c for c in cmd if c not in ('--shard', '1/2', '--layout', 'sparse', '--max-level', '1')]
        cmd += ['--mode', 'direct', '--size', '32x24', '--spp', '1', '-o', out + '.png', '--quiet']
    env = dict(os.environ, ASAN_OPTIONS='detect_leaks=0:quarantine_size_mb=16', UBSAN_OPTIONS='print_stacktrace=1')
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    err = p.stderr
    lines = [l for l in err.splitlines() if 'error:' in l]
    san = 'AddressSanitizer' in err or 'runtime error' in err or 'LeakSanitizer' in err
    ok = (p.returncode == 0 and not san) or (p.returncode in (1, 2) and len(lines) == 1 and not san)
    left = os.path.exists(out + '.probes') or os.path.exists(out + '.png')
    if p.returncode != 0 and left:
        ok = False
    okc += p.returncode == 0
    if not ok:
        bad += 1
        print('BAD rc=%d %s\n%s' % (p.returncode, ' '.join(cmd), err[-1500:]))
    for f in (out + '.probes', out + '.png'):
        if os.path.exists(f):
            os.remove(f)
print('%d runs, %d bad, %d succeeded' % (N, bad, okc))
