/* Which compiled-out parts of the bake kernels a pass needs (bake_features.h).
 * Read off the parameters themselves, so the mask cannot disagree with what
 * the kernel is told to do. */
#include "bake/bake_features.h"

#include "bake/gpu_types.h"

#include <stdio.h>

uint32_t pb_bake_features(const gpu_bake_params *p)
{
    uint32_t f = 0;
    f |= p->nee ? PB_FEATURE_PROBE_NEE : 0u;
    f |= p->guide ? PB_FEATURE_GUIDE : 0u;
    f |= p->light_cells ? PB_FEATURE_LIGHT_CELLS : 0u;
    f |= p->volume.probes ? PB_FEATURE_VOLUME : 0u;
    f |= p->light_select ? PB_FEATURE_LIGHT_SELECT : 0u;
    f |= p->emitter_count ? PB_FEATURE_EMITTERS : 0u;
    f |= p->env_count ? PB_FEATURE_ENVIRONMENT : 0u;
    f |= p->light_count ? PB_FEATURE_LIGHTS : 0u;
    f |= (p->scene.flags & PB_SCENE_VERTEX_COLORS) ? PB_FEATURE_VERTEX_COLORS : 0u;
    f |= (p->scene.flags & PB_SCENE_SHADING_NORMALS) ? PB_FEATURE_SHADING_NORMALS : 0u;
    f |= (p->scene.flags & PB_SCENE_TRANSMISSION) ? PB_FEATURE_TRANSMISSION : 0u;
    f |= p->emitter_count && !p->emitters_by_area ? PB_FEATURE_SOLID_ANGLE : 0u;
    f |= (p->scene.flags & PB_SCENE_NORMAL_MAPS) ? PB_FEATURE_NORMAL_MAPS : 0u;
    return f;
}

void pb_bake_features_name(uint32_t features, char *out, size_t size)
{
    static const char *names[] = {"probe-nee", "guide", "light-cells", "volume", "light-select",
                                  "emitters", "environment", "lights", "vertex-colours", "shading-normals", "transmission",
                                  "solid-angle", "normal-maps"};
    size_t used = 0;
    if (size)
        out[0] = '\0';
    for (uint32_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        if (!(features & (1u << i)))
            continue;
        int w = snprintf(out + used, size - used, "%s%s", used ? " " : "", names[i]);
        if (w < 0 || (size_t)w >= size - used)
            return;
        used += (size_t)w;
    }
    if (!features && size)
        snprintf(out, size, "none");
}
