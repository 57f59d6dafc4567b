/* The feature mask the bake kernels are specialised to (PB_BAKE_FEATURES,
 * constant_id 2 in shaders/include/bake.glsl): one bit per estimator or
 * scene feature whose code can be compiled out. */
#ifndef PB_BAKE_FEATURES_H
#define PB_BAKE_FEATURES_H

#include "bake/bake_types.h"

#include <stddef.h>
#include <stdint.h>

enum {
    PB_FEATURE_PROBE_NEE = 1u << 0,     /* nee: light samples drawn from the probe */
    PB_FEATURE_GUIDE = 1u << 1,         /* guide: path guiding's learned table */
    PB_FEATURE_LIGHT_CELLS = 1u << 2,   /* light_cells: emitters drawn per cell */
    PB_FEATURE_VOLUME = 1u << 3,        /* volume: --indirect volume feedback */
    PB_FEATURE_LIGHT_SELECT = 1u << 4,  /* light_select: one punctual light drawn per hit */
    PB_FEATURE_EMITTERS = 1u << 5,      /* emitter_count: emissive triangles sampled */
    PB_FEATURE_ENVIRONMENT = 1u << 6,   /* env_count: the environment sampled */
    PB_FEATURE_LIGHTS = 1u << 7,        /* light_count: punctual lights */
    PB_FEATURE_VERTEX_COLORS = 1u << 8, /* scene.flags: COLOR_0 */
    PB_FEATURE_SHADING_NORMALS = 1u << 9, /* scene.flags: vertex normals bent from the faces */
    PB_FEATURE_TRANSMISSION = 1u << 10,   /* scene.flags: thin glass */
    PB_FEATURE_SOLID_ANGLE = 1u << 11,    /* emitters sampled by solid angle where near */
    PB_FEATURE_NORMAL_MAPS = 1u << 12,    /* scene.flags: normal maps bend the shading normals */
};

/* The features a pass with these parameters uses: a pipeline specialised to
 * a mask that lacks one of them would give wrong results, so the bake makes
 * its pipelines with the union over its passes and checks every pass. */
uint32_t pb_bake_features(const gpu_bake_params *p);

/* The mask's features by name, space-separated ("none" for 0), for logs. */
void pb_bake_features_name(uint32_t features, char *out, size_t size);

#endif
