/*
 * probebake scene: a glTF 2.0 file flattened to world-space triangles.
 *
 * The scene is a triangle soup: triangle i has its three vertices at
 * positions[9*i .. 9*i+8], in the scene's *local* frame, which is the world
 * frame translated by -origin (origin = centre of the world-space AABB, kept
 * in double so scenes 1e7 m from the world origin keep float precision).
 * Transforms are composed in double; only the rebased result is rounded to
 * float. Degenerate (zero-area), NaN and Inf triangles are dropped and
 * counted in pb_scene_stats.
 */
#ifndef PROBEBAKE_SCENE_H
#define PROBEBAKE_SCENE_H

#include "probebake/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum pb_alpha_mode {
    PB_ALPHA_OPAQUE = 0,
    PB_ALPHA_MASK = 1,
    PB_ALPHA_BLEND = 2
} pb_alpha_mode;

typedef enum pb_wrap {
    PB_WRAP_REPEAT = 0,
    PB_WRAP_CLAMP = 1,
    PB_WRAP_MIRROR = 2
} pb_wrap;

/* Linear-space factors exactly as glTF states them, emission already
 * multiplied by KHR_materials_emissive_strength. Texture indices are into
 * pb_scene.textures, -1 when absent. */
typedef struct pb_material {
    float base_color[4];
    float emissive[3];
    float metallic;
    float roughness;
    float alpha_cutoff;       /* glTF default 0.5 */
    int32_t base_color_texture;
    int32_t emissive_texture;
    uint32_t alpha_mode;      /* pb_alpha_mode */
    uint32_t double_sided;
    char name[64];
    /* KHR_materials_transmission (a thin surface): the share of the light
     * meeting it that goes straight through, tinted by the base colour:
     * transmissionFactor x (1 - metallic). 0: none. Such a material is
     * alpha-blended, base_color[3] its coverage (docs/scene.md). Last, so
     * pb_scene_hash of a scene without transmission is what it was before. */
    float transmission;
    /* With transmission, from a transmissionTexture on a material that was
     * opaque: the colour texture's alpha is not coverage but that texture's
     * red channel, which scales transmission per texel (coverage 1, the
     * light through tinted as without a texture). 0 otherwise. */
    uint32_t transmission_in_alpha;
    /* glTF normalTexture: the scene texture of tangent-space normals
     * (linear RGB, +X along increasing u, +Y against increasing v, as glTF
     * says), -1 for none; normal_scale multiplies the sampled normal's X and
     * Y (normalTexture.scale, default 1). The tangent frame is the file's
     * (pb_scene.tangents) where given, else each triangle's from its
     * texture coordinates (docs/bake.md, "Normal maps"). After the fields
     * above, so a scene without normal maps keeps its hash. */
    int32_t normal_texture;
    float normal_scale;
    /* With transmission on a material whose alpha is its coverage: the
     * texture whose red channel scales transmission per texel (glTF's
     * transmissionTexture), -1 for none. After the fields above, so a scene
     * without one keeps its hash. */
    int32_t transmission_texture;
} pb_material;

/* Decoded texture: RGBA8 texels at pb_scene.texels[offset ...], row-major,
 * first row = top of the image (glTF UV (0,0) is the top-left corner). */
typedef struct pb_texture {
    uint32_t width, height;
    uint64_t offset;          /* in texels (uint32 RGBA8 words) */
    uint32_t wrap_s, wrap_t;  /* pb_wrap */
    uint32_t srgb;            /* 1 for colour textures (base colour, emissive) */
} pb_texture;

typedef enum pb_light_type {
    PB_LIGHT_DIRECTIONAL = 0,
    PB_LIGHT_POINT = 1,
    PB_LIGHT_SPOT = 2
} pb_light_type;

/* KHR_lights_punctual light in the local frame. `direction` is where the
 * light points (the node's -Z). range 0 = infinite. Angles in radians. */
typedef struct pb_light {
    uint32_t type;            /* pb_light_type */
    float color[3];
    float intensity;
    float range;
    float inner_cone, outer_cone;
    float position[3];
    float direction[3];
    char name[64];
} pb_light;

/* Perspective or orthographic camera in the local frame; the camera looks
 * along `forward` (the node's -Z) with `up` its +Y. */
