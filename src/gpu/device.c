/* Instance, validation messenger, device listing and choice, context life. */
#include "common/common.h"
#include "gpu/gpu.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define VALIDATION_LAYER "VK_LAYER_KHRONOS_validation"
#define TIMESTAMP_CAPACITY 64

const char *pb_vk_result_name(VkResult vr)
{
    switch (vr) {
#define CASE(x) case x: return #x;
        CASE(VK_SUCCESS) CASE(VK_NOT_READY) CASE(VK_TIMEOUT) CASE(VK_INCOMPLETE)
        CASE(VK_ERROR_OUT_OF_HOST_MEMORY) CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
        CASE(VK_ERROR_INITIALIZATION_FAILED) CASE(VK_ERROR_DEVICE_LOST)
        CASE(VK_ERROR_MEMORY_MAP_FAILED) CASE(VK_ERROR_LAYER_NOT_PRESENT)
        CASE(VK_ERROR_EXTENSION_NOT_PRESENT) CASE(VK_ERROR_FEATURE_NOT_PRESENT)
        CASE(VK_ERROR_INCOMPATIBLE_DRIVER) CASE(VK_ERROR_TOO_MANY_OBJECTS)
        CASE(VK_ERROR_FORMAT_NOT_SUPPORTED) CASE(VK_ERROR_UNKNOWN)
        CASE(VK_ERROR_OUT_OF_POOL_MEMORY) CASE(VK_ERROR_INVALID_SHADER_NV)
#undef CASE
    default: return "VK_ERROR_(other)";
    }
}

pb_result pb_vk_fail(pb_context *ctx, pb_error *err, VkResult vr, const char *what)
{
    const char *dev = ctx ? ctx->info.name : "Vulkan";
    switch (vr) {
    case VK_ERROR_DEVICE_LOST:
        return pb_fail(err, PB_ERROR_DEVICE_LOST,
                       "%s: device lost during %s (driver reset, GPU hang or watchdog; try a smaller "
                       "rays_per_submit)", dev, what);
    case VK_ERROR_OUT_OF_DEVICE_MEMORY:
        return pb_fail(err, PB_ERROR_OUT_OF_DEVICE_MEMORY, "%s: out of device memory during %s", dev, what);
    case VK_ERROR_OUT_OF_HOST_MEMORY:
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory during %s", dev, what);
    default:
        return pb_fail(err, PB_ERROR_VULKAN, "%s: %s failed: %s", dev, what, pb_vk_result_name(vr));
    }
}

static VKAPI_ATTR VkBool32 VKAPI_CALL on_validation(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT type,
                                                    const VkDebugUtilsMessengerCallbackDataEXT *data, void *user)
{
    (void)type;
    pb_context *ctx = user;
    pb_log_level level = PB_LOG_DEBUG;
    if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)
        level = PB_LOG_ERROR;
    else if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT)
        level = PB_LOG_WARN;
    if (level >= PB_LOG_WARN) {
        ctx->validation_messages++;
        pb_logf(&ctx->desc.log, level, "vulkan validation: %s", data->pMessage ? data->pMessage : "(no message)");
    }
    return VK_FALSE;
}

static int has_layer(const char *name)
{
    uint32_t n = 0;
    if (vkEnumerateInstanceLayerProperties(&n, NULL) != VK_SUCCESS || n == 0)
        return 0;
    VkLayerProperties *props = calloc(n, sizeof *props);
    int found = 0;
    if (props && vkEnumerateInstanceLayerProperties(&n, props) == VK_SUCCESS)
        for (uint32_t i = 0; i < n; ++i)
            found |= strcmp(props[i].layerName, name) == 0;
    free(props);
    return found;
}

static pb_result load_loader(pb_error *err)
{
    if (volkInitialize() != VK_SUCCESS)
        return pb_fail(err, PB_ERROR_NO_DEVICE,
                       "no Vulkan loader found (libvulkan.so.1); install libvulkan1 and a driver "
                       "(mesa-vulkan-drivers for the CPU device lavapipe)");
    if (volkGetInstanceVersion() < VK_API_VERSION_1_2)
        return pb_fail(err, PB_ERROR_NO_DEVICE, "the Vulkan loader is older than 1.2");
    return PB_OK;
}

