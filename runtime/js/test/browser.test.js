// The viewer page (runtime/web) in headless Chromium against the C renderer:
// the demo scene baked by probebake, drawn indirect-only by three.js through
// runtime/js/three-probes.js (linear float target, read back by the page) and
// by `probebake render --mode indirect` (the Vulkan kernel through the same
// sampling code) at the same camera and size; plus a malformed volume and a
// page whose module does not load, which the page must report, not draw.
// Needs a Vulkan device (lavapipe) for the bake and the render, Debian's
// chromium, and runtime/node_modules (npm ci).
//   PB_PROBEBAKE=build/probebake PB_CHROMIUM=/usr/bin/chromium node --test runtime/js/test/browser.test.js
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { createServer } from 'node:http';
import { mkdtempSync, readFileSync, writeFileSync, rmSync, existsSync, statSync, copyFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, normalize, extname, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseProbes } from '../probes.js';
import { launch } from './headless.js';

const root = normalize(join(dirname(fileURLToPath(import.meta.url)), '..', '..', '..'));
const probebake = process.env.PB_PROBEBAKE;
const chromium = process.env.PB_CHROMIUM || '/usr/bin/chromium';
const dir = mkdtempSync(join(tmpdir(), 'pb-browser-'));
const W = 160, H = 120;
const camera = ['--eye', '0,1.5,2.3', '--target', '0,1.2,0', '--fov', '60'];
let server, base;

const types = { '.html': 'text/html', '.js': 'text/javascript', '.json': 'application/json', '.gltf': 'model/gltf+json' };

// a static server: the repository at /, the test's files at /t/
before(async () => {
    server = createServer((req, res) => {
        const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
        const file = path.startsWith('/t/') ? join(dir, path.slice(3)) : join(root, path);
        if (!file.startsWith(root) && !file.startsWith(dir)) { res.writeHead(403).end(); return; }
        if (!existsSync(file) || !statSync(file).isFile()) { res.writeHead(404).end(); return; }
        res.writeHead(200, { 'content-type': types[extname(file)] || 'application/octet-stream' });
        res.end(readFileSync(file));
    });
    await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
    base = `http://127.0.0.1:${server.address().port}`;
});
after(() => { server.close(); if (!process.env.PB_KEEP) rmSync(dir, { recursive: true, force: true }); else console.log(`# kept ${dir}`); });

// the page in headless Chromium's WebGL2 on a software Vulkan (lavapipe where
// installed, see headless.js; the result names it); its
// result once it has written one (two minutes of real time at most: the
// slowest page seen took 12 s on a loaded 2-core machine)
const PAGE_TIMEOUT_MS = 120000;
async function pageResult(query) {
    const browser = await launch(chromium, W, H);
    try {
        await browser.goto(`${base}/runtime/web/index.html?${query}`);
        const text = await browser.waitFor("document.getElementById('pb-result').textContent", PAGE_TIMEOUT_MS);
        const r = JSON.parse(text);
        // the message a user sees over the canvas
        r.shownError = await browser.evaluate(
            "(e => e.style.display === 'block' ? e.textContent : null)(document.getElementById('error'))");
        return r;
    } finally {
        await browser.close();
    }
}

function readPFM(path) {
    const b = readFileSync(path);
    const head = b.subarray(0, 64).toString('latin1').split('\n');
    const [w, h] = head[1].split(' ').map(Number);
    const offset = head[0].length + head[1].length + head[2].length + 3;
    const f = new Float32Array(b.buffer.slice(b.byteOffset + offset, b.byteOffset + offset + w * h * 12));
    const rgb = new Float32Array(w * h * 3); // top row first
    for (let y = 0; y < h; ++y) rgb.set(f.subarray(3 * w * (h - 1 - y), 3 * w * (h - y)), 3 * w * y);
    return { w, h, rgb };
}