typedef struct pb_camera {
    uint32_t perspective;     /* 1 perspective, 0 orthographic */
    float yfov;               /* radians, perspective only */
    float aspect;             /* 0 when the file does not give one */
    float znear, zfar;        /* zfar 0 = infinite */
    float xmag, ymag;         /* orthographic only */
    float position[3];
    float forward[3];
    float up[3];
    char name[64];
} pb_camera;

typedef struct pb_scene_stats {
    uint64_t triangles_in;        /* triangles assembled from all primitives */
    uint64_t dropped_degenerate;  /* zero area after transformation */
    uint64_t dropped_nonfinite;   /* NaN or Inf vertex */
    uint32_t primitives;          /* mesh primitives instanced by nodes */
    uint32_t primitives_skipped;  /* points and lines: not surfaces */
    uint32_t normals_generated;   /* primitives without NORMAL (flat normals made) */
    uint32_t nodes;               /* nodes visited in the default scene */
    uint32_t textures_in;         /* the file's glTF textures */
    uint32_t textures_unread;     /* of them, read by no material where the bake samples (normal, occlusion and
                                     unused maps, metallic ones no fold reads): never decoded */
    char extensions_used[512];    /* the file's extensionsUsed, comma-separated ("" for none) */
    char extensions_applied[512]; /* those of them the loader applies; the rest are ignored (logged) */
} pb_scene_stats;

typedef struct pb_scene {
    uint32_t triangle_count;
    float *positions;         /* 9 floats per triangle, local frame */
    float *normals;           /* 9 floats per triangle, unit vertex normals */
    float *texcoords;         /* 6 floats per triangle (TEXCOORD_0, 0 if absent) */
    float *colors;            /* 12 floats per triangle, RGBA per corner (glTF COLOR_0, linear; white where a
                                 primitive has none); NULL when no primitive has vertex colours */
    uint32_t *material;       /* material index per triangle */
    float *tangents;          /* 12 floats per triangle, per corner the file's tangent (glTF TANGENT of a
                                 normal-mapped primitive): unit x, y, z, then w = +-1, its handedness (the
                                 bitangent is w (n x t)); all 0 at a corner without one, whose normal map takes
                                 its frame from the texture coordinates. NULL when no triangle has one */

    uint32_t material_count;
    pb_material *materials;   /* at least one: a default grey material is appended if needed */
    uint32_t texture_count;
    pb_texture *textures;
    uint64_t texel_count;
    uint32_t *texels;         /* RGBA8, R in the low byte */
    uint32_t light_count;
    pb_light *lights;
    uint32_t camera_count;
    pb_camera *cameras;

    double origin[3];         /* world = local + origin */
    float bounds_min[3];      /* local frame; zero for an empty scene */
    float bounds_max[3];
    pb_scene_stats stats;
    char path[1024];          /* file it was loaded from, "" if built in memory */
} pb_scene;

/* The largest radiometric value (radiance, radiant intensity, irradiance) a
 * bake or render accepts from a scene, sky or environment map. The bake's
 * float arithmetic multiplies such values by geometry and sampling factors
 * (1/d² over a ray offset, 1/pdf of a small emitter: up to about 1e12) and
 * sums up to 65536 rays: 1e20 leaves that product below float's 3.4e38. */
#define PB_MAX_RADIOMETRIC 1e20f

/* Zero fields mean the defaults listed on each line. */
typedef struct pb_scene_desc {
    pb_log log;
    uint32_t skip_textures;   /* 1: do not decode images (info, bench); default 0 */
    /* Decoded-size limits, checked from an image's header before it is
     * decoded (a 144-byte JPEG can claim 11000 x 11000 pixels: 484 MB). An
     * image past a limit is a warning and its material keeps its factor. */
    uint64_t max_texture_pixels;       /* per image; default PB_MAX_TEXTURE_PIXELS */
    uint64_t max_texture_total_pixels; /* all images of a file; default PB_MAX_TEXTURE_TOTAL_PIXELS */
    uint32_t face_normals;    /* 1: every triangle keeps its face normal, whatever NORMAL says (flat
                                 shading: `--shading-normals face`); default 0, the file's vertex normals */
    uint32_t no_normal_maps;  /* 1: normalTexture is not read (`--normal-maps off`); default 0, read */
    /* Images decoded ahead of the material pass on the host's threads (the
     * scene and the messages are the same either way): PB_DECODE_AHEAD_AUTO
     * (0) where there is something to overlap (two or more images, 1 MiB of
     * them, two or more cores), _ALWAYS whatever their size and the cores
     * (tests and the fuzzer compare it with _NEVER), _NEVER (no threads). */
    uint32_t decode_ahead;
} pb_scene_desc;

