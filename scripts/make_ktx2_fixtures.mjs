// Writes tests/data/ktx2/: small KTX2 files made by Basis Universal's own
// encoder (npm ktx2-encoder, which wraps it), and beside each ETC1S one the
// RGBA8 pixels Binomial's transcoder (three.js's pinned basis_transcoder)
// decodes from it: the reference test_scene holds probebake's decoder to,
// byte for byte. Run by scripts/make_ktx2_fixtures.sh; the outputs are
// committed, so the tests need neither package.
//
//   node scripts/make_ktx2_fixtures.mjs ENCODER_DIR TRANSCODER_JS OUT_DIR
import fs from "fs";
import path from "path";
import { loadTranscoder, transcodeBaseLevel } from "./basis_transcoder.mjs";

const [encoderDir, transcoderJs, outDir] = process.argv.slice(2);
const { encodeToKTX2 } = await import(path.resolve(encoderDir, "node_modules/ktx2-encoder/dist/node/index.js"));
const { PNG } = await import(path.resolve(encoderDir, "node_modules/pngjs/lib/png.js"));

// Deterministic pictures: smooth gradients, value noise with hard edges (many
// distinct blocks, so large codebooks and long prefix codes), blocks of every
// contrast, grey, and flat.
function rng(seed) {
  let s = seed >>> 0;
  return () => ((s = (Math.imul(s, 1664525) + 1013904223) >>> 0) / 4294967296);
}
function picture(w, h, kind) {
  const px = new Uint8Array(w * h * 4), r = rng(w * 131 + h);
  const lattice = Array.from({ length: 64 }, () => r());
  const noise = (x, y) => lattice[((x >> 3) * 7 + (y >> 3) * 13) & 63];
  for (let y = 0; y < h; y++)
    for (let x = 0; x < w; x++) {
      const i = (y * w + x) * 4;
      if (kind === "gradient") {
        px[i] = (x * 255) / (w - 1); px[i + 1] = (y * 255) / (h - 1); px[i + 2] = ((x ^ y) * 9) & 255;
        px[i + 3] = 255 - (x * 200) / (w - 1);
      } else if (kind === "noise") {
        const n = noise(x, y), edge = (x + 2 * y) % 29 < 3 ? 90 : 0;
        px[i] = Math.min(255, n * 220 + edge + r() * 30); px[i + 1] = Math.min(255, (1 - n) * 180 + r() * 60);
        px[i + 2] = Math.min(255, ((x * y) & 127) + edge); px[i + 3] = 255;
      } else if (kind === "contrast") { // per block a grey and a spread up to ETC1's widest tables
        const b = lattice[((x >> 2) * 5 + (y >> 2) * 11) & 63], d = 8 + 175 * lattice[((x >> 2) * 3 + (y >> 2) * 17 + 1) & 63];
        const t = [-1, -0.3, 0.3, 1][(x * 3 + y * 5 + (x >> 2)) & 3], v = Math.max(0, Math.min(255, 40 + 175 * b + t * d));
        px[i] = v; px[i + 1] = Math.max(0, Math.min(255, v + ((x & 2) ? 12 : -12))); px[i + 2] = 255 - v; px[i + 3] = 255;
      } else if (kind === "grey") {
        px[i] = px[i + 1] = px[i + 2] = (noise(x, y) * 255 + y * 3) & 255; px[i + 3] = 255;
      } else { px[i] = 200; px[i + 1] = 120; px[i + 2] = 40; px[i + 3] = 255; }
    }
  return px;
}

const basis = await loadTranscoder(transcoderJs);

