/* Inputs that must be regular files, outputs that never destroy what they
 * replace (include/probebake/files.h has the rules). */
#define _DEFAULT_SOURCE /* realpath, fchown */
#define _POSIX_C_SOURCE 200809L
#include "common/common.h"
#include "probebake/files.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define CHUNK_BYTES (1u << 20) /* writes between cancellation checks */

/* What a non-regular file is, for "PATH: is ..." messages. */
static const char *kind_of(mode_t m)
{
    if (S_ISDIR(m))
        return "is a directory";
    if (S_ISFIFO(m))
        return "is not a regular file (a FIFO)";
    if (S_ISCHR(m))
        return "is not a regular file (a character device)";
    if (S_ISBLK(m))
        return "is not a regular file (a block device)";
    if (S_ISSOCK(m))
        return "is not a regular file (a socket)";
    return "is not a regular file";
}

/* ------------------------------------------------------------ inputs */

pb_result pb_input_open(const char *path, uint64_t max_bytes, FILE **out, uint64_t *size, pb_error *err)
{
    *out = NULL;
    /* non-blocking: opening a FIFO with no writer must not hang */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return pb_fail(err, PB_ERROR_IO, "%s: cannot open: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return pb_fail(err, PB_ERROR_IO, "%s: cannot stat: %s", path, strerror(e));
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return pb_fail(err, PB_ERROR_IO, "%s: %s", path, kind_of(st.st_mode));
    }
    if ((uint64_t)st.st_size > max_bytes) {
        close(fd);
        return pb_fail(err, PB_ERROR_TOO_LARGE, "%s: %llu bytes, more than the %llu this input may have", path,
                       (unsigned long long)st.st_size, (unsigned long long)max_bytes);
    }
    int flags = fcntl(fd, F_GETFL);
    if (flags >= 0)
        fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        close(fd);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory opening a stream", path);
    }
    *out = f;
    if (size)
        *size = (uint64_t)st.st_size;
    return PB_OK;
}

pb_result pb_input_read(const char *path, uint64_t max_bytes, unsigned char **bytes, uint64_t *size, pb_error *err)
{
    *bytes = NULL;
    *size = 0;
    FILE *f;
    uint64_t n = 0;
    pb_result r = pb_input_open(path, max_bytes, &f, &n, err);
    if (r != PB_OK)
        return r;
    if (n >= SIZE_MAX) {
        fclose(f);
        return pb_fail(err, PB_ERROR_TOO_LARGE, "%s: too large for this machine's address space", path);
    }
    unsigned char *b = pb_malloc_large((size_t)n + 1); /* a large scene's file: huge pages */
    if (!b) {
        fclose(f);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory for %llu bytes", path,
                       (unsigned long long)n);
    }
    size_t got = fread(b, 1, (size_t)n, f);
    fclose(f);
    if (got != n) {
        free(b);
        return pb_fail(err, PB_ERROR_IO, "%s: read %zu of %llu bytes", path, got, (unsigned long long)n);
    }
    b[n] = 0;
    *bytes = b;
    *size = n;
    return PB_OK;
}

/* ------------------------------------------------------------ outputs */

/* The directory part of path ("." when none), malloc'd. */
static char *dir_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        return strdup(".");
    if (slash == path)
        return strdup("/");
    char *d = malloc((size_t)(slash - path) + 1);
    if (d) {
        memcpy(d, path, (size_t)(slash - path));
        d[slash - path] = '\0';
    }
    return d;
}

/* Creates a fresh temporary file beside `target`, mode 0666 & ~umask (the
 * kernel applies the umask). Its name goes to *tmp (malloc'd). */
static int create_temp(const char *target, char **tmp)
{
    size_t len = strlen(target) + 64;
    char *name = malloc(len);
    if (!name)
        return errno = ENOMEM, -1;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    for (unsigned attempt = 0; attempt < 100; ++attempt) {
        snprintf(name, len, "%s.tmp-%ld-%lx-%u", target, (long)getpid(), (unsigned long)ts.tv_nsec, attempt);
        int fd = open(name, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) {
            *tmp = name;
            return fd;
        }
        if (errno != EEXIST)
            break;
    }
    int e = errno;
    free(name);
    errno = e;
    return -1;
}

