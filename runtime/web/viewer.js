// probebake viewer: loads a glTF scene with three.js's GLTFLoader and its
// .probes volume, lights the scene's standard materials with the volume
// (runtime/js/three-probes.js), orbit camera, toggles. Query parameters:
//   scene, probes        URLs of the glTF and the volume (required)
//   eye, target, fov     camera (x,y,z; x,y,z; vertical degrees), else the
//                        scene's first camera, else a view of the bounds
//   mode                 full | direct | indirect (the radio buttons)
//   test=1, w, h         render once at w x h in the chosen mode into a float
//                        target, linear (no tone mapping), and write the image
//                        and a summary into <pre id="pb-result"> as JSON: what
//                        runtime/js/test/browser.test.js reads through headless
//                        Chromium
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { KTX2Loader } from 'three/addons/loaders/KTX2Loader.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { parseProbes } from '../js/probes.js';
import { ProbeVolume } from '../js/three-probes.js';

const params = new URLSearchParams(location.search);
const testing = params.get('test') === '1';
const vec = (name) => params.get(name) && params.get(name).split(',').map(Number);

// index.html's reporter: the error over the canvas and, for the test, in pb-result
const showError = globalThis.pbShowError;

async function fetchBytes(url) {
    const r = await fetch(url);
    if (!r.ok) throw new Error(`${url}: HTTP ${r.status} ${r.statusText}`);
    return r.arrayBuffer();
}

// A GLTFLoader for what the baker reads (README, "glTF extensions"): Draco and
// meshopt geometry and KTX2 textures, through the decoders three.js ships
// (Google's Draco and Binomial's Basis Universal transcoder as WebAssembly,
// meshoptimizer's decoder). KTX2 is transcoded to a format the renderer's
// device samples, so the loader asks the renderer first.
function gltfLoader(renderer) {
    const libs = new URL('../node_modules/three/examples/jsm/libs/', import.meta.url).href;
    return new GLTFLoader()
        .setDRACOLoader(new DRACOLoader().setDecoderPath(`${libs}draco/gltf/`))
        .setKTX2Loader(new KTX2Loader().setTranscoderPath(`${libs}basis/`).detectSupport(renderer))
        .setMeshoptDecoder(MeshoptDecoder);
}

function probeSpheres(v) {
    // a sparse volume's spacing is its finest level's
    const s = v.sparse ? Math.min(...v.spacing) : Math.min(...v.spacing.filter((x, k) => v.counts[k] > 1), Infinity);
    const r = Number.isFinite(s) ? 0.08 * s : 0.05;
    const mesh = new THREE.InstancedMesh(new THREE.SphereGeometry(r, 16, 8), new THREE.MeshBasicMaterial(),
        v.probeCount);
    const m = new THREE.Matrix4(), c = new THREE.Color();
    for (let p = 0; p < v.probeCount; ++p) {
        // a sparse volume's empty probe (docs/sparse.md, step 7) is not a place: scaled away
        if (v.sparse && v.flags[p] === 0) m.makeScale(0, 0, 0);
        else m.makeTranslation(v.origin[0] + v.positions[3 * p], v.origin[1] + v.positions[3 * p + 1],
            v.origin[2] + v.positions[3 * p + 2]);
        mesh.setMatrixAt(p, m);
        if (v.flags[p] & 1) // mean radiance E / pi from the DC term (Y00 = 0.282095)
            c.setRGB(...[0, 1, 2].map((k) => Math.max(0, v.sh[27 * p + k] * 0.282095 / Math.PI)),
                THREE.LinearSRGBColorSpace);
        else
            c.setRGB(1, 0.05, 0.05);
        mesh.setColorAt(p, c);
    }
    mesh.visible = false;
    return mesh;
}