// The page's indirect-only image of a scene (the demo unless `scene`, a path
// the server knows) lit by /t/PROBES against the C renderer's PFMs: surface
// pixels, the metric of `render --mode diff`. Returns the relative RMSE
// against each PFM; the first must be within rounding (below).
async function pageMatchesC(probes, pfm, scene = '/tests/scenes/demo.gltf', view = 'eye=0,1.5,2.3&target=0,1.2,0&fov=60',
    others = [], minCovered = 0.5, bound = 1e-3) {
    const c = readPFM(join(dir, pfm));
    const q = `scene=${scene}&probes=/t/${probes}&mode=indirect&test=1&w=${W}&h=${H}&${view}`;
    const r = await pageResult(q);
    assert.equal(r.error, undefined, r.error);
    assert.equal(r.width, W);
    assert.equal(r.height, H);
    assert.equal(r.nan, 0, 'NaN or infinite pixels');
    if (r.mapFormats && r.mapFormats.length) console.log(`# colour maps held as ${r.mapFormats.join(', ')}`);
    const bytes = Buffer.from(r.rgb, 'base64');
    const js = new Float32Array(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.length));
    const misplaced = Buffer.from(r.misplaced, 'base64');
    // surface pixels: where the C image has indirect light, less those the
    // page found shaded at a misplaced point (viewer.js, `check`); the metric of
    // `render --mode diff`: RMS difference over the mean
    let se = 0, sum = 0, count = 0, far = 0, worst = 0;
    const lum = (a, i) => 0.2126 * a[3 * i] + 0.7152 * a[3 * i + 1] + 0.0722 * a[3 * i + 2];
    for (let i = 0; i < W * H; ++i) {
        const lc = lum(c.rgb, i), lj = lum(js, i);
        if (!(lc > 0) || misplaced[i]) continue;
        ++count;
        sum += lc;
        se += (lj - lc) ** 2;
        far += Math.abs(lj - lc) > 0.01 * lc;
        worst = Math.max(worst, Math.abs(lj - lc) / lc);
    }
    const rrmse = Math.sqrt(se / count) / (sum / count);
    console.log(`# drawn by ${r.glRenderer}`);
    console.log(`# ${count} surface pixels (${r.misplacedCount} left out as misplaced): relative RMSE ` +
        `${rrmse.toExponential(2)}, ${far} differ by more than 1 %, worst ${worst.toExponential(2)}`);
    assert.ok(r.misplacedCount <= 0.01 * W * H, `${r.misplacedCount} pixels shaded away from where they were drawn`);
    assert.ok(count > minCovered * W * H, `${count} pixels compared`);
    // Same data (float32 SH and positions, the same float16 depth texels) and
    // the same GLSL: what differs is float rounding of the shading point
    // (interpolated by the rasterizer, hit by a ray in C) and of the sampler's
    // arithmetic on two devices. The bound: 1e-3, ten times the 1e-4 that
    // test_sample allows between the Vulkan sampler and its C reference per
    // query; pixels at silhouettes (the other surface) are few and count in it.
    assert.ok(rrmse < bound, `relative RMSE ${rrmse}`);
    // the same metric against other C images (same surface pixels)
    return [rrmse, ...others.map((f) => {
        const o = readPFM(join(dir, f));
        let se2 = 0, sum2 = 0, n2 = 0;
        for (let i = 0; i < W * H; ++i) {
            const lc = lum(c.rgb, i);
            if (!(lc > 0) || misplaced[i]) continue;
            const lo = lum(o.rgb, i);
            ++n2, sum2 += lc, se2 += (lum(js, i) - lo) ** 2;
        }
        return Math.sqrt(se2 / n2) / (sum2 / n2);
    })];
}

test('the page lights the demo scene as the C renderer does', async () => {
    assert.ok(probebake, 'PB_PROBEBAKE names the probebake binary');
    const scene = join(root, 'tests/scenes/demo.gltf');
    execFileSync(probebake, ['bake', scene, '--spacing', '0.5', '--rays', '128', '--passes', '2', '--quiet',
        '-o', join(dir, 'demo.probes')]);
    execFileSync(probebake, ['render', scene, '--volume', join(dir, 'demo.probes'), '--mode', 'indirect',
        '--size', `${W}x${H}`, '--spp', '1', ...camera, '--pfm', '--quiet', '-o', join(dir, 'c.png')]);
    // the reader on a real bake: every probe's SH as `inspect --json` prints it
    const v = parseProbes(new Uint8Array(readFileSync(join(dir, 'demo.probes'))), 'demo.probes');
    const j = JSON.parse(execFileSync(probebake, ['inspect', join(dir, 'demo.probes'), '--json'],
        { maxBuffer: 1 << 28 }).toString());
    assert.equal(j.probe_list.length, v.probeCount);
    for (const p of j.probe_list)
        for (let k = 0; k < 27; ++k) assert.equal(v.sh[27 * p.index + k], Math.fround(p.sh[k]), `probe ${p.index}`);
    await pageMatchesC('demo.probes', 'c.pfm');
});

