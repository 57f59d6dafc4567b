/* LD_PRELOAD shim for test_out_of_memory.sh: the PB_FAIL_ALLOC-th heap
 * allocation made from main on (malloc, calloc, realloc, aligned_alloc,
 * posix_memalign; counted from 1) fails as if the host were out of memory.
 * Allocations before main (the shared libraries' static constructors, which
 * no program can answer) are not counted. Without the variable nothing
 * fails; with PB_FAIL_ALLOC_COUNT=FILE the number of allocations counted is
 * written there at exit, so a test can aim at each of them. glibc only: main
 * is found through __libc_start_main. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *(*real_malloc)(size_t);
static void *(*real_calloc)(size_t, size_t);
static void *(*real_realloc)(void *, size_t);
static void *(*real_aligned_alloc)(size_t, size_t);
static int (*real_posix_memalign)(void **, size_t, size_t);
static atomic_ulong calls;
static unsigned long fail_at; /* 0: never */
static atomic_int in_main;
static int ready;

/* dlsym may allocate (calloc) before the real functions are known: those
 * first bytes come from here and are never freed */
static char bootstrap[4096];
static size_t bootstrap_used;

static void init(void)
{
    if (ready)
        return;
    ready = -1; /* resolving */
    real_malloc = (void *(*)(size_t))dlsym(RTLD_NEXT, "malloc");
    real_calloc = (void *(*)(size_t, size_t))dlsym(RTLD_NEXT, "calloc");
    real_realloc = (void *(*)(void *, size_t))dlsym(RTLD_NEXT, "realloc");
    real_aligned_alloc = (void *(*)(size_t, size_t))dlsym(RTLD_NEXT, "aligned_alloc");
    real_posix_memalign = (int (*)(void **, size_t, size_t))dlsym(RTLD_NEXT, "posix_memalign");
    const char *at = getenv("PB_FAIL_ALLOC");
    fail_at = at ? strtoul(at, NULL, 10) : 0;
    ready = 1;
}

/* PB_FAIL_ALLOC_OURS=1: only allocations called from the program itself are
 * counted (not from a shared library: the Vulkan driver, the C++ runtime),
 * so a command that drives a device can fail in its own code only */
static int ours_only;
static void *program_base;

static int from_program(void *caller)
{
    Dl_info info;
    return dladdr(caller, &info) && info.dli_fbase == program_base;
}

static int fails_from(void *caller)
{
    if (!atomic_load(&in_main) || (ours_only && !from_program(caller)))
        return 0;
    unsigned long n = atomic_fetch_add(&calls, 1) + 1;
    return fail_at && n == fail_at;
}

/* main, with counting on */
static int (*real_main)(int, char **, char **);

static int counted_main(int argc, char **argv, char **envp)
{
    atomic_store(&in_main, 1);
    return real_main(argc, argv, envp);
}

int __libc_start_main(int (*main)(int, char **, char **), int argc, char **argv, void (*init)(void),
                      void (*fini)(void), void (*rtld_fini)(void), void *stack_end)
{
    int (*start)(int (*)(int, char **, char **), int, char **, void (*)(void), void (*)(void), void (*)(void), void *) =
        (int (*)(int (*)(int, char **, char **), int, char **, void (*)(void), void (*)(void), void (*)(void),
                 void *))dlsym(RTLD_NEXT, "__libc_start_main");
    real_main = main;
    Dl_info info;
    const char *ours = getenv("PB_FAIL_ALLOC_OURS");
    ours_only = ours && !strcmp(ours, "1") && dladdr((void *)main, &info);
    program_base = ours_only ? info.dli_fbase : NULL;
    return start(counted_main, argc, argv, init, fini, rtld_fini, stack_end);
}

static void *from_bootstrap(size_t n)
{
    n = (n + 15) & ~(size_t)15;
    if (bootstrap_used + n > sizeof bootstrap)
        return NULL;
    void *p = bootstrap + bootstrap_used;
    bootstrap_used += n;
    return p;
}

static int is_bootstrap(const void *p)
{
    return (const char *)p >= bootstrap && (const char *)p < bootstrap + sizeof bootstrap;
}

void *malloc(size_t n)
{
    init();
    if (ready < 0)
        return from_bootstrap(n);
    if (fails_from(__builtin_return_address(0))) {
        errno = ENOMEM;
        return NULL;
    }
    return real_malloc(n);
}

void *calloc(size_t a, size_t b)
{
    init();
    if (ready < 0) {
        void *p = b && a > (size_t)-1 / b ? NULL : from_bootstrap(a * b);
        if (p)
            memset(p, 0, a * b);
        return p;
    }
    if (fails_from(__builtin_return_address(0))) {
        errno = ENOMEM;
        return NULL;
    }
    return real_calloc(a, b);
}

void *realloc(void *p, size_t n)
{
    init();
    if (is_bootstrap(p)) { /* never happens in practice: move it to the real heap */
        void *q = real_malloc(n);
        size_t left = (size_t)(bootstrap + sizeof bootstrap - (char *)p); /* bytes of the buffer from p on */
        if (q)
            memcpy(q, p, n < left ? n : left);
        return q;
    }
    if (fails_from(__builtin_return_address(0))) {
        errno = ENOMEM;
        return NULL;
    }
    return real_realloc(p, n);
}

void free(void *p)
{
    static void (*real_free)(void *);
    if (!p || is_bootstrap(p))
        return;
    if (!real_free)
        real_free = (void (*)(void *))dlsym(RTLD_NEXT, "free");
    real_free(p);
}

void *aligned_alloc(size_t align, size_t n)
{
    init();
    if (fails_from(__builtin_return_address(0))) {
        errno = ENOMEM;
        return NULL;
    }
    return real_aligned_alloc(align, n);
}

int posix_memalign(void **out, size_t align, size_t n)
{
    init();
    if (fails_from(__builtin_return_address(0)))
        return ENOMEM;
    return real_posix_memalign(out, align, n);
}

__attribute__((destructor)) static void report(void)
{
    const char *path = getenv("PB_FAIL_ALLOC_COUNT");
    if (!path)
        return;
    FILE *f = fopen(path, "w");
    if (f) {
        fprintf(f, "%lu\n", (unsigned long)atomic_load(&calls));
        fclose(f);
    }
}