// Test mode's second pass: per pixel, the distance between the shading
// position the fragment got (the interpolated world position the volume is
// sampled at) and the position its depth and window coordinates give. They
// agree to the depth buffer's precision on a correct rasterizer and page.
// Chromium's bundled SwiftShader shades blocks of the demo's floor 2 cm to
// 20 cm from where it draws them (depth and the interpolated world position
// disagree; lavapipe's and the C renderer's agree: runtime/js/test/headless.js);
// the test reports such pixels, leaves them
// out of the comparison and allows at most 1 % of them.
const check = { on: false, invProj: new THREE.Matrix4(), camWorld: new THREE.Matrix4(), size: new THREE.Vector2() };
function checkable(m) {
    const inner = m.onBeforeCompile;
    m.onBeforeCompile = (sh, r) => {
        inner(sh, r);
        if (!check.on) return;
        Object.assign(sh.uniforms, { pbInvProj: { value: check.invProj }, pbCamWorld: { value: check.camWorld },
            pbSize: { value: check.size } });
        sh.fragmentShader = 'uniform mat4 pbInvProj;\nuniform mat4 pbCamWorld;\nuniform vec2 pbSize;\n' +
            sh.fragmentShader.replace(/}\s*$/, `    vec4 pb_ndc = vec4(gl_FragCoord.xy / pbSize * 2.0 - 1.0, gl_FragCoord.z * 2.0 - 1.0, 1.0);
    vec4 pb_vp = pbInvProj * pb_ndc;
    vec3 pb_fc = (pbCamWorld * vec4(pb_vp.xyz / pb_vp.w, 1.0)).xyz;
    gl_FragColor = vec4(distance(pb_fc, pb_world_position), 0.0, 0.0, 1.0);
}`);
    };
    m.customProgramCacheKey = () => `probebake-volume${check.on ? '-check' : ''}`;
}

