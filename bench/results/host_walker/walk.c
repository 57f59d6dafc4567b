/* pb_trace_cpu (the host walker) on The Crypt: 4,096 probes x 128 probe rays, one
 * thread, three runs, and a hash of the hits (bench/RESULTS.md, "The host walker's box
 * test"). Built against build/libprobebake_core.a with test_bvh's link line. */
#include "probebake/probebake.h"
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec * 1e3 + t.tv_nsec * 1e-6; }
int main(int argc, char **argv) {
  pb_scene *s; pb_bvh *b; pb_error e;
  if (pb_scene_load(argv[1], NULL, &s, &e) || pb_bvh_build(s, NULL, &b, &e)) { puts(e.message); return 1; }
  pb_probe_grid g; pb_probe_grid_fit(s->bounds_min, s->bounds_max, 4096, &g);
  uint32_t P = pb_probe_grid_count(&g), R = 128, n = P * R;
  pb_ray *rays = malloc(sizeof *rays * n); pb_hit *h = malloc(sizeof *h * n);
  pb_probe_rays(&g, 0, P, R, 1, rays);
  for (int k = 0; k < 3; ++k) { double t0 = now(); pb_trace_cpu(s, b, rays, n, PB_TRACE_CLOSEST, h, 1); double t1 = now();
    uint64_t hs = 0; for (uint32_t i = 0; i < n; ++i) hs = hs * 31 + h[i].triangle;
    printf("%u rays, 1 thread: %.0f ms (%.2f Mrays/s), hash %llx\n", n, t1 - t0, n / (t1 - t0) / 1e3, (unsigned long long)hs); }
}
