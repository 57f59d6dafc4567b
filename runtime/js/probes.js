// Reads a probebake volume (.probes, docs/format.md) in the browser or in
// node: an ES module with no dependencies. The checks are the C reader's
// (src/io/volume_file.c), with the same messages, so a page can show why a
// file was refused instead of drawing nothing.
//
//   import { parseProbes } from './probes.js';
//   const volume = parseProbes(await (await fetch('scene.probes')).arrayBuffer());

export const PROBES_VERSION = 4;

const HEADER_BYTES = 512;
const MAX_PROBES = 1 << 28;
const DEPTH_FORMAT_F16_METRES = 1; // version 1
const DEPTH_FORMAT_F16_UNITS = 2;  // versions 2 to 4
const SH_FORMAT_F32 = 1;
const STD_ERROR_UNKNOWN = -1;
const SPARSE_HEAD = 32, SPARSE_BRICK_PROBES = 64, SPARSE_MAX_LEVELS = 3, SPARSE_EMPTY = 0x0fffffff;

/** Probe flag bits (docs/format.md, "flags"). */
export const PROBE_VALID = 1, PROBE_RELOCATED = 2, PROBE_DILATED = 4, PROBE_OUTSIDE = 8, PROBE_CONVERGED = 16;

const align16 = (x) => Math.ceil(x / 16) * 16;

/** Half floats of a probe's depth tile: (n + 2)^2 texels of 2 halves. */
export const tileHalves = (n) => 2 * (n + 2) * (n + 2);

// Section offsets as the writer lays them out (layout_of in volume_file.c).
function layoutOf(probes, n, version) {
    const l = { base: HEADER_BYTES };
    l.offset = align16(l.base + probes * 12);
    l.flags = align16(l.offset + probes * 12);
    l.sh = align16(l.flags + probes * 4);
    l.depth = align16(l.sh + probes * 27 * 4);
    l.end = l.depth + probes * tileHalves(n) * 2;
    l.accounting = 0;
    if (version >= 3) {
        l.accounting = align16(l.end);
        l.end = l.accounting + probes * 8;
    }
    return l;
}

/** IEEE half (as a uint16) to a number. */
export function halfToFloat(h) {
    const s = h & 0x8000 ? -1 : 1, e = (h >> 10) & 0x1f, m = h & 0x3ff;
    if (e === 0) return s * m * 2 ** -24;
    if (e === 31) return m ? NaN : s * Infinity;
    return s * (1 + m / 1024) * 2 ** (e - 15);
}

const f32 = new Float32Array(1), u32 = new Uint32Array(f32.buffer);

/** A number to the nearest IEEE half, ties to even (pb_half_from_float). */
export function floatToHalf(x) {
    f32[0] = x;
    const b = u32[0], sign = (b >>> 16) & 0x8000, e = (b >>> 23) & 0xff;
    let m = b & 0x7fffff;
    if (e === 255) return sign | 0x7c00 | (m ? 0x200 : 0);
    const he = e - 127 + 15;
    if (he >= 31) return sign | 0x7c00;
    if (he <= 0) { // subnormal or zero: shift the implicit 1 in and round
        if (he < -10) return sign;
        m |= 0x800000;
        const shift = 14 - he, half = 1 << (shift - 1), rest = m & ((1 << shift) - 1);
        let r = m >>> shift;
        if (rest > half || (rest === half && (r & 1))) r += 1;
        return sign | r;
    }
    const rest = m & 0x1fff;
    let r = (he << 10) | (m >>> 13);
    if (rest > 0x1000 || (rest === 0x1000 && (r & 1))) r += 1; // may carry into the exponent: still right
    return sign | r;
}

/** The depth unit a writer picks for a max distance (pb_volume_depth_unit). */
export function depthUnit(maxDistance) {
    if (!(maxDistance > 0) || !Number.isFinite(maxDistance)) return 1;
    let u = 2 ** Math.ceil(Math.log2(maxDistance / 128));
    while (u / 2 >= maxDistance / 128) u /= 2; // log2 rounding at exact powers
    while (u < maxDistance / 128) u *= 2;
    return Math.fround(u);
}

