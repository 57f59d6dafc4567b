// runtime/js/probes.js against volumes the C code writes (tests/make_test_volume.c)
// and against `probebake inspect --json` of the same files, plus every malformed
// case tests/test_volume.c has. Run by ctest (test_js):
//   PB_PROBEBAKE=build/probebake PB_MAKE_TEST_VOLUME=build/tests/make_test_volume \
//   node --test runtime/js/test/probes.test.js
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, writeFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseProbes, halfToFloat, floatToHalf, depthUnit, tileHalves, sparseSamplerWords, PROBE_RELOCATED,
    PROBE_DILATED } from '../probes.js';

const probebake = process.env.PB_PROBEBAKE, maker = process.env.PB_MAKE_TEST_VOLUME;
const dir = mkdtempSync(join(tmpdir(), 'pb-js-'));
process.on('exit', () => rmSync(dir, { recursive: true, force: true }));

function fixture() {
    assert.ok(maker, 'PB_MAKE_TEST_VOLUME names tests/make_test_volume');
    const path = join(dir, 'fixture.probes');
    execFileSync(maker, [path]);
    return { path, bytes: readFileSync(path) };
}

const u8 = (b) => new Uint8Array(b.buffer, b.byteOffset, b.byteLength).slice();

test('reads what the C writer wrote, as inspect --json does', () => {
    assert.ok(probebake, 'PB_PROBEBAKE names the probebake binary');
    const { path, bytes } = fixture();
    const v = parseProbes(u8(bytes), path);
    const j = JSON.parse(execFileSync(probebake, ['inspect', path, '--json']).toString());
    assert.equal(v.version, j.version);
    assert.equal(v.probeCount, j.probes);
    assert.deepEqual(v.counts, j.counts);
    assert.deepEqual(v.origin, j.origin);
    assert.deepEqual(v.spacing, j.spacing);
    assert.equal(v.n, j.octmap_res);
    assert.equal(v.tile, v.n + 2);
    assert.equal(v.irradiance, j.sh === 'irradiance');
    assert.equal(v.directIncluded, j.direct);
    assert.equal(v.depthUnit, j.depth_unit);
    assert.equal(v.sceneHash, j.scene_hash);
    assert.equal(v.depth.length, v.probeCount * tileHalves(v.n));
    for (const p of j.probe_list) {
        const i = p.index;
        for (let c = 0; c < 27; ++c) assert.equal(v.sh[27 * i + c], Math.fround(p.sh[c]), `probe ${i} SH ${c}`);
        for (let k = 0; k < 3; ++k) // inspect prints the world position in double; ours is relative, in float
            assert.ok(Math.abs(v.origin[k] + v.positions[3 * i + k] - p.position[k]) < 1e-6, `probe ${i} axis ${k}`);
        assert.equal(v.paths[i], p.paths);
        assert.equal(v.stdError[i], p.std_error === null ? -1 : Math.fround(p.std_error));
        const names = [];
        const bits = ['valid', 'relocated', 'dilated', 'outside', 'converged'];
        bits.forEach((b, k) => { if (v.flags[i] & (1 << k)) names.push(b); });
        assert.deepEqual(names, p.flags, `probe ${i} flags`);
    }
    assert.ok(v.flags[1] & PROBE_RELOCATED && v.flags[4] & PROBE_DILATED);
    assert.equal(v.positions[3 * 1 + 1], 0.25); // base y 0 + relocation offset 0.25
});

