/* Ordered outputs in one chained launch against a count launch, a scan and a
 * write launch (SLUICE_CHAIN=0), call by call on the same records: the
 * ordered split of floats by a threshold (sluice_partition) and the ordered
 * compaction (sluice_compact). Both contexts must give the same records in
 * the same order (exit status 1 otherwise). Prints B's (the chained launch's)
 * speed over A's: the median and quartiles of the pairs, each timed from the
 * call to the finish of the queue.
 *
 *   bench_ordered_ab [--n N] [--pairs P]
 */
#define _POSIX_C_SOURCE 200809L
#include "bench_ab.h"
#include "sluice/streams.h"

#include <stdint.h>
#include <time.h>

#define PROG "bench_ordered_ab"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct side {
    sluice_context *ctx;
    sluice_stream *in, *flags, *lo, *hi;
} side;

static void side_destroy(side *s)
{
    sluice_stream_destroy(s->in);
    sluice_stream_destroy(s->flags);
    sluice_stream_destroy(s->lo);
    sluice_stream_destroy(s->hi);
    sluice_context_destroy(s->ctx);
}

/* A context with ordered outputs chained (`chain`) or in two launches, and
 * its streams holding `v` and `f`; 0 after saying why (side_destroy frees
 * what was made). */
static int side_create(side *s, char name, int chain, const float *v, const uint32_t *f, size_t n)
{
    /* read once, when the context is created */
    if (setenv("SLUICE_CHAIN", chain ? "1" : "0", 1) != 0 ||
        !bench_ab_context(PROG, name, NULL, &s->ctx))
        return 0;
    sluice_context *c = s->ctx;
    if (sluice_stream_create(c, 4, n, &s->in) || sluice_stream_create(c, 4, n, &s->flags) ||
        sluice_stream_create(c, 4, n, &s->lo) || sluice_stream_create(c, 4, n, &s->hi) ||
        sluice_stream_upload(s->in, v, n) || sluice_stream_upload(s->flags, f, n)) {
        fprintf(stderr, PROG ": variant %c: %s\n", name, sluice_context_error(c));
        return 0;
    }
    return 1;
}

/* One call of primitive `which` (0: split, 1: compaction) with the queue
 * finished; its seconds, or -1 after saying why. */
static double run(side *s, int which)
{
    const float t = 0.5f;
    double t0 = now();
    sluice_status st = sluice_stream_clear(s->lo);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(s->hi);
    if (st == SLUICE_OK)
        st = which == 0
                 ? sluice_partition(s->ctx, s->in, SLUICE_F32, &t, s->lo, s->hi, SLUICE_ORDERED)
                 : sluice_compact(s->ctx, s->in, s->flags, s->lo, SLUICE_ORDERED);
    if (st == SLUICE_OK)
        st = sluice_context_finish(s->ctx);
    if (st != SLUICE_OK) {
        fprintf(stderr, PROG ": %s\n", sluice_context_error(s->ctx));
        return -1;
    }
    return now() - t0;
}

/* Do both sides hold the same output records (in order)? */
static int same_output(side *a, side *b, size_t n, uint32_t *x, uint32_t *y)
{
    sluice_stream *sa[2] = {a->lo, a->hi}, *sb[2] = {b->lo, b->hi};
    for (int k = 0; k < 2; ++k) {
        size_t na = 0, nb = 0;
        if (sluice_stream_download(sa[k], x, n, &na) || sluice_stream_download(sb[k], y, n, &nb))
            return 0;
        if (na != nb || memcmp(x, y, na * sizeof *x) != 0)
            return 0;
    }
    return 1;
}

int main(int argc, char **argv)
{
    size_t n = (size_t)1 << 24;
    unsigned pairs = 30;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--n") && i + 1 < argc) {
            n = strtoull(argv[++i], NULL, 10);
        } else if (!strcmp(argv[i], "--pairs") && i + 1 < argc) {
            pairs = (unsigned)strtoul(argv[++i], NULL, 10);
        } else {
            fprintf(stderr,
                    "usage: " PROG " [--n N] [--pairs P]\n"
                    "Ordered split and compaction of N records (default 2^24) in one chained\n"
                    "launch (B) against two launches (A, SLUICE_CHAIN=0), P pairs each\n"
                    "(default 30); checks that both give the same records.\n");
            return strcmp(argv[i], "--help") == 0 ? 0 : 2;
        }
    }
    if (n == 0 || n > ((size_t)1 << 28) || pairs == 0 || pairs > 10000) {
        fprintf(stderr, PROG ": --n must be 1 .. 2^28 and --pairs 1 .. 10000\n");
        return 2;
    }
    float *v = malloc(n * sizeof *v);
    uint32_t *f = malloc(n * sizeof *f), *x = malloc(n * sizeof *x), *y = malloc(n * sizeof *y);
    double *ta = malloc(pairs * sizeof *ta), *tb = malloc(pairs * sizeof *tb);
    side a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    int rc = 1;
    if (!v || !f || !x || !y || !ta || !tb) {
        fprintf(stderr, PROG ": out of memory\n");
        goto done;
    }
    uint32_t r = 2463534242u; /* xorshift32 */
    for (size_t i = 0; i < n; ++i) {
        r ^= r << 13;
        r ^= r >> 17;
        r ^= r << 5;
        v[i] = (float)(r >> 8) * (1.0f / 16777216.0f);
        f[i] = (r >> 3) & 1u;
    }
    if (!side_create(&a, 'A', 0, v, f, n) || !side_create(&b, 'B', 1, v, f, n))
        goto done;
    sluice_device_info dev;
    sluice_context_device(b.ctx, &dev);
    printf("device: %s / %s; %zu records, %u pairs (A then B, then B then A)\n", dev.platform,
           dev.name, n, pairs);
    printf("B: one chained launch; A: count launch, scan, write launch (SLUICE_CHAIN=0)\n");
    rc = 0;
    for (int which = 0; which < 2 && rc == 0; ++which) {
        const char *name = which ? "compact_ordered" : "split_f32_ordered";
        for (int w = 0; w < 2; ++w) /* warm: kernels built, caches touched */
            if (run(&a, which) < 0 || run(&b, which) < 0)
                rc = 1;
        for (unsigned p = 0; p < pairs && rc == 0; ++p) {
            int b_first = p & 1u;
            double t1 = run(b_first ? &b : &a, which), t2 = run(b_first ? &a : &b, which);
            ta[p] = b_first ? t2 : t1;
            tb[p] = b_first ? t1 : t2;
            if (t1 < 0 || t2 < 0)
                rc = 1;
        }
        if (rc)
            break;
        if (!same_output(&a, &b, n, x, y)) {
            fprintf(stderr, PROG ": %s: the two variants' records differ\n", name);
            rc = 1;
            break;
        }
        double q[3];
        if (!bench_ab_ratio(ta, tb, pairs, q)) {
            rc = 1;
            break;
        }
        printf("%-18s A %.3f ms, B %.3f ms (medians; best %.3f, %.3f; worst %.3f, %.3f); "
               "B/A speed %.3f (quartiles %.3f, %.3f); same records\n",
               name, 1e3 * ta[pairs / 2], 1e3 * tb[pairs / 2], 1e3 * ta[0], 1e3 * tb[0],
               1e3 * ta[pairs - 1], 1e3 * tb[pairs - 1], q[1], q[0], q[2]);
    }
done:
    side_destroy(&a); /* destroy accepts what was never made */
    side_destroy(&b);
    free(v);
    free(f);
    free(x);
    free(y);
    free(ta);
    free(tb);
    return rc;
}
