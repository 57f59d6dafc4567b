/* load_bench: what one divergent 16-byte load costs a Vulkan kernel, by the
 * way it reads: storage buffer, buffer reference (32- or 64-bit components),
 * uniform texel buffer (rgba32ui, or r32ui four times), storage texel buffer
 * (imageLoad of rgba32ui), uniform buffer (the one that llvmpipe reads
 * inline, lane by lane but without a mask or a call; at most 64 KiB there, so
 * it runs only when the records fit: --records 1024 or fewer). Each kernel (load_bench/load_bench.comp) walks
 * random 64-byte records, four loads per step, so the loads of a SIMD
 * group's lanes diverge as a BVH traversal's do. The kinds run in
 * interleaved rounds (lavapipe's rate drifts between minutes), each the best
 * of --repeat dispatches; the table gives the median over rounds per step
 * and the ratio to the 64-bit buffer reference (the native64 kernels' loads).
 * Every kind reads the same bytes: each invocation's sum must equal the CPU
 * reference's walk (walk_cpu, the kernel's arithmetic in C; exit 1 if not),
 * and with --validation the layer must stay silent.
 *
 *   load_bench [--records N] [--steps N] [--invocations N] [--rounds N]
 *              [--repeat N] [--device INDEX] [--validation] [--json FILE] [--csv FILE]
 *
 * bench/RESULTS.md, "Texel loads", has its numbers on lavapipe. */
#define _POSIX_C_SOURCE 200809L
#ifndef VK_NO_PROTOTYPES
#define VK_NO_PROTOTYPES
#endif
#include <volk.h>

#include "load_bench_0.spv.h"
#include "load_bench_1.spv.h"
#include "load_bench_2.spv.h"
#include "load_bench_3.spv.h"
#include "load_bench_4.spv.h"
#include "load_bench_5.spv.h"
#include "load_bench_6.spv.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#define KINDS 7
#define KIND_UNIFORM 6
#define UNIFORM_BYTES 65536u /* the kernel's uniform block: 4,096 words */
static const char *const kind_names[KINDS] = {
    "storage buffer uvec4", "buffer reference uvec4", "buffer reference u64vec2",
    "uniform texel rgba32ui", "uniform texel r32ui x4", "storage texel rgba32ui", "uniform buffer uvec4"};
static const uint32_t *const kind_spirv[KINDS] = {load_bench_0, load_bench_1, load_bench_2, load_bench_3,
                                                  load_bench_4, load_bench_5, load_bench_6};
static const size_t kind_bytes[KINDS] = {sizeof load_bench_0, sizeof load_bench_1, sizeof load_bench_2,
                                         sizeof load_bench_3, sizeof load_bench_4, sizeof load_bench_5,
                                         sizeof load_bench_6};

typedef struct bench {
    VkInstance instance;
    VkPhysicalDevice physical;
    VkDevice device;
    VkQueue queue;
    uint32_t family;
    VkPhysicalDeviceMemoryProperties memory;
    int int64;
} bench;

static uint32_t validation_messages;

static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                 VkDebugUtilsMessageTypeFlagsEXT type,
                                                 const VkDebugUtilsMessengerCallbackDataEXT *data, void *user)
{
    (void)type, (void)user;
    if (severity & (VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)) {
        ++validation_messages;
        fprintf(stderr, "load_bench: validation: %s\n", data->pMessage);
    }
    return VK_FALSE;
}

static void die(const char *what, VkResult r)
{
    fprintf(stderr, "load_bench: %s failed (VkResult %d)\n", what, (int)r);
    exit(1);
}
#define VK(call) do { VkResult r_ = (call); if (r_ != VK_SUCCESS) die(#call, r_); } while (0)

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

typedef struct buffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
    void *mapped;
    VkDeviceAddress address;
} buffer;