static pb_result create_instance(pb_context *ctx, int validation, pb_error *err)
{
    const char *layers[1] = {VALIDATION_LAYER};
    const char *exts[2] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME, VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME};
    if (validation && !has_layer(VALIDATION_LAYER))
        return pb_fail(err, PB_ERROR_UNSUPPORTED,
                       "validation requested but %s is not installed (Debian: vulkan-validationlayers)",
                       VALIDATION_LAYER);
    VkApplicationInfo app = {VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "probebake";
    app.applicationVersion = VK_MAKE_VERSION(PB_VERSION_MAJOR, PB_VERSION_MINOR, PB_VERSION_PATCH);
    app.pEngineName = "probebake";
    app.apiVersion = VK_API_VERSION_1_2;
    VkDebugUtilsMessengerCreateInfoEXT mi = {VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    mi.pfnUserCallback = on_validation;
    mi.pUserData = ctx;
    /* synchronisation validation too: a missing barrier between kernels is
     * a bug no single-threaded CPU device would show */
    VkValidationFeatureEnableEXT enables[1] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
    VkValidationFeaturesEXT vf = {VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
    vf.enabledValidationFeatureCount = 1;
    vf.pEnabledValidationFeatures = enables;
    vf.pNext = &mi; /* the messenger also catches messages from instance creation itself */
    VkInstanceCreateInfo ci = {VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ci.pApplicationInfo = &app;
    if (validation) {
        ci.enabledLayerCount = 1;
        ci.ppEnabledLayerNames = layers;
        ci.enabledExtensionCount = 2;
        ci.ppEnabledExtensionNames = exts;
        ci.pNext = &vf;
    }
    VkResult vr = vkCreateInstance(&ci, NULL, &ctx->instance);
    if (vr == VK_ERROR_INCOMPATIBLE_DRIVER)
        return pb_fail(err, PB_ERROR_NO_DEVICE,
                       "no Vulkan 1.2 driver found (VK_ERROR_INCOMPATIBLE_DRIVER); install a GPU driver, or "
                       "mesa-vulkan-drivers for the CPU device lavapipe");
    if (vr != VK_SUCCESS)
        return pb_vk_fail(NULL, err, vr, "vkCreateInstance");
    volkLoadInstanceOnly(ctx->instance);
    if (validation) {
        PFN_vkCreateDebugUtilsMessengerEXT create_messenger =
            (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(ctx->instance, "vkCreateDebugUtilsMessengerEXT");
        ctx->destroy_messenger = (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(
            ctx->instance, "vkDestroyDebugUtilsMessengerEXT");
        if (!create_messenger || !ctx->destroy_messenger)
            return pb_fail(err, PB_ERROR_UNSUPPORTED, "VK_EXT_debug_utils is not available with validation");
        vr = create_messenger(ctx->instance, &mi, NULL, &ctx->messenger);
        if (vr != VK_SUCCESS)
            return pb_vk_fail(NULL, err, vr, "vkCreateDebugUtilsMessengerEXT");
    }
    return PB_OK;
}

/* Fills `info` and says whether the device has what probebake needs. */
static void describe(VkPhysicalDevice pd, uint32_t index, pb_device_info *info)
{
    memset(info, 0, sizeof *info);
    info->index = index;
    VkPhysicalDeviceDriverProperties driver = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
    VkPhysicalDeviceSubgroupProperties subgroup = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES, &driver};
    VkPhysicalDeviceMaintenance3Properties m3 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES, &subgroup};
    VkPhysicalDeviceProperties2 p2 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &m3};
    vkGetPhysicalDeviceProperties2(pd, &p2);
    const VkPhysicalDeviceProperties *p = &p2.properties;
    snprintf(info->name, sizeof info->name, "%s", p->deviceName);
    snprintf(info->driver, sizeof info->driver, "%.120s / %.120s", driver.driverName, driver.driverInfo);
    info->api_version = p->apiVersion;
    switch (p->deviceType) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: info->type = PB_DEVICE_DISCRETE_GPU; break;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: info->type = PB_DEVICE_INTEGRATED_GPU; break;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: info->type = PB_DEVICE_VIRTUAL_GPU; break;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: info->type = PB_DEVICE_CPU; break;
    default: info->type = PB_DEVICE_OTHER; break;
    }
    info->subgroup_size = subgroup.subgroupSize;
    info->max_storage_buffer_range = p->limits.maxStorageBufferRange;
    info->max_memory_allocation = m3.maxMemoryAllocationSize;
    VkPhysicalDeviceMemoryProperties mem;
    vkGetPhysicalDeviceMemoryProperties(pd, &mem);
    for (uint32_t i = 0; i < mem.memoryHeapCount; ++i)
        if ((mem.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) &&
            mem.memoryHeaps[i].size > info->device_local_bytes)
            info->device_local_bytes = mem.memoryHeaps[i].size;

    VkPhysicalDeviceVulkan12Features f12 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceFeatures2 f2 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    info->usable = 1;
    if (p->apiVersion < VK_API_VERSION_1_2) {
        info->usable = 0;
        snprintf(info->unusable_reason, sizeof info->unusable_reason, "Vulkan %u.%u < 1.2",
                 VK_API_VERSION_MAJOR(p->apiVersion), VK_API_VERSION_MINOR(p->apiVersion));
        return;
    }
    vkGetPhysicalDeviceFeatures2(pd, &f2);
    info->shader_int64 = f2.features.shaderInt64 != 0;
    info->shader_float64 = f2.features.shaderFloat64 != 0;
    if (!f12.bufferDeviceAddress) {
        info->usable = 0;
        snprintf(info->unusable_reason, sizeof info->unusable_reason, "no bufferDeviceAddress");
    }
    /* shaderInt64 and shaderFloat64 are not needed: addresses are uvec2 in the
     * kernels and the exact edge functions use 32-bit integers. */
    uint32_t qn = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &qn, NULL);
    VkQueueFamilyProperties qf[16];
    if (qn > 16)
        qn = 16;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &qn, qf);
    int compute = 0;
    for (uint32_t i = 0; i < qn; ++i)
        compute |= (qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT) != 0;
    if (!compute && info->usable) {
        info->usable = 0;
        snprintf(info->unusable_reason, sizeof info->unusable_reason, "no compute queue");
    }
}

