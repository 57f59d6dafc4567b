// A probebake volume lighting three.js materials: the volume's textures (the
// layout runtime/probe_sample.glsl reads, docs/format.md "Texture contract")
// and a patch for MeshStandardMaterial / MeshPhysicalMaterial that adds the
// volume's irradiance to the diffuse indirect light, through the same
// sampling code as the C reference (runtime/js/probe_sample_glsl.js is
// generated from it).
//
//   import { parseProbes } from './probes.js';
//   import { ProbeVolume } from './three-probes.js';
//   const volume = new ProbeVolume(parseProbes(await (await fetch('demo.probes')).arrayBuffer()));
//   scene.traverse((o) => { if (o.isMesh) volume.applyTo(o.material); });
import * as THREE from 'three';
import { probeSampleGLSL } from './probe_sample_glsl.js';
import { sparseSamplerWords } from './probes.js';

const TEXELS_PER_ROW = 2048; // WebGL2 guarantees 2048 per side

function dataTexture(data, width, height, format, type) {
    const t = new THREE.DataTexture(data, width, height, format, type);
    t.minFilter = t.magFilter = THREE.NearestFilter; // the sampler fetches texels and weighs probes itself
    t.generateMipmaps = false;
    t.flipY = false;
    t.colorSpace = THREE.NoColorSpace;
    t.needsUpdate = true;
    return t;
}

/** The textures and uniforms of one volume (parseProbes' result): a grid,
 *  or sparse bricks (then the sampler is compiled with PB_SPARSE). */
export class ProbeVolume {
    constructor(v) {
        if (!v.grid && !v.sparse)
            throw new Error('the volume has placed points, not a grid or bricks: the sampler interpolates a grid');
        if (!v.irradiance) throw new Error('the volume holds radiance SH; the sampler reads irradiance');
        const P = v.probeCount, tile = v.tile;
        const words = v.sparse ? sparseSamplerWords(v.sparse) : null;
        // one width for every texture indexed by pb_texel_2d
        const W = Math.min(Math.max(7 * P, words ? words.length : 0), TEXELS_PER_ROW);
        const probes = new Float32Array(W * Math.ceil(P / W) * 4);
        const sh = new Float32Array(W * Math.ceil(7 * P / W) * 4);
        const T = Math.ceil(Math.sqrt(P)), rows = Math.ceil(P / T);
        const depth = new Uint16Array(T * tile * rows * tile * 2);
        const tileHalves = 2 * tile * tile;
        for (let p = 0; p < P; ++p) {
            probes.set(v.positions.subarray(3 * p, 3 * p + 3), 4 * p);
            probes[4 * p + 3] = v.flags[p];
            sh.set(v.sh.subarray(27 * p, 27 * p + 27), 28 * p);
            const tx = (p % T) * tile, ty = Math.floor(p / T) * tile;
            for (let y = 0; y < tile; ++y)
                depth.set(v.depth.subarray(p * tileHalves + 2 * y * tile, p * tileHalves + 2 * (y + 1) * tile),
                    2 * ((ty + y) * T * tile + tx));
        }
        this.volume = v;
        this.textures = {
            probes: dataTexture(probes, W, Math.ceil(P / W), THREE.RGBAFormat, THREE.FloatType),
            sh: dataTexture(sh, W, Math.ceil(7 * P / W), THREE.RGBAFormat, THREE.FloatType),
            depth: dataTexture(depth, T * tile, rows * tile, THREE.RGFormat, THREE.HalfFloatType),
        };
        if (words) { // R32UI, word i at texel i: the layout tables pb_sparse_word reads
            const padded = new Uint32Array(W * Math.ceil(words.length / W));
            padded.set(words);
            const t = dataTexture(padded, W, padded.length / W, THREE.RedIntegerFormat, THREE.UnsignedIntType);
            t.internalFormat = 'R32UI';
            this.textures.sparse = t;
        }
        // shared by every patched material: change .value to retune them all
        this.uniforms = {
            pb_probes: { value: this.textures.probes },
            pb_sh: { value: this.textures.sh },
            pb_depth: { value: this.textures.depth },
            pb_tex_width: { value: W },
            pb_depth_tiles_per_row: { value: T },
            pb_grid_origin: { value: new THREE.Vector3(0, 0, 0) },
            pb_grid_spacing: { value: new THREE.Vector3(...v.spacing) },
            // a sparse volume: the coarsest cells per axis (origin and spacing are the lattice's, the finest level's)
            pb_grid_counts: { value: Int32Array.from(v.sparse ? v.sparse.cells : v.counts) }, // ivec3: three sets int vectors from arrays
            pb_octmap_res: { value: v.n },
            pb_normal_bias: { value: 0.1 },
            pb_view_bias: { value: 0.1 },
            pb_depth_unit: { value: v.depthUnit },
            // the volume's frame: world minus the volume's origin
            pb_frame_origin: { value: new THREE.Vector3(...v.origin) },
            pb_intensity: { value: 1.0 },
        };
        if (words) {
            this.uniforms.pb_sparse = { value: this.textures.sparse };
            this.uniforms.pb_levels = { value: v.sparse.levels };
        }
    }

    /** Patches a MeshStandardMaterial or MeshPhysicalMaterial (in place) so
     *  the volume lights its diffuse indirect term; returns it. */
    applyTo(material) {
        if (!material.isMeshStandardMaterial)
            throw new Error('ProbeVolume.applyTo: a MeshStandardMaterial or MeshPhysicalMaterial');
        if (material.userData.probebakeVolume === this) return material; // shared by several meshes: once
        if (material.userData.probebakeVolume)
            throw new Error('ProbeVolume.applyTo: the material is lit by another volume already');
        material.userData.probebakeVolume = this;
        const uniforms = this.uniforms, previous = material.onBeforeCompile;
        material.onBeforeCompile = (shader, renderer) => {
            if (previous) previous.call(material, shader, renderer);
            Object.assign(shader.uniforms, uniforms);
            shader.vertexShader = shader.vertexShader
                .replace('void main() {', 'out vec3 pb_world_position;\nvoid main() {')
                .replace('#include <project_vertex>', `#include <project_vertex>
    {
        vec4 pb_p = vec4(transformed, 1.0);
#ifdef USE_INSTANCING
        pb_p = instanceMatrix * pb_p;
#endif
        pb_world_position = (modelMatrix * pb_p).xyz;
    }`);
            shader.fragmentShader = shader.fragmentShader
                .replace('void main() {', `in vec3 pb_world_position;
uniform vec3 pb_frame_origin;
uniform float pb_intensity;
${this.volume.sparse ? '#define PB_SPARSE\n' : ''}${probeSampleGLSL}
void main() {`)
                .replace('#include <lights_fragment_maps>', `#include <lights_fragment_maps>
    {
        // world-space normal and view direction; the volume's frame is world - pb_frame_origin
        vec3 pb_n = normalize(inverseTransformDirection(normal, viewMatrix));
        vec3 pb_v = normalize(cameraPosition - pb_world_position);
        irradiance += pb_intensity * pb_volume_irradiance(pb_world_position - pb_frame_origin, pb_n, pb_v);
    }`);
        };
        material.customProgramCacheKey = () => (this.volume.sparse ? 'probebake-volume-sparse' : 'probebake-volume');
        material.needsUpdate = true;
        return material;
    }

    dispose() {
        for (const t of Object.values(this.textures)) t.dispose();
    }
}
