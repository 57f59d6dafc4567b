#define _POSIX_C_SOURCE 200809L
/* probebake devices: the Vulkan devices, their type, driver, memory and
 * subgroup size, and whether probebake can use them. */
#include "cli/cli.h"

#include <stdio.h>
#include <string.h>

int cmd_devices(const options *o)
{
    pb_device_info infos[16];
    uint32_t n = 0;
    pb_error err;
    if (pb_enumerate_devices(infos, 16, &n, &err) != PB_OK)
        return cli_fail(&err);
    if (n > 16)
        n = 16;
    if (o->json) {
        printf("[");
        for (uint32_t i = 0; i < n; ++i) {
            const pb_device_info *d = &infos[i];
            printf("%s\n  {\"index\": %u, \"name\": ", i ? "," : "", d->index);
            json_string(d->name);
            printf(", \"type\": \"%s\", \"driver\": ", pb_device_type_name(d->type));
            json_string(d->driver);
            printf(", \"vulkan\": \"%u.%u\", \"device_local_bytes\": %llu, \"subgroup_size\": %u, "
                   "\"max_storage_buffer_range\": %llu, \"max_memory_allocation\": %llu, \"shader_int64\": %s, "
                   "\"shader_float64\": %s, \"kernels\": \"%s\", \"usable\": %s}",
                   (d->api_version >> 22) & 0x7f, (d->api_version >> 12) & 0x3ff,
                   (unsigned long long)d->device_local_bytes, d->subgroup_size,
                   (unsigned long long)d->max_storage_buffer_range, (unsigned long long)d->max_memory_allocation,
                   d->shader_int64 ? "true" : "false", d->shader_float64 ? "true" : "false",
                   d->shader_int64 && d->shader_float64 ? "native64" : "portable", d->usable ? "true" : "false");
        }
        printf("\n]\n");
        return 0;
    }
    if (n == 0) {
        fprintf(stderr, "probebake: error: no Vulkan device found\n");
        return 1;
    }
    printf("%-5s %-40s %-15s %-32s %10s %8s %-8s\n", "index", "name", "type", "driver", "memory", "subgroup",
           "kernels");
    for (uint32_t i = 0; i < n; ++i) {
        const pb_device_info *d = &infos[i];
        printf("%-5u %-40.40s %-15s %-32.32s %7.1f GiB %8u %-8s%s%s\n", d->index, d->name,
               pb_device_type_name(d->type), d->driver, d->device_local_bytes / 1073741824.0, d->subgroup_size,
               d->shader_int64 && d->shader_float64 ? "native64" : "portable", d->usable ? "" : "  unusable: ",
               d->usable ? "" : d->unusable_reason);
    }
    return 0;
}