// The malformed files of tests/test_volume.c, made the same way: one u32
// overwritten, or the file cut short; the message names the problem.
test('malformed files throw errors that say what is wrong', () => {
    const { bytes } = fixture();
    const size = bytes.length;
    const cases = [
        ['magic', 0, 0x21212121, 0, 'not a probebake volume'],
        ['version', 8, 99, 0, 'version 99'],
        ['count', 20, 0, 0, 'probe count'],
        ['grid', 24, 7, 0, 'grid counts'],
        ['octmap', 36, 1000, 0, 'octahedral'],
        ['section', 160, 12345, 0, 'section offsets'],
        ['unit', 180, 0, 0, 'depth unit'],
        ['unit-nan', 180, 0x7fc00000, 0, 'depth unit'],
        ['depth-format', 128, 1, 0, 'depth format'],
        ['truncated', 0, 0, 1000, 'truncated'],
        ['accounting-offset', 392, 16, 0, 'section offsets'],
        ['std-error-negative', size - 4, 0xbf000000, 0, 'probe 5 has a negative or non-finite standard error'],
        ['std-error-nan', size - 4, 0x7fc00000, 0, 'standard error'],
        ['header', 0, 0, 100, 'truncated header'],
        ['empty', 0, 0, -1, 'not a probebake volume'],
        // version 4's sparse flag belongs to point lists with a layout section, never to a grid
        ['sparse', 16, new DataView(u8(bytes).buffer).getUint32(16, true) | 16, 0, 'sparse flag in a grid'],
    ];
    for (const [name, offset, value, keep, needle] of cases) {
        let copy = u8(bytes);
        if (keep > 0) copy = copy.slice(0, keep < 200 ? keep : size - keep);
        else if (keep < 0) copy = new Uint8Array(0);
        else new DataView(copy.buffer).setUint32(offset, value >>> 0, true);
        assert.throws(() => parseProbes(copy.buffer, `${name}.probes`),
            (e) => e instanceof Error && e.message.startsWith(`${name}.probes: `) && e.message.includes(needle),
            `${name}: wants "${needle}"`);
        // the C reader refuses the same bytes
        if (probebake && keep >= 0) {
            const p = join(dir, `${name}.probes`);
            writeFileSync(p, copy);
            assert.throws(() => execFileSync(probebake, ['inspect', p], { stdio: 'pipe' }), `${name}: C reader`);
        }
    }
});

// A sparse volume (two levels, 1 + 7 bricks, 27 chunk entries; the fuzz
// seed tests/fuzz/volume_corpus/seed-sparse2, a real bake): what inspect
// --json reports, the sampler's tables, and the C reader's refusals.
test('reads sparse bricks as inspect --json does, and refuses damaged layouts', () => {
    assert.ok(probebake, 'PB_PROBEBAKE names the probebake binary');
    const path = join(dirname(fileURLToPath(import.meta.url)), '../../../tests/fuzz/volume_corpus/seed-sparse2');
    const bytes = readFileSync(path);
    const v = parseProbes(u8(bytes), 'seed-sparse2');
    const j = JSON.parse(execFileSync(probebake, ['inspect', path, '--json']).toString());
    assert.equal(v.grid, false);
    assert.equal(v.probeCount, j.probes);
    assert.equal(v.sparse.levels, j.sparse.levels);
    assert.deepEqual(v.sparse.cells, j.sparse.cells);
    assert.equal(v.sparse.chunkCount, j.sparse.chunk_entries);
    const perLevel = [0, 0, 0];
    for (let b = 0; b < v.sparse.brickCount; ++b) ++perLevel[v.sparse.bricks[4 * b + 3]];
    assert.deepEqual(perLevel, j.sparse.bricks);
    for (const p of j.probe_list)
        for (let c = 0; c < 27; ++c) assert.equal(v.sh[27 * p.index + c], Math.fround(p.sh[c]), `probe ${p.index}`);
    // the sampler's words: offsets, then the tables in order
    const w = sparseSamplerWords(v.sparse), B = v.sparse.brickCount;
    assert.deepEqual(Array.from(w.subarray(0, 4)), [4, 5, 5 + 27, 5 + 27 + 4 * B]);
    assert.equal(w.length, 5 + 27 + 4 * B + 64 * B);
    assert.equal(w[w[2] + 4 * 1 + 3], v.sparse.bricks[4 * 1 + 3]);
    assert.equal(w[w[3] + 64 * B - 1], v.sparse.brickProbes[64 * B - 1]);
    // damaged layouts: one word changed, both readers refuse, with the C reader's words
    const dv = new DataView(u8(bytes).buffer), at = Number(dv.getBigUint64(416, true));
    const head = 32, bricksAt = at + head, probesAt = bricksAt + 16 * B, cellsAt = probesAt + 256 * B;
    const chunksAt = cellsAt + 4;
    // two chunk entries naming different fine bricks: swapping in the other puts it elsewhere
    const named = [...v.sparse.chunks.keys()].filter((s) => v.sparse.chunks[s] !== 0x0fffffff &&
        v.sparse.bricks[4 * v.sparse.chunks[s] + 3] === 1);
    const s0 = named[0], other = v.sparse.chunks[named.find((s) => v.sparse.chunks[s] !== v.sparse.chunks[s0])];
    const cases = [
        ['levels', at, 5, 'levels (1 to 3)'],
        ['brick-level', bricksAt + 12, 2, 'has level 2 of 2'],
        ['brick-outside', bricksAt + 16 + 0, 99, 'lies outside the cells'],
        ['brick-probe', probesAt + 4 * 10, 100000, 'names probe 100000'],
        ['cell-depth', cellsAt, (3 << 28) >>> 0, 'has depth 3'],
        ['cell-chunks', cellsAt, ((1 << 28) | 5) >>> 0, 'points past the chunks'],
        ['chunk-brick', chunksAt, 200, 'names brick 200'],
        ['chunk-elsewhere', chunksAt + 4 * s0, other, `names brick ${other} elsewhere`],
        ['layout-offset', 416, at + 16, 'section offsets'],
    ];
    for (const [name, offset, value, needle] of cases) {
        const copy = u8(bytes);
        new DataView(copy.buffer).setUint32(offset, value >>> 0, true);
        assert.throws(() => parseProbes(copy.buffer, `${name}.probes`),
            (e) => e instanceof Error && e.message.startsWith(`${name}.probes: `) && e.message.includes(needle),
            `${name}: wants "${needle}"`);
        const p = join(dir, `${name}.probes`);
        writeFileSync(p, copy);
        assert.throws(() => execFileSync(probebake, ['inspect', p], { stdio: 'pipe' }), `${name}: C reader`);
    }
    assert.throws(() => parseProbes(u8(bytes).slice(0, bytes.length - 4).buffer, 'cut.probes'), /truncated/);
});

