/* trace_bench: incoherent probe rays through probebake's kernel and, in the
 * same run on the same rays, through Embree 3 (rtcIntersect1 on all host
 * cores). Prints a table and writes JSON.
 *
 *   trace_bench [--probes N] [--rays N] [--repeat N] [--instanced K]
 *               [--leaf N] [--tc C] [--device D] [--portable] [--shuffle]
 *               [--scene-loads auto|address|texel]
 *               [--bounce | --bounce-sorted] [--json FILE] [SCENE ...]
 *
 * --leaf and --tc set the BVH's maximum leaf size and SAH traversal cost.
 * --shuffle traces the rays in a fixed random order. --bounce traces, instead
 * of the probe rays, one cosine bounce ray from each probe ray's first front
 * hit, in the probe rays' order (as the bake's megakernel meets them);
 * --bounce-sorted the same rays sorted by direction and origin (as a
 * wavefront bake could trace them).
 * --portable runs the kernels built without shaderInt64/shaderFloat64 even
 * where the device has them (to measure what the native64 build buys).
 * --scene-loads picks how the kernel reads the BVH (pb_scene_loads; default
 * auto: texels on CPU devices, addresses on GPUs).
 *
 * Rays: a probe grid over the scene bounds, `--rays` spherical-Fibonacci
 * directions per probe, randomly rotated per probe (pb_probe_rays). GPU rates
 * are reported from timestamp queries (kernel only) and from wall time
 * (pb_trace: copies and submission included). Each timing is the median of
 * `--repeat` runs after one warm-up. --instanced K also benches The Crypt
 * instanced K times through glTF nodes (written to bench/out/). */
#define _POSIX_C_SOURCE 200809L
#include "common/common.h"
#include "probebake/probebake.h"

#include "bench_util.h"
#include "bounce_rays.h"
#include "embree_peer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

typedef struct options {
    uint32_t probes, rays, repeat, instanced;
    pb_bvh_desc bvh;
    const char *device, *json;
    const char *scenes[16];
    int scene_count;
    int validation;           /* --validation: fail on any Vulkan validation message */
    int portable;             /* --portable: the kernels without 64-bit types */
    uint32_t scene_loads;     /* --scene-loads: pb_scene_loads */
    int shuffle;              /* --shuffle: rays in a random order (what incoherence costs) */
    int bounce;               /* --bounce: the probe rays' bounce rays, 1 in the bake's order, 2 sorted */
} options;

typedef struct result {
    char scene[256];
    uint32_t triangles, probes, rays;
    double bvh_ms, bvh_cold_ms, bvh_sah, bytes_per_tri;
    uint32_t bvh_depth;
    double gpu_kernel_ms, gpu_wall_ms, embree_ms, embree_build_ms;
    double agree; /* fraction of rays where GPU and Embree agree on hit/miss and distance */
} result;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, uint32_t n)
{
    qsort(v, n, sizeof *v, cmp_double);
    return n ? v[n / 2] : 0.0;
}

/* Writes The Crypt's triangles once as a mesh and instances it k times in a
 * square grid of glTF nodes, so the loader and its transforms do the work. */
static const char *write_instanced(const pb_scene *s, uint32_t k)
{
    static char gltf_path[512];
    mkdir("bench/out", 0755);
    const char *bin_path = "bench/out/instanced.bin";
    snprintf(gltf_path, sizeof gltf_path, "bench/out/instanced_x%u.gltf", k);
    FILE *f = fopen(bin_path, "wb");
    if (!f)
        return NULL;
    size_t bytes = (size_t)s->triangle_count * 36;
    fwrite(s->positions, 1, bytes, f);
    fclose(f);
    f = fopen(gltf_path, "w");
    if (!f)
        return NULL;
    uint32_t side = (uint32_t)ceil(sqrt((double)k));
    float ex = s->bounds_max[0] - s->bounds_min[0], ez = s->bounds_max[2] - s->bounds_min[2];
    fprintf(f, "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[");
    for (uint32_t i = 0; i < k; ++i)
        fprintf(f, "%s%u", i ? "," : "", i);
    fprintf(f, "]}],\"nodes\":[");
    for (uint32_t i = 0; i < k; ++i)
        fprintf(f, "%s{\"mesh\":0,\"translation\":[%.6f,0,%.6f]}", i ? "," : "", (i % side) * ex * 1.05,
                (i / side) * ez * 1.05);
    fprintf(f, "],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
               "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\"}],"
               "\"bufferViews\":[{\"buffer\":0,\"byteLength\":%zu}],"
               "\"buffers\":[{\"byteLength\":%zu,\"uri\":\"instanced.bin\"}]}\n",
            3 * s->triangle_count, bytes, bytes);
    fclose(f);
    return gltf_path;
}

