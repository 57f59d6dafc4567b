// Rewrites a glTF file's KTX2 (KHR_texture_basisu) images as PNG, decoded by
// Binomial's Basis Universal transcoder (three.js's pinned build, from
// runtime/node_modules: scripts/install-deps.sh installs it), for tools that
// read no KTX2 (probebake reads ETC1S and UASTC itself: docs/scene.md,
// "Textures"), and as a second decoder to hold probebake's to.
//
//   node scripts/ktx2_to_png.mjs IN.gltf OUT.gltf
//   node scripts/ktx2_to_png.mjs IN.glb OUT.glb
//
// Each KTX2 image's base level (first layer and face) becomes an 8-bit RGBA
// PNG: in a .glb, appended to its binary chunk; in a .gltf, a file beside OUT
// (OUT's stem, then the image's index). A texture reading it through
// KHR_texture_basisu reads it as its core source (a texture that already has
// a core source keeps it), and the extension leaves extensionsUsed and
// extensionsRequired once no texture uses it. Other images and buffers are
// kept; relative URIs are rewritten for OUT's folder. A bad input
// is one error line naming the file, exit status 1, and no output written.
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { loadTranscoder, transcodeBaseLevel, TranscodeError } from './basis_transcoder.mjs';

const KTX2_ID = Buffer.from([0xab, 0x4b, 0x54, 0x58, 0x20, 0x32, 0x30, 0xbb, 0x0d, 0x0a, 0x1a, 0x0a]);
const GLB_MAGIC = 0x46546c67, CHUNK_JSON = 0x4e4f534a, CHUNK_BIN = 0x004e4942;

class InputError extends Error {}

// ---- glTF and GLB in and out ------------------------------------------------

function readGltf(file) {
    const bytes = fs.readFileSync(file);
    if (bytes.length >= 12 && bytes.readUInt32LE(0) === GLB_MAGIC) {
        let json = null, bin = null;
        for (let o = 12; o + 8 <= bytes.length;) {
            const len = bytes.readUInt32LE(o), type = bytes.readUInt32LE(o + 4);
            if (o + 8 + len > bytes.length) throw new InputError('a GLB chunk runs past the end of the file');
            const chunk = bytes.subarray(o + 8, o + 8 + len);
            if (type === CHUNK_JSON && !json) json = chunk;
            else if (type === CHUNK_BIN && !bin) bin = chunk;
            o += 8 + len;
        }
        if (!json) throw new InputError('a GLB without a JSON chunk');
        return { glb: true, gltf: parseJson(json), bin: bin ? Buffer.from(bin) : Buffer.alloc(0) };
    }
    return { glb: false, gltf: parseJson(bytes), bin: null };
}

function parseJson(bytes) {
    try {
        return JSON.parse(bytes.toString('utf8'));
    } catch (e) {
        throw new InputError(`malformed JSON: ${e.message}`);
    }
}

const pad4 = (n) => (n + 3) & ~3;

function writeGlb(gltf, bin) {
    const json = Buffer.from(JSON.stringify(gltf));
    const jsonLen = pad4(json.length), binLen = pad4(bin.length);
    const out = Buffer.alloc(12 + 8 + jsonLen + (bin.length ? 8 + binLen : 0), 0);
    out.writeUInt32LE(GLB_MAGIC, 0);
    out.writeUInt32LE(2, 4);
    out.writeUInt32LE(out.length, 8);
    out.writeUInt32LE(jsonLen, 12);
    out.writeUInt32LE(CHUNK_JSON, 16);
    json.copy(out, 20);
    out.fill(0x20, 20 + json.length, 20 + jsonLen); // JSON is padded with spaces
    if (bin.length) {
        out.writeUInt32LE(binLen, 20 + jsonLen);
        out.writeUInt32LE(CHUNK_BIN, 24 + jsonLen);
        bin.copy(out, 28 + jsonLen);
    }
    return out;
}

