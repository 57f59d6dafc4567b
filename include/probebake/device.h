/*
 * probebake device: a Vulkan compute context (through volk, so no link-time
 * dependency on a particular loader).
 *
 * Device choice: discrete GPU > integrated GPU > virtual GPU > CPU (lavapipe)
 * unless pb_context_desc.device names one by index ("1") or by a substring of
 * its name ("llvmpipe"). Every candidate and the choice are logged.
 *
 * With `validation` set, VK_LAYER_KHRONOS_validation is enabled and every
 * message it sends is counted (pb_context_validation_messages) and logged:
 * tests fail on any.
 *
 * Threads: create and destroy contexts from one thread at a time (volk's
 * instance-level function table is process-wide); a context, once made, is
 * used by one thread at a time.
 */
#ifndef PROBEBAKE_DEVICE_H
#define PROBEBAKE_DEVICE_H

#include "probebake/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum pb_device_type {
    PB_DEVICE_OTHER = 0,
    PB_DEVICE_INTEGRATED_GPU = 1,
    PB_DEVICE_DISCRETE_GPU = 2,
    PB_DEVICE_VIRTUAL_GPU = 3,
    PB_DEVICE_CPU = 4
} pb_device_type;

typedef struct pb_device_info {
    uint32_t index;
    char name[256];
    uint32_t type;                /* pb_device_type */
    char driver[256];             /* driver name and info, e.g. "llvmpipe / Mesa 22.3.6" */
    uint32_t api_version;         /* VK_MAKE_API_VERSION packing */
    uint64_t device_local_bytes;  /* largest device-local heap */
    uint32_t subgroup_size;
    uint64_t max_storage_buffer_range;
    uint64_t max_memory_allocation;
    uint32_t usable;              /* 1 if it has what probebake needs (Vulkan 1.2, bufferDeviceAddress, compute) */
    uint32_t shader_int64;        /* optional: with shaderFloat64 too, the faster "native64" kernels run */
    uint32_t shader_float64;
    char unusable_reason[128];
} pb_device_info;

typedef struct pb_context pb_context;

/* How kernels read the BVH's nodes and triangles: both read the same bytes
 * and give the same hits; which is faster depends on the device. */
typedef enum pb_scene_loads {
    PB_SCENE_LOADS_AUTO = 0,    /* texels on CPU devices (lavapipe: measured faster), addresses elsewhere */
    PB_SCENE_LOADS_ADDRESS = 1, /* buffer device address loads */
    PB_SCENE_LOADS_TEXEL = 2    /* storage texel buffer loads (imageLoad of 16-byte texels) */
} pb_scene_loads;

/* Zero fields mean the defaults listed on each line. */
typedef struct pb_context_desc {
    const char *device;           /* NULL: best device; "N" index or name substring */
    uint32_t validation;          /* 1: enable the Khronos validation layer */
    uint32_t rays_per_submit;     /* default 1<<20: bounds one submit's run time (GPU watchdogs) */
    uint32_t force_staging;       /* 1: never map device buffers, copy through staging buffers as on a
                                     discrete GPU (tests that path on UMA devices such as lavapipe) */
    pb_log log;
    /* Fault injection, for tests of the error paths (0: off): the Nth device
     * memory allocation fails with VK_ERROR_OUT_OF_DEVICE_MEMORY, the Nth
     * submission with VK_ERROR_DEVICE_LOST, as real drivers report them. */
    uint32_t fail_allocation;
    uint32_t fail_submission;
    uint32_t portable_kernels;    /* 1: run the kernels that need neither shaderInt64 nor shaderFloat64
                                     even where the device has them (tests that path; same results) */
    uint32_t scene_loads;         /* pb_scene_loads; 0: AUTO */
    /* Fault injection, as fail_allocation: the Nth new pipeline fails with
     * VK_ERROR_OUT_OF_HOST_MEMORY (it may be made on a worker thread) */
    uint32_t fail_pipeline;
} pb_context_desc;

/* Lists the Vulkan devices. Writes up to `capacity` entries to `out` (may be
 * NULL when capacity is 0) and the total to *count.
 *  Returns PB_ERROR_NO_DEVICE when no Vulkan loader/ICD is present. */
pb_result pb_enumerate_devices(pb_device_info *out, uint32_t capacity, uint32_t *count, pb_error *err);

/* Creates a context on the chosen device. desc may be NULL.
 *  Returns PB_ERROR_NO_DEVICE (no loader, no device, no match, nothing usable),
 *  PB_ERROR_UNSUPPORTED (validation asked but the layer is not installed). */
pb_result pb_context_create(const pb_context_desc *desc, pb_context **out, pb_error *err);

/* Waits for the device to be idle and frees the context. NULL is allowed. */
void pb_context_destroy(pb_context *ctx);

/* Information about the device in use. */
const pb_device_info *pb_context_device(const pb_context *ctx);

/* "discrete GPU", "CPU", ... for a pb_device_type. */
const char *pb_device_type_name(uint32_t type);

/* 1 when this context runs the *_native64 kernels (shaderInt64 and
 * shaderFloat64 enabled), 0 for the portable ones. */
int pb_context_native64(const pb_context *ctx);

/* 1 when this context's kernels read the BVH as texels (pb_scene_loads; a
 * scene over the device's texel-view limit is still read through addresses). */
int pb_context_scene_texels(const pb_context *ctx);

/* Number of validation-layer messages (warnings and errors) received so far. */
uint32_t pb_context_validation_messages(const pb_context *ctx);

#ifdef __cplusplus
}
#endif
#endif