static int bench_scene(pb_context *ctx, RTCDevice edev, const char *path, const options *o, result *res)
{
    memset(res, 0, sizeof *res);
    snprintf(res->scene, sizeof res->scene, "%s", path);
    pb_scene_desc sd = {{0}, 1};
    pb_scene *s = NULL;
    pb_error err;
    if (pb_scene_load(path, &sd, &s, &err) != PB_OK) {
        fprintf(stderr, "trace_bench: %s\n", err.message);
        return 0;
    }
    res->triangles = s->triangle_count;

    /* BVH build: median of repeats after one warm-up (the first build of a
     * process also pays the page faults of fresh allocations: ~25 % on The
     * Crypt; bench/RESULTS.md gives both) */
    double *times = malloc(sizeof(double) * (o->repeat + 1));
    pb_bvh *bvh = NULL;
    for (uint32_t r = 0; r <= o->repeat; ++r) {
        pb_bvh_destroy(bvh);
        if (pb_bvh_build(s, &o->bvh, &bvh, &err) != PB_OK) {
            fprintf(stderr, "trace_bench: %s\n", err.message);
            free(times);
            pb_scene_destroy(s);
            return 0;
        }
        if (r == 0)
            res->bvh_cold_ms = bvh->stats.build_ms;
        else
            times[r - 1] = bvh->stats.build_ms;
    }
    res->bvh_ms = median(times, o->repeat);
    res->bvh_sah = bvh->stats.sah_cost;
    res->bvh_depth = bvh->stats.depth;

    pb_gpu_scene *gs = NULL;
    if (pb_gpu_scene_create(ctx, s, bvh, &gs, &err) != PB_OK) {
        fprintf(stderr, "trace_bench: %s\n", err.message);
        pb_bvh_destroy(bvh);
        pb_scene_destroy(s);
        free(times);
        return 0;
    }
    uint64_t traversal = 0;
    pb_gpu_scene_bytes(gs, &traversal);
    res->bytes_per_tri = (double)traversal / (s->triangle_count ? s->triangle_count : 1);

    pb_probe_grid grid;
    pb_probe_grid_fit(s->bounds_min, s->bounds_max, o->probes, &grid);
    uint32_t probes = pb_probe_grid_count(&grid), n = probes * o->rays;
    res->probes = probes;
    res->rays = n;
    pb_ray *rays = malloc((size_t)n * sizeof *rays);
    pb_hit *hits = malloc((size_t)n * sizeof *hits);
    float *et = malloc((size_t)n * sizeof *et);
    pb_probe_rays(&grid, 0, probes, o->rays, 1, rays);
    if (o->shuffle) { /* Fisher-Yates with a fixed xorshift stream: the same order every run */
        uint64_t x = 0x9e3779b97f4a7c15ull;
        for (uint32_t i = n - 1; i > 0; --i) {
            x ^= x << 13, x ^= x >> 7, x ^= x << 17;
            uint32_t j = (uint32_t)(x % (i + 1));
            pb_ray t = rays[i];
            rays[i] = rays[j], rays[j] = t;
        }
    }

    double *kt = malloc(sizeof(double) * o->repeat), *wt = malloc(sizeof(double) * o->repeat);
    pb_trace_stats st;
    if (o->bounce) { /* the probe rays' first hits, then their bounce rays */
        int traced = pb_trace(ctx, gs, rays, n, PB_TRACE_CLOSEST, hits, &st, &err) == PB_OK;
        if (!traced)
            fprintf(stderr, "trace_bench: %s\n", err.message);
        else if (!(n = bench_bounce_rays(s, rays, hits, n, o->bounce == 2)))
            fprintf(stderr, "trace_bench: %s: no probe ray hits a front face, so there are no bounce rays\n", path);
        if (!traced || !n) {
            free(rays), free(hits), free(et), free(kt), free(wt), free(times);
            pb_gpu_scene_destroy(gs);
            pb_bvh_destroy(bvh);
            pb_scene_destroy(s);
            return 0;
        }
        res->rays = n;
    }
    pb_trace(ctx, gs, rays, n, PB_TRACE_CLOSEST, hits, &st, &err); /* warm-up */
    for (uint32_t r = 0; r < o->repeat; ++r) {
        if (pb_trace(ctx, gs, rays, n, PB_TRACE_CLOSEST, hits, &st, &err) != PB_OK) {
            fprintf(stderr, "trace_bench: %s\n", err.message);
            break;
        }
        kt[r] = st.kernel_ms;
        wt[r] = st.wall_ms;
    }
    res->gpu_kernel_ms = median(kt, o->repeat);
    res->gpu_wall_ms = median(wt, o->repeat);

    /* Embree on the same triangles (local frame) and rays */
    embree_peer peer;
    if (!embree_peer_build(edev, s, 0, &peer)) {
        fprintf(stderr, "trace_bench: Embree could not build %s\n", path);
        free(rays), free(hits), free(et), free(kt), free(wt), free(times);
        pb_gpu_scene_destroy(gs);
        pb_bvh_destroy(bvh);
        pb_scene_destroy(s);
        return 0;
    }
    res->embree_build_ms = peer.build_ms;
    embree_peer_trace(&peer, rays, n, et); /* warm-up */
    for (uint32_t r = 0; r < o->repeat; ++r)
        wt[r] = embree_peer_trace(&peer, rays, n, et);
    res->embree_ms = median(wt, o->repeat);
    uint32_t agree = 0;
    for (uint32_t i = 0; i < n; ++i) {
        int gh = hits[i].triangle != PB_NO_HIT, eh = et[i] < INFINITY;
        agree += gh == eh && (!gh || fabsf(hits[i].t - et[i]) <= 1e-4f * fmaxf(1.f, et[i]));
    }
    res->agree = (double)agree / n;
    embree_peer_release(&peer);

    free(rays), free(hits), free(et), free(kt), free(wt), free(times);
    pb_gpu_scene_destroy(gs);
    pb_bvh_destroy(bvh);
    pb_scene_destroy(s);
    return 1;
}