test('the page lights the demo scene from sparse bricks as the C renderer does', async () => {
    // three levels refined where the probes disagree: cages at every level and
    // lookups that cross level boundaries, through the R32UI layout texture
    const scene = join(root, 'tests/scenes/demo.gltf');
    const out = execFileSync(probebake, ['bake', scene, '--layout', 'sparse', '--spacing', '0.5', '--max-level', '2',
        '--refine-error', '0.3', '--rays', '64', '--passes', '2', '-o', join(dir, 'sparse.probes')],
        { stdio: ['ignore', 'pipe', 'pipe'] }).toString();
    const v = parseProbes(new Uint8Array(readFileSync(join(dir, 'sparse.probes'))), 'sparse.probes');
    assert.ok(v.sparse && v.sparse.levels === 3, 'a sparse volume of 3 levels');
    const perLevel = [0, 0, 0];
    for (let b = 0; b < v.sparse.brickCount; ++b) ++perLevel[v.sparse.bricks[4 * b + 3]];
    assert.ok(perLevel.every((n) => n > 0), `bricks at every level: ${perLevel} (${out.trim()})`);
    execFileSync(probebake, ['render', scene, '--volume', join(dir, 'sparse.probes'), '--mode', 'indirect',
        '--size', `${W}x${H}`, '--spp', '1', ...camera, '--pfm', '--quiet', '-o', join(dir, 'c-sparse.png')]);
    await pageMatchesC('sparse.probes', 'c-sparse.pfm');
});

// three.js shades with the mesh's vertex normals, and so do the bake and the
// C renderer (docs/bake.md, "Shading normals"): the glTF Duck, its texture
// left out (three.js filters it, the C renderer reads the nearest texel),
// baked under a white sky and drawn indirect-only by both. Against the C
// image with face normals the page must differ far more than rounding.
test('the page shades the Duck with its vertex normals as the C renderer does', async (t) => {
    const duckDir = join(root, '..', 'shared', 'scenes', 'samples', 'Duck');
    if (!existsSync(join(duckDir, 'Duck.gltf'))) { t.skip(`${duckDir} absent`); return; }
    const g = JSON.parse(readFileSync(join(duckDir, 'Duck.gltf'), 'utf8'));
    for (const m of g.materials) {
        delete m.pbrMetallicRoughness.baseColorTexture;
        m.pbrMetallicRoughness.baseColorFactor = [0.8, 0.7, 0.2, 1];
    }
    delete g.textures; delete g.images; delete g.samplers;
    writeFileSync(join(dir, 'duck.gltf'), JSON.stringify(g));
    copyFileSync(join(duckDir, 'Duck0.bin'), join(dir, 'Duck0.bin'));
    const scene = join(dir, 'duck.gltf');
    const view = ['--eye', '1.6,1.4,1.6', '--target', '0.1,0.8,0', '--fov', '60'];
    execFileSync(probebake, ['bake', scene, '--spacing', '0.25', '--sky', '1,1,1', '--rays', '128', '--passes', '2',
        '--quiet', '-o', join(dir, 'duck.probes')]);
    for (const [normals, png] of [['vertex', 'c-duck.png'], ['face', 'c-duck-face.png']])
        execFileSync(probebake, ['render', scene, '--volume', join(dir, 'duck.probes'), '--mode', 'indirect',
            '--size', `${W}x${H}`, '--spp', '1', ...view, '--shading-normals', normals, '--pfm', '--quiet',
            '-o', join(dir, png)]);
    const [same, face] = await pageMatchesC('duck.probes', 'c-duck.pfm', '/t/duck.gltf',
        'eye=1.6,1.4,1.6&target=0.1,0.8,0&fov=60', ['c-duck-face.pfm'], 0.1);
    console.log(`# against the C image with face normals: relative RMSE ${face.toExponential(2)}`);
    assert.ok(face > 10 * Math.max(same, 1e-4), `face normals ${face} vs vertex normals ${same}`);
});

