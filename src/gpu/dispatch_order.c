/* The order of a dispatch's workgroups (shaders/include/dispatch_order.glsl).
 * llvmpipe splits a dispatch of n workgroups into one contiguous run of n/T
 * per thread (lp_cs_tpool: iter_per_thread = n / T) and waits for the
 * slowest. A bake's or a trace's workgroups follow the probe grid, whose
 * halves can differ in cost by tens of ms a dispatch on The Crypt, with the
 * other core idle meanwhile (bench/RESULTS.md, "Workgroups spread over
 * lavapipe's threads"). Kernels that take a stride map workgroup w to
 * w s mod n: every run then samples the whole grid. */
#include "gpu/gpu.h"

#define PB_SPREAD_BLOCK 8u /* dispatch_order.glsl's */

static uint32_t gcd(uint32_t a, uint32_t b)
{
    while (b) {
        uint32_t t = a % b;
        a = b, b = t;
    }
    return a;
}

uint32_t pb_dispatch_spread(uint32_t groups)
{
    groups /= PB_SPREAD_BLOCK; /* runs of this many workgroups keep their order (their probes share cache) */
    if (groups < 3 || groups > 65535) /* w s must fit in 32 bits */
        return 1;
    uint32_t s = (uint32_t)(groups * 0.6180339887) | 1u; /* a Weyl sequence: runs of it are evenly spread */
    while (gcd(s, groups) != 1)
        s += 2;
    return s % groups;
}