/* Where a regular-file output really goes: a symbolic link's target (so
 * the link stays a link; a target that does not exist yet is created), else
 * the path itself. malloc'd. */
static char *resolve_target(const char *path, pb_error *err)
{
    char *cur = strdup(path);
    for (int hops = 0; cur && hops < 40; ++hops) {
        struct stat lst;
        if (lstat(cur, &lst) != 0 || !S_ISLNK(lst.st_mode))
            return cur; /* a file, or a new name */
        char link[PATH_MAX];
        ssize_t n = readlink(cur, link, sizeof link - 1);
        if (n < 0) {
            pb_fail(err, PB_ERROR_IO, "%s: cannot read the symbolic link: %s", path, strerror(errno));
            free(cur);
            return NULL;
        }
        link[n] = '\0';
        char *next;
        if (link[0] == '/') {
            next = strdup(link);
        } else { /* relative to the link's own directory */
            char *dir = dir_of(cur);
            size_t len = (dir ? strlen(dir) : 0) + (size_t)n + 2;
            next = dir ? malloc(len) : NULL;
            if (next)
                snprintf(next, len, "%s/%s", dir, link);
            free(dir);
        }
        free(cur);
        cur = next;
    }
    if (!cur)
        pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path);
    else {
        pb_fail(err, PB_ERROR_IO, "%s: too many levels of symbolic links", path);
        free(cur);
    }
    return NULL;
}

pb_result pb_output_check(const char *path, const char *const *inputs, int input_count, pb_error *err)
{
    if (!strcmp(path, "-"))
        return PB_OK;
    struct stat st;
    int exists = stat(path, &st) == 0;
    if (exists) {
        if (S_ISDIR(st.st_mode) || S_ISSOCK(st.st_mode) || S_ISBLK(st.st_mode))
            return pb_fail(err, PB_ERROR_IO, "%s: %s: not an output", path, kind_of(st.st_mode));
        for (int i = 0; i < input_count; ++i) {
            struct stat in;
            if (inputs[i] && stat(inputs[i], &in) == 0 && in.st_dev == st.st_dev && in.st_ino == st.st_ino)
                return pb_fail(err, PB_ERROR_INVALID_ARGUMENT, "%s: is the same file as the input %s: refusing to "
                               "overwrite it", path, inputs[i]);
        }
        if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode))
            return PB_OK; /* written directly */
    }
    /* a regular file or a new name: the temporary goes beside the real target */
    char *target = resolve_target(path, err);
    if (!target)
        return err ? err->code : PB_ERROR_IO;
    char *dir = dir_of(target);
    pb_result r = PB_OK;
    char *tmp = NULL;
    int fd = dir ? create_temp(target, &tmp) : -1;
    if (fd < 0) {
        r = pb_fail(err, PB_ERROR_IO, "%s: cannot write in %s: %s", path, dir ? dir : "?", strerror(errno));
    } else {
        close(fd);
        unlink(tmp);
    }
    free(tmp);
    free(dir);
    free(target);
    return r;
}

static pb_result write_all(int fd, const char *path, const unsigned char *b, uint64_t size, pb_cancel_fn cancel,
                           void *user, pb_error *err)
{
    uint64_t done = 0;
    while (done < size) {
        if (cancel && cancel(user))
            return pb_fail(err, PB_ERROR_CANCELLED, "%s: cancelled; nothing written", path);
        size_t want = size - done > CHUNK_BYTES ? CHUNK_BYTES : (size_t)(size - done);
        ssize_t w = write(fd, b + done, want);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return pb_fail(err, PB_ERROR_IO, "%s: write failed: %s", path, w < 0 ? strerror(errno) : "no progress");
        done += (uint64_t)w;
    }
    return PB_OK;
}

/* A write in progress (files.h). `tmp` is NULL when the output is written
 * in place: standard output, a character device or a FIFO. */
struct pb_output {
    int fd;
    int owns_fd;       /* not standard output: closed at the end */
    char *path;        /* as the caller named it, for messages */
    char *target;      /* what the temporary file is renamed to */
    char *tmp;
    pb_cancel_fn cancel;
    void *user;
};