/* A host-visible buffer (lavapipe and integrated GPUs: device memory too). */
static buffer make_buffer(bench *b, VkDeviceSize size, VkBufferUsageFlags usage)
{
    buffer out = {0};
    VkBufferCreateInfo bi = {VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = size;
    bi.usage = usage | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
    VK(vkCreateBuffer(b->device, &bi, NULL, &out.buffer));
    VkMemoryRequirements mr;
    vkGetBufferMemoryRequirements(b->device, out.buffer, &mr);
    VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    uint32_t type = UINT32_MAX;
    for (uint32_t i = 0; i < b->memory.memoryTypeCount && type == UINT32_MAX; ++i)
        if ((mr.memoryTypeBits >> i & 1) && (b->memory.memoryTypes[i].propertyFlags & want) == want)
            type = i;
    if (type == UINT32_MAX)
        die("finding host-visible memory", VK_ERROR_FEATURE_NOT_PRESENT);
    VkMemoryAllocateFlagsInfo fi = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    fi.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo ai = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &fi};
    ai.allocationSize = mr.size;
    ai.memoryTypeIndex = type;
    VK(vkAllocateMemory(b->device, &ai, NULL, &out.memory));
    VK(vkBindBufferMemory(b->device, out.buffer, out.memory, 0));
    VK(vkMapMemory(b->device, out.memory, 0, size, 0, &out.mapped));
    VkBufferDeviceAddressInfo da = {VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
    da.buffer = out.buffer;
    out.address = vkGetBufferDeviceAddress(b->device, &da);
    return out;
}

static void free_buffer(bench *b, buffer *x)
{
    vkDestroyBuffer(b->device, x->buffer, NULL);
    vkFreeMemory(b->device, x->memory, NULL);
}

/* The kernel's hash and walk in C: the CPU reference each kind's sums are checked against. */
static uint32_t hash_u32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    return x ^ (x >> 16);
}

