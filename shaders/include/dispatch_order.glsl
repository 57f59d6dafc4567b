// The workgroup a dispatch's w-th of n stands for (src/gpu/dispatch_order.c):
// lavapipe hands each of its T threads one contiguous run of n / T
// workgroups, so the costlier half of a grid of probes would keep one thread
// busy while the other waits. Blocks of 8 workgroups keep their order (their
// probes share cache); block b becomes b s mod (n / 8), with the host's
// stride s coprime to n / 8 and near it over the golden ratio, which spreads
// every run over the whole dispatch (a tail of n mod 8 stays in place; s <= 1
// keeps the order). Each invocation's work depends only on the index it
// gets, so the results do not change.
#ifndef PB_DISPATCH_ORDER_GLSL
#define PB_DISPATCH_ORDER_GLSL

#define PB_SPREAD_BLOCK 8u

uint spread_group(uint w, uint n, uint s)
{
    uint blocks = n / PB_SPREAD_BLOCK;
    if (s <= 1u || w >= blocks * PB_SPREAD_BLOCK)
        return w;
    return (w / PB_SPREAD_BLOCK * s) % blocks * PB_SPREAD_BLOCK + w % PB_SPREAD_BLOCK; // blocks <= 65535: no overflow
}

#endif
