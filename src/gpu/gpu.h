/* The Vulkan compute layer: plain structs with create/destroy pairs.
 *
 * device.c   instance, validation messenger, device listing and choice
 * buffer.c   buffers (device address, mapped when host-visible), staging copies
 * pipeline.c compute pipelines from embedded SPIR-V (push constants only:
 *            every array is reached through a buffer device address)
 * submit.c   one command buffer, bounded submissions, timestamp queries
 *
 * Device-level calls go through the context's own volk table (no global
 * device dispatch), so several contexts can live side by side. */
#ifndef PB_GPU_H
#define PB_GPU_H

#ifndef VK_NO_PROTOTYPES
#define VK_NO_PROTOTYPES
#endif
#include <volk.h>

#include <pthread.h>
#include <stdatomic.h>

#include "probebake/device.h"

typedef struct pb_context {
    pb_context_desc desc;
    pb_device_info info;
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    /* extension entry point of *this* instance: volk's instance table is
     * global and follows the last instance created */
    PFN_vkDestroyDebugUtilsMessengerEXT destroy_messenger;
    VkPhysicalDevice physical;
    VkDevice device;
    struct VolkDeviceTable vk;
    VkQueue queue;
    uint32_t queue_family;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    VkQueryPool timestamps;
    uint32_t timestamp_capacity;
    uint32_t timestamp_count;    /* written in the current command buffer */
    double timestamp_period_ns;  /* 0: timestamps unsupported on this queue */
    uint64_t timestamp_mask;
    VkPhysicalDeviceMemoryProperties memory;
    VkPhysicalDeviceLimits limits;
    uint64_t max_allocation;
    uint64_t allocated;          /* device-local bytes allocated through pb_buffer_create */
    double intervals_ms[32];     /* timestamp pairs of the last submission, in order */
    uint32_t interval_count;
    atomic_uint validation_messages; /* pipelines are made on worker threads too (pb_pipelines_begin) */
    uint32_t allocations, submissions; /* counted for desc.fail_allocation / fail_submission */
    uint32_t pipeline_jobs;      /* new pipelines asked for, counted for desc.fail_pipeline */
    int recording;
    int native64;                /* shaderInt64 + shaderFloat64 enabled: run the *_native64 kernels */
    struct pb_pipeline_entry *pipelines; /* the pipeline cache (pb_pipeline_create), destroyed with the context */
    uint32_t pipeline_count, pipeline_capacity;
    uint32_t pipelines_created;  /* driver pipeline creations, for tests and logs */
    VkDescriptorSetLayout scene_set_layout; /* set 0 of every pipeline: the scene's texel views (pb_gpu_scene) */
    int scene_texels;            /* kernels read nodes and triangles as texels (desc.scene_loads, device type) */
} pb_context;

/* SPIR-V and its size for kernel `name` on this context: the _native64
 * variant where 64-bit types are enabled, else the portable one (see
 * CMakeLists.txt). Both headers must be included. */