// The viewer reads what the baker reads (README, "glTF extensions"): the demo
// scene with its geometry as Draco and as meshopt (tests/gltf_compress) and its
// lattice texture as KTX2, ETC1S with Draco and UASTC (Zstandard) with meshopt
// (tests/data/ktx2/demo_lattice*.ktx2, written by Basis Universal's encoder;
// KHR_texture_basisu required, no PNG kept), each
// baked, then drawn indirect-only by the C renderer and by the page (three.js's
// Draco, meshopt and Basis Universal decoders) within the demo's bound. Before,
// the page's plain GLTFLoader refused all three.
test('the page reads Draco, meshopt and KTX2 files as the baker does', async () => {
    const compress = process.env.PB_GLTF_COMPRESS;
    assert.ok(compress, 'PB_GLTF_COMPRESS names tests/gltf_compress');
    for (const [codec, lattice] of [['draco', 'demo_lattice'], ['meshopt', 'demo_lattice_uastc']]) {
        copyFileSync(join(root, `tests/data/ktx2/${lattice}.ktx2`), join(dir, `${lattice}.ktx2`));
        const file = join(dir, `demo-${codec}.gltf`);
        execFileSync(compress, [codec, join(root, 'tests/scenes/demo.gltf'), file]);
        const g = JSON.parse(readFileSync(file, 'utf8'));
        g.images = [{ uri: `${lattice}.ktx2`, mimeType: 'image/ktx2' }];
        for (const tex of g.textures) {
            delete tex.source;
            tex.extensions = { ...tex.extensions, KHR_texture_basisu: { source: 0 } };
        }
        for (const list of ['extensionsUsed', 'extensionsRequired'])
            g[list] = [...new Set([...(g[list] || []), 'KHR_texture_basisu'])];
        writeFileSync(file, JSON.stringify(g));
        const info = JSON.parse(execFileSync(probebake, ['info', file, '--json']).toString());
        assert.ok(info.extensions_applied.includes('KHR_texture_basisu') && info.textures === 1,
            `${codec}: ${JSON.stringify(info.extensions_applied)}, ${info.textures} textures`);
        execFileSync(probebake, ['bake', file, '--spacing', '0.5', '--rays', '128', '--passes', '2', '--quiet',
            '-o', join(dir, `demo-${codec}.probes`)]);
        execFileSync(probebake, ['render', file, '--volume', join(dir, `demo-${codec}.probes`), '--mode', 'indirect',
            '--size', `${W}x${H}`, '--spp', '1', ...camera, '--pfm', '--quiet', '-o', join(dir, `c-${codec}.png`)]);
        await pageMatchesC(`demo-${codec}.probes`, `c-${codec}.pfm`, `/t/demo-${codec}.gltf`);
    }
});

test('a malformed volume gives a visible error, not a blank canvas', async () => {
    const good = readFileSync(join(dir, 'demo.probes'));
    writeFileSync(join(dir, 'cut.probes'), good.subarray(0, 700));
    const newer = Buffer.from(good);
    newer.writeUInt32LE(99, 8);
    writeFileSync(join(dir, 'newer.probes'), newer);
    for (const [file, needle] of [['cut.probes', 'truncated'], ['newer.probes', 'version 99'],
        ['missing.probes', 'HTTP 404']]) {
        const r = await pageResult(`scene=/tests/scenes/demo.gltf&probes=/t/${file}&test=1&w=${W}&h=${H}`);
        assert.ok(r.error && r.error.includes(needle), `${file}: ${JSON.stringify(r).slice(0, 200)}`);
        assert.ok(r.shownError && r.shownError.includes(needle), `${file}: the page shows no error`);
    }
    // a page whose module cannot load (here: the page away from viewer.js and
    // three.js) says so instead of staying blank
    copyFileSync(join(root, 'runtime/web/index.html'), join(dir, 'index.html'));
    const browser = await launch(chromium, W, H);
    try {
        await browser.goto(`${base}/t/index.html?scene=/tests/scenes/demo.gltf&probes=/t/demo.probes&test=1`);
        const r = JSON.parse(await browser.waitFor("document.getElementById('pb-result').textContent",
            PAGE_TIMEOUT_MS));
        assert.match(r.error || '', /could not load .*\/t\/viewer\.js/, JSON.stringify(r));
    } finally {
        await browser.close();
    }
});

test('a Chromium that stops answering fails the command, not the run', async () => {
    const browser = await launch(chromium, W, H, { commandTimeoutMs: 2000 });
    process.kill(browser.pid, 'SIGSTOP');
    try {
        await assert.rejects(browser.evaluate('1 + 1'), /Runtime\.evaluate: no reply from .* in 2000 ms/);
    } finally {
        process.kill(browser.pid, 'SIGCONT');
        await browser.close();
    }
});

test('a screenshot of the page', async () => {
    const browser = await launch(chromium, 640, 480);
    try {
        await browser.goto(`${base}/runtime/web/index.html?scene=/tests/scenes/demo.gltf&probes=/t/demo.probes` +
            '&eye=0,1.5,2.3&target=0,1.2,0&fov=60');
        // the viewer names the volume once it is set up, then draws every frame
        const info = await browser.waitFor(
            "document.getElementById('error').textContent || document.getElementById('info').textContent",
            PAGE_TIMEOUT_MS);
        assert.match(info, /^\d+ probes \(/, info); // not an error
        await browser.evaluate('new Promise((ok) => requestAnimationFrame(() => requestAnimationFrame(ok)))');
        const png = await browser.screenshot();
        assert.ok(png.length > 10000, 'a non-trivial PNG');
        writeFileSync(join(dir, 'viewer.png'), png);
        if (process.env.PB_SCREENSHOT) copyFileSync(join(dir, 'viewer.png'), process.env.PB_SCREENSHOT);
    } finally {
        await browser.close();
    }
});