// An image's bytes: a bufferView, a data URI or a file beside the glTF.
function imageBytes(doc, image, dir) {
    if (image.bufferView !== undefined) {
        const view = (doc.gltf.bufferViews || [])[image.bufferView];
        if (!view) throw new InputError(`bufferView ${image.bufferView} does not exist`);
        const data = bufferBytes(doc, view.buffer, dir);
        const begin = view.byteOffset || 0, end = begin + view.byteLength;
        if (!(end <= data.length)) throw new InputError(`bufferView ${image.bufferView} lies outside its buffer`);
        return data.subarray(begin, end);
    }
    return uriBytes(image.uri, dir);
}

function bufferBytes(doc, index, dir) {
    const buffer = (doc.gltf.buffers || [])[index];
    if (!buffer) throw new InputError(`buffer ${index} does not exist`);
    if (buffer.uri === undefined) {
        if (!doc.glb || index !== 0) throw new InputError(`buffer ${index} has no URI and is not a GLB's chunk`);
        return doc.bin;
    }
    return uriBytes(buffer.uri, dir);
}

function uriBytes(uri, dir) {
    if (typeof uri !== 'string') throw new InputError('an image with neither a bufferView nor a URI');
    if (uri.startsWith('data:')) {
        const comma = uri.indexOf(',');
        if (comma < 0 || !uri.slice(0, comma).endsWith(';base64')) throw new InputError('a data URI that is not base64');
        return Buffer.from(uri.slice(comma + 1), 'base64');
    }
    const file = path.join(dir, decodeURIComponent(uri));
    try {
        return fs.readFileSync(file);
    } catch (e) {
        throw new InputError(`cannot read ${file}: ${e.code || e.message}`);
    }
}

// ---- PNG out: 8-bit RGBA, no filter, zlib from node ----------------------------

function png(width, height, rgba) {
    const raw = Buffer.alloc((width * 4 + 1) * height);
    for (let y = 0; y < height; ++y) // each row: filter type 0, then its bytes
        Buffer.from(rgba.buffer, rgba.byteOffset + y * width * 4, width * 4).copy(raw, y * (width * 4 + 1) + 1);
    const chunk = (type, data) => {
        const head = Buffer.alloc(8);
        head.writeUInt32BE(data.length, 0);
        head.write(type, 4, 'latin1');
        const crc = Buffer.alloc(4);
        crc.writeUInt32BE(zlib.crc32(Buffer.concat([head.subarray(4), data])) >>> 0, 0);
        return Buffer.concat([head, data, crc]);
    };
    const ihdr = Buffer.alloc(13);
    ihdr.writeUInt32BE(width, 0);
    ihdr.writeUInt32BE(height, 4);
    ihdr[8] = 8; // bits per channel
    ihdr[9] = 6; // RGBA
    return Buffer.concat([Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]), chunk('IHDR', ihdr),
        chunk('IDAT', zlib.deflateSync(raw)), chunk('IEND', Buffer.alloc(0))]);
}

// ---- the rewrite -------------------------------------------------------------------

const isKtx2 = (image, bytes) => image.mimeType === 'image/ktx2' || KTX2_ID.equals(bytes.subarray(0, 12));

