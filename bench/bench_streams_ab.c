/*
 * bench_streams_ab: ordered outputs placed by a count launch, a scan and a
 * write launch (variant A, the context option no_chain) against one
 * chained launch (variant B, the default on PoCL's CPU devices:
 * sluice_chain_ in kernels/sluice.cl), on the same records, to tell their
 * difference from the noise of a shared machine (bench_raytrace_ab and
 * bench_knn_ab do the same for the ray tracer and the kNN search).
 *
 * Each primitive runs in both contexts, alternating call by call, A B then
 * B A, so that drift in the machine's speed falls on both alike; the result
 * is the median over call pairs of B's speed over A's, with its quartiles,
 * and each variant's best time. The unordered form of each primitive runs
 * in B's context beside them, for the bound the chain aims at: the same
 * single pass over the input, without the order.
 *
 *   bench_streams_ab [--n N] [--pairs N]
 *
 * Exit status 0 when both variants wrote the same records in the same
 * order, 1 when not, 2 on bad arguments or setup errors.
 */
#include "bench_ab.h"
#include "bench_args.h"
#include "bench_machine.h"
#include "sluice/streams.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PROG "bench_streams_ab"

static void usage(FILE *out)
{
    fprintf(out, "usage: " PROG " [--n N] [--pairs N]\n"
                 "Times the ordered split (a partition of floats at 0) and the ordered compaction\n"
                 "(every other record, at random) placed by a count launch, a scan and a write\n"
                 "launch (A: the context option no_chain) against one chained launch (B: the\n"
                 "default on CPUs), the two alternating call by call, and prints the median\n"
                 "over call pairs of B's speed over A's with its quartiles.\n\n"
                 "  --n N      records (default 16777216)\n"
                 "  --pairs N  timed call pairs, after 2 warm-up pairs (default 30)\n"
                 "  --help     this text\n");
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* One context's streams: the records, the compaction's flags, two outputs. */
typedef struct variant {
    sluice_context *ctx;
    sluice_stream *in, *flags, *lo, *hi;
} variant;

enum { SPLIT, COMPACT, PRIMITIVES };
static const char *const primitive_name[PRIMITIVES] = {"split_f32", "compact"};

static int variant_make(variant *v, char name, int no_chain, const float *x, const uint32_t *f,
                        size_t n)
{
    char err[512];
    sluice_context_options co;
    memset(&co, 0, sizeof co);
    co.no_chain = no_chain;
    memset(v, 0, sizeof *v);
    if (sluice_context_create(&co, &v->ctx, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, PROG ": variant %c: %s\n", name, err);
        return 0;
    }
    if (sluice_stream_create(v->ctx, 4, n, &v->in) ||
        sluice_stream_create(v->ctx, 4, n, &v->flags) ||
        sluice_stream_create(v->ctx, 4, n, &v->lo) || sluice_stream_create(v->ctx, 4, n, &v->hi) ||
        sluice_stream_upload(v->in, x, n) || sluice_stream_upload(v->flags, f, n)) {
        fprintf(stderr, PROG ": variant %c: %s\n", name, sluice_context_error(v->ctx));
        return 0;
    }
    return 1;
}

static void variant_free(variant *v)
{
    sluice_stream *s[] = {v->in, v->flags, v->lo, v->hi};
    for (size_t i = 0; i < sizeof s / sizeof *s; ++i)
        sluice_stream_destroy(s[i]);
    sluice_context_destroy(v->ctx);
}

/* Runs primitive p once (its outputs emptied first); its time in seconds,
 * or -1 after saying why. */
static double run(variant *v, int p, sluice_output_mode mode)
{
    float zero = 0.0f;
    if (sluice_stream_set_length(v->lo, 0) || sluice_stream_set_length(v->hi, 0) ||
        sluice_context_finish(v->ctx))
        goto fail;
    double t0 = now();
    sluice_status st = p == SPLIT
                           ? sluice_partition(v->ctx, v->in, SLUICE_F32, &zero, v->lo, v->hi, mode)
                           : sluice_compact(v->ctx, v->in, v->flags, v->lo, mode);
    if (st != SLUICE_OK || sluice_context_finish(v->ctx) != SLUICE_OK)
        goto fail;
    return now() - t0;
fail:
    fprintf(stderr, PROG ": %s: %s\n", primitive_name[p], sluice_context_error(v->ctx));
    return -1.0;
}

/* The records of `s` (n at most), into a new array; NULL on failure. */
static uint32_t *download(sluice_stream *s, size_t n, size_t *len)
{
    uint32_t *r = malloc((n ? n : 1) * sizeof *r);
    if (!r || sluice_stream_download(s, r, n, len) != SLUICE_OK) {
        free(r);
        return NULL;
    }
    return r;
}

/* Do both variants' outputs of their last run hold the same records? */
static int same_outputs(variant *a, variant *b, size_t n)
{
    int same = 1;
    sluice_stream *sa[] = {a->lo, a->hi}, *sb[] = {b->lo, b->hi};
    for (int o = 0; o < 2 && same; ++o) {
        size_t la = 0, lb = 0;
        uint32_t *ra = download(sa[o], n, &la), *rb = download(sb[o], n, &lb);
        same = ra && rb && la == lb && memcmp(ra, rb, la * sizeof *ra) == 0;
        free(ra);
        free(rb);
    }
    return same;
}

int main(int argc, char **argv)
{
    unsigned n = 1u << 24, pairs = 30;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--n") == 0 && val) {
            if (!bench_parse_uint(val, 1u << 28, &n) || n == 0) {
                fprintf(stderr, PROG ": --n: want 1 .. 268435456 records, got '%s'\n", val);
                return 2;
            }
            ++i;
        } else if (strcmp(a, "--pairs") == 0 && val) {
            if (!bench_parse_uint(val, 100000, &pairs) || pairs == 0) {
                fprintf(stderr, PROG ": --pairs: want 1 .. 100000, got '%s'\n", val);
                return 2;
            }
            ++i;
        } else {
            fprintf(stderr, PROG ": %s: unknown option or missing value (try --help)\n", a);
            return 2;
        }
    }
    float *x = malloc((size_t)n * sizeof *x);
    uint32_t *f = malloc((size_t)n * sizeof *f);
    double *t[3] = {malloc(pairs * sizeof(double)), malloc(pairs * sizeof(double)),
                    malloc(pairs * sizeof(double))};
    if (!x || !f || !t[0] || !t[1] || !t[2]) {
        fprintf(stderr, PROG ": out of memory\n");
        return 2;
    }
    uint32_t s = 2463534242u; /* xorshift32: the same records every run */
    for (unsigned i = 0; i < n; ++i) {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        x[i] = (float)(s >> 8) * 0x1p-24f - 0.5f;
        f[i] = (s >> 3) & 1u;
    }
    variant va = {0}, vb = {0};
    int ok = variant_make(&va, 'A', 1, x, f, n) && variant_make(&vb, 'B', 0, x, f, n);
    int status = ok ? 0 : 2;
    if (ok) {
        bench_machine m;
        bench_machine_probe(vb.ctx, &m);
        sluice_device_info info;
        sluice_context_device(vb.ctx, &info);
        printf("CPU: %s (%s), kernels' block emission: %s; device: %s / %s\n", m.cpu, m.isa,
               m.block, info.platform, info.name);
        printf("n = %u, %u pairs; A: count launch, scan, write launch; B: chained\n", n, pairs);
        printf("%-10s %12s %12s %14s %22s\n", "primitive", "A best ms", "B best ms", "unordered ms",
               "B/A speed (quartiles)");
    }
    for (int p = 0; ok && p < PRIMITIVES; ++p) {
        for (unsigned r = 0; ok && r < pairs + 2; ++r) {
            /* A B, then B A; the unordered run after both */
            double ta, tb;
            if (r & 1) {
                tb = run(&vb, p, SLUICE_ORDERED);
                ta = run(&va, p, SLUICE_ORDERED);
            } else {
                ta = run(&va, p, SLUICE_ORDERED);
                tb = run(&vb, p, SLUICE_ORDERED);
            }
            if (ta < 0 || tb < 0) {
                ok = 0;
                status = 2;
                break;
            }
            if (r == 0 && !same_outputs(&va, &vb, n)) {
                fprintf(stderr, PROG ": %s: the variants' outputs differ\n", primitive_name[p]);
                status = 1;
            }
            double tu = run(&vb, p, SLUICE_UNORDERED);
            if (tu < 0) {
                ok = 0;
                status = 2;
                break;
            }
            if (r >= 2) {
                t[0][r - 2] = ta;
                t[1][r - 2] = tb;
                t[2][r - 2] = tu;
            }
        }
        double q[3];
        if (!ok)
            break;
        if (!bench_ab_ratio(t[0], t[1], pairs, q)) {
            fprintf(stderr, PROG ": out of memory\n");
            status = 2;
            break;
        }
        qsort(t[2], pairs, sizeof(double), bench_ab_cmp_double);
        printf("%-10s %12.3f %12.3f %14.3f %8.3fx (%.3f-%.3f)\n", primitive_name[p], 1e3 * t[0][0],
               1e3 * t[1][0], 1e3 * t[2][0], q[1], q[0], q[2]);
    }
    if (va.ctx)
        variant_free(&va);
    if (vb.ctx)
        variant_free(&vb);
    free(x);
    free(f);
    for (int i = 0; i < 3; ++i)
        free(t[i]);
    return status;
}
