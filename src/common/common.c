#define _GNU_SOURCE /* sysconf(_SC_PHYS_PAGES), sched_getaffinity */
#include "common/common.h"

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

static const char *const result_names[PB_RESULT_COUNT] = {
    "PB_OK",
    "PB_ERROR_INVALID_ARGUMENT",
    "PB_ERROR_IO",
    "PB_ERROR_PARSE",
    "PB_ERROR_UNSUPPORTED",
    "PB_ERROR_OUT_OF_HOST_MEMORY",
    "PB_ERROR_NO_DEVICE",
    "PB_ERROR_DEVICE_LOST",
    "PB_ERROR_OUT_OF_DEVICE_MEMORY",
    "PB_ERROR_TOO_LARGE",
    "PB_ERROR_VULKAN",
    "PB_ERROR_CANCELLED",
};

const char *pb_result_name(pb_result r)
{
    if ((unsigned)r >= PB_RESULT_COUNT)
        return "PB_ERROR_UNKNOWN";
    return result_names[r];
}

pb_result pb_fail(pb_error *err, pb_result code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
        /* one line: a message is printed after "error: " by the CLI */
        for (char *c = err->message; *c; ++c)
            if (*c == '\n' || *c == '\r')
                *c = ' ';
        err->code = code;
    }
    return code;
}

void pb_error_clear(pb_error *err)
{
    if (err) {
        err->code = PB_OK;
        err->message[0] = '\0';
    }
}

void pb_logf(const pb_log *log, pb_log_level level, const char *fmt, ...)
{
    if (!log || !log->fn)
        return;
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    log->fn(level, line, log->user_data);
}

double pb_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* The cores this process may run on, not the machine's: a Slurm job's
 * cgroup, a container's cpuset or `taskset` narrow the affinity mask, and
 * threads for every online core would then share the few allowed ones. */
uint32_t pb_host_threads(void)
{
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0) {
        int n = CPU_COUNT(&set);
        if (n > 0)
            return (uint32_t)n;
    }
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1u : (uint32_t)n;
}

typedef struct parallel_job {
    uint64_t count, grain;
    atomic_uint_fast64_t next;
    pb_range_fn fn;
    void *user;
} parallel_job;

static void *parallel_worker(void *arg)
{
    parallel_job *job = arg;
    for (;;) {
        uint64_t begin = atomic_fetch_add(&job->next, job->grain);
        if (begin >= job->count)
            break;
        uint64_t end = begin + job->grain < job->count ? begin + job->grain : job->count;
        job->fn(job->user, begin, end);
    }
    return NULL;
}

void pb_parallel_for(uint64_t count, uint64_t grain, uint32_t threads, pb_range_fn fn, void *user)
{
    if (count == 0)
        return;
    if (grain == 0)
        grain = 1;
    if (threads == 0)
        threads = pb_host_threads();
    uint64_t blocks = (count + grain - 1) / grain;
    if (threads > blocks)
        threads = (uint32_t)blocks;
    if (threads <= 1) {
        fn(user, 0, count);
        return;
    }
    parallel_job job = {.count = count, .grain = grain, .fn = fn, .user = user};
    atomic_init(&job.next, 0);
    pthread_t tids[64];
    if (threads > 64)
        threads = 64;
    uint32_t started = 0;
    for (uint32_t i = 1; i < threads; ++i)
        if (pthread_create(&tids[started], NULL, parallel_worker, &job) == 0)
            ++started;
    parallel_worker(&job); /* the calling thread works too; if no thread started, it does it all */
    for (uint32_t i = 0; i < started; ++i)
        pthread_join(tids[i], NULL);
}

uint64_t pb_hash64(const void *data, size_t size, uint64_t seed)
{
    const unsigned char *p = data;
    uint64_t h = 1469598103934665603ull ^ seed;
    for (size_t i = 0; i < size; ++i) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

/* The advice on every page of [p, p + bytes). glibc maps an array this
 * large afresh and does not touch it, so nothing has faulted its pages in
 * yet; the whole mapping is advised, not only its 2 MiB pages, because
 * advice on part of a mapping splits it, and glibc's realloc can then no
 * longer move it with mremap (which keeps the advice) and copies it. */
static void *advise_huge(void *p, size_t bytes)
{
#if defined(MADV_HUGEPAGE)
    const uintptr_t huge = (uintptr_t)2 << 20;
    if (p && bytes >= 4 * huge) {
        uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE);
        uintptr_t first = (uintptr_t)p & ~(page - 1), end = ((uintptr_t)p + bytes + page - 1) & ~(page - 1);
        (void)madvise((void *)first, end - first, MADV_HUGEPAGE);
    }
#else
    (void)bytes;
#endif
    return p;
}

void pb_advise_huge(void *p, size_t bytes)
{
    (void)advise_huge(p, bytes);
}

void *pb_malloc_large(size_t size)
{
    return advise_huge(malloc(size), size);
}

void *pb_calloc_large(size_t count, size_t size)
{
    return advise_huge(calloc(count, size), count * size); /* calloc has checked the product */
}

void *pb_realloc_large(void *p, size_t size)
{
    return advise_huge(realloc(p, size), size);
}

uint64_t pb_host_memory_bytes(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && size > 0 ? (uint64_t)pages * (uint64_t)size : 0;
}
