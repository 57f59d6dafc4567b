// Light cells (src/bake/light_cells.h): next-event estimation draws an
// emitter cluster from the table of the cell holding the shading point (a
// mixture of power and measured unoccluded light), then a triangle in it by
// power; a triangle's density is its power density times the cell's ratio
// for its cluster. CPU reference: src/bake/light_cells.c.
#ifndef PB_LIGHT_CELLS_GLSL
#define PB_LIGHT_CELLS_GLSL

// The table slot of the cell holding x, or -1 (draw by power).
int light_cell(BakeParams P, vec3 x)
{
    if (!bake_feature(PB_FEATURE_LIGHT_CELLS) || addr_null(P.light_cells))
        return -1;
    uint slot = UintBuf(P.light_cell_slots).v[grid_cell(x, P.light_origin, P.light_dims.xyz)];
    return slot == 0xffffffffu ? -1 : int(slot);
}

// An emitter (leaf-ordered triangle) from slot lc with two random numbers;
// ratio: its density over its power density.
uint light_cell_sample(BakeParams P, int lc, float u0, float u1, out float ratio)
{
    Vec4Buf table = Vec4Buf(P.light_cells);
    uint C = P.light_dims.w, base = uint(lc) * C;
    float xc = u0 * float(C);
    uint i = min(uint(xc), C - 1u);
    vec4 e = table.v[base + i];
    uint c = xc - float(i) < e.x ? i : floatBitsToUint(e.y);
    ratio = table.v[base + c].z;
    UintBuf range = UintBuf(P.light_clusters);
    uint first = range.v[2u * c], n = range.v[2u * c + 1u];
    EmitterBuf members = EmitterBuf(P.light_members);
    float xt = u1 * float(n);
    uint j = min(uint(xt), n - 1u);
    Emitter m = members.e[first + j];
    return xt - float(j) < m.prob ? m.tri : members.e[first + m.alias].tri;
}

// The ratio of triangle tri's density to its power density in slot lc.
float light_cell_ratio(BakeParams P, int lc, uint tri)
{
    if (lc < 0)
        return 1.0;
    uint c = UintBuf(P.light_cluster_of).v[tri];
    return Vec4Buf(P.light_cells).v[uint(lc) * P.light_dims.w + c].z;
}

#endif
