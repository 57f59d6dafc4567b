/* The volume's scene hash (pb_scene_hash, the file's `scene_hash`) on a
 * thread of its own. It reads every position byte by byte (FNV-1a: the
 * format's, so its values stay), 150 ms for 4M triangles on one core, and a
 * bake needs it only when it writes the volume: the bake starts it before
 * its first stage and waits for it in the last, so it runs beside the
 * passes. */
#ifndef PB_SCENE_HASH_JOB_H
#define PB_SCENE_HASH_JOB_H

#include "probebake/scene.h"

#include <pthread.h>

typedef struct pb_scene_hash_job {
    const pb_scene *scene; /* read by the thread: must outlive the job's wait */
    uint64_t hash;
    pthread_t thread;
    int started;  /* pb_scene_hash_start ran and pb_scene_hash_wait has not */
    int threaded; /* a thread computes it; else (none could start) the wait does */
} pb_scene_hash_job;

void pb_scene_hash_start(pb_scene_hash_job *job, const pb_scene *scene);

/* The hash: joins the thread (once; later calls return it again). */
uint64_t pb_scene_hash_wait(pb_scene_hash_job *job);

#endif
