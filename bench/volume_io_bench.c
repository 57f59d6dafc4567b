/* volume_io_bench: what a large volume costs the host after the device is
 * done (convert its depth tiles, write the file) and what reading it back
 * costs, each against its floor in the same run.
 *
 *   volume_io_bench [--probes N] [--octmap N] [--repeat N] [--dir DIR]
 *                   [--json FILE] [--csv FILE]
 *
 * A synthetic grid volume of N probes (default 1,000,000: 1.4 GB at the
 * default 16 x 16 octahedral maps) is made once. Rows:
 *   depth  the volume stage's conversion of depth sums to half tiles
 *          (pb_half_pairs on the CPU's best path: F16C on x86-64), against
 *          one conversion at a time (PB_HALF_SCALAR, which it must match bit
 *          for bit)
 *   write  pb_volume_write: sections straight from the volume's arrays to a
 *          temporary file, fsync, rename; against write(2) of the same bytes
 *          from one ready buffer, then fsync: what any writer of the file pays
 *   read   pb_volume_read: sections straight into the arrays, every value
 *          checked; against read(2) of the whole file into one buffer
 *          (advised for huge pages, as the reader's arrays are)
 * Each write and read runs in a child process (fork), --repeat times
 * (default 3), ours first in even rounds and the peer's first in odd ones;
 * the table gives medians of the time and of the memory the operation added
 * to its process (peak RSS over the RSS it started with; the peer's ready
 * buffer counts). Every file written must be the bytes of the volume
 * written once before the rounds, and the volume read back must equal the
 * one made: else exit 1.
 * bench/RESULTS.md, "The host's tail of a large bake", has its numbers. */
#define _GNU_SOURCE /* wait4 */
#include "bench_util.h"
#include "common/common.h"
#include "io/half_pairs.h"

#include <fcntl.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define MAX_REPEAT 64

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

/* Resident bytes of this process now (/proc/self/statm). */
static double rss_bytes(void)
{
    long pages = 0, resident = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    if (f) {
        if (fscanf(f, "%ld %ld", &pages, &resident) != 2)
            resident = 0;
        fclose(f);
    }
    return (double)resident * (double)sysconf(_SC_PAGESIZE);
}

/* A plausible grid volume: SH and depth moments from a seeded generator,
 * finite everywhere (the writer refuses anything else). */
static int make_volume(pb_volume *v, uint32_t probes, uint32_t octmap)
{
    memset(v, 0, sizeof *v);
    uint32_t side = 1;
    while ((uint64_t)side * side * side < probes)
        ++side;
    v->flags = PB_VOLUME_IRRADIANCE | PB_VOLUME_GRID;
    v->probe_count = probes;
    v->counts[0] = v->counts[1] = side;
    v->counts[2] = (probes + side * side - 1) / (side * side);
    if ((uint64_t)v->counts[0] * v->counts[1] * v->counts[2] != probes) /* a grid of exactly N */
        v->counts[0] = probes, v->counts[1] = v->counts[2] = 1;
    v->octmap_res = octmap;
    for (int k = 0; k < 3; ++k)
        v->spacing[k] = 0.25;
    v->settings.rays_per_probe = 256, v->settings.passes = 1, v->settings.max_distance = 40.f;
    snprintf(v->device, sizeof v->device, "volume_io_bench");
    pb_error err;
    if (pb_volume_alloc(v, &err) != PB_OK) {
        fprintf(stderr, "volume_io_bench: %s\n", err.message);
        return 0;
    }
    uint32_t state = 12345u;
    uint64_t halves = (uint64_t)probes * pb_volume_tile_halves(octmap);
    for (uint64_t i = 0; i < halves; ++i) {
        state = state * 1664525u + 1013904223u;
        v->depth[i] = (uint16_t)((state >> 9) % 0x7bffu); /* a finite positive half */
    }
    for (uint64_t i = 0; i < 27ull * probes; ++i) {
        state = state * 1664525u + 1013904223u;
        v->sh[i] = (float)(state >> 8) * 0x1p-24f;
    }
    for (uint32_t p = 0; p < probes; ++p) {
        for (int k = 0; k < 3; ++k)
            v->base[3 * (size_t)p + k] = 0.25f * (float)(k == 0 ? p % side : k == 1 ? p / side % side : p / side / side);
        v->probe_flags[p] = PB_PROBE_VALID;
        v->probe_paths[p] = 256;
        v->probe_std_error[p] = 0.01f;
    }
    return 1;
}

