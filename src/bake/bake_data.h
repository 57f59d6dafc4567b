/* Scene data in the bake kernels' form, built once and shared by the GPU
 * host loop (bake.c) and the CPU reference (bake_cpu.c), so both shade from
 * identical numbers. */
#ifndef PB_BAKE_DATA_H
#define PB_BAKE_DATA_H

#include "bake/bake_types.h"
#include "probebake/scene.h"

/* out: scene->light_count entries. */
void pb_bake_lights(const pb_scene *scene, gpu_light *out);

/* out: scene->material_count entries. */
void pb_bake_materials(const pb_scene *scene, gpu_shade_material *out);

/* 12 floats (3 rows of 4) per probe slot: the rotation of probe id
 * ids[slot] (the w of its position record, as uint bits) in this pass. */
void pb_bake_rotations(uint32_t seed, uint32_t pass, const float *probes4, uint32_t count, float *out12);

/* The id stored in a probe's position record. */
uint32_t pb_probe_record_id(const float *probe4);

#endif