async function main() {
    const sceneUrl = params.get('scene'), probesUrl = params.get('probes');
    if (!sceneUrl || !probesUrl) throw new Error('give ?scene=URL.gltf&probes=URL.probes');
    const width = testing ? Number(params.get('w') || 256) : innerWidth;
    const height = testing ? Number(params.get('h') || 192) : innerHeight;
    const renderer = new THREE.WebGLRenderer({ antialias: !testing, preserveDrawingBuffer: true });
    renderer.setPixelRatio(testing ? 1 : devicePixelRatio);
    renderer.setSize(width, height);
    renderer.toneMapping = THREE.ACESFilmicToneMapping;
    document.body.appendChild(renderer.domElement);

    // parseProbes throws, naming the problem, for a malformed or newer file:
    // reported as soon as the volume arrives, not after the scene has loaded
    const [gltf, v] = await Promise.all([gltfLoader(renderer).loadAsync(sceneUrl),
        fetchBytes(probesUrl).then((bytes) => parseProbes(bytes, probesUrl))]);
    const volume = new ProbeVolume(v);

    const scene = gltf.scene;
    scene.background = new THREE.Color(0, 0, 0);
    const lights = [], emissive = new Map();
    scene.traverse((o) => {
        if (o.isLight) lights.push(o);
        if (o.isMesh) {
            for (const m of Array.isArray(o.material) ? o.material : [o.material]) {
                if (!m.isMeshStandardMaterial || emissive.has(m)) continue;
                volume.applyTo(m);
                if (testing) checkable(m);
                if (testing) { // shade as the C renderer does: nearest texel (src/bvh/alpha.h); both shade
                    // with the vertex normals (docs/bake.md, "Shading normals"), flat where a mesh has none
                    for (const t of [m.map, m.emissiveMap])
                        if (t) { t.minFilter = t.magFilter = THREE.NearestFilter; t.generateMipmaps = false; t.needsUpdate = true; }
                }
                emissive.set(m, m.emissive.clone());
            }
        }
    });
    const spheres = probeSpheres(v);
    scene.add(spheres);

    const box = new THREE.Box3().setFromObject(scene);
    const camera = new THREE.PerspectiveCamera(Number(params.get('fov') || 60), width / height,
        0.01 * box.getSize(new THREE.Vector3()).length(), 100 * box.getSize(new THREE.Vector3()).length());
    const eye = vec('eye'), target = vec('target');
    if (eye && target) {
        camera.position.set(...eye);
        camera.lookAt(...target);
    } else if (gltf.cameras.length) {
        const c = gltf.cameras[0];
        c.updateWorldMatrix(true, false);
        camera.position.setFromMatrixPosition(c.matrixWorld);
        camera.quaternion.setFromRotationMatrix(c.matrixWorld);
        if (c.isPerspectiveCamera) camera.fov = c.fov;
    } else {
        camera.position.copy(box.getCenter(new THREE.Vector3())).add(new THREE.Vector3(0, 0, box.getSize(new THREE.Vector3()).z));
    }
    camera.updateProjectionMatrix();
    camera.updateMatrixWorld();
    check.invProj.copy(camera.projectionMatrixInverse);
    check.camWorld.copy(camera.matrixWorld);

    // modes: the volume holds direct light unless it was baked with --direct exclude,
    // so 'full' shows three's lights only when the volume lacks them
    function setMode(mode) {
        const lightsOn = mode === 'direct' || (mode === 'full' && !v.directIncluded);
        for (const l of lights) l.visible = lightsOn;
        volume.uniforms.pb_intensity.value = mode === 'direct' ? 0 : 1;
        for (const [m, e] of emissive) m.emissive.copy(mode === 'indirect' ? new THREE.Color(0, 0, 0) : e);
        document.getElementById('info').textContent =
            `${v.probeCount} probes (${v.sparse ? `${v.sparse.brickCount} bricks, ${v.sparse.levels} levels` : v.counts.join(' x ')}), direct light ${v.directIncluded ? 'in the volume' : 'from three.js lights'}`;
    }
    const mode = params.get('mode') || 'full';
    for (const input of document.querySelectorAll('input[name=mode]')) {
        input.checked = input.value === mode;
        input.addEventListener('change', () => setMode(input.value));
    }
    document.getElementById('spheres').addEventListener('change', (e) => { spheres.visible = e.target.checked; });
    setMode(mode);

    if (testing) {
        // linear radiance, no tone mapping: a float target read back row by row (bottom row first)
        const rt = new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType });
        renderer.setRenderTarget(rt);
        renderer.render(scene, camera);
        const px = new Float32Array(width * height * 4);
        renderer.readRenderTargetPixels(rt, 0, 0, width, height, px);
        renderer.setRenderTarget(null);
        renderer.render(scene, camera); // the canvas too, for a screenshot
        check.on = true;
        check.size.set(width, height);
        for (const m of emissive.keys()) m.needsUpdate = true;
        renderer.setRenderTarget(rt);
        renderer.render(scene, camera);
        const dist = new Float32Array(width * height * 4);
        renderer.readRenderTargetPixels(rt, 0, 0, width, height, dist);
        renderer.setRenderTarget(null);
        const rgb = new Float32Array(width * height * 3), misplaced = new Uint8Array(width * height);
        let nan = 0, misplacedCount = 0;
        for (let y = 0; y < height; ++y)
            for (let x = 0; x < width; ++x) {
                const src = (height - 1 - y) * width + x; // top row first, as the C image
                for (let k = 0; k < 3; ++k) {
                    const f = px[4 * src + k];
                    nan += Number.isNaN(f) || !Number.isFinite(f);
                    rgb[3 * (y * width + x) + k] = f;
                }
                // 2 cm: far above the 16-bit depth buffer's error here, far below what was seen
                if (dist[4 * src] > 0.02) misplaced[y * width + x] = 1, ++misplacedCount;
            }
        const bytes8 = new Uint8Array(rgb.buffer);
        let bin = '';
        for (let i = 0; i < bytes8.length; i += 8192) bin += String.fromCharCode(...bytes8.subarray(i, i + 8192));
        const b64 = btoa(bin);
        let mbin = '';
        for (let i = 0; i < misplaced.length; i += 8192) mbin += String.fromCharCode(...misplaced.subarray(i, i + 8192));
        // which WebGL implementation drew it (the test logs it: software drivers differ)
        const gl = renderer.getContext(), info = gl.getExtension('WEBGL_debug_renderer_info');
        const glRenderer = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
        // the colour maps as the device holds them: a KTX2 texture's transcoded format (three.js's
        // constant) is what the test needs to know how exactly its texels can match
        const maps = [...emissive.keys()].map((m) => m.map).filter(Boolean);
        const mapFormats = [...new Set(maps.map((t) => `${t.isCompressedTexture ? 'compressed ' : ''}${t.format}`))];
        document.getElementById('pb-result').textContent = JSON.stringify({ width, height, nan, rgb: b64,
            misplaced: btoa(mbin), misplacedCount, glRenderer, mapFormats });
        return;
    }
    // orbit about the point ahead of the camera, as far as the scene's centre
    // (taken before OrbitControls, whose constructor turns the camera to its target)
    const ahead = camera.getWorldDirection(new THREE.Vector3());
    const pivot = eye && target ? new THREE.Vector3(...target) : camera.position.clone().addScaledVector(ahead,
        Math.max(0.1, camera.position.distanceTo(box.getCenter(new THREE.Vector3()))));
    const controls = new OrbitControls(camera, renderer.domElement);
    controls.target.copy(pivot);
    controls.update();
    addEventListener('resize', () => {
        camera.aspect = innerWidth / innerHeight;
        camera.updateProjectionMatrix();
        renderer.setSize(innerWidth, innerHeight);
    });
    renderer.setAnimationLoop(() => { controls.update(); renderer.render(scene, camera); });
}

main().catch((e) => showError(e.message));