static int volumes_equal(const pb_volume *a, const pb_volume *b)
{
    size_t n = a->probe_count;
    return a->probe_count == b->probe_count && a->octmap_res == b->octmap_res &&
           !memcmp(a->base, b->base, 12 * n) && !memcmp(a->offset, b->offset, 12 * n) &&
           !memcmp(a->probe_flags, b->probe_flags, 4 * n) && !memcmp(a->sh, b->sh, 108 * n) &&
           !memcmp(a->depth, b->depth, 2 * n * pb_volume_tile_halves(a->octmap_res)) &&
           !memcmp(a->probe_paths, b->probe_paths, 4 * n) && !memcmp(a->probe_std_error, b->probe_std_error, 4 * n);
}

/* What a child reports: ms, the bytes it added, and 0 or a failure. */
typedef struct op_result {
    double ms, added;
    int failed;
} op_result;

enum { OP_WRITE, OP_RAW_WRITE, OP_READ, OP_RAW_READ };

typedef struct job {
    const pb_volume *v;
    const char *ours, *raw, *ref; /* file paths; ref: the volume written once, the peer's bytes */
} job;

static int raw_write(const char *path, const unsigned char *b, uint64_t size)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0)
        return 0;
    uint64_t done = 0;
    while (done < size) {
        ssize_t w = write(fd, b + done, size - done > (1u << 20) ? (1u << 20) : (size_t)(size - done));
        if (w <= 0)
            break;
        done += (uint64_t)w;
    }
    int ok = done == size && fsync(fd) == 0;
    return close(fd) == 0 && ok;
}

static unsigned char *raw_read(const char *path, uint64_t *size)
{
    struct stat st;
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0 || fstat(fd, &st) != 0) {
        if (fd >= 0)
            close(fd);
        return NULL;
    }
    /* advised for huge pages, as the reader's arrays are: the floor is the
     * read, not the page faults */
    unsigned char *b = pb_malloc_large((size_t)st.st_size ? (size_t)st.st_size : 1);
    uint64_t done = 0;
    while (b && done < (uint64_t)st.st_size) {
        ssize_t r = read(fd, b + done, (size_t)st.st_size - done);
        if (r <= 0)
            break;
        done += (uint64_t)r;
    }
    close(fd);
    if (!b || done != (uint64_t)st.st_size) {
        free(b);
        return NULL;
    }
    *size = done;
    return b;
}

/* One operation in this (child) process. */
static op_result run_op(const job *jb, int op)
{
    op_result res = {0, 0, 0};
    unsigned char *bytes = NULL;
    uint64_t size = 0;
    double rss0 = rss_bytes(); /* the peer's ready buffer counts as memory it adds, not as time */
    if (op == OP_RAW_WRITE && !(bytes = raw_read(jb->ref, &size)))
        return res.failed = 1, res;
    double t0 = now_ms();
    pb_error err;
    pb_volume back;
    switch (op) {
    case OP_WRITE:
        res.failed = pb_volume_write(jb->ours, jb->v, &err) != PB_OK;
        break;
    case OP_RAW_WRITE:
        res.failed = !raw_write(jb->raw, bytes, size);
        break;
    case OP_READ:
        res.failed = pb_volume_read(jb->ours, &back, &err) != PB_OK;
        break;
    default:
        res.failed = !(bytes = raw_read(jb->ours, &size));
        break;
    }
    res.ms = now_ms() - t0;
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    res.added = (double)ru.ru_maxrss * 1024.0 - rss0;
    if (op == OP_READ && !res.failed) {
        res.failed = !volumes_equal(&back, jb->v);
        pb_volume_free(&back);
    }
    if (res.failed && op != OP_RAW_WRITE && op != OP_RAW_READ)
        fprintf(stderr, "volume_io_bench: %s\n", err.message);
    free(bytes);
    return res;
}

