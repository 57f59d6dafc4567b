// `probebake export VOLUME --textures DIR` against the texture contract
// (docs/format.md): the KTX2 files, read by the KTX2 parser three.js bundles
// (ktx-parse, from npm), hold exactly what parseProbes reads from the same
// volume, where the manifest says. Needs runtime/node_modules (npm ci).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { read as readKTX2 } from 'three/examples/jsm/libs/ktx-parse.module.js';
import { parseProbes, tileHalves, sparseSamplerWords } from '../probes.js';

const probebake = process.env.PB_PROBEBAKE, maker = process.env.PB_MAKE_TEST_VOLUME;
const dir = mkdtempSync(join(tmpdir(), 'pb-export-'));
process.on('exit', () => rmSync(dir, { recursive: true, force: true }));

const VK_FORMAT_R16G16_SFLOAT = 83, VK_FORMAT_R32_UINT = 98, VK_FORMAT_R32G32B32A32_SFLOAT = 109;

function ktx(path) {
    const k = readKTX2(new Uint8Array(readFileSync(path)));
    const level = k.levels[0].levelData;
    return { k, bytes: level, f32: new Float32Array(level.slice().buffer), u16: new Uint16Array(level.slice().buffer),
        u32: new Uint32Array(level.slice().buffer) };
}

test('exported textures hold the volume as the contract says', () => {
    assert.ok(probebake && maker, 'PB_PROBEBAKE and PB_MAKE_TEST_VOLUME are set');
    const src = join(dir, 'v.probes'), out = join(dir, 'tex');
    execFileSync(maker, [src]);
    execFileSync(probebake, ['export', src, '--textures', out]);
    const v = parseProbes(new Uint8Array(readFileSync(src)), src);
    const m = JSON.parse(readFileSync(join(out, 'manifest.json')));
    assert.equal(m.format, 'probebake-textures');
    assert.equal(m.probes, v.probeCount);
    assert.deepEqual(m.frame_origin, v.origin);
    assert.deepEqual(m.uniforms.pb_grid_counts, v.counts);
    assert.equal(m.uniforms.pb_octmap_res, v.n);
    assert.equal(m.uniforms.pb_depth_unit, v.depthUnit);
    const W = m.uniforms.pb_tex_width, T = m.uniforms.pb_depth_tiles_per_row, tile = v.tile;

    const probes = ktx(join(out, m.textures.pb_probes.file));
    assert.equal(probes.k.vkFormat, VK_FORMAT_R32G32B32A32_SFLOAT);
    assert.equal(probes.k.pixelWidth, W);
    assert.equal(probes.k.dataFormatDescriptor[0].samples.length, 4);
    const sh = ktx(join(out, m.textures.pb_sh.file));
    assert.equal(sh.k.vkFormat, VK_FORMAT_R32G32B32A32_SFLOAT);
    assert.equal(sh.k.pixelWidth, W);
    const depth = ktx(join(out, m.textures.pb_depth.file));
    assert.equal(depth.k.vkFormat, VK_FORMAT_R16G16_SFLOAT);
    assert.equal(depth.k.pixelWidth, T * tile);
    assert.equal(depth.k.dataFormatDescriptor[0].samples.length, 2);

    for (let p = 0; p < v.probeCount; ++p) {
        for (let k = 0; k < 3; ++k) assert.equal(probes.f32[4 * p + k], v.positions[3 * p + k]);
        assert.equal(probes.f32[4 * p + 3], v.flags[p]);
        for (let c = 0; c < 27; ++c) assert.equal(sh.f32[28 * p + c], v.sh[27 * p + c]); // texel 7p + c/4
        assert.equal(sh.f32[28 * p + 27], 0);
        const tx = (p % T) * tile, ty = Math.floor(p / T) * tile, rowHalves = 2 * T * tile;
        for (let y = 0; y < tile; ++y)
            for (let x = 0; x < 2 * tile; ++x)
                assert.equal(depth.u16[(ty + y) * rowHalves + 2 * tx + x], v.depth[p * tileHalves(v.n) + y * 2 * tile + x]);
    }
});

test('export refuses what it cannot write, with one line naming the problem', () => {
    const src = join(dir, 'v2.probes');
    execFileSync(maker, [src]);
    const bad = [['export', src], ['export', src, '--textures', '/proc/version/x'], ['export', join(dir, 'missing.probes'), '--textures', dir]];
    for (const args of bad) {
        let err;
        try { execFileSync(probebake, args, { stdio: 'pipe' }); } catch (e) { err = e; }
        assert.ok(err && err.status !== 0, `${args.join(' ')}: non-zero exit`);
        const lines = err.stderr.toString().trim().split('\n');
        assert.equal(lines.length, 1, lines.join(' | '));
        assert.match(lines[0], /^probebake: error: /);
    }
});

