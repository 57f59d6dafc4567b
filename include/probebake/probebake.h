/*
 * probebake — light probe volume baker (C11 API)
 *
 * WHAT IT DOES
 *   Loads a glTF 2.0 scene, flattens it to world-space triangles (rebased to
 *   the bounding-box centre in double precision), builds a binned-SAH BVH on
 *   all host cores, uploads it to a Vulkan device (any GPU, or Mesa lavapipe
 *   on a CPU) and traces rays there with GLSL compute kernels. Every kernel
 *   has a CPU reference in this library (pb_bvh_trace_cpu and friends).
 *
 * WHAT IT DOES NOT DO (yet, or ever)
 *   - No skinning, morph targets, KHR_texture_transform or sparse accessors:
 *     a file that *requires* an unsupported extension is refused, one that
 *     merely uses it loads with the extension ignored.
 *   - No hardware ray tracing: traversal is software, so it runs everywhere.
 *   - The library never prints and never exits: messages go to the log
 *     callback of the descriptor, errors come back as pb_result + pb_error.
 *
 * WALK-THROUGH
 *   pb_scene *scene; pb_error err;
 *   pb_scene_load("room.gltf", NULL, &scene, &err);      // 1. scene
 *   pb_bvh *bvh;  pb_bvh_build(scene, NULL, &bvh, &err);  // 2. BVH
 *   pb_context *ctx; pb_context_create(NULL, &ctx, &err); // 3. device
 *   pb_gpu_scene *gs; pb_gpu_scene_create(ctx, scene, bvh, &gs, &err);
 *   pb_trace(ctx, gs, rays, n, PB_TRACE_CLOSEST, hits, NULL, &err);
 *   ... destroy in reverse order.
 *
 * CONVENTIONS (see docs/)
 *   glTF axes: right-handed, +Y up, metres. Scene positions are *local*:
 *   original = local + scene->origin (double). Triangles are indexed in
 *   scene order everywhere in this API; the GPU's leaf order stays internal.
 *
 * ERRORS
 *   Every fallible function returns pb_result (PB_OK == 0). When `err` is not
 *   NULL it receives the code and one line naming the file and the problem.
 *
 * THREADS
 *   Objects are not internally synchronised: use one from one thread at a
 *   time. Distinct objects may be used from distinct threads.
 */
#ifndef PROBEBAKE_H
#define PROBEBAKE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PB_VERSION_MAJOR 0
#define PB_VERSION_MINOR 1
#define PB_VERSION_PATCH 0
#define PB_VERSION_STRING "0.1.0"

typedef enum pb_result {
    PB_OK = 0,
    PB_ERROR_INVALID_ARGUMENT,   /* a parameter or descriptor field is out of range */
    PB_ERROR_IO,                 /* a file could not be read or written */
    PB_ERROR_PARSE,              /* malformed input file */
    PB_ERROR_UNSUPPORTED,        /* valid input using something we do not implement */
    PB_ERROR_OUT_OF_HOST_MEMORY,
    PB_ERROR_NO_DEVICE,          /* no Vulkan device, or none matching --device */
    PB_ERROR_DEVICE_LOST,
    PB_ERROR_OUT_OF_DEVICE_MEMORY,
    PB_ERROR_TOO_LARGE,          /* work refused before allocation: exceeds a device limit */
    PB_ERROR_VULKAN,             /* any other Vulkan failure */
    PB_ERROR_CANCELLED,
    PB_RESULT_COUNT
} pb_result;

/* One-line error report. `message` always ends in '\0'. */
typedef struct pb_error {
    pb_result code;
    char message[512];
} pb_error;

/* Stable name of a result code ("PB_ERROR_PARSE"). Never NULL. */
const char *pb_result_name(pb_result r);

typedef enum pb_log_level {
    PB_LOG_DEBUG = 0,
    PB_LOG_INFO,
    PB_LOG_WARN,
    PB_LOG_ERROR
} pb_log_level;

/* Log sink. `message` is one line without a trailing newline. */
typedef void (*pb_log_fn)(pb_log_level level, const char *message, void *user_data);

typedef struct pb_log {
    pb_log_fn fn;      /* NULL: messages are dropped */
    void *user_data;
} pb_log;

#ifdef __cplusplus
}
#endif

#include "probebake/scene.h"
#include "probebake/bvh.h"
#include "probebake/device.h"
#include "probebake/trace.h"
#include "probebake/sh.h"
#include "probebake/octahedral.h"
#include "probebake/volume.h"

#endif /* PROBEBAKE_H */