static void output_free(pb_output *o)
{
    free(o->path);
    free(o->target);
    free(o->tmp);
    free(o);
}

pb_result pb_output_begin(const char *path, pb_cancel_fn cancel, void *user, pb_output **out, pb_error *err)
{
    *out = NULL;
    pb_output *o = calloc(1, sizeof *o);
    int to_stdout = !strcmp(path, "-");
    if (o)
        o->path = strdup(to_stdout ? "standard output" : path); /* what messages call it */
    if (!o || !o->path) {
        free(o);
        return pb_fail(err, PB_ERROR_OUT_OF_HOST_MEMORY, "%s: out of host memory", path);
    }
    o->fd = -1, o->cancel = cancel, o->user = user;
    if (to_stdout) {
        o->fd = STDOUT_FILENO;
        *out = o;
        return PB_OK;
    }
    struct stat st;
    int exists = stat(path, &st) == 0;
    pb_result r = PB_OK;
    if (exists && (S_ISDIR(st.st_mode) || S_ISSOCK(st.st_mode) || S_ISBLK(st.st_mode))) {
        r = pb_fail(err, PB_ERROR_IO, "%s: %s: not an output", path, kind_of(st.st_mode));
    } else if (exists && (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode))) {
        /* a device or pipe: write into it; renaming over it would replace it */
        o->fd = open(path, O_WRONLY | O_CLOEXEC);
        if (o->fd < 0)
            r = pb_fail(err, PB_ERROR_IO, "%s: cannot open for writing: %s", path, strerror(errno));
    } else if (!(o->target = resolve_target(path, err))) {
        r = err ? err->code : PB_ERROR_IO;
    } else if ((o->fd = create_temp(o->target, &o->tmp)) < 0) {
        r = pb_fail(err, PB_ERROR_IO, "%s: cannot create a file there: %s", path, strerror(errno));
    } else if (exists) { /* keep what the replaced file had */
        if (fchown(o->fd, st.st_uid, st.st_gid) != 0) {
            /* not ours to give away: keep our ownership, the mode still */
        }
        fchmod(o->fd, st.st_mode & 07777);
    }
    if (r != PB_OK) {
        output_free(o);
        return r;
    }
    o->owns_fd = 1;
    *out = o;
    return PB_OK;
}

pb_result pb_output_put(pb_output *o, const void *bytes, uint64_t size, pb_error *err)
{
    return write_all(o->fd, o->path, bytes, size, o->cancel, o->user, err);
}

void pb_output_abort(pb_output *o)
{
    if (!o)
        return;
    if (o->owns_fd)
        close(o->fd);
    if (o->tmp)
        unlink(o->tmp); /* never leave a partial file behind */
    output_free(o);
}

pb_result pb_output_commit(pb_output *o, pb_error *err)
{
    const char *path = o->path;
    pb_result r = PB_OK;
    if (o->tmp && fsync(o->fd) != 0)
        r = pb_fail(err, PB_ERROR_IO, "%s: fsync failed: %s", path, strerror(errno));
    if (o->owns_fd && close(o->fd) != 0 && r == PB_OK)
        r = pb_fail(err, PB_ERROR_IO, "%s: close failed: %s", path, strerror(errno));
    o->owns_fd = 0;
    if (o->tmp) {
        if (r == PB_OK && o->cancel && o->cancel(o->user))
            r = pb_fail(err, PB_ERROR_CANCELLED, "%s: cancelled; nothing written", path);
        if (r == PB_OK && rename(o->tmp, o->target) != 0)
            r = pb_fail(err, PB_ERROR_IO, "%s: cannot replace the file: %s", path, strerror(errno));
        if (r == PB_OK) {
            free(o->tmp);
            o->tmp = NULL; /* renamed: nothing to remove */
        }
    }
    pb_output_abort(o);
    return r;
}

pb_result pb_output_write(const char *path, const void *bytes, uint64_t size, pb_cancel_fn cancel, void *user,
                          pb_error *err)
{
    pb_output *o;
    pb_result r = pb_output_begin(path, cancel, user, &o, err);
    if (r == PB_OK)
        r = pb_output_put(o, bytes, size, err);
    if (r != PB_OK) {
        pb_output_abort(o);
        return r;
    }
    return pb_output_commit(o, err);
}
