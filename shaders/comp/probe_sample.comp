#version 460
// probe_sample: the run-time sampling function (probe_sample.glsl) for a
// batch of queries (point, normal, view direction; vec4 each), irradiance
// out. CPU reference: pb_sample_cpu (src/sample/probe_sample.c). It exists
// so the shipped GLSL is tested; the renderer includes it directly.
#extension GL_GOOGLE_include_directive : require

#include "probe_sample.glsl"

layout(local_size_x = 64) in;

layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer QueryOut { vec4 v[]; };

// pb_gpu_batch's push constants (src/gpu/gpu.h), then the volume's references
layout(push_constant) uniform Push {
    pb_addr queries;   // 3 vec4 per query: point, normal, view
    pb_addr out_rgb;
    uint count;
    PbVolumeRefs volume;
} pc;

void main()
{
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count)
        return;
    pb_volume = pc.volume;
    vec3 p = PbVec4Buf(pc.queries).v[3 * i].xyz;
    vec3 n = PbVec4Buf(pc.queries).v[3 * i + 1].xyz;
    vec3 v = PbVec4Buf(pc.queries).v[3 * i + 2].xyz;
    QueryOut(pc.out_rgb).v[i] = vec4(pb_volume_irradiance(pb_volume, p, n, v), 0.0);
}
