/*
 * bench_streams: runs each stream primitive on 2^24 records (by default) and
 * writes bench/results/streams.json with records/s and effective GB/s per
 * primitive, beside two peers measured in the same run:
 *   (a) the bound: a copy kernel's bandwidth on the same device;
 *   (b) a plain single-thread C implementation of the same primitive.
 * Targets are ratios against those peers, so a noisy shared machine moves
 * both sides together. Times are the best of several runs after a warm-up.
 *
 * Effective bytes count the payload a primitive must read and write once
 * (e.g. a split reads n records and writes n), not the traffic the
 * implementation actually causes.
 */
#include "bench_machine.h"
#include "sluice/sluice.h"
#include "sluice/streams.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct result {
    const char *name;
    double records;       /* records processed per run */
    double bytes;         /* effective bytes per run */
    double seconds;       /* best time */
    double c_seconds;     /* plain C single-thread, 0 if none */
    const char *c_name;   /* what the C peer is */
    double scratch_bytes; /* -1 if not measured */
} result;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static uint32_t xorshift(uint32_t *s)
{
    uint32_t x = *s;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *s = x;
}

static sluice_context *ctx;
static int reps = 10;

#define TRY(call)                                                                                  \
    do {                                                                                           \
        sluice_status st_ = (call);                                                                \
        if (st_ != SLUICE_OK) {                                                                    \
            fprintf(stderr, "bench_streams: %s failed: %s\n", #call, sluice_context_error(ctx));   \
            exit(1);                                                                               \
        }                                                                                          \
    } while (0)

/* Best time of `reps` runs of `run` (after one warm-up), each followed by a
 * finish so that the queue is drained. `prep` (may be NULL) runs untimed
 * before each run. */
typedef void (*bench_fn)(void *arg);
static double best_of(bench_fn prep, bench_fn run, void *arg, int n_reps)
{
    double best = 1e30;
    for (int r = 0; r <= n_reps; ++r) {
        if (prep)
            prep(arg);
        TRY(sluice_context_finish(ctx));
        double t0 = now();
        run(arg);
        TRY(sluice_context_finish(ctx));
        double t = now() - t0;
        if (r > 0 && t < best)
            best = t;
    }
    return best;
}

static double best_of_c(bench_fn prep, bench_fn run, void *arg, int n_reps)
{
    double best = 1e30;
    for (int r = 0; r < n_reps; ++r) {
        if (prep)
            prep(arg);
        double t0 = now();
        run(arg);
        double t = now() - t0;
        if (t < best)
            best = t;
    }
    return best;
}

/* ---- shared state of the benchmarks ---- */
typedef struct bench {
    size_t n;
    uint32_t *keys, *vals, *tmp_k, *tmp_v, *out;
    float *f, *fout;
    sluice_stream *s_in, *s_out, *s_out2, *s_keys, *s_vals, *s_flags;
    sluice_kernel *copy, *chain;
    sluice_stream *chain_a, *chain_b;
    float threshold;
    sluice_output_mode mode;
    uint32_t cells;
    volatile uint32_t sink;
} bench;

static const char *copy_src = "#include \"sluice.cl\"\n"
                              "__kernel void copy(SLUICE_PARAMS, global const uint *in,"
                              " global uint *out)\n"
                              "{\n"
                              "    SLUICE_FOR_EACH(i) out[i] = in[i];\n"
                              "}\n"
                              "__kernel void increment(SLUICE_PARAMS, global const uint *in,"
                              " global uint *out)\n"
                              "{\n"
                              "    SLUICE_FOR_EACH(i) out[i] = in[i] + 1u;\n"
                              "}\n";

static void run_copy(void *a)
{
    bench *b = a;
    TRY(sluice_kernel_launch(b->copy));
}

static void run_scan(void *a)
{
    bench *b = a;
    TRY(sluice_scan(ctx, b->s_in, b->s_out, SLUICE_U32, 0, NULL));
}

static void c_scan(void *a)
{
    bench *b = a;
    uint32_t s = 0;
    for (size_t i = 0; i < b->n; ++i) {
        uint32_t x = b->keys[i];
        b->out[i] = s;
        s += x;
    }
}

static void run_reduce(void *a)
{
    bench *b = a;
    uint32_t r;
    TRY(sluice_reduce(ctx, b->s_in, SLUICE_U32, SLUICE_SUM, &r));
    b->sink = r;
}

static void c_reduce(void *a)
{
    bench *b = a;
    uint32_t s = 0;
    for (size_t i = 0; i < b->n; ++i)
        s += b->keys[i];
    b->sink = s;
}

static void run_partition(void *a)
{
    bench *b = a;
    TRY(sluice_partition(ctx, b->s_in, SLUICE_F32, &b->threshold, b->s_out, b->s_out2, b->mode));
}

/* Branch-free C partition: write to both sides, advance one. */
static void c_partition(void *a)
{
    bench *b = a;
    size_t lo = 0, hi = 0;
    float t = b->threshold;
    float *below = b->fout, *above = (float *)b->tmp_k;
    for (size_t i = 0; i < b->n; ++i) {
        float x = b->f[i];
        int c = x < t;
        below[lo] = x;
        above[hi] = x;
        lo += (size_t)c;
        hi += (size_t)!c;
    }
    b->sink = (uint32_t)lo;
}

static void run_compact(void *a)
{
    bench *b = a;
    TRY(sluice_compact(ctx, b->s_in, b->s_flags, b->s_out, b->mode));
}

static void c_compact(void *a)
{
    bench *b = a;
    size_t k = 0;
    for (size_t i = 0; i < b->n; ++i) {
        b->out[k] = b->keys[i];
        k += b->vals[i] != 0;
    }
    b->sink = (uint32_t)k;
}

static void prep_sort(void *a)
{
    bench *b = a;
    TRY(sluice_stream_upload(b->s_keys, b->keys, b->n));
    TRY(sluice_stream_upload(b->s_vals, b->vals, b->n));
}

static void run_radix(void *a)
{
    bench *b = a;
    TRY(sluice_sort_radix(ctx, b->s_keys, b->s_vals));
}

static void run_bitonic(void *a)
{
    bench *b = a;
    TRY(sluice_sort_bitonic(ctx, b->s_keys, b->s_vals));
}

typedef struct kv {
    uint32_t k, v;
} kv;

static int cmp_kv(const void *x, const void *y)
{
    uint32_t a = ((const kv *)x)->k, b = ((const kv *)y)->k;
    return a < b ? -1 : a > b;
}

static void prep_c_sort(void *a)
{
    bench *b = a;
    kv *p = (kv *)b->tmp_k; /* tmp_k and tmp_v are one 2n array */
    for (size_t i = 0; i < b->n; ++i) {
        p[i].k = b->keys[i];
        p[i].v = b->vals[i];
    }
}

static void c_qsort(void *a)
{
    bench *b = a;
    qsort(b->tmp_k, b->n, sizeof(kv), cmp_kv);
}

/* Plain single-thread LSD radix sort of key-value pairs: 8-bit digits, four
 * stable counting passes (the textbook algorithm). */
static void c_radix(void *a)
{
    bench *b = a;
    kv *src = (kv *)b->tmp_k, *dst = malloc(b->n * sizeof(kv));
    if (!dst)
        exit(1);
    for (int shift = 0; shift < 32; shift += 8) {
        size_t count[257] = {0};
        for (size_t i = 0; i < b->n; ++i)
            count[((src[i].k >> shift) & 255u) + 1]++;
        for (int d = 0; d < 256; ++d)
            count[d + 1] += count[d];
        for (size_t i = 0; i < b->n; ++i)
            dst[count[(src[i].k >> shift) & 255u]++] = src[i];
        kv *t = src;
        src = dst;
        dst = t;
    }
    /* After four passes the result is back in the original array. */
    free(dst);
}

static void run_cell_search(void *a)
{
    bench *b = a;
    TRY(sluice_cell_index_search(ctx, b->s_keys, b->cells, b->s_out));
}

static void run_cell_count(void *a)
{
    bench *b = a;
    TRY(sluice_cell_index_count(ctx, b->s_keys, b->cells, b->s_out));
}

static void c_cell_count(void *a)
{
    bench *b = a;
    memset(b->out, 0, (b->cells + 1) * sizeof *b->out);
    for (size_t i = 0; i < b->n; ++i)
        if (b->tmp_v[i] < b->cells)
            b->out[b->tmp_v[i] + 1]++;
    for (uint32_t c = 0; c < b->cells; ++c)
        b->out[c + 1] += b->out[c];
}

static void run_route(void *a)
{
    bench *b = a;
    TRY(sluice_route_bounded(ctx, b->s_keys, b->s_vals, b->cells, 8, b->s_out, b->s_out2,
                             b->s_flags));
}

static void c_route(void *a)
{
    bench *b = a;
    uint32_t *fill = b->tmp_k, *slots = b->out;
    memset(fill, 0, b->cells * sizeof *fill);
    for (size_t i = 0; i < b->n; ++i) {
        uint32_t k = b->keys[i] % b->cells, f = fill[k]++;
        if (f < 8)
            slots[(size_t)k * 8 + f] = b->vals[i];
    }
}

static void run_chain(void *a)
{
    bench *b = a;
    for (int i = 0; i < 100; ++i) {
        TRY(sluice_kernel_set_input(b->chain, 0, i % 2 ? b->chain_b : b->chain_a));
        TRY(sluice_kernel_set_stream(b->chain, 1, i % 2 ? b->chain_a : b->chain_b, 1));
        TRY(sluice_kernel_launch(b->chain));
    }
}

static void usage(FILE *f)
{
    fprintf(f, "usage: bench_streams [--n N] [--reps R] [--out FILE] [--skip-bitonic]\n"
               "Measures every stream primitive on N records (default 2^24) against a copy\n"
               "kernel (the bandwidth bound) and plain single-thread C, and writes JSON.\n");
}

int main(int argc, char **argv)
{
    size_t n = (size_t)1 << 24;
    const char *out_path = "bench/results/streams.json";
    int skip_bitonic = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--n") && i + 1 < argc) {
            n = strtoull(argv[++i], NULL, 0);
        } else if (!strcmp(argv[i], "--reps") && i + 1 < argc) {
            reps = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--out") && i + 1 < argc) {
            out_path = argv[++i];
        } else if (!strcmp(argv[i], "--skip-bitonic")) {
            skip_bitonic = 1;
        } else if (!strcmp(argv[i], "--help")) {
            usage(stdout);
            return 0;
        } else {
            usage(stderr);
            return 2;
        }
    }
    if (n < 1024 || reps < 1) {
        fprintf(stderr, "bench_streams: need --n >= 1024 and --reps >= 1\n");
        return 2;
    }
    char err[512];
    if (sluice_context_create(NULL, &ctx, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "bench_streams: %s\n", err);
        return 1;
    }
    sluice_device_info info;
    sluice_context_device(ctx, &info);
    bench_machine mach;
    bench_machine_probe(ctx, &mach);
    fprintf(stderr,
            "device: %s, n = %zu, best of %d runs\nCPU: %s (%s), kernels' block emission: %s\n",
            info.name, n, reps, mach.cpu, mach.isa, mach.block);

    bench b = {0};
    b.n = n;
    b.cells = (uint32_t)(n / 16);
    b.keys = malloc(n * 4);
    b.vals = malloc(n * 4);
    b.tmp_k = malloc(n * 8); /* also holds n key-value pairs */
    b.tmp_v = malloc(n * 4);
    b.out = malloc((n + 1) * 8);
    b.f = malloc(n * 4);
    b.fout = malloc(n * 4);
    if (!b.keys || !b.vals || !b.tmp_k || !b.tmp_v || !b.out || !b.f || !b.fout) {
        fprintf(stderr, "bench_streams: out of host memory\n");
        return 1;
    }
    uint32_t seed = 0x9e3779b9u;
    for (size_t i = 0; i < n; ++i) {
        b.keys[i] = xorshift(&seed);
        b.vals[i] = (uint32_t)i;
        b.f[i] = (float)(xorshift(&seed) >> 8) / 16777216.0f;
    }
    b.threshold = 0.5f;
    size_t cap = (size_t)b.cells * 8 > n ? (size_t)b.cells * 8 : n;
    TRY(sluice_stream_create(ctx, 4, n, &b.s_in));
    TRY(sluice_stream_create(ctx, 4, cap + 1, &b.s_out));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_out2));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_keys));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_vals));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_flags));
    sluice_program *prog;
    TRY(sluice_program_create_source(ctx, "bench_copy.cl", copy_src, NULL, &prog));
    TRY(sluice_kernel_create(prog, "copy", &b.copy));
    TRY(sluice_kernel_create(prog, "increment", &b.chain));

    result res[16];
    int nr = 0;
    /* (a) the bound: copy n uint32 */
    TRY(sluice_stream_upload(b.s_in, b.keys, n));
    TRY(sluice_kernel_set_input(b.copy, 0, b.s_in));
    TRY(sluice_kernel_set_stream(b.copy, 1, b.s_out2, 1));
    double t_copy = best_of(NULL, run_copy, &b, reps);
    double copy_gbs = 8.0 * (double)n / t_copy / 1e9;
    fprintf(stderr, "copy: %.2f GB/s\n", copy_gbs);

    res[nr++] = (result){"scan_u32_exclusive",
                         (double)n,
                         8.0 * (double)n,
                         best_of(NULL, run_scan, &b, reps),
                         best_of_c(NULL, c_scan, &b, reps),
                         "serial loop",
                         -1};
    res[nr++] = (result){"reduce_u32_sum",
                         (double)n,
                         4.0 * (double)n,
                         best_of(NULL, run_reduce, &b, reps),
                         best_of_c(NULL, c_reduce, &b, reps),
                         "serial loop",
                         -1};
    TRY(sluice_stream_upload(b.s_in, b.f, n));
    for (int m = 0; m < 2; ++m) {
        b.mode = m ? SLUICE_UNORDERED : SLUICE_ORDERED;
        double t = best_of(NULL, run_partition, &b, reps);
        res[nr++] = (result){m ? "split_f32_unordered" : "split_f32_ordered",
                             (double)n,
                             8.0 * (double)n,
                             t,
                             best_of_c(NULL, c_partition, &b, reps),
                             "branch-free serial loop",
                             (double)sluice_context_scratch_bytes(ctx)};
    }
    /* Compaction keeping half the records, flags given as a uint32 stream. */
    for (size_t i = 0; i < n; ++i)
        b.vals[i] = b.keys[i] & 1u;
    TRY(sluice_stream_upload(b.s_in, b.keys, n));
    TRY(sluice_stream_upload(b.s_flags, b.vals, n));
    for (int m = 0; m < 2; ++m) {
        b.mode = m ? SLUICE_UNORDERED : SLUICE_ORDERED;
        double t = best_of(NULL, run_compact, &b, reps);
        res[nr++] = (result){m ? "compact_unordered" : "compact_ordered",
                             (double)n,
                             10.0 * (double)n,
                             t,
                             best_of_c(NULL, c_compact, &b, reps),
                             "branch-free serial loop",
                             (double)sluice_context_scratch_bytes(ctx)};
    }
    for (size_t i = 0; i < n; ++i)
        b.vals[i] = (uint32_t)i;
    /* Sorts of n key-value pairs. */
    int sort_reps = reps < 3 ? reps : 3;
    double t_radix = best_of(prep_sort, run_radix, &b, sort_reps);
    double t_qsort = best_of_c(prep_c_sort, c_qsort, &b, 1);
    double t_cradix = best_of_c(prep_c_sort, c_radix, &b, sort_reps);
    res[nr++] = (result){"sort_radix_kv",
                         (double)n,
                         16.0 * (double)n,
                         t_radix,
                         t_cradix,
                         "single-thread LSD radix sort",
                         -1};
    int i_radix = nr - 1;
    double t_bitonic = 0;
    if (!skip_bitonic) {
        t_bitonic = best_of(prep_sort, run_bitonic, &b, 1);
        res[nr++] = (result){"sort_bitonic_kv", (double)n, 16.0 * (double)n, t_bitonic, t_qsort,
                             "qsort",           -1};
    }
    /* Cell index of n sorted keys into n/16 cells. */
    for (size_t i = 0; i < n; ++i)
        b.tmp_v[i] = (uint32_t)((uint64_t)i * b.cells / n);
    TRY(sluice_stream_upload(b.s_keys, b.tmp_v, n));
    res[nr++] = (result){"cell_index_search",
                         (double)n,
                         4.0 * (double)n + 4.0 * b.cells,
                         best_of(NULL, run_cell_search, &b, reps),
                         best_of_c(NULL, c_cell_count, &b, reps),
                         "serial counting",
                         -1};
    res[nr++] = (result){"cell_index_count",
                         (double)n,
                         4.0 * (double)n + 4.0 * b.cells,
                         best_of(NULL, run_cell_count, &b, reps),
                         best_of_c(NULL, c_cell_count, &b, reps),
                         "serial counting",
                         -1};
    /* Bounded routing of n payloads into n/16 buckets of 8 slots. */
    for (size_t i = 0; i < n; ++i)
        b.tmp_v[i] = b.keys[i] % b.cells;
    TRY(sluice_stream_upload(b.s_keys, b.tmp_v, n));
    TRY(sluice_stream_upload(b.s_vals, b.vals, n));
    TRY(sluice_stream_grow(b.s_out2, b.cells));
    TRY(sluice_stream_grow(b.s_flags, b.cells));
    res[nr++] = (result){"route_bounded_8",
                         (double)n,
                         8.0 * (double)n,
                         best_of(NULL, run_route, &b, reps),
                         best_of_c(NULL, c_route, &b, reps),
                         "serial loop",
                         -1};
    /* Launch overhead: 100 dependent launches over 1024 records. */
    TRY(sluice_stream_create(ctx, 4, 1024, &b.chain_a));
    TRY(sluice_stream_create(ctx, 4, 1024, &b.chain_b));
    TRY(sluice_stream_upload(b.chain_a, b.keys, 1024));
    double t_chain = best_of(NULL, run_chain, &b, reps);
    uint32_t check[1024];
    TRY(sluice_stream_download(b.chain_a, check, 1024, NULL));
    if (check[0] != b.keys[0] + 100u * (uint32_t)(reps + 1)) {
        fprintf(stderr, "bench_streams: the launch chain computed a wrong result\n");
        return 1;
    }

    /* Report. */
    FILE *f = fopen(out_path, "w");
    if (!f) {
        fprintf(stderr, "bench_streams: cannot write %s\n", out_path);
        return 1;
    }
    fprintf(f,
            "{\n  \"device\": \"%s\",\n  \"cpu\": \"%s\",\n  \"cpu_isa\": \"%s\",\n  "
            "\"kernel_block_path\": \"%s\",\n  \"records\": %zu,\n  \"runs\": %d,\n",
            info.name, mach.cpu, mach.isa, mach.block, n, reps);
    fprintf(f, "  \"copy_gb_per_s\": %.3f,\n  \"primitives\": [\n", copy_gbs);
    printf("%-22s %12s %10s %9s %10s %12s\n", "primitive", "Mrecords/s", "GB/s", "of copy", "vs C",
           "scratch %");
    for (int i = 0; i < nr; ++i) {
        const result *r = &res[i];
        double gbs = r->bytes / r->seconds / 1e9;
        double scratch_pct = r->scratch_bytes / (4.0 * (double)n) * 100.0;
        char scratch[32] = "-";
        if (r->scratch_bytes >= 0)
            snprintf(scratch, sizeof scratch, "%.3f%%", scratch_pct);
        printf("%-22s %12.1f %10.2f %8.0f%% %9.2fx %12s\n", r->name, r->records / r->seconds / 1e6,
               gbs, 100.0 * gbs / copy_gbs, r->c_seconds / r->seconds, scratch);
        char scratch_json[64] = "null";
        if (r->scratch_bytes >= 0)
            snprintf(scratch_json, sizeof scratch_json, "%.0f", r->scratch_bytes);
        fprintf(f,
                "    {\"name\": \"%s\", \"seconds\": %.6f, \"records_per_s\": %.1f, "
                "\"gb_per_s\": %.3f, \"fraction_of_copy\": %.3f, \"c_peer\": \"%s\", "
                "\"c_seconds\": %.6f, \"speedup_vs_c\": %.3f, \"scratch_bytes\": %s}%s\n",
                r->name, r->seconds, r->records / r->seconds, gbs, gbs / copy_gbs, r->c_name,
                r->c_seconds, r->c_seconds / r->seconds, scratch_json, i + 1 < nr ? "," : "");
    }
    double per_launch_us = t_chain / 100.0 * 1e6;
    printf(
        "qsort of %zu pairs: %.3f s; radix sort is %.1fx faster than qsort, %.2fx than C radix\n",
        n, t_qsort, t_qsort / t_radix, t_cradix / t_radix);
    printf("chain of 100 dependent launches: %.2f us per launch\n", per_launch_us);
    fprintf(f, "  ],\n  \"qsort_seconds\": %.6f,\n", t_qsort);
    fprintf(f, "  \"launch_chain_us_per_launch\": %.3f,\n", per_launch_us);
    fprintf(f, "  \"targets\": {\n");
    const result *sp_o = &res[2], *sp_u = &res[3], *scan = &res[0];
    double frac_o = sp_o->bytes / sp_o->seconds / 1e9 / copy_gbs;
    double frac_u = sp_u->bytes / sp_u->seconds / 1e9 / copy_gbs;
    double frac_s = scan->bytes / scan->seconds / 1e9 / copy_gbs;
    fprintf(f, "    \"split_ordered_ge_50pct_copy\": %s,\n", frac_o >= 0.5 ? "true" : "false");
    fprintf(f, "    \"split_unordered_ge_50pct_copy\": %s,\n", frac_u >= 0.5 ? "true" : "false");
    fprintf(f, "    \"scan_ge_50pct_copy\": %s,\n", frac_s >= 0.5 ? "true" : "false");
    fprintf(f, "    \"radix_ge_5x_qsort\": %s,\n", t_qsort / t_radix >= 5 ? "true" : "false");
    fprintf(f, "    \"radix_ge_1.5x_c_radix\": %s,\n",
            t_cradix / res[i_radix].seconds >= 1.5 ? "true" : "false");
    fprintf(f, "    \"launch_le_10us\": %s,\n", per_launch_us <= 10 ? "true" : "false");
    fprintf(f, "    \"split_scratch_le_1pct\": %s\n",
            res[2].scratch_bytes <= 0.01 * 4.0 * (double)n ? "true" : "false");
    fprintf(f, "  }\n}\n");
    fclose(f);
    (void)t_bitonic;

    sluice_kernel_destroy(b.copy);
    sluice_kernel_destroy(b.chain);
    sluice_program_destroy(prog);
    sluice_stream *all[] = {b.s_in,   b.s_out,   b.s_out2,  b.s_keys,
                            b.s_vals, b.s_flags, b.chain_a, b.chain_b};
    for (size_t i = 0; i < sizeof all / sizeof *all; ++i)
        sluice_stream_destroy(all[i]);
    sluice_context_destroy(ctx);
    free(b.keys);
    free(b.vals);
    free(b.tmp_k);
    free(b.tmp_v);
    free(b.out);
    free(b.f);
    free(b.fout);
    return 0;
}
