// scripts/ktx2_to_png.mjs: KTX2 images (UASTC and ETC1S, which probebake
// also reads itself) rewritten as PNG by Basis Universal's transcoder; the
// output loads in probebake without KHR_texture_basisu and holds the texels
// the transcoder gives (tests/data/ktx2/*.rgba), from a .glb and from a .gltf
// with external files written to another folder; bad input is one error line
// and no file. Needs node and runtime/node_modules (three.js's transcoder).
//   PB_PROBEBAKE=build/probebake node --test tests/test_ktx2_to_png.mjs
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import zlib from 'node:zlib';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
const script = path.join(root, 'scripts/ktx2_to_png.mjs');
const probebake = process.env.PB_PROBEBAKE;
const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'pb-ktx2png-'));
after(() => fs.rmSync(dir, { recursive: true, force: true }));

const run = (...args) => spawnSync(process.execPath, [script, ...args], { encoding: 'utf8' });
const info = (file) => {
    const r = spawnSync(probebake, ['info', file, '--json'], { encoding: 'utf8' });
    assert.equal(r.status, 0, r.stderr);
    return { json: JSON.parse(r.stdout), stderr: r.stderr };
};

// The pixels of a PNG the script wrote: 8-bit RGBA, every row filter 0.
function pngPixels(bytes) {
    assert.ok(bytes.subarray(0, 8).equals(Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a])));
    let o = 8, width = 0, height = 0;
    const idat = [];
    while (o < bytes.length) {
        const len = bytes.readUInt32BE(o), type = bytes.toString('latin1', o + 4, o + 8);
        const data = bytes.subarray(o + 8, o + 8 + len);
        assert.equal(bytes.readUInt32BE(o + 8 + len), zlib.crc32(bytes.subarray(o + 4, o + 8 + len)) >>> 0, `${type} CRC`);
        if (type === 'IHDR') {
            width = data.readUInt32BE(0), height = data.readUInt32BE(4);
            assert.deepEqual([data[8], data[9]], [8, 6], '8-bit RGBA');
        } else if (type === 'IDAT') idat.push(data);
        o += 12 + len;
    }
    const raw = zlib.inflateSync(Buffer.concat(idat));
    const px = Buffer.alloc(width * height * 4);
    for (let y = 0; y < height; ++y) {
        assert.equal(raw[y * (width * 4 + 1)], 0, `row ${y}: filter 0`);
        raw.copy(px, y * width * 4, y * (width * 4 + 1) + 1, (y + 1) * (width * 4 + 1));
    }
    return { width, height, px };
}

// the first chunk after the JSON of a GLB, and its JSON
function glbParts(file) {
    const b = fs.readFileSync(file);
    const jlen = b.readUInt32LE(12);
    const json = JSON.parse(b.toString('utf8', 20, 20 + jlen));
    const bin = b.subarray(28 + jlen, 28 + jlen + b.readUInt32LE(20 + jlen));
    return { json, bin };
}

test('a UASTC image in a .glb becomes the PNG of its transcoded texels', () => {
    assert.ok(probebake, 'PB_PROBEBAKE names the probebake binary');
    const src = path.join(root, 'tests/fuzz/corpus/ktx2-uastc_gradient.glb');
    // before: probebake reads the UASTC image itself, without a warning
    const before = info(src);
    assert.doesNotMatch(before.stderr, /warning/);
    assert.equal(before.json.textures, 1);
    const out = path.join(dir, 'uastc.glb');
    const r = run(src, out);
    assert.equal(r.status, 0, r.stderr);
    const after = info(out);
    assert.equal(after.json.textures, 1);
    assert.doesNotMatch(after.stderr, /warning/);
    assert.ok(!after.json.extensions_used.includes('KHR_texture_basisu'), JSON.stringify(after.json.extensions_used));
    const { json, bin } = glbParts(out);
    assert.equal(json.textures[0].source, 0);
    assert.equal(json.textures[0].extensions, undefined);
    const view = json.bufferViews[json.images[0].bufferView];
    assert.equal(view.byteOffset % 4, 0);
    const { width, height, px } = pngPixels(bin.subarray(view.byteOffset, view.byteOffset + view.byteLength));
    assert.deepEqual([width, height], [16, 16]);
    assert.ok(px.equals(fs.readFileSync(path.join(root, 'tests/data/ktx2/uastc_gradient.rgba'))),
        'the transcoder\'s texels');
});

