// Binomial's Basis Universal transcoder under node: three.js's pinned build
// (runtime/node_modules, installed by scripts/install-deps.sh), shared by
// scripts/ktx2_to_png.mjs and scripts/make_ktx2_fixtures.mjs.
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
export const transcoderJs = path.join(root, 'runtime/node_modules/three/examples/jsm/libs/basis/basis_transcoder.js');

// A KTX2 file the transcoder refuses or cannot decode.
export class TranscodeError extends Error {}

export async function loadTranscoder(js = transcoderJs) {
    if (!fs.existsSync(js))
        throw new Error(`${js} is missing: scripts/install-deps.sh installs three.js into runtime/node_modules`);
    // an Emscripten module written for CommonJS or a browser global: given require and its paths
    const factory = new Function('require', '__filename', '__dirname', `${fs.readFileSync(js, 'utf8')}\nreturn BASIS;`);
    const BASIS = factory(createRequire(import.meta.url), js, path.dirname(js));
    const basis = await BASIS({ wasmBinary: fs.readFileSync(js.replace(/\.js$/, '.wasm')) });
    basis.initializeBasis();
    return basis;
}

const RGBA32 = 13; // transcoder_texture_format::cTFRGBA32

// The base level's first image of a KTX2 file as 8-bit RGBA, top row first.
export function transcodeBaseLevel(basis, bytes) {
    const file = new basis.KTX2File(new Uint8Array(bytes));
    try {
        if (!file.isValid()) throw new TranscodeError('not a KTX2 file the Basis Universal transcoder reads');
        if (!file.isETC1S() && !file.isUASTC()) throw new TranscodeError('a KTX2 image in neither ETC1S nor UASTC');
        const width = file.getWidth(), height = file.getHeight();
        if (!file.startTranscoding()) throw new TranscodeError('the transcoder cannot start on it');
        const rgba = new Uint8Array(file.getImageTranscodedSizeInBytes(0, 0, 0, RGBA32));
        if (rgba.length !== width * height * 4 || !file.transcodeImage(rgba, 0, 0, 0, RGBA32, 0, -1, -1))
            throw new TranscodeError('its base level does not transcode');
        return { width, height, rgba, codec: file.isUASTC() ? 'UASTC' : 'ETC1S', alpha: file.getHasAlpha(),
            levels: file.getLevels() };
    } finally {
        file.close();
        file.delete();
    }
}
