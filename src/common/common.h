/* Small helpers shared by every stage: error reporting, logging, timing and
 * a fork-join parallel loop over host threads. No global state. */
#ifndef PB_COMMON_H
#define PB_COMMON_H

#include "probebake/probebake.h"

#include <stdarg.h>
#include <stdint.h>

#if defined(__GNUC__)
#define PB_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define PB_PRINTF(f, a)

#endif

/* Records `code` and a formatted one-line message in err (may be NULL) and
 * returns code, so callers can `return pb_fail(err, PB_ERROR_IO, ...)`. */
pb_result pb_fail(pb_error *err, pb_result code, const char *fmt, ...) PB_PRINTF(3, 4);

/* Clears err (code PB_OK, empty message). err may be NULL. */
void pb_error_clear(pb_error *err);

/* Formats and forwards one line to log->fn (no-op when fn is NULL). */
void pb_logf(const pb_log *log, pb_log_level level, const char *fmt, ...) PB_PRINTF(3, 4);

/* Monotonic wall clock in milliseconds. */
double pb_now_ms(void);

/* Host cores this process may run on: its affinity mask, else the online
 * cores (at least 1). */
uint32_t pb_host_threads(void);

/* Calls fn(user, begin, end) over [0, count) split into contiguous blocks of
 * `grain` items, on up to `threads` threads (0: all cores). Blocks are
 * handed out dynamically; fn must be safe to run concurrently on disjoint
 * ranges. Runs inline when one thread suffices. */
typedef void (*pb_range_fn)(void *user, uint64_t begin, uint64_t end);
void pb_parallel_for(uint64_t count, uint64_t grain, uint32_t threads, pb_range_fn fn, void *user);

/* FNV-1a over bytes; used for scene hashes and deterministic seeds. */
uint64_t pb_hash64(const void *data, size_t size, uint64_t seed);

/* malloc, calloc and realloc for large arrays that are filled right after
 * (per triangle, per BVH node, per probe): they ask the kernel (Linux, where
 * transparent huge pages are "madvise") to back the array's untouched 2 MiB
 * pages with huge pages, so its first touch takes one fault per 2 MiB, not
 * per 4 KiB (bench/RESULTS.md, "Huge pages for large arrays"). Arrays under
 * 8 MiB are left alone. Freed with free(); a hint only, ignored where
 * unsupported. */
void *pb_malloc_large(size_t size);
/* The same advice for an array made elsewhere (a std::vector's reserved
 * storage) before anything touches it. */
void pb_advise_huge(void *p, size_t bytes);
void *pb_calloc_large(size_t count, size_t size);
void *pb_realloc_large(void *p, size_t size);

/* Physical memory of this machine in bytes (0 if unknown). */
uint64_t pb_host_memory_bytes(void);

/* Luminance of linear RGB, Rec. 709 / sRGB primaries (what images, guiding
 * and error metrics weigh colours by). */
static inline float pb_luminance(const float rgb[3])
{
    return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

#endif
