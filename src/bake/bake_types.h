/* C mirrors of shaders/include/bake.glsl, field for field. */
#ifndef PB_BAKE_TYPES_H
#define PB_BAKE_TYPES_H

#include "bake/gpu_types.h"
#include "probebake/environment.h"
#include "sample/sample_gpu.h"

/* gpu_shade_material.tex[2] bits (ShadeMaterial.tex.z in bake.glsl) */
#define PB_MATERIAL_DOUBLE_SIDED 1
#define PB_MATERIAL_TAU_IN_ALPHA 2 /* pb_material.transmission_in_alpha */

typedef struct gpu_shade_material {
    float base_color[4];
    float emissive_metallic[4];
    int32_t tex[4]; /* base colour texture, emissive texture, PB_MATERIAL_* bits, transmission (float bits) */
    int32_t normal_map[2]; /* normal texture (-1: none), its scale (float bits): load_normal_map */
    int32_t tau_texture;   /* pb_material.transmission_texture: load_tau_texture */
    int32_t pad;
} gpu_shade_material;
_Static_assert(sizeof(gpu_shade_material) == 64, "ShadeMaterial layout");

typedef struct gpu_light {
    float position_type[4];
    float direction_range[4];
    float radiance[4];
    float cone[4];
} gpu_light;
_Static_assert(sizeof(gpu_light) == 64, "Light layout");

/* Pass indices from here on are relocation passes (their own RNG streams);
 * bake_trace then traces only each probe ray's first hit, all relocation
 * reads (bake.glsl has the same value). */
#define PB_RELOCATION_PASS 0x80000000u

/* Relocation's rays are turned by this seed, not the bake's: where a probe
 * ends up (and whether it is classified inside) does not change with
 * --seed, so bakes that differ in their seed compare probes at the same
 * places (bench/RESULTS.md, "Session 33's bake against the session's
 * start": a seed-dependent placement put a floor under that bench's probe
 * error). Still keyed by probe
 * and iteration: a part of a bake relocates its probes as the whole does. */
#define PB_RELOCATION_SEED 0x9e3779b9u

typedef struct gpu_bake_params {
    gpu_scene_refs scene;
    uint64_t materials, lights, probes, rotations, directions, rays, reduced, probe_list, emitters, emit_pdf, env,
        counters, nee;
    float env_rotation[4];
    uint32_t first_probe, probe_count, rays_per_probe, pass_index, seed, bounces, light_count, octmap_res;
    float max_distance, lobe_power;
    uint32_t direct;
    float lobe_cutoff;
    uint32_t emitter_count, env_width, env_height, env_count;
    gpu_volume_refs volume;
    uint64_t light_table;
    uint32_t light_select;
    float indirect_clamp;
    uint64_t guide, guide_slots;
    float guide_origin[4];
    uint32_t guide_dims[4];
    float light_origin[4];
    uint32_t light_dims[4];
    uint64_t light_cells, light_cell_slots, light_clusters, light_members, light_cluster_of;
    uint64_t depth_lists; /* bake_depth's ray lists (depth_lists.h) */
    uint64_t depth_sum;   /* bake_depth's sums over the passes: uint64 address per block (depth_sums.h) */
    uint32_t depth_block_probes; /* probe slots per block of them */
    uint32_t emitters_by_area;   /* pb_bake_desc.emitters_by_area */
} gpu_bake_params;
_Static_assert(offsetof(gpu_bake_params, env_rotation) == 160, "BakeParams layout");
_Static_assert(offsetof(gpu_bake_params, guide_origin) == 368, "BakeParams layout");
_Static_assert(offsetof(gpu_bake_params, light_cells) == 432, "BakeParams layout");
_Static_assert(sizeof(gpu_bake_params) == 496, "BakeParams layout");
_Static_assert(sizeof(pb_env_texel) == 32, "EnvTexel layout");

typedef struct gpu_emitter {
    uint32_t tri;
    float prob;
    uint32_t alias;
    float pad;
} gpu_emitter;
_Static_assert(sizeof(gpu_emitter) == 16, "Emitter layout");

typedef struct bake_push {
    uint64_t params;
    uint32_t spread;         /* bake_trace's workgroup stride (pb_dispatch_spread) */
    uint32_t paths_per_lane; /* bake_restart's K (1: one path per invocation, as bake_trace) */
    uint32_t lane_group;     /* bake_restart: invocations whose paths interleave (the device's subgroup) */
    uint32_t pad;
} bake_push;
_Static_assert(sizeof(bake_push) == 24, "bake push layout");

/* bake_wave.comp's push constants (src/bake/stages/wave.c). */
typedef struct wave_push {
    uint64_t params, wave, paths;
    uint32_t mode, in_q, out_c, out_s, zero_q, capacity;
} wave_push;
_Static_assert(sizeof(wave_push) == 48, "bake_wave push layout");

/* A wavefront path's state: bake_wave.comp's PB_WAVE_VEC4 + PB_WAVE_UVEC4. */
#define PB_WAVE_PATH_VEC4 16u

/* The depth filter ignores rays whose lobe weight cos^power is below 1e-4 of
 * the peak: cutoff = 1e-4^(1/power) (0.83 at power 50). */
float pb_depth_lobe_cutoff(float power);

/* Floats per probe in the reduced buffer (bake_sh.comp). */
#define PB_REDUCED_SH_STRIDE 40u

#endif
