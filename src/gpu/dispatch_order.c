/* The order of a dispatch's workgroups (shaders/include/dispatch_order.glsl).
 * llvmpipe splits a dispatch of n workgroups into one contiguous run of n/T
 * per thread (lp_cs_tpool: iter_per_thread = n / T) and waits for the
 * slowest. A bake's or a trace's workgroups follow the probe grid, whose
 * halves can differ in cost by tens of ms a dispatch on The Crypt, with the
 * other core idle meanwhile (bench/RESULTS.md, "Workgroups spread over
 * lavapipe's threads"). Kernels that take the stride map block b of 8
 * workgroups to b s mod (n / 8): every run then samples the whole grid. */
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
    uint32_t blocks = groups / PB_SPREAD_BLOCK; /* runs of 8 workgroups keep their order (their probes share cache) */
    if (blocks < 5 || blocks > 65535) /* b s must fit in 32 bits */
        return 1;
    /* a Weyl sequence, b / golden ratio mod 1, whose runs are evenly spread: the
     * stride coprime to `blocks` nearest blocks / golden ratio, other than 1 and
     * blocks - 1 (the order kept or mirrored) */
    uint32_t start = (uint32_t)(blocks * 0.6180339887);
    for (uint32_t d = 0; d < blocks; ++d) {
        if (start + d <= blocks - 2 && gcd(start + d, blocks) == 1)
            return start + d;
        if (start >= d + 2 && gcd(start - d, blocks) == 1)
            return start - d;
    }
    return 1; /* 6 blocks: only 1 and 5 are coprime */
}
