/*
 * probebake files: how every input is opened and every output written.
 *
 * Inputs (scenes and their buffers, environment maps, points files,
 * volumes) must be regular files: a directory, FIFO, device or socket is a
 * one-line error naming the path and what it is, decided by fstat on the
 * opened descriptor (opened non-blocking, so a FIFO cannot hang the open)
 * before any size is trusted, and sizes are bounded before allocating.
 *
 * Outputs:
 *  - a regular file (or a new name) is written atomically: a temporary file
 *    beside the target, fsync, rename. A new file gets 0666 & ~umask (the
 *    kernel applies the umask), a replaced one keeps its mode;
 *  - a symbolic link is followed: its target is written (atomically, in the
 *    target's directory) and the link stays a link;
 *  - a character device or FIFO is written directly, never renamed over:
 *    `-o /dev/null` discards, `-o /dev/full` fails with ENOSPC;
 *  - a directory or socket is an error;
 *  - "-" is standard output.
 * A failed or cancelled write leaves no temporary file and the previous
 * output untouched.
 */
#ifndef PROBEBAKE_FILES_H
#define PROBEBAKE_FILES_H

#include "probebake/base.h"

#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Opens `path` for reading if it is a regular file of at most max_bytes.
 *  out: receives the stream (the caller fcloses it); size: its bytes.
 *  Returns PB_ERROR_IO (cannot open, "is a directory", "is not a regular
 *  file (a FIFO)", ...) or PB_ERROR_TOO_LARGE, each naming the path. */
pb_result pb_input_open(const char *path, uint64_t max_bytes, FILE **out, uint64_t *size, pb_error *err);

/* Reads the whole regular file `path` (at most max_bytes) into a malloc'd
 * buffer with one extra zero byte after `size` bytes (text parsers may rely
 * on it). Errors as pb_input_open, plus PB_ERROR_OUT_OF_HOST_MEMORY. */
pb_result pb_input_read(const char *path, uint64_t max_bytes, unsigned char **bytes, uint64_t *size, pb_error *err);

/* Cancellation of a write in progress: nonzero to stop (checked between
 * chunks and before the rename). NULL: never. */
typedef int (*pb_cancel_fn)(void *user);

/* Whether `path` can take an output, before any work that produces it:
 * refuses a directory, a socket, a missing or unwritable directory (tried by
 * creating and removing a file there), and an output that is the same file
 * (same device and inode: hard links and symlinks included) as one of the
 * `input_count` inputs (NULL entries are skipped). "-" is fine. */
pb_result pb_output_check(const char *path, const char *const *inputs, int input_count, pb_error *err);

/* Writes size bytes to `path` by the rules above. PB_ERROR_IO naming the
 * path, PB_ERROR_CANCELLED when cancel asked (nothing replaced). */
pb_result pb_output_write(const char *path, const void *bytes, uint64_t size, pb_cancel_fn cancel, void *user,
                          pb_error *err);

/* The same write in pieces, for outputs too large to hold twice: begin
 * (the checks and the temporary file), put each piece in order, then commit
 * (fsync, cancellation check, rename; frees the handle either way) or abort
 * (removes the temporary file; NULL is fine). On an error from begin *out is
 * NULL; after an error from put the caller aborts. */
typedef struct pb_output pb_output;
pb_result pb_output_begin(const char *path, pb_cancel_fn cancel, void *user, pb_output **out, pb_error *err);
pb_result pb_output_put(pb_output *o, const void *bytes, uint64_t size, pb_error *err);
pb_result pb_output_commit(pb_output *o, pb_error *err);
void pb_output_abort(pb_output *o);

#ifdef __cplusplus
}
#endif
#endif
