/* Light cells learned once per (GPU scene, seed) and uploaded in the
 * kernels' leaf order (light_cells_gpu.h). */
#include "bake/light_cells_gpu.h"

#include "bake/bake_types.h"
#include "bake/surface_cells.h"
#include "common/common.h"

#include <stdlib.h>
#include <string.h>

static pb_result upload(pb_context *ctx, pb_buffer *b, uint64_t bytes, const char *what, const void *data,
                        pb_error *err)
{
    pb_result r = pb_buffer_create(ctx, bytes, PB_MEMORY_DEVICE, what, b, err);
    return r == PB_OK ? pb_buffer_upload(ctx, b, 0, data, bytes, err) : r;
}

/* The cells' shadow rays on the device: its any-hit answers are the host
 * walker's (test_trace), so the tables are the bytes pb_trace_cpu would
 * give, and a GPU traces the 0.5 M rays of The Crypt's cells in
 * milliseconds where the host's walker took most of the cells' time. */
typedef struct device_tracer {
    pb_context *ctx;
    pb_gpu_scene *gs;
} device_tracer;

static pb_result trace_on_device(void *user, const pb_ray *rays, uint32_t count, pb_hit *hits, pb_error *err)
{
    const device_tracer *t = user;
    return pb_trace(t->ctx, t->gs, rays, count, PB_TRACE_ANY, hits, NULL, err);
}

static pb_result learn(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, uint32_t seed,
                       const pb_bake_emitters *emitters, pb_light_cells_gpu *g, pb_error *err)
{
    pb_bake_pass tp;
    memset(&tp, 0, sizeof tp);
    tp.scene = scene, tp.bvh = gs->bvh, tp.seed = seed, tp.emitters = emitters;
    double t0 = pb_now_ms();
    pb_light_cells *lc = &g->host;
    device_tracer dt = {ctx, gs};
    pb_result r = pb_light_cells_build(&tp, trace_on_device, &dt, lc, err);
    if (r != PB_OK || !lc->table)
        return r;
    uint32_t cells = pb_cell_grid_cells(&lc->grid), E = emitters->count, T = scene->triangle_count;
    pb_logf(&ctx->desc.log, PB_LOG_INFO, "light cells: %u emitters in %u clusters, %u of %u cells measured (%.0f ms)",
            E, lc->clusters, lc->learned, cells, pb_now_ms() - t0);
    uint32_t *leaf_of = malloc(T * sizeof *leaf_of), *cluster_leaf = malloc(T * sizeof *cluster_leaf);
    gpu_emitter *members = malloc(E * sizeof *members);
    if (!leaf_of || !cluster_leaf || !members) {
        r = pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for light cells (%u emitters)", E);
    } else {
        for (uint32_t k = 0; k < T; ++k)
            leaf_of[gs->tri_order[k]] = k, cluster_leaf[k] = lc->cluster_of[gs->tri_order[k]];
        for (uint32_t i = 0; i < E; ++i)
            members[i] = (gpu_emitter){leaf_of[lc->member_tri[i]], lc->member_keep[i], lc->member_alias[i], 0.f};
        r = upload(ctx, &g->table, (uint64_t)lc->learned * lc->clusters * 16, "light cell tables", lc->table, err);
    }
    if (r == PB_OK)
        r = upload(ctx, &g->slots, (uint64_t)cells * 4, "light cell index", lc->slot, err);
    if (r == PB_OK)
        r = upload(ctx, &g->clusters, (uint64_t)lc->clusters * 8, "light clusters", lc->cluster_range, err);
    if (r == PB_OK)
        r = upload(ctx, &g->members, (uint64_t)E * sizeof *members, "light cluster members", members, err);
    if (r == PB_OK)
        r = upload(ctx, &g->cluster_of, (uint64_t)T * 4, "emitter clusters", cluster_leaf, err);
    free(leaf_of), free(cluster_leaf), free(members);
    return r;
}

pb_result pb_light_cells_gpu_get(pb_context *ctx, const pb_scene *scene, pb_gpu_scene *gs, uint32_t seed,
                                 const pb_bake_emitters *emitters, const pb_light_cells_gpu **out, int *learned,
                                 pb_error *err)
{
    *out = NULL;
    if (learned)
        *learned = 0;
    if (gs->light_cells && gs->light_cells->seed == seed) {
        *out = gs->light_cells;
        pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "light cells: reused (seed %u)", seed);
        return PB_OK;
    }
    pb_light_cells_gpu *g = calloc(1, sizeof *g);
    if (!g)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory for light cells");
    g->seed = seed;
    pb_result r = learn(ctx, scene, gs, seed, emitters, g, err);
    if (r != PB_OK) {
        pb_light_cells_gpu_free(ctx, g);
        return r;
    }
    pb_light_cells_gpu_free(ctx, gs->light_cells); /* another seed's */
    gs->light_cells = g;
    *out = g;
    if (learned)
        *learned = 1;
    return PB_OK;
}

void pb_light_cells_gpu_free(pb_context *ctx, pb_light_cells_gpu *g)
{
    if (!g)
        return;
    pb_buffer *bufs[5] = {&g->table, &g->slots, &g->clusters, &g->members, &g->cluster_of};
    for (int i = 0; i < 5; ++i)
        pb_buffer_destroy(ctx, bufs[i]);
    pb_light_cells_free(&g->host);
    free(g);
}
