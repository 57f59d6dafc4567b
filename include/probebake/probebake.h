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

#include "probebake/base.h"
#include "probebake/scene.h"
#include "probebake/bvh.h"
#include "probebake/device.h"
#include "probebake/trace.h"
#include "probebake/sh.h"
#include "probebake/octahedral.h"
#include "probebake/files.h"
#include "probebake/volume.h"
#include "probebake/bake.h"
#include "probebake/environment.h"
#include "probebake/sample.h"
#include "probebake/render.h"

#endif /* PROBEBAKE_H */
