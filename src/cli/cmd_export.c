/* probebake export VOLUME --textures DIR: the volume as the WebGL2
 * sampler's textures (KTX2) and a manifest (docs/format.md, "Texture
 * contract"). */
#include "cli/cli.h"
#include "probebake/files.h"
#include "probebake/volume.h"

#include <stdio.h>

int cmd_export(const options *o)
{
    if (!o->scene)
        return cli_usage_error("%s needs a VOLUME file", "export");
    if (!o->textures)
        return cli_usage_error("%s needs --textures DIR", "export");
    pb_volume v;
    pb_error err;
    if (pb_volume_read(o->scene, &v, &err) != PB_OK)
        return cli_fail(&err);
    pb_result r = pb_volume_export_textures(&v, o->textures, &err);
    if (r == PB_OK && !o->log.quiet && (v.flags & PB_VOLUME_SPARSE))
        printf("wrote %s/manifest.json, probes.ktx2, sh.ktx2, depth.ktx2, sparse.ktx2: %u probe%s in %u brick%s (%u "
               "levels), %ux%u depth texels per probe\n", o->textures, v.probe_count, cli_plural(v.probe_count),
               v.sparse->brick_count, cli_plural(v.sparse->brick_count),
               v.sparse->levels, v.octmap_res + 2, v.octmap_res + 2);
    else if (r == PB_OK && !o->log.quiet)
        printf("wrote %s/manifest.json, probes.ktx2, sh.ktx2, depth.ktx2: %u probe%s (%u x %u x %u), %ux%u depth "
               "texels per probe\n", o->textures, v.probe_count, cli_plural(v.probe_count), v.counts[0], v.counts[1], v.counts[2],
               v.octmap_res + 2, v.octmap_res + 2);
    pb_volume_free(&v);
    return r == PB_OK ? 0 : cli_fail(&err);
}