static const char *basename_of(const char *p)
{
    const char *b = strrchr(p, '/');
    return b ? b + 1 : p;
}

int main(int argc, char **argv)
{
    options o = {.probes = 4096, .rays = 256, .repeat = 3, .instanced = 0, .json = "bench/out/trace_bench.json"};
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--probes") && v)
            o.probes = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--rays") && v)
            o.rays = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--repeat") && v)
            o.repeat = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--instanced") && v)
            o.instanced = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--leaf") && v)
            o.bvh.max_leaf_size = (uint32_t)atoi(argv[++i]);
        else if (!strcmp(a, "--tc") && v)
            o.bvh.traversal_cost = (float)atof(argv[++i]);
        else if (!strcmp(a, "--device") && v)
            o.device = argv[++i];
        else if (!strcmp(a, "--validation"))
            o.validation = 1;
        else if (!strcmp(a, "--portable"))
            o.portable = 1;
        else if (!strcmp(a, "--scene-loads") && v) {
            const char *l = argv[++i];
            o.scene_loads = !strcmp(l, "address") ? PB_SCENE_LOADS_ADDRESS
                            : !strcmp(l, "texel") ? PB_SCENE_LOADS_TEXEL
                            : !strcmp(l, "auto") ? PB_SCENE_LOADS_AUTO : 99u;
            if (o.scene_loads == 99u) {
                fprintf(stderr, "trace_bench: --scene-loads takes auto, address or texel\n");
                return 2;
            }
        } else if (!strcmp(a, "--shuffle"))
            o.shuffle = 1;
        else if (!strcmp(a, "--bounce"))
            o.bounce = 1;
        else if (!strcmp(a, "--bounce-sorted"))
            o.bounce = 2;
        else if (!strcmp(a, "--json") && v)
            o.json = argv[++i];
        else if (a[0] == '-') {
            fprintf(stderr, "trace_bench: unknown option %s\n", a);
            return 2;
        } else if (o.scene_count < 15)
            o.scenes[o.scene_count++] = a;
    }
    if (!o.probes || !o.rays || !o.repeat || (uint64_t)o.probes * o.rays > (1u << 28)) {
        fprintf(stderr, "trace_bench: --probes, --rays and --repeat must be positive, probes*rays <= 2^28\n");
        return 2;
    }
    if (!o.scene_count)
        o.scene_count = bench_default_scenes("trace_bench", o.scenes, 15); /* room for --instanced */
    const char *crypt = "../shared/scenes/openarena/oacmpdm1.glb";
    if (o.instanced) {
        pb_scene_desc sd = {{0}, 1};
        pb_scene *s = NULL;
        pb_error err;
        if (pb_scene_load(crypt, &sd, &s, &err) == PB_OK) {
            const char *p = write_instanced(s, o.instanced);
            if (p)
                o.scenes[o.scene_count++] = p;
            pb_scene_destroy(s);
        } else {
            fprintf(stderr, "trace_bench: --instanced needs %s: %s\n", crypt, err.message);
        }
    }

    pb_context_desc cd = {o.device, (uint32_t)o.validation, 0, 0, {0}};
    cd.portable_kernels = (uint32_t)o.portable;
    cd.scene_loads = o.scene_loads;
    pb_context *ctx = NULL;
    pb_error err;
    if (pb_context_create(&cd, &ctx, &err) != PB_OK) {
        fprintf(stderr, "trace_bench: %s\n", err.message);
        return 1;
    }
    RTCDevice edev = rtcNewDevice(NULL);
    const pb_device_info *dev = pb_context_device(ctx);
    uint32_t host_threads = pb_host_threads();
    const char *kernels = pb_context_native64(ctx) ? "native64" : "portable";
    const char *loads = pb_context_scene_texels(ctx) ? "texel" : "address";
    const char *rays_of = o.bounce == 2 ? "bounce rays, sorted" : o.bounce ? "bounce rays" : "probe rays";
    printf("device: %s (%s), %s kernels, %s loads; Embree 3 on %u host threads; %s%s\n", dev->name, dev->driver,
           kernels, loads, host_threads, rays_of, o.shuffle ? ", shuffled" : "");
    printf("%-22s %9s %8s %6s %8s %9s %11s %11s %5s %11s %8s %7s\n", "scene", "tris", "bvh ms", "depth", "B/tri",
           "rays", "gpu Mr/s", "gpu wall", "busy", "embree Mr/s", "ratio", "agree");
    result res[16];
    int nres = 0;
    double least_busy = 1.0;
    for (int i = 0; i < o.scene_count; ++i) {
        if (!bench_scene(ctx, edev, o.scenes[i], &o, &res[nres]))
            continue;
        result *r = &res[nres++];
        double gk = r->gpu_kernel_ms > 0 ? r->rays / (r->gpu_kernel_ms * 1e3) : 0;
        double gw = r->rays / (r->gpu_wall_ms * 1e3), em = r->rays / (r->embree_ms * 1e3);
        double busy = r->gpu_kernel_ms / r->gpu_wall_ms; /* of pb_trace's wall time, the kernel's share */
        least_busy = busy < least_busy ? busy : least_busy;
        printf("%-22.22s %9u %8.1f %6u %8.1f %9u %11.2f %11.2f %4.0f%% %11.2f %8.3f %6.2f%%\n", basename_of(r->scene),
               r->triangles, r->bvh_ms, r->bvh_depth, r->bytes_per_tri, r->rays, gk, gw, 100 * busy, em, gk / em,
               100 * r->agree);
        fflush(stdout);
    }
    /* An H100 fed this way dropped its SM clock from 1,980 to 345-705 MHz
     * after about 4 s, and the kernel rate with it (bench/RESULTS.md, "NVIDIA
     * H100, third lease"): say so where the device is a GPU left idle */
    if (nres && least_busy < 0.5 && dev->type != PB_DEVICE_CPU)
        printf("note: the GPU ran kernels %.0f%% of the time (rays come from the host); a driver may lower its clocks "
               "in such runs, and the kernel rate with them: fewer --probes keep a run short\n",
               100 * least_busy);
    mkdir("bench/out", 0755);
    FILE *f = fopen(o.json, "w");
    if (f) {
        fprintf(f, "{\n  \"bench\": \"trace\",\n  \"device\": \"%s\",\n  \"driver\": \"%s\",\n"
                   "  \"kernels\": \"%s\",\n  \"scene_loads\": \"%s\",\n  \"host_threads\": %u,\n"
                   "  \"rays_per_probe\": %u,\n  \"rays_of\": \"%s\",\n"
                   "  \"results\": [\n",
                dev->name, dev->driver, kernels, loads, host_threads, o.rays, rays_of);
        for (int i = 0; i < nres; ++i) {
            result *r = &res[i];
            double gk = r->gpu_kernel_ms > 0 ? r->rays / (r->gpu_kernel_ms * 1e3) : 0;
            double em = r->rays / (r->embree_ms * 1e3);
            fprintf(f,
                    "    {\"scene\": \"%s\", \"triangles\": %u, \"probes\": %u, \"rays\": %u, \"bvh_build_ms\": %.3f, \"bvh_first_build_ms\": %.3f,"
                    " \"bvh_depth\": %u, \"bvh_sah\": %.3f, \"gpu_bytes_per_triangle\": %.2f,"
                    " \"gpu_kernel_ms\": %.3f, \"gpu_wall_ms\": %.3f, \"gpu_busy\": %.4f, \"gpu_mrays_kernel\": %.4f,"
                    " \"gpu_mrays_wall\": %.4f, \"embree_build_ms\": %.3f, \"embree_ms\": %.3f,"
                    " \"embree_mrays\": %.4f, \"ratio_gpu_kernel_to_embree\": %.4f, \"hit_agreement\": %.6f}%s\n",
                    basename_of(r->scene), r->triangles, r->probes, r->rays, r->bvh_ms, r->bvh_cold_ms, r->bvh_depth,
                    r->bvh_sah,
                    r->bytes_per_tri, r->gpu_kernel_ms, r->gpu_wall_ms, r->gpu_kernel_ms / r->gpu_wall_ms, gk,
                    r->rays / (r->gpu_wall_ms * 1e3),
                    r->embree_build_ms, r->embree_ms, em, gk / em, r->agree, i + 1 < nres ? "," : "");
        }
        fprintf(f, "  ]\n}\n");
        fclose(f);
        printf("wrote %s\n", o.json);
    }
    rtcReleaseDevice(edev);
    uint32_t vmsgs = pb_context_validation_messages(ctx);
    if (vmsgs)
        fprintf(stderr, "%s: %u Vulkan validation messages\n", argv[0], vmsgs);
    pb_context_destroy(ctx);
    return nres == o.scene_count && !vmsgs ? 0 : 1;
}
