#version 460
// spherical_triangle: spherical_triangle.glsl over a batch of triangles seen
// from points, a uniform pair each: the solid angle and the direction drawn.
// CPU reference: src/bake/spherical_triangle.c. The bake samples emitters
// with it (path.glsl); this kernel tests it alone, on shapes the scenes
// rarely hold (slivers, near-hemispheres, the threshold's edge).
#extension GL_GOOGLE_include_directive : require

#include "address.glsl"
#include "spherical_triangle.glsl"

layout(local_size_x = 64) in;

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Vec4In { vec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer Vec4Out { vec4 v[]; };

layout(push_constant) uniform Push {
    pb_addr inputs;  // 5 vec4 per entry: x, v0, v1, v2 (xyz), (u1, u2, 0, 0)
    pb_addr outputs; // vec4 per entry: the direction (xyz; 0 where not sampled), the solid angle
    uint count;
} pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    Vec4In in_ = Vec4In(pc.inputs);
    vec3 x = in_.v[5u * i].xyz, v0 = in_.v[5u * i + 1u].xyz, v1 = in_.v[5u * i + 2u].xyz, v2 = in_.v[5u * i + 3u].xyz;
    vec2 u = in_.v[5u * i + 4u].xy;
    float area = spherical_triangle_area(x, v0, v1, v2);
    vec3 w = spherical_triangle_sampled(area) ? spherical_triangle_sample(x, v0, v1, v2, area, u.x, u.y) : vec3(0.0);
    Vec4Out(pc.outputs).v[i] = vec4(w, area);
}
