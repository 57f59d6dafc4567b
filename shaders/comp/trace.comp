#version 460
// trace: one invocation per ray, closest hit or (ANY_HIT) any hit.
// Input pb_ray[], output pb_hit[] with the triangle in leaf order (the host
// maps it back to scene order). CPU reference: pb_trace_cpu.
#extension GL_GOOGLE_include_directive : require

#include "traverse.glsl"
#include "dispatch_order.glsl"

layout(local_size_x = 64) in;
layout(constant_id = 2) const uint ANY_HIT = 0u;

struct Ray {
    vec4 org_tmin;
    vec4 dir_tmax;
};

struct Hit {
    float t;
    uint tri;
    float u;
    float v;
    uint backface;
};

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer RayBuf { Ray r[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer HitBuf { Hit h[]; };

layout(push_constant) uniform Push {
    SceneRefs scene;
    pb_addr rays;
    pb_addr hits;
    uint count;
    uint spread; // dispatch_order.glsl
} pc;

void main()
{
    uint i = spread_group(gl_WorkGroupID.x, gl_NumWorkGroups.x, pc.spread) * 64u + gl_LocalInvocationID.x;
    if (i >= pc.count)
        return;
    Ray ray = RayBuf(pc.rays).r[i];
    vec3 dir = ray.dir_tmax.xyz;
    TraceResult tr = trace_ray(pc.scene, ray.org_tmin.xyz, dir, ray.org_tmin.w, ray.dir_tmax.w, ANY_HIT != 0u);
    Hit h;
    h.t = tr.t;
    h.tri = tr.tri;
    h.u = tr.u;
    h.v = tr.v;
    h.backface = 0u;
    if (tr.tri != PB_NO_HIT) {
        Tri t = load_tri(pc.scene.tris, tr.tri);
        h.backface = is_backface(t.v0, t.v1, t.v2, dir) ? 1u : 0u;
    }
    HitBuf(pc.hits).h[i] = h;
}
