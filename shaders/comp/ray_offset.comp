#version 460
// ray_offset: robust origins for rays leaving surfaces, one per point.
// Input: points and unit normals (vec4 each, w unused); output: origins.
// CPU reference: pb_offset_ray_origin. The bake's kernels include
// ray_offset.glsl directly; this kernel exists so the include is tested.
#extension GL_GOOGLE_include_directive : require
#include "address.glsl"

#include "ray_offset.glsl"

layout(local_size_x = 64) in;

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Vec4In { vec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer Vec4Out { vec4 v[]; };

layout(push_constant) uniform Push {
    pb_addr points;
    pb_addr normals;
    pb_addr origins;
    uint count;
} pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    vec3 p = Vec4In(pc.points).v[i].xyz;
    vec3 n = Vec4In(pc.normals).v[i].xyz;
    Vec4Out(pc.origins).v[i] = vec4(offset_ray_origin(p, n), 0.0);
}