test('an ETC1S image beside a .gltf, written to another folder', () => {
    // a one-triangle .gltf reading a KTX2 file and a .bin, both beside it
    const srcDir = path.join(dir, 'in'), outDir = path.join(dir, 'out');
    fs.mkdirSync(srcDir);
    fs.mkdirSync(outDir);
    fs.copyFileSync(path.join(root, 'tests/data/ktx2/etc1s_gradient_alpha.ktx2'), path.join(srcDir, 'colour map.ktx2'));
    const pos = Buffer.from(new Float32Array([0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1]).buffer);
    fs.writeFileSync(path.join(srcDir, 'tri.bin'), pos);
    const gltf = {
        asset: { version: '2.0' }, extensionsUsed: ['KHR_texture_basisu'], extensionsRequired: ['KHR_texture_basisu'],
        scenes: [{ nodes: [0] }], nodes: [{ mesh: 0 }],
        meshes: [{ primitives: [{ attributes: { POSITION: 0, TEXCOORD_0: 1 }, material: 0 }] }],
        materials: [{ pbrMetallicRoughness: { baseColorTexture: { index: 0 } } }],
        textures: [{ extensions: { KHR_texture_basisu: { source: 0 } } }],
        images: [{ uri: 'colour%20map.ktx2', mimeType: 'image/ktx2' }],
        accessors: [{ bufferView: 0, componentType: 5126, count: 3, type: 'VEC3' },
            { bufferView: 1, componentType: 5126, count: 3, type: 'VEC2' }],
        bufferViews: [{ buffer: 0, byteLength: 36 }, { buffer: 0, byteOffset: 36, byteLength: 24 }],
        buffers: [{ byteLength: 60, uri: 'tri.bin' }],
    };
    const src = path.join(srcDir, 'tri.gltf');
    fs.writeFileSync(src, JSON.stringify(gltf));
    const out = path.join(outDir, 'tri.gltf');
    const r = run(src, out);
    assert.equal(r.status, 0, r.stderr);
    const json = JSON.parse(fs.readFileSync(out, 'utf8'));
    assert.equal(json.buffers[0].uri, '../in/tri.bin');
    assert.equal(json.images[0].uri, 'tri_image0.png');
    assert.equal(json.extensionsRequired, undefined);
    const { width, height, px } = pngPixels(fs.readFileSync(path.join(outDir, 'tri_image0.png')));
    assert.deepEqual([width, height], [37, 21]);
    assert.ok(px.equals(fs.readFileSync(path.join(root, 'tests/data/ktx2/etc1s_gradient_alpha.rgba'))));
    const i = info(out);
    assert.equal(i.json.textures, 1);
    assert.doesNotMatch(i.stderr, /warning/);
});

test('bad input: one error line naming the file, exit 1, no output', () => {
    const src = path.join(root, 'tests/fuzz/corpus/ktx2-etc1s_gradient_alpha.glb');
    const b = fs.readFileSync(src);
    // the KTX2 image's level index pointing past the file: the transcoder refuses it
    const { json } = glbParts(src);
    const view = json.bufferViews[json.images[0].bufferView];
    const cut = Buffer.from(b);
    const ktx = 28 + b.readUInt32LE(12) + view.byteOffset; // the image's first byte
    cut.writeUInt32LE(0x7fffffff, ktx + 80); // level 0's byteOffset
    const bad = path.join(dir, 'bad.glb'), out = path.join(dir, 'bad-out.glb');
    fs.writeFileSync(bad, cut);
    for (const [args, needle] of [[[bad, out], /image 0: /], [[src, path.join(dir, 'x.gltf')], /OUT must be a \.glb/],
        [[path.join(dir, 'missing.glb'), out], /ENOENT/]]) {
        const r = run(...args);
        assert.equal(r.status, 1, r.stderr);
        const lines = r.stderr.trim().split('\n');
        assert.equal(lines.length, 1, r.stderr);
        assert.match(lines[0], new RegExp(`^ktx2_to_png: error: ${args[0].replace(/[.*+?^${}()|[\]\\]/g, '\\$&')}: `));
        assert.match(lines[0], needle);
        assert.ok(!fs.existsSync(args[1]), `${args[1]} written`);
    }
});