static int type_rank(uint32_t type)
{
    switch (type) {
    case PB_DEVICE_DISCRETE_GPU: return 4;
    case PB_DEVICE_INTEGRATED_GPU: return 3;
    case PB_DEVICE_VIRTUAL_GPU: return 2;
    case PB_DEVICE_CPU: return 1;
    default: return 0;
    }
}

static const char *const type_names[] = {"other", "integrated GPU", "discrete GPU", "virtual GPU", "CPU"};

pb_result pb_enumerate_devices(pb_device_info *out, uint32_t capacity, uint32_t *count, pb_error *err)
{
    pb_error_clear(err);
    *count = 0;
    pb_result r = load_loader(err);
    if (r != PB_OK)
        return r;
    pb_context tmp;
    memset(&tmp, 0, sizeof tmp);
    r = create_instance(&tmp, 0, err);
    if (r != PB_OK)
        return r;
    uint32_t n = 0;
    vkEnumeratePhysicalDevices(tmp.instance, &n, NULL);
    VkPhysicalDevice *pds = calloc(n ? n : 1, sizeof *pds);
    if (pds && n)
        vkEnumeratePhysicalDevices(tmp.instance, &n, pds);
    for (uint32_t i = 0; pds && i < n && i < capacity; ++i)
        describe(pds[i], i, &out[i]);
    *count = pds ? n : 0;
    free(pds);
    vkDestroyInstance(tmp.instance, NULL);
    return PB_OK;
}

const char *pb_device_type_name(uint32_t type)
{
    return type < 5 ? type_names[type] : "other";
}

static pb_result pick_device(pb_context *ctx, pb_error *err)
{
    uint32_t n = 0;
    VkResult vr = vkEnumeratePhysicalDevices(ctx->instance, &n, NULL);
    if (vr != VK_SUCCESS || n == 0)
        return pb_fail(err, PB_ERROR_NO_DEVICE,
                       "no Vulkan device found (install a GPU driver, or mesa-vulkan-drivers for lavapipe)");
    VkPhysicalDevice *pds = calloc(n, sizeof *pds);
    pb_device_info *infos = calloc(n, sizeof *infos);
    if (!pds || !infos) {
        free(pds), free(infos);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory listing devices");
    }
    vkEnumeratePhysicalDevices(ctx->instance, &n, pds);
    int best = -1;
    const char *want = ctx->desc.device;
    char *end = NULL;
    long want_index = want && *want ? strtol(want, &end, 10) : -1;
    int by_index = want && *want && end && *end == '\0';
    for (uint32_t i = 0; i < n; ++i) {
        describe(pds[i], i, &infos[i]);
        pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "device %u: %s (%s, %s)%s%s", i, infos[i].name,
                pb_device_type_name(infos[i].type), infos[i].driver, infos[i].usable ? "" : " unusable: ",
                infos[i].usable ? "" : infos[i].unusable_reason);
        int match = 1;
        if (by_index)
            match = (long)i == want_index;
        else if (want && *want)
            match = strstr(infos[i].name, want) != NULL;
        if (!match)
            continue;
        if (!infos[i].usable) {
            if (want && *want) {
                pb_result r = pb_fail(err, PB_ERROR_NO_DEVICE, "device %u (%s) cannot run probebake: %s", i,
                                      infos[i].name, infos[i].unusable_reason);
                free(pds), free(infos);
                return r;
            }
            continue;
        }
        if (best < 0 || type_rank(infos[i].type) > type_rank(infos[best].type))
            best = (int)i;
    }
    if (best < 0) {
        pb_result r = want && *want ? pb_fail(err, PB_ERROR_NO_DEVICE, "no Vulkan device matches '%s' "
                                                                        "(see `probebake devices`)", want)
                                    : pb_fail(err, PB_ERROR_NO_DEVICE, "no usable Vulkan device (need Vulkan 1.2 with "
                                                                        "bufferDeviceAddress and a compute queue)");
        free(pds), free(infos);
        return r;
    }
    ctx->physical = pds[best];
    ctx->info = infos[best];
    pb_logf(&ctx->desc.log, PB_LOG_INFO, "using device %d: %s (%s)", best, infos[best].name,
            pb_device_type_name(infos[best].type));
    free(pds), free(infos);
    return PB_OK;
}