// Version 2 (no accounting section) and version 1 (float16 metres, converted on
// read as the C reader does) files, made from a version-3 one as
// tests/test_volume.c makes them.
test('version 1 and 2 files still read', () => {
    const { bytes } = fixture();
    const b = u8(bytes), dv = new DataView(b.buffer);
    const accounting = Number(dv.getBigUint64(392, true));
    const depthAt = Number(dv.getBigUint64(168, true));
    const n = dv.getUint32(36, true), P = dv.getUint32(20, true);
    const v2end = depthAt + P * tileHalves(n) * 2;
    assert.ok(accounting >= v2end);
    dv.setUint32(8, 2, true);
    dv.setBigUint64(392, 0n, true);
    const v2 = parseProbes(b.slice(0, v2end).buffer, 'v2');
    assert.equal(v2.version, 2);
    assert.ok(v2.stdError.every((e) => e === -1));
    assert.ok(v2.paths.every((p) => p === v2.rays * v2.passes));
    assert.throws(() => parseProbes(b.buffer, 'v2-long'), /header describes/);

    dv.setUint32(8, 1, true);
    dv.setUint32(128, 1, true); // float16 metres
    dv.setUint32(180, 0, true);
    const maxd = dv.getFloat32(124, true); // 30 m: unit 0.25
    const put = (t, m1, m2) => { dv.setUint16(depthAt + 4 * t, m1, true); dv.setUint16(depthAt + 4 * t + 2, m2, true); };
    put(0, floatToHalf(10), floatToHalf(100));
    put(1, floatToHalf(300), 0x7c00); // past max distance, square overflowed
    put(2, 0x7e00, 0x7e00);           // NaN
    const v1 = parseProbes(b.slice(0, v2end).buffer, 'v1');
    assert.equal(v1.depthUnit, depthUnit(maxd));
    assert.equal(v1.depthUnit, 0.25);
    const d = Array.from(v1.depth.subarray(0, 6), halfToFloat);
    assert.deepEqual(d, [40, 1600, 120, 14400, 120, 14400]);
    assert.ok(v1.depth.every((h) => (h & 0x7c00) !== 0x7c00), 'no Inf or NaN after conversion');
});

test('half floats round as the C code does', () => {
    assert.equal(floatToHalf(1), 0x3c00);
    assert.equal(floatToHalf(65504), 0x7bff);
    assert.equal(floatToHalf(65520), 0x7c00);  // rounds up to Inf
    assert.equal(floatToHalf(2 ** -24), 0x0001);
    assert.equal(floatToHalf(2 ** -25), 0x0000); // tie to even
    assert.equal(floatToHalf(3 * 2 ** -25), 0x0002);
    assert.equal(floatToHalf(1 + 2 ** -11), 0x3c00); // tie to even
    assert.equal(floatToHalf(1 + 3 * 2 ** -11), 0x3c02);
    for (let h = 0; h < 0x7c00; ++h) assert.equal(floatToHalf(halfToFloat(h)), h);
    assert.equal(floatToHalf(-2), 0xc000);
});