/**
 * Parses a .probes file. Returns
 *   {version, counts:[x,y,z], origin:[x,y,z], spacing:[x,y,z], n, tile,
 *    flags: Uint32Array, positions: Float32Array (P x 3, relative to origin,
 *    relocation applied), sh: Float32Array (P x 27, as in the file),
 *    depth: Uint16Array (half floats, the atlas as stored: tile p at p x tile^2
 *    texels, 2 halves each, in depth units), depthUnit, maxDistance,
 *    irradiance, directIncluded, grid, sparse (null, or the bricks: see
 *    readSparse; origin is then the lattice origin and spacing the finest
 *    level's), paths: Uint32Array, stdError:
 *    Float32Array (-1 unknown), probeCount, seed, sceneHash (hex), techniques,
 *    device}
 * and throws an Error naming the problem for a bad magic, a newer version, a
 * truncated file or out-of-range offsets. `name` goes in front of messages.
 */
export function parseProbes(buffer, name = 'volume') {
    const bytes = buffer instanceof ArrayBuffer ? new Uint8Array(buffer)
        : new Uint8Array(buffer.buffer, buffer.byteOffset, buffer.byteLength);
    const fail = (what) => { throw new Error(`${name}: ${what}`); };
    const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const magic = String.fromCharCode(...bytes.subarray(0, 8));
    if (bytes.length < 8 || magic !== 'PBVOLUME') fail('not a probebake volume (bad magic)');
    if (bytes.length < HEADER_BYTES) fail(`truncated header (${bytes.length} of ${HEADER_BYTES} bytes)`);
    const u32 = (o) => dv.getUint32(o, true), f32 = (o) => dv.getFloat32(o, true), f64 = (o) => dv.getFloat64(o, true);
    const u64 = (o) => dv.getBigUint64(o, true);
    const version = u32(8);
    if (version > PROBES_VERSION || version === 0)
        fail(`volume format version ${version}; this reader reads versions 1 to ${PROBES_VERSION}`);
    const flags = u32(16), P = u32(20), counts = [u32(24), u32(28), u32(32)], n = u32(36);
    const origin = [f64(40), f64(48), f64(56)], spacing = [f64(64), f64(72), f64(80)];
    const maxDistance = f32(124);
    if (u32(12) !== HEADER_BYTES) fail('unexpected header size');
    if (P === 0 || P > MAX_PROBES) fail('probe count out of range');
    if (n < 1 || n > 256 || u32(176) !== n + 2) fail('octahedral map size out of range');
    if (u32(128) !== (version === 1 ? DEPTH_FORMAT_F16_METRES : DEPTH_FORMAT_F16_UNITS) || u32(132) !== SH_FORMAT_F32)
        fail('unknown SH or depth format');
    if (version >= 2 && !(f32(180) > 0 && Number.isFinite(f32(180)))) fail('depth unit not a positive finite number');
    if ((flags & 4) && counts[0] * counts[1] * counts[2] !== P) fail('grid counts do not match the probe count');
    const sparseFlag = (flags & 16) !== 0;
    if (sparseFlag && (version < 4 || (flags & (4 | 8))))
        fail('sparse flag in a grid, a part or a file older than version 4');
    const l = layoutOf(P, n, version);
    if (sparseFlag) { // the sparse section's size is in its head (sparse_bytes in volume_file.c)
        const at = align16(l.end);
        if (u64(416) !== BigInt(at)) fail('section offsets do not match the sizes');
        if (bytes.length < at + SPARSE_HEAD) fail('truncated sparse layout');
        if (u32(at + 4) >= 1 << 20 || u32(at + 8) >= 1 << 20 || u32(at + 12) >= 1 << 20)
            fail('sparse layout with too many cells');
        const cells = u32(at + 4) * u32(at + 8) * u32(at + 12), bricks = u32(at + 16), chunks = u32(at + 20);
        l.sparse = at;
        l.end = at + SPARSE_HEAD + bricks * 16 + bricks * SPARSE_BRICK_PROBES * 4 + cells * 4 + chunks * 4;
    } else if (version >= 4 && u64(416) !== 0n) {
        fail('sparse layout offset in a volume without the sparse flag');
    }
    const at = [l.base, l.offset, l.flags, l.sh, l.depth];
    for (let k = 0; k < 5; ++k)
        if (u64(136 + 8 * k) !== BigInt(at[k])) fail('section offsets do not match the sizes');
    if (version >= 3 && u64(392) !== BigInt(l.accounting)) fail('section offsets do not match the sizes');
    if (bytes.length !== l.end) fail(`file is ${bytes.length} bytes, the header describes ${l.end} (truncated?)`);

    // sections are 16-byte aligned and little-endian: copy them out (the
    // buffer may be unaligned or big-endian hosts may read it; DataView is safe)
    const floats = (offset, count) => {
        const out = new Float32Array(count);
        for (let i = 0; i < count; ++i) out[i] = f32(offset + 4 * i);
        return out;
    };
    const positions = floats(l.base, 3 * P), offsets = floats(l.offset, 3 * P);
    for (let i = 0; i < 3 * P; ++i) positions[i] = positions[i] + offsets[i];
    const probeFlags = new Uint32Array(P);
    for (let i = 0; i < P; ++i) probeFlags[i] = u32(l.flags + 4 * i);
    const sh = floats(l.sh, 27 * P);
    const halves = P * tileHalves(n), depth = new Uint16Array(halves);
    for (let i = 0; i < halves; ++i) depth[i] = dv.getUint16(l.depth + 2 * i, true);
    const paths = new Uint32Array(P), stdError = new Float32Array(P);
    for (let i = 0; i < P; ++i) {
        if (version < 3) { // every probe got what the header says; its error is unknown
            paths[i] = Math.min(u32(104) * u32(108), 0xffffffff);
            stdError[i] = STD_ERROR_UNKNOWN;
            continue;
        }
        paths[i] = u32(l.accounting + 8 * i);
        const e = f32(l.accounting + 8 * i + 4);
        if (!((e >= 0 && Number.isFinite(e)) || e === STD_ERROR_UNKNOWN))
            fail(`probe ${i} has a negative or non-finite standard error`);
        stdError[i] = e;
    }
    let unit;
    if (version === 1) { // metres, which overflowed past 256 m: clamp and re-express in units
        const maxd = maxDistance > 0 && Number.isFinite(maxDistance) ? maxDistance : 65504;
        unit = depthUnit(maxd);
        for (let t = 0; t < halves; t += 2) {
            let m1 = halfToFloat(depth[t]), m2 = halfToFloat(depth[t + 1]);
            m1 = m1 >= 0 && m1 <= maxd ? m1 : maxd;
            m2 = m2 >= 0 && m2 <= Math.fround(maxd * maxd) ? m2 : Math.fround(maxd * maxd);
            depth[t] = floatToHalf(Math.fround(m1 / unit));
            depth[t + 1] = floatToHalf(Math.fround(Math.fround(m2 / unit) / unit));
        }
    } else {
        unit = f32(180);
    }
    const device = new TextDecoder().decode(bytes.subarray(248, 376)).replace(/\0.*$/s, '');
    const sparse = sparseFlag ? readSparse(dv, l.sparse, P, fail) : null;
    return {
        version, probeCount: P, counts, origin, spacing, n, tile: n + 2,
        flags: probeFlags, positions, sh, depth, depthUnit: unit, maxDistance,
        irradiance: (flags & 1) !== 0, directIncluded: (flags & 2) !== 0, grid: (flags & 4) !== 0,
        sparse, paths, stdError, seed: u64(88), sceneHash: u64(96).toString(16).padStart(16, '0'),
        rays: u32(104), passes: u32(108), bounces: u32(112), techniques: u32(388), device,
    };
}