static pb_result create_device(pb_context *ctx, pb_error *err)
{
    uint32_t qn = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(ctx->physical, &qn, NULL);
    VkQueueFamilyProperties qf[16];
    if (qn > 16)
        qn = 16;
    vkGetPhysicalDeviceQueueFamilyProperties(ctx->physical, &qn, qf);
    /* prefer a compute-only family (async compute), else any with compute */
    int fam = -1;
    for (uint32_t i = 0; i < qn; ++i)
        if ((qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT) && !(qf[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) && fam < 0)
            fam = (int)i;
    for (uint32_t i = 0; i < qn && fam < 0; ++i)
        if (qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT)
            fam = (int)i;
    ctx->queue_family = (uint32_t)fam;
    float prio = 1.0f;
    VkDeviceQueueCreateInfo qci = {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qci.queueFamilyIndex = ctx->queue_family;
    qci.queueCount = 1;
    qci.pQueuePriorities = &prio;
    VkPhysicalDeviceVulkan12Features f12 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    f12.bufferDeviceAddress = VK_TRUE;
    VkPhysicalDeviceFeatures2 f2 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    /* 64-bit types are optional: enabled only for the native64 kernels */
    ctx->native64 = ctx->info.shader_int64 && ctx->info.shader_float64 && !ctx->desc.portable_kernels;
    f2.features.shaderInt64 = ctx->native64 ? VK_TRUE : VK_FALSE;
    f2.features.shaderFloat64 = ctx->native64 ? VK_TRUE : VK_FALSE;
    pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "kernels: %s", ctx->native64 ? "native64 (shaderInt64 + shaderFloat64)"
            : ctx->desc.portable_kernels ? "portable (asked for)" : "portable (no shaderInt64 or shaderFloat64)");
    VkDeviceCreateInfo dci = {VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &f2};
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    VkResult vr = vkCreateDevice(ctx->physical, &dci, NULL, &ctx->device);
    if (vr != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "vkCreateDevice");
    volkLoadDeviceTable(&ctx->vk, ctx->device);
    ctx->vk.vkGetDeviceQueue(ctx->device, ctx->queue_family, 0, &ctx->queue);

    VkDescriptorSetLayoutBinding views[2] = {
        {0, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
        {1, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL}};
    VkDescriptorSetLayoutCreateInfo dsl = {VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    dsl.bindingCount = 2;
    dsl.pBindings = views;
    if ((vr = ctx->vk.vkCreateDescriptorSetLayout(ctx->device, &dsl, NULL, &ctx->scene_set_layout)) != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "vkCreateDescriptorSetLayout");
    ctx->scene_texels = ctx->desc.scene_loads == PB_SCENE_LOADS_TEXEL ||
                        (ctx->desc.scene_loads == PB_SCENE_LOADS_AUTO && ctx->info.type == PB_DEVICE_CPU);
    pb_logf(&ctx->desc.log, PB_LOG_DEBUG, "scene loads: %s (%s)", ctx->scene_texels ? "texels" : "addresses",
            ctx->desc.scene_loads != PB_SCENE_LOADS_AUTO ? "asked for"
            : ctx->scene_texels ? "CPU device" : "GPU device");

    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(ctx->physical, &props);
    ctx->limits = props.limits;
    ctx->max_allocation = ctx->info.max_memory_allocation;
    vkGetPhysicalDeviceMemoryProperties(ctx->physical, &ctx->memory);
    uint32_t bits = qf[ctx->queue_family].timestampValidBits;
    if (bits && props.limits.timestampPeriod > 0.f) {
        ctx->timestamp_period_ns = props.limits.timestampPeriod;
        ctx->timestamp_mask = bits >= 64 ? ~0ull : ((1ull << bits) - 1);
    }

    VkCommandPoolCreateInfo pci = {VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pci.queueFamilyIndex = ctx->queue_family;
    if ((vr = ctx->vk.vkCreateCommandPool(ctx->device, &pci, NULL, &ctx->pool)) != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "vkCreateCommandPool");
    VkCommandBufferAllocateInfo cai = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cai.commandPool = ctx->pool;
    cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cai.commandBufferCount = 1;
    if ((vr = ctx->vk.vkAllocateCommandBuffers(ctx->device, &cai, &ctx->cmd)) != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "vkAllocateCommandBuffers");
    VkFenceCreateInfo fci = {VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    if ((vr = ctx->vk.vkCreateFence(ctx->device, &fci, NULL, &ctx->fence)) != VK_SUCCESS)
        return pb_vk_fail(ctx, err, vr, "vkCreateFence");
    if (ctx->timestamp_period_ns > 0) {
        VkQueryPoolCreateInfo qpi = {VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
        qpi.queryType = VK_QUERY_TYPE_TIMESTAMP;
        qpi.queryCount = TIMESTAMP_CAPACITY;
        if ((vr = ctx->vk.vkCreateQueryPool(ctx->device, &qpi, NULL, &ctx->timestamps)) != VK_SUCCESS)
            return pb_vk_fail(ctx, err, vr, "vkCreateQueryPool");
        ctx->timestamp_capacity = TIMESTAMP_CAPACITY;
    }
    return PB_OK;
}

pb_result pb_context_create(const pb_context_desc *desc, pb_context **out, pb_error *err)
{
    pb_error_clear(err);
    *out = NULL;
    if (desc && desc->scene_loads > PB_SCENE_LOADS_TEXEL)
        return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "scene_loads %u is not a pb_scene_loads", desc->scene_loads);
    pb_context *ctx = calloc(1, sizeof *ctx);
    if (!ctx)
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "out of host memory");
    if (desc)
        ctx->desc = *desc;
    if (!ctx->desc.rays_per_submit)
        ctx->desc.rays_per_submit = 1u << 20;
    pb_result r = load_loader(err);
    if (r == PB_OK)
        r = create_instance(ctx, ctx->desc.validation != 0, err);
    if (r == PB_OK)
        r = pick_device(ctx, err);
    if (r == PB_OK)
        r = create_device(ctx, err);
    if (r != PB_OK) {
        pb_context_destroy(ctx);
        return r;
    }
    *out = ctx;
    return PB_OK;
}

void pb_context_destroy(pb_context *ctx)
{
    if (!ctx)
        return;
    if (ctx->device) {
        ctx->vk.vkDeviceWaitIdle(ctx->device);
        pb_pipeline_cache_release(ctx);
        if (ctx->scene_set_layout)
            ctx->vk.vkDestroyDescriptorSetLayout(ctx->device, ctx->scene_set_layout, NULL);
        if (ctx->timestamps)
            ctx->vk.vkDestroyQueryPool(ctx->device, ctx->timestamps, NULL);
        if (ctx->fence)
            ctx->vk.vkDestroyFence(ctx->device, ctx->fence, NULL);
        if (ctx->pool)
            ctx->vk.vkDestroyCommandPool(ctx->device, ctx->pool, NULL);
        ctx->vk.vkDestroyDevice(ctx->device, NULL);
    }
    if (ctx->messenger && ctx->destroy_messenger)
        ctx->destroy_messenger(ctx->instance, ctx->messenger, NULL);
    if (ctx->instance)
        vkDestroyInstance(ctx->instance, NULL);
    free(ctx);
}

const pb_device_info *pb_context_device(const pb_context *ctx)
{
    return &ctx->info;
}

int pb_context_native64(const pb_context *ctx)
{
    return ctx ? ctx->native64 : 0;
}

int pb_context_scene_texels(const pb_context *ctx)
{
    return ctx ? ctx->scene_texels : 0;
}

uint32_t pb_context_validation_messages(const pb_context *ctx)
{
    return ctx->validation_messages;
}