#define PB_KERNEL_SPIRV(ctx, name)                                                                                      \
    ((ctx)->native64 ? pb_spv_##name##_native64 : pb_spv_##name),                                                      \
        ((ctx)->native64 ? sizeof pb_spv_##name##_native64 : sizeof pb_spv_##name)

/* Maps a Vulkan error to a pb_result and a message naming `what`. */
pb_result pb_vk_fail(pb_context *ctx, pb_error *err, VkResult vr, const char *what);
const char *pb_vk_result_name(VkResult vr);

typedef enum pb_memory_kind {
    PB_MEMORY_DEVICE = 0,    /* device-local; mapped too when the device is UMA */
    PB_MEMORY_UPLOAD = 1,    /* host-visible, coherent: staging towards the device */
    PB_MEMORY_DOWNLOAD = 2   /* host-visible, cached if possible: staging back */
} pb_memory_kind;

typedef struct pb_buffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
    VkDeviceSize size;
    VkDeviceAddress address;
    void *mapped;            /* NULL when not host-visible */
    int device_local;
} pb_buffer;

/* Creates a buffer of `size` bytes (> 0) usable as storage buffer, transfer
 * source/destination and by device address. `what` names it in errors.
 * Refuses (PB_ERROR_TOO_LARGE) sizes over maxMemoryAllocationSize before
 * allocating. */
/* The memory type a buffer of `kind` takes from the types in type_bits, and
 * whether it stays mapped (device memory only where it is also host-cached);
 * type -1 where none fits. Pure: tested against other devices' tables. */
typedef struct pb_memory_choice {
    int type;
    int mapped;
} pb_memory_choice;
pb_memory_choice pb_buffer_memory_choice(const VkPhysicalDeviceMemoryProperties *mp, uint32_t type_bits,
                                         pb_memory_kind kind, int force_staging);

pb_result pb_buffer_create(pb_context *ctx, VkDeviceSize size, pb_memory_kind kind, const char *what, pb_buffer *out,
                           pb_error *err);
void pb_buffer_destroy(pb_context *ctx, pb_buffer *b);

/* Copies host data into a buffer: memcpy when mapped, else through a staging
 * buffer and a submission of its own (so: not while recording). */
pb_result pb_buffer_upload(pb_context *ctx, pb_buffer *dst, VkDeviceSize offset, const void *data, VkDeviceSize size,
                           pb_error *err);
pb_result pb_buffer_download(pb_context *ctx, const pb_buffer *src, VkDeviceSize offset, void *data,
                             VkDeviceSize size, pb_error *err);

/* Makes `count` records of `record_bytes` each at `offset` in dst where the
 * device reads them: fill(user, out, first, n) writes records [first, first
 * + n) to out, and is called on all host cores for disjoint ranges. Mapped
 * memory (UMA) is written in place; elsewhere each staging buffer's worth is
 * made and copied in turn. A large array (the scene's triangles) is then
 * neither held twice on the host nor copied once more. */
typedef void (*pb_fill_fn)(void *user, void *out, uint64_t first, uint64_t n);
pb_result pb_buffer_fill(pb_context *ctx, pb_buffer *dst, VkDeviceSize offset, uint32_t record_bytes, uint64_t count,
                         pb_fill_fn fill, void *user, pb_error *err);

typedef struct pb_pipeline {
    VkPipelineLayout layout;
    VkPipeline pipeline;
    uint32_t push_size;
    uint32_t local_size;
    uint32_t cached;            /* owned by the context's cache: pb_pipeline_destroy only forgets it */
} pb_pipeline;

/* The context keeps every pipeline it made, keyed by SPIR-V, specialisation
 * constants and push-constant size: lavapipe spends 0.4 s creating the bake
 * kernel, and a sparse bake or --indirect volume runs several bakes on one
 * context (and the tests run hundreds). */
typedef struct pb_pipeline_entry {
    const uint32_t *spirv;
    size_t spirv_bytes;
    uint32_t push_size, local_size, spec_count, spec[16];
    pb_pipeline pipeline;
} pb_pipeline_entry;

/* Compute pipeline from SPIR-V words; `spec` holds `spec_count` uint32
 * specialisation constants with ids 0..spec_count-1 (kernels that read the
 * scene: 0 the traversal stack, 1 PB_SCENE_TEXELS, then their own). Its
 * layout is set 0 = ctx->scene_set_layout plus `push_size` bytes of push
 * constants. Made once per context
 * for each (SPIR-V, constants, push size, local size) and then reused; the
 * caller still calls pb_pipeline_destroy (a no-op on a cached one). */
pb_result pb_pipeline_create(pb_context *ctx, const uint32_t *spirv, size_t spirv_bytes, uint32_t push_size,
                             const uint32_t *spec, uint32_t spec_count, uint32_t local_size, const char *what,
                             pb_pipeline *out, pb_error *err);
void pb_pipeline_destroy(pb_context *ctx, pb_pipeline *p);

/* Pipelines made on worker threads while the caller does other host work:
 * lavapipe spends about 0.2 s of NIR work on the bake kernel, and the bake
 * learns its light cells and fills its buffers meanwhile. Begin copies out
 * the cached ones and starts a thread per new one; end waits for them, then
 * caches, counts and logs them on the caller's thread, and returns the
 * first failure (then every `out` is cleared). Each begin needs its end
 * (also on the caller's error paths), before the context is destroyed. */
typedef struct pb_pipeline_request {
    const uint32_t *spirv;
    size_t spirv_bytes;
    uint32_t push_size;
    const uint32_t *spec;
    uint32_t spec_count;
    uint32_t local_size;
    const char *what;
    pb_pipeline *out;
} pb_pipeline_request;

#define PB_PIPELINE_BATCH_MAX 8
typedef struct pb_pipeline_job {
    pb_context *ctx;
    pb_pipeline_request request; /* its spec points at the job's own copy */
    uint32_t spec[16];
    pthread_t thread;
    int threaded;
    int inject;                  /* desc.fail_pipeline chose this one: it fails without a driver call */
    VkResult result;
    const char *stage;           /* the failing Vulkan call */
    pb_pipeline made;
    double ms;
} pb_pipeline_job;

typedef struct pb_pipeline_batch {
    pb_pipeline_job jobs[PB_PIPELINE_BATCH_MAX];
    uint32_t count;
} pb_pipeline_batch;

pb_result pb_pipelines_begin(pb_context *ctx, const pb_pipeline_request *requests, uint32_t count,
                             pb_pipeline_batch *batch, pb_error *err);
pb_result pb_pipelines_end(pb_context *ctx, pb_pipeline_batch *batch, pb_error *err);
/* Destroys every cached pipeline (pb_context_destroy calls it). */
void pb_pipeline_cache_release(pb_context *ctx);

/* Recording: begin, add work, then submit and wait (bounded submissions are
 * the caller's loop). Timestamps written in between are read after the wait. */
pb_result pb_cmd_begin(pb_context *ctx, pb_error *err);
void pb_cmd_dispatch(pb_context *ctx, const pb_pipeline *p, const void *push, uint32_t groups);
void pb_cmd_dispatch2(pb_context *ctx, const pb_pipeline *p, const void *push, uint32_t groups_x, uint32_t groups_y);
/* The stride that spreads a dispatch of `groups` workgroups over lavapipe's
 * threads, for kernels that read it (dispatch_order.c); 1 keeps the order. */
uint32_t pb_dispatch_spread(uint32_t groups);
/* A dispatch whose group counts the device wrote (uvec3 at `offset` of `args`). */
void pb_cmd_dispatch_indirect(pb_context *ctx, const pb_pipeline *p, const void *push, const pb_buffer *args,
                              VkDeviceSize offset);
/* Binds descriptor set 0 (a scene's texel views) for p's next dispatches:
 * kernels that read the scene need it bound whichever loads they use. */
void pb_cmd_bind_set(pb_context *ctx, const pb_pipeline *p, VkDescriptorSet set);
void pb_cmd_barrier(pb_context *ctx); /* all compute/transfer writes -> reads */
void pb_cmd_barrier_indirect(pb_context *ctx); /* compute writes -> indirect dispatch arguments and reads */
void pb_cmd_barrier_to_host(pb_context *ctx); /* device writes -> host reads after the wait */
void pb_cmd_copy(pb_context *ctx, const pb_buffer *src, VkDeviceSize src_offset, const pb_buffer *dst,
                 VkDeviceSize dst_offset, VkDeviceSize size);
void pb_cmd_timestamp(pb_context *ctx); /* no-op without timestamp support */
/* Submits, waits, and returns the summed intervals between timestamp pairs
 * (0,1), (2,3), ... in milliseconds through gpu_ms (may be NULL); each pair's
 * interval is also left in ctx->intervals_ms[0 .. interval_count). */
pb_result pb_cmd_submit_wait(pb_context *ctx, double *gpu_ms, pb_error *err);

/* A test kernel over a batch, synchronously (src/gpu/batch.c): `count`
 * entries of in_stride bytes in, out_stride bytes out, one invocation per
 * entry in workgroups of 64. The kernel's push constants are (inputs address,
 * outputs address, count, 3 unused words) and then `extra` (extra_bytes, at
 * most 96; NULL for none): exact_diff.comp, spherical_triangle.comp and
 * probe_sample.comp (extra: the volume's references), which test shading
 * and sampling math against their C references. */
pb_result pb_gpu_batch(pb_context *ctx, const uint32_t *spirv, size_t spirv_bytes, const char *name, const void *extra,
                       uint32_t extra_bytes, const void *in, uint32_t in_stride, void *out, uint32_t out_stride,
                       uint32_t count, pb_error *err);

#endif
