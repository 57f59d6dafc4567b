/* Embree 3 as the benches' CPU peer (bench/embree_peer.h). */
#include "embree_peer.h"
#include "common/common.h"

#include <math.h>
#include <string.h>

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
        rh.ray.org_x = r->origin[0];
        rh.ray.org_y = r->origin[1];
        rh.ray.org_z = r->origin[2];
        rh.ray.dir_x = r->direction[0];
        rh.ray.dir_y = r->direction[1];
        rh.ray.dir_z = r->direction[2];
        rh.ray.tnear = r->tmin;
        rh.ray.tfar = r->tmax;
        rh.ray.time = 0.f;
        rh.ray.mask = 0xffffffffu;
        rh.ray.id = 0;
        rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(j->scene, &ctx, &rh);
        j->t[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? INFINITY : rh.ray.tfar;
    }
}

int embree_peer_build(RTCDevice dev, const pb_scene *s, embree_peer *out)
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

void embree_peer_release(embree_peer *p)
{
    rtcReleaseScene(p->scene);
    memset(p, 0, sizeof *p);
}
