/* The scene hash beside the bake (scene_hash_job.h). */
#include "bake/scene_hash_job.h"

#include <string.h>

static void *hash_thread(void *arg)
{
    pb_scene_hash_job *job = arg;
    job->hash = pb_scene_hash(job->scene);
    return NULL;
}

void pb_scene_hash_start(pb_scene_hash_job *job, const pb_scene *scene)
{
    memset(job, 0, sizeof *job);
    job->scene = scene;
    job->started = 1;
    job->threaded = pthread_create(&job->thread, NULL, hash_thread, job) == 0;
}

uint64_t pb_scene_hash_wait(pb_scene_hash_job *job)
{
    if (job->started) {
        if (job->threaded)
            pthread_join(job->thread, NULL);
        else
            job->hash = pb_scene_hash(job->scene);
        job->started = job->threaded = 0;
    }
    return job->hash;
}