/* run_op in a child, so each operation's peak memory is its own. */
static op_result in_child(const job *jb, int op)
{
    int fds[2];
    op_result res = {0, 0, 1};
    if (pipe(fds) != 0)
        return res;
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        close(fds[0]);
        op_result r = run_op(jb, op);
        ssize_t w = write(fds[1], &r, sizeof r);
        _exit(w == (ssize_t)sizeof r ? 0 : 1);
    }
    close(fds[1]);
    if (pid > 0 && read(fds[0], &res, sizeof res) != (ssize_t)sizeof res)
        res.failed = 1;
    close(fds[0]);
    int status = 0;
    if (pid > 0)
        waitpid(pid, &status, 0);
    if (pid < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        res.failed = 1;
    return res;
}

static int files_same(const char *a, const char *b)
{
    uint64_t na = 0, nb = 0;
    unsigned char *x = raw_read(a, &na), *y = raw_read(b, &nb);
    int same = x && y && na == nb && !memcmp(x, y, (size_t)na);
    free(x);
    free(y);
    return same;
}

int main(int argc, char **argv)
{
    uint32_t probes = 1000000, octmap = 16, repeat = 3;
    const char *dir = "/tmp", *json = NULL, *csv = NULL;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--probes") && next)
            probes = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--octmap") && next)
            octmap = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--repeat") && next)
            repeat = (uint32_t)strtoul(argv[++i], NULL, 10);
        else if (!strcmp(a, "--dir") && next)
            dir = argv[++i];
        else if (!strcmp(a, "--json") && next)
            json = argv[++i];
        else if (!strcmp(a, "--csv") && next)
            csv = argv[++i];
        else {
            fprintf(stderr, "usage: volume_io_bench [--probes N] [--octmap N] [--repeat N] [--dir DIR] [--json FILE] "
                            "[--csv FILE]\n");
            return 2;
        }
    }
    if (!probes || octmap < 1 || octmap > 64 || !repeat || repeat > MAX_REPEAT) {
        fprintf(stderr, "volume_io_bench: --probes >= 1, --octmap 1-64 and --repeat 1-%d\n", MAX_REPEAT);
        return 2;
    }
    pb_volume v;
    if (!make_volume(&v, probes, octmap))
        return 1;
    uint64_t file_bytes = pb_volume_file_bytes(&v);
    char ours[1024], raw[1024], ref[1024];
    snprintf(ours, sizeof ours, "%s/volume_io_bench-%ld.probes", dir, (long)getpid());
    snprintf(raw, sizeof raw, "%s/volume_io_bench-%ld.raw", dir, (long)getpid());
    snprintf(ref, sizeof ref, "%s/volume_io_bench-%ld.ref", dir, (long)getpid());
    job jb = {&v, ours, raw, ref};
    printf("volume_io_bench: %u probes, %ux%u octahedral maps, %.1f MiB file, %u rounds, files in %s\n", probes,
           octmap, octmap, file_bytes / 1048576.0, repeat, dir);

    /* depth: the volume stage's conversion, in this process (no I/O) */
    uint32_t n = octmap, w = n + 2, rows = probes < 65536 ? probes : 65536; /* a slab of probes, reused */
    float *sums = malloc(sizeof(float) * 2 * n * n * (size_t)rows);
    uint16_t *fast = malloc(2 * sizeof(uint16_t) * w * w * (size_t)rows),
             *slow = malloc(2 * sizeof(uint16_t) * w * w * (size_t)rows);
    if (!sums || !fast || !slow)
        return fprintf(stderr, "volume_io_bench: out of memory\n"), 1;
    uint32_t state = 777u;
    for (size_t i = 0; i < 2 * (size_t)n * n * rows; ++i) {
        state = state * 1664525u + 1013904223u;
        float d = (float)(state >> 8) * 0x1p-24f * 40.f;
        sums[i] = i & 1 ? d * d * 3.f : d * 3.f; /* three passes' sums of distance and square */
    }
    pb_half_path best = pb_half_best_path();
    double conv[2][MAX_REPEAT];
    int mismatch = 0;
    for (uint32_t r = 0; r < repeat; ++r)
        for (int k = 0; k < 2; ++k) {
            uint16_t *out = k ? slow : fast;
            double t0 = now_ms();
            for (uint32_t done = 0; done < probes; done += rows) {
                uint32_t m = probes - done < rows ? probes - done : rows;
                for (uint32_t p = 0; p < m; ++p)
                    for (uint32_t y = 0; y < n; ++y) {
                        const float *in = sums + 2 * ((size_t)p * n * n + (size_t)y * n);
                        uint16_t *o = out + 2 * ((size_t)p * w * w + (size_t)(y + 1) * w + 1);
                        pb_half_pairs(k ? PB_HALF_SCALAR : best, in, o, n, 3 * 0.5, 3 * 0.25);
                    }
            }
            conv[k][r] = now_ms() - t0;
        }
    for (size_t p = 0; p < rows; ++p)
        for (uint32_t y = 1; y <= n; ++y)
            mismatch |= memcmp(fast + 2 * (p * w * w + y * w + 1), slow + 2 * (p * w * w + y * w + 1),
                               2 * n * sizeof *fast) != 0;
    free(sums), free(fast), free(slow);

    op_result res[4][MAX_REPEAT];
    pb_error err;
    int failed = mismatch;
    if (!failed && pb_volume_write(ref, &v, &err) != PB_OK) {
        fprintf(stderr, "volume_io_bench: %s\n", err.message);
        failed = 1;
    }
    /* each round: the two writes, then the two reads of our file, the
     * peer first in odd rounds (the page cache's state moves with the order) */
    for (uint32_t r = 0; r < repeat && !failed; ++r) {
        static const int order[2][4] = {{OP_WRITE, OP_RAW_WRITE, OP_READ, OP_RAW_READ},
                                        {OP_RAW_WRITE, OP_WRITE, OP_RAW_READ, OP_READ}};
        for (int k = 0; k < 4; ++k) {
            int op = order[r & 1][k];
            res[op][r] = in_child(&jb, op);
            failed |= res[op][r].failed;
        }
        if (!failed && (!files_same(ours, ref) || !files_same(raw, ref))) {
            fprintf(stderr, "volume_io_bench: a file written is not the volume's bytes\n");
            failed = 1;
        }
        printf("round %u: write %.0f / %.0f ms, read %.0f / %.0f ms (ours / peer)\n", r + 1, res[OP_WRITE][r].ms,
               res[OP_RAW_WRITE][r].ms, res[OP_READ][r].ms, res[OP_RAW_READ][r].ms);
        unlink(ours);
        unlink(raw);
    }
    unlink(ref);
    if (failed) {
        fprintf(stderr, "volume_io_bench: %s\n",
                mismatch ? "bulk depth conversion differs from one at a time" : "an operation failed");
        pb_volume_free(&v);
        return 1;
    }
    double med[4][2]; /* ms, added MiB */
    for (int k = 0; k < 4; ++k) {
        double t[MAX_REPEAT], m[MAX_REPEAT];
        for (uint32_t r = 0; r < repeat; ++r)
            t[r] = res[k][r].ms, m[r] = res[k][r].added / 1048576.0;
        med[k][0] = bench_median(t, repeat), med[k][1] = bench_median(m, repeat);
    }
    double conv_fast = bench_median(conv[0], repeat), conv_slow = bench_median(conv[1], repeat);
    double mib = file_bytes / 1048576.0, depth_mib = (double)probes * w * w * 4 / 1048576.0;
    const char *path_name = best == PB_HALF_F16C ? "F16C" : "scalar";
    printf("\n| step | ours ms | peer ms | ours / peer | ours MiB/s | ours added MiB | peer added MiB | peer |\n");
    printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n");
    printf("| depth tiles (%s) | %.1f | %.1f | %.3f | %.0f | - | - | one conversion at a time |\n", path_name,
           conv_fast, conv_slow, conv_fast / conv_slow, depth_mib / (conv_fast / 1e3));
    printf("| write | %.1f | %.1f | %.3f | %.0f | %.1f | %.1f | write(2) of one ready buffer + fsync |\n",
           med[OP_WRITE][0], med[OP_RAW_WRITE][0], med[OP_WRITE][0] / med[OP_RAW_WRITE][0],
           mib / (med[OP_WRITE][0] / 1e3), med[OP_WRITE][1], med[OP_RAW_WRITE][1]);
    printf("| read | %.1f | %.1f | %.3f | %.0f | %.1f | %.1f | read(2) into one buffer |\n", med[OP_READ][0],
           med[OP_RAW_READ][0], med[OP_READ][0] / med[OP_RAW_READ][0], mib / (med[OP_READ][0] / 1e3),
           med[OP_READ][1], med[OP_RAW_READ][1]);
    const char *names[3] = {"depth", "write", "read"};
    double rows_v[3][6] = {{conv_fast, conv_slow, 0, 0, depth_mib, 0},
                           {med[OP_WRITE][0], med[OP_RAW_WRITE][0], med[OP_WRITE][1], med[OP_RAW_WRITE][1], mib, 0},
                           {med[OP_READ][0], med[OP_RAW_READ][0], med[OP_READ][1], med[OP_RAW_READ][1], mib, 0}};
    if (csv) {
        FILE *f = fopen(csv, "w");
        if (!f)
            return fprintf(stderr, "volume_io_bench: cannot write %s\n", csv), 1;
        fprintf(f, "step,probes,octmap,ours_ms,peer_ms,ratio,mib,ours_added_mib,peer_added_mib\n");
        for (int k = 0; k < 3; ++k)
            fprintf(f, "%s,%u,%u,%.3f,%.3f,%.4f,%.1f,%.1f,%.1f\n", names[k], probes, octmap, rows_v[k][0],
                    rows_v[k][1], rows_v[k][0] / rows_v[k][1], rows_v[k][4], rows_v[k][2], rows_v[k][3]);
        fclose(f);
        printf("wrote %s\n", csv);
    }
    if (json) {
        FILE *f = fopen(json, "w");
        if (!f)
            return fprintf(stderr, "volume_io_bench: cannot write %s\n", json), 1;
        fprintf(f, "{\"bench\": \"volume_io_bench\", \"probes\": %u, \"octmap\": %u, \"repeat\": %u, "
                   "\"file_mib\": %.1f, \"depth_conversion\": \"%s\", \"rows\": [",
                probes, octmap, repeat, mib, path_name);
        for (int k = 0; k < 3; ++k)
            fprintf(f, "%s\n  {\"step\": \"%s\", \"ours_ms\": %.3f, \"peer_ms\": %.3f, \"ratio\": %.4f, "
                       "\"ours_added_mib\": %.1f, \"peer_added_mib\": %.1f}",
                    k ? "," : "", names[k], rows_v[k][0], rows_v[k][1], rows_v[k][0] / rows_v[k][1], rows_v[k][2],
                    rows_v[k][3]);
        fprintf(f, "\n]}\n");
        fclose(f);
        printf("wrote %s\n", json);
    }
    pb_volume_free(&v);
    return 0;
}
