// Real SH L2: include/probebake/sh.h (same constants, order and axes).
#ifndef PB_SH_GLSL
#define PB_SH_GLSL

void sh_basis(vec3 d, out float y[9])
{
    y[0] = 0.28209479177387814;
    y[1] = 0.48860251190291992 * d.y;
    y[2] = 0.48860251190291992 * d.z;
    y[3] = 0.48860251190291992 * d.x;
    y[4] = 1.09254843059207907 * d.x * d.y;
    y[5] = 1.09254843059207907 * d.y * d.z;
    y[6] = 0.31539156525252005 * (3.0 * d.z * d.z - 1.0);
    y[7] = 1.09254843059207907 * d.x * d.z;
    y[8] = 0.54627421529603953 * (d.x * d.x - d.y * d.y);
}

#endif
