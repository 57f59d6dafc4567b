#version 460
// exact_diff: exact_diff.glsl over a batch of (a, b, c, d), one float each.
// CPU reference: pb_exact_diff (src/bvh/exact_diff.h). The triangle test
// includes exact_diff.glsl; this kernel tests it on inputs far outside what
// traversal reaches (denormals, every exponent, cancellation, overflow).
#extension GL_GOOGLE_include_directive : require

#include "address.glsl"
#include "exact_diff.glsl"

layout(local_size_x = 64) in;

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Vec4In { vec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer FloatOut { float v[]; };

layout(push_constant) uniform Push {
    pb_addr inputs;
    pb_addr outputs;
    uint count;
} pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    vec4 q = Vec4In(pc.inputs).v[i];
    FloatOut(pc.outputs).v[i] = exact_diff(q.x, q.y, q.z, q.w);
}