const fixtures = [
  { name: "etc1s_gradient_alpha", w: 37, h: 21, kind: "gradient", opts: { isUASTC: false, generateMipmap: false } },
  { name: "etc1s_noise_mips", w: 128, h: 96, kind: "noise", opts: { isUASTC: false, generateMipmap: true, qualityLevel: 255 } },
  { name: "etc1s_noise_low", w: 64, h: 40, kind: "noise", opts: { isUASTC: false, generateMipmap: false, qualityLevel: 1 } },
  { name: "etc1s_grey", w: 19, h: 33, kind: "grey", opts: { isUASTC: false, generateMipmap: false, isSetKTX2SRGBTransferFunc: false } },
  { name: "etc1s_contrast", w: 48, h: 40, kind: "contrast", opts: { isUASTC: false, generateMipmap: false, qualityLevel: 255 } },
  { name: "etc1s_flat", w: 8, h: 8, kind: "flat", opts: { isUASTC: false, generateMipmap: false } },
  // the demo scene's lattice texture, for the runtime's browser test (a KTX2 variant of the demo)
  { name: "demo_lattice", png: "tests/scenes/demo.gltf", opts: { isUASTC: false, generateMipmap: true, qualityLevel: 255 } },
  { name: "demo_lattice_uastc", png: "tests/scenes/demo.gltf", opts: { isUASTC: true, generateMipmap: true } },
  // UASTC: Zstandard supercompressed (the encoder's default) or stored as it is, plain or
  // rate-distortion optimised, at the encoder's default and slower effort
  { name: "uastc_gradient", w: 16, h: 16, kind: "gradient", opts: { isUASTC: true, generateMipmap: false } },
  { name: "uastc_noise_mips", w: 128, h: 96, kind: "noise", opts: { isUASTC: true, needSupercompression: false, generateMipmap: true } },
  { name: "uastc_gradient_rdo", w: 37, h: 21, kind: "gradient", opts: { isUASTC: true, enableRDO: true, generateMipmap: false } },
  { name: "uastc_contrast_slow", w: 48, h: 40, kind: "contrast", opts: { isUASTC: true, needSupercompression: false, uastcLDRQualityLevel: 3, generateMipmap: false } },
  // every UASTC mode and partition pattern, and the trit and quint codes past their range
  // (which decode modulo 3 or 5): 1,024 random blocks the transcoder accepts, in place of
  // an encoded picture's
  { name: "uastc_random_blocks", w: 128, h: 128, kind: "flat", random: true, opts: { isUASTC: true, needSupercompression: false, generateMipmap: false } },
];

// Random 16-byte blocks, each kept if the transcoder decodes it alone (in a
// 4 x 4 file): it refuses the reserved mode and pattern indices past their tables.
async function validRandomBlocks(count) {
  const one = Buffer.from(await encodeToKTX2(new Uint8Array(64).fill(128), {
    isUASTC: true, needSupercompression: false, generateMipmap: false,
    imageDecoder: async (b) => ({ data: b, width: 4, height: 4 }) }));
  const at = Number(one.readBigUInt64LE(80)), r = rng(20261129), out = Buffer.alloc(16 * count);
  for (let n = 0; n < count;) {
    const block = Buffer.from(Array.from({ length: 16 }, () => Math.floor(r() * 256)));
    block.copy(one, at);
    try { transcodeBaseLevel(basis, one); } catch { continue; }
    block.copy(out, 16 * n++);
  }
  return out;
}
fs.mkdirSync(outDir, { recursive: true });
// the first image of a glTF, a PNG in a data URI
function gltfPng(file) {
  const uri = JSON.parse(fs.readFileSync(file, "utf8")).images[0].uri;
  const png = PNG.sync.read(Buffer.from(uri.slice(uri.indexOf(",") + 1), "base64"));
  return { w: png.width, h: png.height, px: new Uint8Array(png.data) };
}
for (const f of fixtures) {
  if (f.png) Object.assign(f, (({ w, h, px }) => ({ w, h, src: px }))(gltfPng(f.png)));
  const src = f.src || picture(f.w, f.h, f.kind);
  const ktx = await encodeToKTX2(src, { ...f.opts, imageDecoder: async (b) => ({ data: b, width: f.w, height: f.h }) });
  if (f.random) { // the base level's blocks replaced (stored as they are: no supercompression)
    const blocks = await validRandomBlocks((f.w / 4) * (f.h / 4));
    const at = Number(Buffer.from(ktx.buffer, ktx.byteOffset).readBigUInt64LE(80));
    if (Number(Buffer.from(ktx.buffer, ktx.byteOffset).readBigUInt64LE(88)) !== blocks.length) throw new Error(f.name + ": level size");
    blocks.copy(Buffer.from(ktx.buffer, ktx.byteOffset, ktx.length), at);
  }
  fs.writeFileSync(path.join(outDir, f.name + ".ktx2"), ktx);
  const t = transcodeBaseLevel(basis, ktx);
  if (t.width !== f.w || t.height !== f.h) throw new Error(f.name + ": unexpected size");
  fs.writeFileSync(path.join(outDir, f.name + ".rgba"), t.rgba);
  console.log(`${f.name}: ${f.w} x ${f.h}, ${ktx.length} bytes, ${t.codec}${t.alpha ? " with alpha" : ""}, ` +
              `${t.levels} level(s)`);
}
