/* Compressed variants of a glTF file, written by the tests/gltf_compress
 * helper (Draco, meshopt, quantized; see its header) into the test's temp
 * directory, and the geometric bound each encoding keeps. */
#ifndef PB_COMPRESSED_VARIANTS_H
#define PB_COMPRESSED_VARIANTS_H

#include "test_util.h"

typedef struct pb_variant {
    const char *mode;  /* gltf_compress mode */
    const char *ext;   /* "gltf" (external .bin) or "glb" */
    int lossless;      /* the encoding keeps every bit: the scene must be identical */
} pb_variant;

static const pb_variant pb_variants[] = {
    {"meshopt", "gltf", 1}, {"meshopt", "glb", 1}, {"meshopt-exp", "glb", 0},
    {"draco", "gltf", 0},   {"draco", "glb", 0},   {"quantize", "glb", 0},
};
#define PB_VARIANT_COUNT (sizeof pb_variants / sizeof pb_variants[0])

/* Writes variant v of `src` as <tag>_<mode>.<ext>; NULL (after a CHECK
 * failure) when the helper fails. */
static inline const char *compressed_variant(const char *src, const char *tag, const pb_variant *v)
{
    static char path[8][512];
    static int slot;
    char *out = path[slot++ & 7], cmd[2048];
    snprintf(out, 512, "%s/%s_%s.%s", temp_dir(), tag, v->mode, v->ext);
    snprintf(cmd, sizeof cmd, "'%s' %s '%s' '%s'", PB_GLTF_COMPRESS, v->mode, src, out);
    int rc = system(cmd);
    CHECKF(rc == 0, "%s failed (%d)", cmd, rc);
    return rc == 0 ? out : NULL;
}

/* Writes `src` with its images as lossless `codec` ("webp" or "avif") as
 * <tag>_<codec>.glb, and the same with each coded image cut in half and the
 * core images kept as fallbacks as <tag>_<codec>-broken.glb (*broken), both
 * from one encoding of the images (most of the helper's time); NULL (after a
 * CHECK failure) when the helper fails. */
static inline const char *compressed_image_variants(const char *src, const char *tag, const char *codec,
                                                    const char **broken)
{
    static char path[4][512];
    static int slot;
    char *out = path[slot++ & 3], *cut = path[slot++ & 3], cmd[2048];
    snprintf(out, 512, "%s/%s_%s.glb", temp_dir(), tag, codec);
    snprintf(cut, 512, "%s/%s_%s-broken.glb", temp_dir(), tag, codec);
    snprintf(cmd, sizeof cmd, "'%s' %s '%s' '%s' '%s'", PB_GLTF_COMPRESS, codec, src, out, cut);
    int rc = system(cmd);
    CHECKF(rc == 0, "%s failed (%d)", cmd, rc);
    *broken = rc == 0 ? cut : NULL;
    return rc == 0 ? out : NULL;
}

/* Largest world-space position error (metres, any axis) an encoding keeps
 * in a scene of bounding-box diagonal `diag` whose vertices lie within
 * `rmax` of the origin. Each encoder quantizes a mesh in its own frame, and
 * a node's similarity transform maps that frame's error vector (length at
 * most sqrt(3) half-steps) to world space scaled as the mesh's extent is,
 * which is at most diag:
 * - Draco, 14 bits over the mesh's largest extent: sqrt(3)/2 diag / 16383;
 * - quantize, each axis over its own extent in normalized SHORT:
 *   diag / 32767 / 2;
 * - meshopt-exp, 16-bit signed mantissas: sqrt(3) 2^-15 of a coordinate's
 *   magnitude, at most rmax + diag for these scenes' nodes;
 * plus float rounding of the dequantization (a few ulps of rmax). */
static inline double variant_position_bound(const pb_variant *v, double diag, double rmax)
{
    double ulps = 8 * fmax(rmax, diag) * 1.1920929e-7;
    if (!strcmp(v->mode, "draco"))
        return sqrt(3.0) / 2 * diag / 16383.0 + ulps;
    if (!strcmp(v->mode, "quantize"))
        return diag / 32767.0 / 2 + ulps;
    if (!strcmp(v->mode, "meshopt-exp"))
        return sqrt(3.0) * ldexp(1.0, -15) * (rmax + diag) + ulps;
    return 0;
}

