/* Embree 3 as the benches' CPU peer (bench/embree_peer.h). */
#include "embree_peer.h"
#include "bvh/alpha.h"
#include "common/common.h"

#include <math.h>
#include <string.h>

static void ray_in(const pb_ray *r, struct RTCRay *ray)
{
    ray->org_x = r->origin[0], ray->org_y = r->origin[1], ray->org_z = r->origin[2];
    ray->dir_x = r->direction[0], ray->dir_y = r->direction[1], ray->dir_z = r->direction[2];
    ray->tnear = r->tmin, ray->tfar = r->tmax;
    ray->time = 0.f, ray->mask = 0xffffffffu, ray->id = 0, ray->flags = 0;
}

typedef struct embree_job {
    RTCScene scene;
    const pb_ray *rays;
    float *t;
} embree_job;

static void embree_range(void *user, uint64_t b, uint64_t e)
{
    embree_job *j = user;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (uint64_t i = b; i < e; ++i) {
        const pb_ray *r = &j->rays[i];
        struct RTCRayHit rh;
        ray_in(r, &rh.ray);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(j->scene, &ctx, &rh);
        j->t[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar;
    }
}

/* Cuts out alpha: a hit where the surface is not opaque is refused. (The
 * RTCHitN accessors are C++ only; in C the hits are read from their
 * structure-of-arrays layout: u, v and primID rows after Ng's three.) */
static void alpha_filter(const struct RTCFilterFunctionNArguments *args)
{
    const pb_scene *s = args->geometryUserPtr;
    const float *f = (const float *)args->hit;
    const unsigned *prim = (const unsigned *)args->hit + 5 * args->N;
    for (unsigned i = 0; i < args->N; ++i)
        if (args->valid[i] == -1 && !pb_alpha_opaque(s, prim[i], f[3 * args->N + i], f[4 * args->N + i]))
            args->valid[i] = 0;
}

int embree_peer_build(RTCDevice dev, const pb_scene *s, int alpha, embree_peer *out)
{
    double t0 = pb_now_ms();
    out->scene = rtcNewScene(dev);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12,
                                        (size_t)s->triangle_count * 3);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, s->triangle_count);
    if (!vb || !ib) {
        rtcReleaseGeometry(g);
        rtcReleaseScene(out->scene);
        return 0;
    }
    memcpy(vb, s->positions, (size_t)s->triangle_count * 36);
    for (uint32_t i = 0; i < 3 * s->triangle_count; ++i)
        ib[i] = i;
    if (alpha) {
        rtcSetGeometryUserData(g, (void *)s);
        rtcSetGeometryIntersectFilterFunction(g, alpha_filter);
        rtcSetGeometryOccludedFilterFunction(g, alpha_filter);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(out->scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(out->scene);
    out->build_ms = pb_now_ms() - t0;
    return 1;
}

double embree_peer_trace(const embree_peer *p, const pb_ray *rays, uint32_t n, float *t)
{
    embree_job job = {p->scene, rays, t};
    double t0 = pb_now_ms();
    pb_parallel_for(n, 1024, 0, embree_range, &job);
    return pb_now_ms() - t0;
}

void embree_peer_cast(void *user, const pb_ray *r, pb_trace_mode mode, pb_hit *hit)
{
    const embree_peer *p = user;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    memset(hit, 0, sizeof *hit);
    hit->triangle = PB_NO_HIT, hit->t = INFINITY;
    if (mode == PB_TRACE_ANY) {
        struct RTCRay ray;
        ray_in(r, &ray);
        rtcOccluded1(p->scene, &ctx, &ray);
        if (ray.tfar < 0.f) /* occluded: Embree names no triangle, and a shadow ray needs none */
            hit->triangle = 0, hit->t = r->tmin;
        return;
    }
    struct RTCRayHit rh;
    ray_in(r, &rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(p->scene, &ctx, &rh);
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
        hit->triangle = rh.hit.primID, hit->t = rh.ray.tfar, hit->u = rh.hit.u, hit->v = rh.hit.v;
}

typedef struct cast_job {
    const embree_peer *peer;
    const pb_ray *rays;
    pb_trace_mode mode;
} cast_job;

static void cast_range(void *user, uint64_t b, uint64_t e)
{
    const cast_job *j = user;
    for (uint64_t i = b; i < e; ++i) {
        pb_hit h;
        embree_peer_cast((void *)j->peer, &j->rays[i], j->mode, &h);
    }
}

double embree_peer_cast_all(const embree_peer *p, const pb_ray *rays, uint64_t n, pb_trace_mode mode)
{
    cast_job job = {p, rays, mode};
    double t0 = pb_now_ms();
    pb_parallel_for(n, 1024, 0, cast_range, &job);
    return pb_now_ms() - t0;
}

void embree_peer_release(embree_peer *p)
{
    rtcReleaseScene(p->scene);
    memset(p, 0, sizeof *p);
}
