/* Octahedral mapping and the bordered-tile texel rule (octahedral.h). */
#include "probebake/octahedral.h"

#include <math.h>

static float sign_not_zero(float v)
{
    return v >= 0.f ? 1.f : -1.f;
}

void pb_oct_encode(const float d[3], float uv[2])
{
    float l1 = fabsf(d[0]) + fabsf(d[1]) + fabsf(d[2]);
    float u = d[0] / l1, v = d[1] / l1;
    if (d[2] < 0.f) { /* fold the lower hemisphere into the corners */
        float fu = (1.f - fabsf(v)) * sign_not_zero(u);
        float fv = (1.f - fabsf(u)) * sign_not_zero(v);
        u = fu, v = fv;
    }
    uv[0] = u;
    uv[1] = v;
}

void pb_oct_decode(const float uv[2], float d[3])
{
    float x = uv[0], y = uv[1], z = 1.f - fabsf(x) - fabsf(y);
    if (z < 0.f) {
        float fx = (1.f - fabsf(y)) * sign_not_zero(x);
        float fy = (1.f - fabsf(x)) * sign_not_zero(y);
        x = fx, y = fy;
    }
    float l = sqrtf(x * x + y * y + z * z);
    d[0] = x / l;
    d[1] = y / l;
    d[2] = z / l;
}

void pb_oct_texel_direction(uint32_t x, uint32_t y, uint32_t n, float d[3])
{
    float uv[2] = {-1.f + (2.f * (float)x + 1.f) / (float)n, -1.f + (2.f * (float)y + 1.f) / (float)n};
    pb_oct_decode(uv, d);
}

void pb_oct_border_source(uint32_t bx, uint32_t by, uint32_t n, uint32_t *x, uint32_t *y)
{
    int on_left = bx == 0, on_right = bx == n + 1, on_top = by == 0, on_bottom = by == n + 1;
    if ((on_left || on_right) && (on_top || on_bottom)) { /* corner: the opposite corner */
        *x = on_left ? n - 1 : 0;
        *y = on_top ? n - 1 : 0;
    } else if (on_top || on_bottom) { /* edge row: mirrored along the edge */
        *x = n - bx;
        *y = on_top ? 0 : n - 1;
    } else if (on_left || on_right) {
        *x = on_left ? 0 : n - 1;
        *y = n - by;
    } else { /* interior */
        *x = bx - 1;
        *y = by - 1;
    }
}