static uint32_t walk_cpu(const uint32_t *words, uint32_t records, uint32_t steps, uint32_t invocation)
{
    uint32_t rec = hash_u32(invocation) & (records - 1u), sum = 0;
    for (uint32_t s = 0; s < steps; ++s) {
        uint32_t v[4] = {0, 0, 0, 0};
        for (uint32_t q = 0; q < 4; ++q)
            for (uint32_t c = 0; c < 4; ++c)
                v[c] ^= words[16 * (size_t)rec + 4 * q + c];
        sum += v[0] + v[3];
        rec = (v[0] ^ v[1] ^ v[2] ^ v[3] ^ s) & (records - 1u);
    }
    return sum;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    uint32_t records = 1u << 16, steps = 128, invocations = 1u << 16, rounds = 3, repeat = 5, device_index = 0;
    int validation = 0;
    const char *json = "bench/out/load_bench.json", *csv = "bench/out/load_bench.csv";
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        int v = i + 1 < argc;
        if (!strcmp(a, "--records") && v) records = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--steps") && v) steps = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--invocations") && v) invocations = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--rounds") && v) rounds = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--repeat") && v) repeat = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--device") && v) device_index = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--json") && v) json = argv[++i];
        else if (!strcmp(a, "--csv") && v) csv = argv[++i];
        else if (!strcmp(a, "--validation")) validation = 1;
        else {
            fprintf(stderr, "load_bench: unknown option %s (see the comment at the top of bench/load_bench.c)\n", a);
            return 2;
        }
    }
    /* records: a power of two of 64-byte records (4 words of 16 bytes each), within one texel view */
    if (records < 2 || (records & (records - 1)) || records > (1u << 24) || !steps || !invocations ||
        invocations % 64 || !rounds || !repeat || rounds > 64) {
        fprintf(stderr, "load_bench: --records a power of two in [2, 2^24], --invocations a multiple of 64, "
                        "--steps, --rounds (<= 64) and --repeat positive\n");
        return 2;
    }
    if (volkInitialize() != VK_SUCCESS) {
        fprintf(stderr, "load_bench: no Vulkan loader\n");
        return 1;
    }
    bench b = {0};
    VkApplicationInfo app = {VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "load_bench";
    app.apiVersion = VK_API_VERSION_1_2;
    const char *layer = "VK_LAYER_KHRONOS_validation", *ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    VkInstanceCreateInfo ici = {VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ici.pApplicationInfo = &app;
    ici.enabledLayerCount = validation ? 1 : 0;
    ici.ppEnabledLayerNames = &layer;
    ici.enabledExtensionCount = validation ? 1 : 0;
    ici.ppEnabledExtensionNames = &ext;
    VK(vkCreateInstance(&ici, NULL, &b.instance));
    volkLoadInstance(b.instance);
    VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
    if (validation) {
        VkDebugUtilsMessengerCreateInfoEXT mi = {VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
        mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT;
        mi.pfnUserCallback = on_message;
        VK(vkCreateDebugUtilsMessengerEXT(b.instance, &mi, NULL, &messenger));
    }
    uint32_t count = 0;
    VK(vkEnumeratePhysicalDevices(b.instance, &count, NULL));
    VkPhysicalDevice devices[16];
    count = count > 16 ? 16 : count;
    VK(vkEnumeratePhysicalDevices(b.instance, &count, devices));
    if (device_index >= count) {
        fprintf(stderr, "load_bench: no Vulkan device %u (%u found)\n", device_index, count);
        return 1;
    }
    b.physical = devices[device_index];
    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(b.physical, &props);
    vkGetPhysicalDeviceMemoryProperties(b.physical, &b.memory);
    VkPhysicalDeviceFeatures2 have = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    vkGetPhysicalDeviceFeatures2(b.physical, &have);
    b.int64 = have.features.shaderInt64 != 0;
    if ((uint64_t)records * 4 > props.limits.maxTexelBufferElements) {
        fprintf(stderr, "load_bench: %u records need %u texels; device allows %u\n", records, records * 4,
                props.limits.maxTexelBufferElements);
        return 1;
    }
    uint32_t qn = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(b.physical, &qn, NULL);
    VkQueueFamilyProperties qf[16];
    qn = qn > 16 ? 16 : qn;
    vkGetPhysicalDeviceQueueFamilyProperties(b.physical, &qn, qf);
    b.family = UINT32_MAX;
    for (uint32_t i = 0; i < qn && b.family == UINT32_MAX; ++i)
        if (qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT)
            b.family = i;
    float prio = 1.f;
    VkDeviceQueueCreateInfo qci = {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qci.queueFamilyIndex = b.family;
    qci.queueCount = 1;
    qci.pQueuePriorities = &prio;
    VkPhysicalDeviceVulkan12Features f12 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    f12.bufferDeviceAddress = VK_TRUE;
    VkPhysicalDeviceFeatures2 f2 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    f2.features.shaderInt64 = b.int64 ? VK_TRUE : VK_FALSE;
    VkDeviceCreateInfo dci = {VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &f2};
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    VK(vkCreateDevice(b.physical, &dci, NULL, &b.device));
    volkLoadDevice(b.device);
    vkGetDeviceQueue(b.device, b.family, 0, &b.queue);

    /* the records: random words, so the walk's next record is random too */
    VkDeviceSize bytes = (VkDeviceSize)records * 64;
    /* the uniform kind needs its whole block bound, so the buffer has at
     * least that many bytes; it runs only if the walk stays inside it */
    int uniform_fits = bytes <= UNIFORM_BYTES && props.limits.maxUniformBufferRange >= UNIFORM_BYTES;
    VkDeviceSize alloc = bytes < UNIFORM_BYTES ? UNIFORM_BYTES : bytes;
    buffer data = make_buffer(&b, alloc, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT |
                                             VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT |
                                             VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
    buffer sums = make_buffer(&b, (VkDeviceSize)invocations * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
    uint32_t *w = data.mapped, x = 12345u;
    for (VkDeviceSize i = 0; i < alloc / 4; ++i) {
        x ^= x << 13, x ^= x >> 17, x ^= x << 5;
        w[i] = x;
    }
    VkBufferView view4, view1;
    VkBufferViewCreateInfo bv = {VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    bv.buffer = data.buffer;
    bv.range = bytes;
    bv.format = VK_FORMAT_R32G32B32A32_UINT;
    VK(vkCreateBufferView(b.device, &bv, NULL, &view4));
    bv.format = VK_FORMAT_R32_UINT;
    VK(vkCreateBufferView(b.device, &bv, NULL, &view1));
    VkDescriptorSetLayoutBinding lb[5] = {
        {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
        {1, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
        {2, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
        {3, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
        {4, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL}};
    VkDescriptorSetLayoutCreateInfo dl = {VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    dl.bindingCount = 5;
    dl.pBindings = lb;
    VkDescriptorSetLayout set_layout;
    VK(vkCreateDescriptorSetLayout(b.device, &dl, NULL, &set_layout));
    VkDescriptorPoolSize ps[4] = {{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1},
                                  {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 2},
                                  {VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, 1},
                                  {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1}};
    VkDescriptorPoolCreateInfo dp = {VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    dp.maxSets = 1;
    dp.poolSizeCount = 4;
    dp.pPoolSizes = ps;
    VkDescriptorPool pool;
    VK(vkCreateDescriptorPool(b.device, &dp, NULL, &pool));
    VkDescriptorSetAllocateInfo sa = {VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    sa.descriptorPool = pool;
    sa.descriptorSetCount = 1;
    sa.pSetLayouts = &set_layout;
    VkDescriptorSet set;
    VK(vkAllocateDescriptorSets(b.device, &sa, &set));
    VkDescriptorBufferInfo whole = {data.buffer, 0, bytes}, block = {data.buffer, 0, UNIFORM_BYTES};
    VkWriteDescriptorSet wr[5];
    memset(wr, 0, sizeof wr);
    for (uint32_t i = 0; i < 5; ++i) {
        wr[i].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
        wr[i].dstSet = set;
        wr[i].dstBinding = i;
        wr[i].descriptorCount = 1;
        wr[i].descriptorType = lb[i].descriptorType;
    }
    wr[0].pBufferInfo = &whole;
    wr[1].pTexelBufferView = &view4;
    wr[2].pTexelBufferView = &view1;
    wr[3].pTexelBufferView = &view4;
    wr[4].pBufferInfo = &block;
    /* a device under 64 KiB of uniform range gets no uniform descriptor
     * (and no uniform kind) */
    vkUpdateDescriptorSets(b.device, props.limits.maxUniformBufferRange >= UNIFORM_BYTES ? 5 : 4, wr, 0, NULL);
    VkPushConstantRange range = {VK_SHADER_STAGE_COMPUTE_BIT, 0, 24};
    VkPipelineLayoutCreateInfo pl = {VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pl.setLayoutCount = 1;
    pl.pSetLayouts = &set_layout;
    pl.pushConstantRangeCount = 1;
    pl.pPushConstantRanges = &range;
    VkPipelineLayout layout;
    VK(vkCreatePipelineLayout(b.device, &pl, NULL, &layout));
    VkPipeline pipes[KINDS] = {0};
    for (int k = 0; k < KINDS; ++k) {
        if ((k == 2 && !b.int64) || (k == KIND_UNIFORM && !uniform_fits))
            continue;
        VkShaderModuleCreateInfo sm = {VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
        sm.codeSize = kind_bytes[k];
        sm.pCode = kind_spirv[k];
        VkShaderModule module;
        VK(vkCreateShaderModule(b.device, &sm, NULL, &module));
        VkComputePipelineCreateInfo ci = {VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
        ci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
        ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
        ci.stage.module = module;
        ci.stage.pName = "main";
        ci.layout = layout;
        VK(vkCreateComputePipelines(b.device, VK_NULL_HANDLE, 1, &ci, NULL, &pipes[k]));
        vkDestroyShaderModule(b.device, module, NULL);
    }
    VkCommandPoolCreateInfo cp = {VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    cp.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    cp.queueFamilyIndex = b.family;
    VkCommandPool cpool;
    VK(vkCreateCommandPool(b.device, &cp, NULL, &cpool));
    VkCommandBufferAllocateInfo ca = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ca.commandPool = cpool;
    ca.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ca.commandBufferCount = 1;
    VkCommandBuffer cmd;
    VK(vkAllocateCommandBuffers(b.device, &ca, &cmd));
    VkFenceCreateInfo fci = {VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    VK(vkCreateFence(b.device, &fci, NULL, &fence));
    struct {
        uint32_t data[2], sums[2], records, steps;
    } push = {{(uint32_t)data.address, (uint32_t)(data.address >> 32)},
              {(uint32_t)sums.address, (uint32_t)(sums.address >> 32)}, records, steps};

    printf("device: %s; %u records of 64 bytes, %u invocations x %u steps of 4 loads; %u rounds, best of %u\n",
           props.deviceName, records, invocations, steps, rounds, repeat);
    double ns[KINDS][64];
    uint32_t *expected = malloc((size_t)invocations * 4);
    if (!expected) {
        fprintf(stderr, "load_bench: out of host memory\n");
        return 1;
    }
    for (uint32_t i = 0; i < invocations; ++i)
        expected[i] = walk_cpu(w, records, steps, i);
    uint32_t wrong[KINDS] = {0};
    int mismatch = 0;
    for (uint32_t round = 0; round < rounds; ++round) {
        for (int k = 0; k < KINDS; ++k) {
            if (!pipes[k])
                continue;
            double best = 1e30;
            for (uint32_t r = 0; r <= repeat; ++r) { /* r == 0: warm-up (llvmpipe compiles at the first dispatch) */
                VK(vkResetCommandBuffer(cmd, 0));
                VkCommandBufferBeginInfo cbi = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
                VK(vkBeginCommandBuffer(cmd, &cbi));
                vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipes[k]);
                vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 1, &set, 0, NULL);
                vkCmdPushConstants(cmd, layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof push, &push);
                vkCmdDispatch(cmd, invocations / 64, 1, 1);
                VkMemoryBarrier mb = {VK_STRUCTURE_TYPE_MEMORY_BARRIER};
                mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
                mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
                vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb,
                                     0, NULL, 0, NULL);
                VK(vkEndCommandBuffer(cmd));
                VkSubmitInfo si = {VK_STRUCTURE_TYPE_SUBMIT_INFO};
                si.commandBufferCount = 1;
                si.pCommandBuffers = &cmd;
                double t0 = now_ms();
                VK(vkQueueSubmit(b.queue, 1, &si, fence));
                VK(vkWaitForFences(b.device, 1, &fence, VK_TRUE, UINT64_MAX));
                double t = now_ms() - t0;
                VK(vkResetFences(b.device, 1, &fence));
                if (r > 0 && t < best)
                    best = t;
            }
            ns[k][round] = best * 1e6 / ((double)invocations * steps);
            for (uint32_t i = 0; i < invocations; ++i)
                wrong[k] += ((const uint32_t *)sums.mapped)[i] != expected[i];
        }
    }
    free(expected);
    int base = pipes[2] ? 2 : 1;
    for (int k = 0; k < KINDS; ++k)
        if (pipes[k] && wrong[k]) {
            fprintf(stderr, "load_bench: %s: %u of %u x %u sums differ from the CPU reference\n", kind_names[k],
                    wrong[k], invocations, rounds);
            mismatch = 1;
        }
    double med[KINDS] = {0};
    for (int k = 0; k < KINDS; ++k)
        if (pipes[k]) {
            qsort(ns[k], rounds, sizeof(double), cmp_double);
            med[k] = ns[k][rounds / 2];
        }
    printf("%-26s %12s %9s %9s %14s\n", "load", "ns / step", "min", "max", "vs u64vec2 ref");
    for (int k = 0; k < KINDS; ++k) {
        if (!pipes[k]) {
            printf("%-26s %12s %s\n", kind_names[k], "-",
                   k == KIND_UNIFORM ? "(records over 64 KiB of uniform range)" : "(no shaderInt64)");
            continue;
        }
        printf("%-26s %12.2f %9.2f %9.2f %14.2f\n", kind_names[k], med[k], ns[k][0], ns[k][rounds - 1],
               med[k] / med[base]);
    }
    mkdir("bench/out", 0755); /* the default outputs' folder, as trace_bench */
    FILE *f = fopen(csv, "w");
    if (f) {
        fprintf(f, "load,round,ns_per_step\n");
        for (int k = 0; k < KINDS; ++k)
            for (uint32_t r = 0; pipes[k] && r < rounds; ++r)
                fprintf(f, "%s,%u,%.3f\n", kind_names[k], r, ns[k][r]);
        fclose(f);
    }
    f = fopen(json, "w");
    if (f) {
        fprintf(f, "{\n  \"bench\": \"load\",\n  \"device\": \"%s\",\n  \"records\": %u,\n  \"invocations\": %u,\n"
                   "  \"steps\": %u,\n  \"rounds\": %u,\n  \"repeat\": %u,\n  \"results\": [\n",
                props.deviceName, records, invocations, steps, rounds, repeat);
        int first = 1;
        for (int k = 0; k < KINDS; ++k) {
            if (!pipes[k])
                continue;
            fprintf(f, "%s    {\"load\": \"%s\", \"ns_per_step_median\": %.3f, \"min\": %.3f, \"max\": %.3f, "
                       "\"vs_u64vec2_reference\": %.3f}",
                    first ? "" : ",\n", kind_names[k], med[k], ns[k][0], ns[k][rounds - 1], med[k] / med[base]);
            first = 0;
        }
        fprintf(f, "\n  ]\n}\n");
        fclose(f);
        printf("wrote %s and %s\n", json, csv);
    } else {
        fprintf(stderr, "load_bench: cannot write %s\n", json);
    }
    for (int k = 0; k < KINDS; ++k)
        if (pipes[k])
            vkDestroyPipeline(b.device, pipes[k], NULL);
    vkDestroyFence(b.device, fence, NULL);
    vkDestroyCommandPool(b.device, cpool, NULL);
    vkDestroyPipelineLayout(b.device, layout, NULL);
    vkDestroyDescriptorPool(b.device, pool, NULL);
    vkDestroyDescriptorSetLayout(b.device, set_layout, NULL);
    vkDestroyBufferView(b.device, view4, NULL);
    vkDestroyBufferView(b.device, view1, NULL);
    free_buffer(&b, &data);
    free_buffer(&b, &sums);
    vkDestroyDevice(b.device, NULL);
    if (messenger)
        vkDestroyDebugUtilsMessengerEXT(b.instance, messenger, NULL);
    vkDestroyInstance(b.instance, NULL);
    if (validation_messages)
        fprintf(stderr, "load_bench: %u validation messages\n", validation_messages);
    return mismatch || validation_messages ? 1 : 0;
}
