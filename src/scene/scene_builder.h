/* Scene builder: collects world-space triangles, materials, textures, lights
 * and cameras from a loader (the glTF wrapper, or an in-memory soup), drops
 * and counts bad triangles, then rebases everything to the AABB centre (on
 * all host cores; the same arrays on any number).
 * C interface so the one C++ file (gltf_load.cpp) stays a thin wrapper. */
#ifndef PB_SCENE_BUILDER_H
#define PB_SCENE_BUILDER_H

#include "probebake/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pb_scene_builder {
    pb_log log;
    /* triangles, world space */
    uint64_t count, capacity;
    double *pos;       /* 9 per triangle */
    float *nrm;        /* 9 per triangle */
    float *uv;         /* 6 per triangle */
    float *rgba;       /* 12 per triangle once any triangle has vertex colours (NULL before) */
    int rgba_pending;  /* rgba made by the last pb_sb_reserve: freed if its batch keeps no triangle */
    float *tan;        /* 12 per triangle once any triangle has tangents (NULL before; 0: none) */
    int tan_pending;   /* tan made by the last pb_sb_reserve: freed as rgba is */
    uint32_t *mat;
    /* everything else */
    pb_material *materials;
    uint32_t material_count, material_capacity;
    pb_texture *textures;
    uint32_t texture_count, texture_capacity;
    uint32_t *texels;
    uint64_t texel_count, texel_capacity;
    pb_light *lights;          /* position/direction fields unused: see light_world */
    double *light_world;       /* 6 per light: world position, world direction */
    uint32_t light_count, light_capacity;
    pb_camera *cameras;
    double *camera_world;      /* 9 per camera: position, forward, up */
    uint32_t camera_count, camera_capacity;
    pb_scene_stats stats;
    int out_of_memory;
} pb_scene_builder;

void pb_sb_init(pb_scene_builder *b, pb_log log);
void pb_sb_free(pb_scene_builder *b);

/* Adds one triangle. p: 9 doubles (world). n: 9 floats or NULL for the flat
 * normal. uv: 6 floats or NULL. rgba: 12 floats (vertex colours) or NULL for
 * white. Degenerate and non-finite triangles are counted and dropped.
 * Returns 0 only when out of memory. */
int pb_sb_add_triangle(pb_scene_builder *b, const double p[9], const float *n, const float *uv, const float *rgba,
                       uint32_t material);

/* A primitive's triangles in one batch, written on several threads:
 * pb_sb_reserve makes room for n more, pb_sb_put_triangle writes each into
 * its own slot (count + i, any thread, any order), and pb_sb_commit takes
 * the n slots in order, dropping those put refused. The arrays and counts
 * come out as n pb_sb_add_triangle calls leave them. */
/* Returns 0 when out of memory. colours: some triangle of the batch has
 * vertex colours (the triangles before it are then made white); tangents:
 * some has tangents (the triangles before it then have none). */
int pb_sb_reserve(pb_scene_builder *b, uint64_t n, int colours, int tangents);
/* Writes slot `slot` (at most count + n - 1 of the last reserve) as
 * pb_sb_add_triangle stores a triangle; touches no other slot and no
 * shared state. tangent: 12 floats (x, y, z, w per corner, world space) or
 * NULL for none; a corner whose tangent cannot be normalized, or whose w is
 * not finite, has none. Returns 0, writing nothing, for a non-finite
 * triangle. */
int pb_sb_put_triangle(pb_scene_builder *b, uint64_t slot, const double p[9], const float *n, const float *uv,
                       const float *rgba, const float *tangent, uint32_t material);
/* keep[i]: what put returned for slot count + i (NULL: all 1). */
void pb_sb_commit(pb_scene_builder *b, uint64_t n, const unsigned char *keep);

/* Appends and returns the index, or -1 when out of memory. */
int32_t pb_sb_add_material(pb_scene_builder *b, const pb_material *m);
/* Copies width*height RGBA8 texels (4 bytes each, R first; any alignment). */
int32_t pb_sb_add_texture(pb_scene_builder *b, const void *texels, uint32_t width, uint32_t height,
                          uint32_t wrap_s, uint32_t wrap_t, uint32_t srgb);
/* pos/dir: world space. */
int32_t pb_sb_add_light(pb_scene_builder *b, const pb_light *l, const double pos[3], const double dir[3]);
int32_t pb_sb_add_camera(pb_scene_builder *b, const pb_camera *c, const double pos[3], const double fwd[3],
                         const double up[3]);

/* Rebases and moves everything into a new pb_scene; the builder is emptied. */
pb_result pb_sb_finish(pb_scene_builder *b, const char *path, pb_scene **out, pb_error *err);

/* The glTF reader (gltf_load.cpp): fills b from the file. */
pb_result pb_gltf_read(const char *path, const pb_scene_desc *desc, pb_scene_builder *b, pb_error *err);

#ifdef __cplusplus
}
#endif
#endif