async function convert(input, output) {
    const doc = readGltf(input);
    const gltf = doc.gltf, inDir = path.dirname(input), outDir = path.dirname(output);
    if (output.toLowerCase().endsWith('.glb') !== doc.glb)
        throw new InputError(`OUT must be a ${doc.glb ? '.glb' : '.gltf'} as IN is (${output})`);
    if (doc.glb && (gltf.buffers || []).length && gltf.buffers[0].uri !== undefined)
        throw new InputError('a GLB whose first buffer is not its binary chunk');
    let basis = null, bin = doc.glb ? doc.bin : Buffer.alloc(0);
    const written = [], converted = new Set();
    for (const [i, image] of (gltf.images || []).entries()) {
        if (image.uri === undefined && image.bufferView === undefined) continue;
        const bytes = imageBytes(doc, image, inDir);
        if (!isKtx2(image, bytes)) continue;
        basis ??= await loadTranscoder();
        let decoded;
        try {
            decoded = transcodeBaseLevel(basis, bytes);
        } catch (e) {
            throw e instanceof TranscodeError ? new InputError(`image ${i}: ${e.message}`) : e;
        }
        const pngBytes = png(decoded.width, decoded.height, decoded.rgba);
        delete image.uri;
        delete image.bufferView;
        image.mimeType = 'image/png';
        if (doc.glb) { // into the binary chunk, 4-byte aligned
            const offset = pad4(bin.length);
            bin = Buffer.concat([bin, Buffer.alloc(offset - bin.length), pngBytes]);
            gltf.bufferViews ??= [];
            image.bufferView = gltf.bufferViews.push({ buffer: 0, byteOffset: offset, byteLength: pngBytes.length }) - 1;
        } else {
            const name = `${path.basename(output, path.extname(output))}_image${i}.png`;
            written.push([path.join(outDir, name), pngBytes]);
            image.uri = encodeURIComponent(name);
        }
        converted.add(i);
        console.log(`image ${i}: ${decoded.codec} ${decoded.width} x ${decoded.height} -> PNG (${pngBytes.length} bytes)`);
    }
    if (converted.size === 0) console.log(`${input}: no KTX2 image; written unchanged`);

    // textures: KHR_texture_basisu's source, when converted, becomes the core one
    let stillUsed = false;
    for (const t of gltf.textures || []) {
        const ext = t.extensions && t.extensions.KHR_texture_basisu;
        if (!ext) continue;
        if (converted.has(ext.source)) {
            if (t.source === undefined) t.source = ext.source;
            delete t.extensions.KHR_texture_basisu;
            if (Object.keys(t.extensions).length === 0) delete t.extensions;
        } else stillUsed = true;
    }
    if (!stillUsed)
        for (const list of ['extensionsUsed', 'extensionsRequired']) {
            if (!gltf[list]) continue;
            gltf[list] = gltf[list].filter((e) => e !== 'KHR_texture_basisu');
            if (gltf[list].length === 0) delete gltf[list];
        }

    // the file's relative URIs (a .gltf's buffers and images, a .glb's external ones), from OUT's folder
    const rebase = (o) => {
        if (typeof o.uri === 'string' && !o.uri.startsWith('data:') && !/^[a-z][a-z0-9+.-]*:/i.test(o.uri) &&
            !written.some(([f]) => path.basename(f) === decodeURIComponent(o.uri)))
            o.uri = path.relative(outDir, path.join(inDir, decodeURIComponent(o.uri))).split(path.sep).map(encodeURIComponent).join('/');
    };
    [...(gltf.buffers || []), ...(gltf.images || [])].forEach(rebase);

    let out;
    if (doc.glb) {
        if (converted.size) {
            gltf.buffers ??= [];
            if (gltf.buffers.length === 0) gltf.buffers.push({});
            gltf.buffers[0].byteLength = bin.length;
        }
        out = writeGlb(gltf, bin);
    } else
        out = Buffer.from(JSON.stringify(gltf, null, 1));
    // everything in memory first: a failure above leaves no file behind
    for (const [file, bytes] of written) fs.writeFileSync(file, bytes);
    fs.writeFileSync(output, out);
    console.log(`wrote ${output}: ${converted.size} KTX2 image(s) as PNG`);
}

const [input, output] = process.argv.slice(2);
if (!input || !output || process.argv.length > 4) {
    console.error('usage: node scripts/ktx2_to_png.mjs IN.gltf OUT.gltf | IN.glb OUT.glb');
    process.exit(2);
}
try {
    await convert(input, output);
} catch (e) {
    console.error(`ktx2_to_png: error: ${input}: ${e instanceof InputError || e.code ? e.message : e.stack}`);
    process.exit(1);
}