/* The bake of a variant against its original's, probe by probe, in units
 * of the two bakes' combined standard error, z = |dE| / sqrt(sa^2 + sb^2),
 * each standard error estimated from VARIANT_PASSES passes. Were the two
 * bakes independent, z would follow |t| with 2 (16 - 1) = 30 degrees of
 * freedom: mean 0.81, standard deviation 0.62, above 5 with probability
 * 2e-5. Both draw the same random numbers over surfaces moved by a fraction
 * of a millimetre, so their differences are smaller (correlated), never
 * larger: every probe within z <= 5, and the mean over n probes within three
 * standard errors of the independent mean. Broken decoding (wrong scale,
 * flipped or missing triangles) lands far above both. */
#define VARIANT_PASSES 16u
#define VARIANT_Z_MAX 5.0
static inline double variant_mean_z_bound(uint32_t n)
{
    return 0.81 + 3 * 0.62 / sqrt((double)(n ? n : 1));
}

/* The scenes the variants are made of: the demo scene, and the shared
 * Cornell box when ../shared/scenes is there. Source i's path and tag; 0
 * (after a SKIP saying so) when it is absent. */
#define PB_VARIANT_SOURCES 2
static inline int variant_source(int i, const char **path, const char **tag)
{
    static char cornell[1024];
    snprintf(cornell, sizeof cornell, "%s/../shared/scenes/cornell/cornellBox.gltf", PB_SOURCE_DIR);
    *path = i == 0 ? PB_SOURCE_DIR "/tests/scenes/demo.gltf" : cornell;
    *tag = i == 0 ? "demo" : "cornell";
    if (!file_exists(*path)) {
        skip("%s not present: only the demo scene's variants checked", *path);
        return 0;
    }
    return 1;
}

/* Source i loaded (NULL after a SKIP or a CHECK failure saying why). */
static inline pb_scene *variant_original(int i, const char **path, const char **tag)
{
    pb_scene *s = NULL;
    pb_error err;
    if (!variant_source(i, path, tag))
        return NULL;
    CHECKF(pb_scene_load(*path, NULL, &s, &err) == PB_OK, "%s", err.message);
    return s;
}

/* Variant v of source `src` written and loaded (NULL after a CHECK
 * failure); *path gets its file. */
static inline pb_scene *variant_scene(const char *src, const char *tag, const pb_variant *v, const char **path)
{
    pb_scene *s = NULL;
    pb_error err;
    *path = compressed_variant(src, tag, v);
    if (*path)
        CHECKF(pb_scene_load(*path, NULL, &s, &err) == PB_OK, "%s", err.message);
    return s;
}

/* A grid placed in the original o's frame, moved into the variant c's
 * (whose origin, the centre of its bounds, moved with the quantization). */
static inline void variant_grid_frame(const pb_scene *o, const pb_scene *c, pb_probe_grid *g)
{
    for (int k = 0; k < 3; ++k)
        g->origin[k] += (float)(o->origin[k] - c->origin[k]);
}

/* Compares per-probe irradiance E and absolute standard error s of a
 * variant's bake (b) with its original's (a) by the bound above; prints a
 * line and CHECKs. Probes with no light or no error estimate are left out.
 * `identical`: the bake must be bit for bit the original's instead. */
static inline void variant_check_bake(const char *path, const char *label, const double *ea, const double *sa,
                                      const double *eb, const double *sb, uint32_t probes)
{
    uint32_t n = 0;
    double z_sum = 0, z_max = 0, rel_max = 0;
    for (uint32_t p = 0; p < probes; ++p) {
        double s2 = sqrt(sa[p] * sa[p] + sb[p] * sb[p]);
        if (!(ea[p] > 0) || !(s2 > 0))
            continue;
        double z = fabs(ea[p] - eb[p]) / s2;
        z_sum += z, z_max = fmax(z_max, z), rel_max = fmax(rel_max, fabs(ea[p] - eb[p]) / ea[p]), ++n;
    }
    double z_mean = n ? z_sum / n : 0, z_bound = variant_mean_z_bound(n);
    printf("  %s: %u probes, |dE| in combined standard errors: mean %.2f (bound %.2f), worst %.2f (bound %.0f); "
           "worst |dE|/E %.4f\n", label, n, z_mean, z_bound, z_max, VARIANT_Z_MAX, rel_max);
    CHECKF(n >= probes / 2 && z_max <= VARIANT_Z_MAX && z_mean <= z_bound, "%s: mean z %.2f (bound %.2f), worst %.2f",
           path, z_mean, z_bound, z_max);
}

#endif