const pow3 = (d) => 3 ** d;

/**
 * The sparse layout section at `at` (docs/format.md "Sparse layout"), checked
 * as the C reader checks it (pb_sparse_layout_validate, same messages):
 *   {levels, cells:[x,y,z], brickCount, chunkCount, bricks: Uint32Array
 *    (4 per brick: coordinates at its level, level), brickProbes:
 *    Uint32Array (64 per brick, x fastest), indirection: Uint32Array (per
 *    coarsest cell, depth << 28 | index), chunks: Uint32Array}
 */
function readSparse(dv, at, P, fail) {
    const u32 = (o) => dv.getUint32(o, true);
    const levels = u32(at), cells = [u32(at + 4), u32(at + 8), u32(at + 12)];
    const B = u32(at + 16), K = u32(at + 20), C = cells[0] * cells[1] * cells[2];
    if (C === 0 || C > 1 << 24 || B === 0 || B > 1 << 22) fail(`sparse layout with ${C} cells and ${B} bricks`);
    const words = (o, count) => {
        const out = new Uint32Array(count);
        for (let i = 0; i < count; ++i) out[i] = u32(o + 4 * i);
        return out;
    };
    let q = at + SPARSE_HEAD;
    const bricks = words(q, 4 * B); q += 16 * B;
    const brickProbes = words(q, SPARSE_BRICK_PROBES * B); q += 4 * SPARSE_BRICK_PROBES * B;
    const indirection = words(q, C); q += 4 * C;
    const chunks = words(q, K);
    if (levels < 1 || levels > SPARSE_MAX_LEVELS) fail(`sparse layout with ${levels} levels (1 to ${SPARSE_MAX_LEVELS})`);
    for (let k = 0; k < 3; ++k)
        if (cells[k] * pow3(levels) >= 1 << 20) fail(`sparse layout with ${cells[k]} cells on axis ${k}`);
    for (let b = 0; b < B; ++b) {
        const level = bricks[4 * b + 3];
        if (level >= levels) fail(`sparse brick ${b} has level ${level} of ${levels}`);
        for (let k = 0; k < 3; ++k)
            if (bricks[4 * b + k] >= cells[k] * pow3(level)) fail(`sparse brick ${b} lies outside the cells`);
        for (let i = 0; i < SPARSE_BRICK_PROBES; ++i)
            if (brickProbes[SPARSE_BRICK_PROBES * b + i] >= P)
                fail(`sparse brick ${b} names probe ${brickProbes[SPARSE_BRICK_PROBES * b + i]} of ${P}`);
    }
    for (let z = 0; z < cells[2]; ++z)
        for (let y = 0; y < cells[1]; ++y)
            for (let x = 0; x < cells[0]; ++x) {
                const c = x + cells[0] * (y + cells[1] * z), e = indirection[c];
                const d = e >>> 28, off = e & SPARSE_EMPTY, cell = [x, y, z];
                if (d >= levels) fail(`sparse cell ${c} has depth ${d}`);
                const m = pow3(d);
                if (d > 0 && off + m * m * m > K) fail(`sparse cell ${c} points past the chunks`);
                for (let s = 0; s < m * m * m; ++s) {
                    const b = d ? chunks[off + s] : off;
                    if (b === SPARSE_EMPTY) continue;
                    if (b >= B) fail(`sparse cell ${c} names brick ${b} of ${B}`);
                    const level = bricks[4 * b + 3];
                    if (level > d) fail(`sparse cell ${c} names a brick finer than its depth`);
                    const sub = [s % m, Math.floor(s / m) % m, Math.floor(s / (m * m))], div = pow3(d - level);
                    for (let k = 0; k < 3; ++k)
                        if (bricks[4 * b + k] !== cell[k] * pow3(level) + Math.floor(sub[k] / div))
                            fail(`sparse cell ${c} names brick ${b} elsewhere`);
                }
            }
    return { levels, cells, brickCount: B, chunkCount: K, bricks, brickProbes, indirection, chunks };
}

/**
 * The layout tables as the sampler reads them (pb_sparse_word in
 * runtime/probe_sample.glsl; build_sparse_words in src/sample/probe_sample.c):
 * four word offsets (indirection, chunks, bricks, brick probes), then those
 * tables, a brick as four words (coordinates, level).
 */
export function sparseSamplerWords(sp) {
    const C = sp.indirection.length, atInd = 4, atChunks = atInd + C, atBricks = atChunks + sp.chunkCount;
    const atProbes = atBricks + 4 * sp.brickCount;
    const w = new Uint32Array(atProbes + SPARSE_BRICK_PROBES * sp.brickCount);
    w.set([atInd, atChunks, atBricks, atProbes]);
    w.set(sp.indirection, atInd);
    w.set(sp.chunks, atChunks);
    w.set(sp.bricks, atBricks);
    w.set(sp.brickProbes, atProbes);
    return w;
}