enum { PB_DECODE_AHEAD_AUTO = 0, PB_DECODE_AHEAD_ALWAYS = 1, PB_DECODE_AHEAD_NEVER = 2 };

/* 8192 x 8192 (256 MiB as RGBA8) per image, and 16 such images per file
 * (4 GiB): an 8K texture loads; a header claiming more is refused unread. */
#define PB_MAX_TEXTURE_PIXELS (8192ull * 8192ull)
#define PB_MAX_TEXTURE_TOTAL_PIXELS (16ull * PB_MAX_TEXTURE_PIXELS)

/* Loads a .gltf or .glb file with the whole node hierarchy of its default
 * scene (scene 0 when none is marked default).
 *  desc: may be NULL (defaults).
 *  out:  receives a scene owned by the caller (pb_scene_destroy); NULL on error.
 *  Returns PB_ERROR_IO (missing file or buffer), PB_ERROR_PARSE (malformed
 *  JSON, truncated buffer, out-of-range accessor or index),
 *  PB_ERROR_UNSUPPORTED (a required extension we do not implement). */
pb_result pb_scene_load(const char *path, const pb_scene_desc *desc, pb_scene **out, pb_error *err);

/* Builds a scene from a triangle soup given in *world* coordinates (double,
 * 9 per triangle); one default material. Used by tests and benches.
 *  material_ids: NULL, or one per triangle into `materials`.
 *  materials: NULL (one default grey material) or material_count entries. */
pb_result pb_scene_from_triangles(const double *world_positions, uint32_t triangle_count,
                                  const uint32_t *material_ids, const pb_material *materials,
                                  uint32_t material_count, pb_scene **out, pb_error *err);

/* Frees everything the scene owns. NULL is allowed. */
void pb_scene_destroy(pb_scene *scene);

/* The scene's identity as a volume records it (settings.scene_hash): a hash
 * of the local triangle positions and the materials, and of the vertex
 * normals where they shade (pb_scene_bent_triangles > 0), and of the file's
 * tangents where a normal map reads them. A volume baked from
 * a different scene (or a changed one, or with --shading-normals face where
 * the normals shade) has another; `merge` refuses to join them. */
uint64_t pb_scene_hash(const pb_scene *scene);

/* Triangles with a vertex normal bent away from the face normal by more
 * than PB_BENT_NORMAL_COS (about 1.1 degrees; the sign is ignored: a normal
 * that only points to the other side bends nothing). The bake and the
 * renderer shade with vertex normals (docs/bake.md, "Shading normals") when
 * there is one; else with the face normals, as fast as before. */
#define PB_BENT_NORMAL_COS 0.9998f
uint64_t pb_scene_bent_triangles(const pb_scene *scene);

/* Materials that are thin glass (transmission > 0). The bake lets rays
 * through them, tinted, where there is one (docs/bake.md, "Thin glass"); a
 * scene without compiles that out. */
uint32_t pb_scene_glass_materials(const pb_scene *scene);

/* Materials with a normal map (normal_texture >= 0). The bake bends its
 * shading normals by them where there is one (docs/bake.md, "Normal maps");
 * a scene without compiles that out. */
uint32_t pb_scene_normal_mapped(const pb_scene *scene);

/* Triangles whose normal map takes its frame from the file's tangents (all
 * three corners have one: pb_scene.tangents); the others' from their texture
 * coordinates. */
uint64_t pb_scene_tangent_triangles(const pb_scene *scene);

/* Default-initialised material (glTF defaults: white, opaque, cutoff 0.5). */
pb_material pb_material_default(void);

#ifdef __cplusplus
}
#endif
#endif