// three-probes.js builds the same textures in the browser: the two sides of
// the contract (C export, JS ProbeVolume) must agree texel by texel and on
// the uniforms that say how the textures are laid out.
test('ProbeVolume lays the textures out as the export does', async () => {
    const { ProbeVolume } = await import('../three-probes.js');
    const src = join(dir, 'pv.probes'), out = join(dir, 'pv-tex');
    execFileSync(maker, [src]);
    execFileSync(probebake, ['export', src, '--textures', out]);
    const v = parseProbes(new Uint8Array(readFileSync(src)), src);
    const m = JSON.parse(readFileSync(join(out, 'manifest.json')));
    const pv = new ProbeVolume(v);
    for (const name of ['pb_tex_width', 'pb_depth_tiles_per_row', 'pb_octmap_res', 'pb_depth_unit'])
        assert.equal(pv.uniforms[name].value, m.uniforms[name], name);
    assert.deepEqual(Array.from(pv.uniforms.pb_grid_counts.value), m.uniforms.pb_grid_counts);
    const pairs = [['probes', 'pb_probes', 'f32'], ['sh', 'pb_sh', 'f32'], ['depth', 'pb_depth', 'u16']];
    for (const [tex, key, kind] of pairs) {
        const t = pv.textures[tex].image, k = ktx(join(out, m.textures[key].file));
        assert.equal(t.width, k.k.pixelWidth, `${key} width`);
        assert.equal(t.height, k.k.pixelHeight, `${key} height`);
        assert.deepEqual(Array.from(t.data), Array.from(k[kind]), `${key} texels`);
    }
});

// A sparse volume (the fuzz seed tests/fuzz/volume_corpus/seed-sparse2, a
// two-level bake): the export adds the layout as an R32UI texture, its
// levels and PB_SPARSE, and ProbeVolume builds the same four textures.
test('a sparse volume exports its layout texture as ProbeVolume builds it', async () => {
    const { ProbeVolume } = await import('../three-probes.js');
    const src = join(dirname(fileURLToPath(import.meta.url)), '../../../tests/fuzz/volume_corpus/seed-sparse2');
    const out = join(dir, 'sparse-tex');
    execFileSync(probebake, ['export', src, '--textures', out]);
    const v = parseProbes(new Uint8Array(readFileSync(src)), src);
    const m = JSON.parse(readFileSync(join(out, 'manifest.json')));
    assert.equal(m.define, 'PB_SPARSE');
    assert.equal(m.uniforms.pb_levels, v.sparse.levels);
    assert.deepEqual(m.uniforms.pb_grid_counts, v.sparse.cells);
    assert.deepEqual(m.uniforms.pb_grid_spacing, v.spacing);
    const sparse = ktx(join(out, m.textures.pb_sparse.file));
    assert.equal(sparse.k.vkFormat, VK_FORMAT_R32_UINT);
    assert.equal(sparse.k.dataFormatDescriptor[0].samples.length, 1);
    assert.equal(sparse.k.pixelWidth, m.uniforms.pb_tex_width);
    const words = sparseSamplerWords(v.sparse);
    assert.deepEqual(Array.from(sparse.u32.subarray(0, words.length)), Array.from(words));
    const pv = new ProbeVolume(v);
    for (const name of ['pb_tex_width', 'pb_depth_tiles_per_row', 'pb_octmap_res', 'pb_depth_unit', 'pb_levels'])
        assert.equal(pv.uniforms[name].value, m.uniforms[name], name);
    assert.deepEqual(Array.from(pv.uniforms.pb_grid_counts.value), m.uniforms.pb_grid_counts);
    const pairs = [['probes', 'pb_probes', 'f32'], ['sh', 'pb_sh', 'f32'], ['depth', 'pb_depth', 'u16'],
        ['sparse', 'pb_sparse', 'u32']];
    for (const [tex, key, kind] of pairs) {
        const t = pv.textures[tex].image, k = ktx(join(out, m.textures[key].file));
        assert.equal(t.width, k.k.pixelWidth, `${key} width`);
        assert.equal(t.height, k.k.pixelHeight, `${key} height`);
        assert.deepEqual(Array.from(t.data), Array.from(k[kind]), `${key} texels`);
    }
});
