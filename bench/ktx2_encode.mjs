// Rewrites a glTF's PNG and JPEG textures as KTX2 (KHR_texture_basisu,
// required, no fallback images: what npm's ktx2-encoder does to an asset)
// with Basis Universal's encoder: ETC1S or UASTC, mipmapped, quality 128.
// bench/gltf_transform_check.sh copies it beside the packages it installs
// (@gltf-transform/core and extensions, ktx2-encoder, pngjs, jpeg-js) and runs
//   node ktx2_encode.mjs SOURCE.gltf OUT.glb etc1s|uastc
import { NodeIO } from "@gltf-transform/core";
import { ALL_EXTENSIONS } from "@gltf-transform/extensions";
import { ktx2 } from "ktx2-encoder/gltf-transform";
import { PNG } from "pngjs";
import jpeg from "jpeg-js";

const [src, dst, codec] = process.argv.slice(2);
if (codec !== "etc1s" && codec !== "uastc") throw new Error("ktx2_encode: codec etc1s or uastc");
// the encoder takes RGBA8: PNG and JPEG decoded in JavaScript
const imageDecoder = async (bytes) => {
  const b = Buffer.from(bytes);
  if (b[0] === 0x89) {
    const p = PNG.sync.read(b);
    return { data: new Uint8Array(p.data), width: p.width, height: p.height };
  }
  const j = jpeg.decode(b, { useTArray: true, formatAsRGBA: true, maxMemoryUsageInMB: 2048 });
  return { data: j.data, width: j.width, height: j.height };
};
const io = new NodeIO().registerExtensions(ALL_EXTENSIONS);
const doc = await io.read(src);
await doc.transform(ktx2({ isUASTC: codec === "uastc", generateMipmap: true, qualityLevel: 128, imageDecoder }));
await io.write(dst, doc);
