#version 460
// dilate: one round of dilation over a probe grid or sparse bricks, one
// probe per invocation: an empty probe with filled neighbours (a grid's
// 3x3x3 cells, or a sparse volume's neighbour table, src/bake/dilate.h) takes their
// weighted mean SH (weights 1/d), in the order and float arithmetic of the
// CPU reference (src/bake/dilate.c); the weight sum's reciprocal comes from
// the host's table (src/bake/dilate.h), so no division rounds differently.
// States: 0 empty, 1 valid, 2 filled by dilation. Jacobi: each round reads
// the states of state_in and writes state_out (the host swaps them between
// rounds); the SH stay in one buffer, written only where a probe is filled:
// a probe reads the SH of neighbours that were valid or filled before the
// round, and the round writes only probes that were empty, so no probe reads
// what the round writes (the rounds used to copy every probe's 27 floats
// from one buffer to another).
#extension GL_GOOGLE_include_directive : require
#include "address.glsl"

layout(local_size_x = 64) in;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer FloatIn { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer FloatRW { float v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer UintIn { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer UintOut { uint v[]; };

layout(push_constant) uniform Push {
    pb_addr sh;        // 27 floats per probe, read and written in place
    pb_addr state_in;  // 1 uint per probe
    pb_addr state_out;
    pb_addr table;     // PB_DILATE_TABLE reciprocals
    pb_addr neighbours; // sparse: 26 probe indices per probe (~0: none), slot order of the loop below; 0: a grid
    pb_addr unused;
    uvec4 counts;      // grid counts x, y, z; w: probes
} pc;

const float W1 = 1.0, W2 = 0.70710677, W3 = 0.57735026; // (float)(1 / sqrt(d2))

void main()
{
    uint p = gl_GlobalInvocationID.x;
    if (p >= pc.counts.w)
        return;
    FloatRW sh = FloatRW(pc.sh);
    UintIn state = UintIn(pc.state_in);
    uint s = state.v[p];
    uint nx = pc.counts.x, ny = pc.counts.y, nz = pc.counts.z;
    precise float sum[27];
    for (int c = 0; c < 27; ++c)
        sum[c] = 0.0;
    ivec4 n = ivec4(0);
    bool sparse = !addr_null(pc.neighbours);
    if (s == 0u) {
        int x = int(p % nx), y = int((p / nx) % ny), z = int(p / (nx * ny));
        uint slot = 0u;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    int d2 = dx * dx + dy * dy + dz * dz;
                    if (d2 == 0)
                        continue;
                    uint q;
                    if (sparse) {
                        q = UintIn(pc.neighbours).v[26u * p + slot++];
                        if (q == 0xffffffffu)
                            continue;
                    } else {
                        int qx = x + dx, qy = y + dy, qz = z + dz;
                        if (qx < 0 || qy < 0 || qz < 0 || qx >= int(nx) || qy >= int(ny) || qz >= int(nz))
                            continue;
                        q = uint(qx) + nx * (uint(qy) + ny * uint(qz));
                    }
                    if (state.v[q] == 0u)
                        continue;
                    float w = d2 == 1 ? W1 : d2 == 2 ? W2 : W3;
                    n[d2]++;
                    for (int c = 0; c < 27; ++c)
                        sum[c] = sum[c] + w * sh.v[27u * q + uint(c)];
                }
    }
    bool fill = s == 0u && n[1] + n[2] + n[3] > 0;
    if (fill) {
        precise float r = FloatIn(pc.table).v[(n[1] * 13 + n[2]) * 9 + n[3]];
        for (int c = 0; c < 27; ++c) {
            precise float v = sum[c] * r;
            sh.v[27u * p + uint(c)] = v;
        }
    }
    UintOut(pc.state_out).v[p] = fill ? 2u : s;
}
