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
 * implementation actually causes. The splits send half the records each way
 * (uniform values against 0.5), and once more every record one way
 * (split_f32_one_way, ordered): an output that takes nothing must cost
 * nothing.
 */
#include "bench_machine.h"
#include "sluice/sluice.h"
#include "sluice/streams.h"

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
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
    double own_copy_s;    /* the best of the copies timed just before its runs */
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

/* The bound, measured all through the run: before every timed run of a
 * primitive, one timed copy of n records (copy_run, set once the copy kernels
 * exist), by the copy kernels in turn, one record or 16 records per step
 * (neither is faster every time on a CPU), and on GPUs also 16-byte records;
 * copy_best and copy_worst keep the best and the worst time, copy_kbest each
 * kernel's best. The
 * streams fit in a large L3 cache, so the copy's bandwidth moves from one
 * moment to the next (20 to 38 GB/s in one hour on a 2-core Xeon); a copy
 * timed once at the start made the "of copy" ratios a matter of when it ran.
 * Interleaved, both sides see the same machine, and the bound is the best
 * copy of the whole run. */
typedef void (*bench_fn)(void *arg);
static bench_fn copy_run;
static double copy_best = 1e30, copy_worst = 0.0, copy_kbest[3] = {1e30, 1e30, 1e30};
static int copy_runs;
static unsigned copy_last; /* the copy kernel copy_run took last */

static double timed(bench_fn run, void *arg)
{
    TRY(sluice_context_finish(ctx));
    double t0 = now();
    run(arg);
    TRY(sluice_context_finish(ctx));
    return now() - t0;
}

/* One timed run of `run`, drained by a finish, preceded by a timed copy
 * (above; not counted when warm_up is set; its time in *copy_t where
 * copy_t is not NULL) and by `prep` (may be NULL), untimed. */
static double copied_run(bench_fn prep, bench_fn run, void *arg, int warm_up, double *copy_t)
{
    if (copy_run) {
        double tc = timed(copy_run, arg);
        if (copy_t)
            *copy_t = tc;
        if (!warm_up) {
            copy_best = tc < copy_best ? tc : copy_best;
            copy_worst = tc > copy_worst ? tc : copy_worst;
            copy_kbest[copy_last] = tc < copy_kbest[copy_last] ? tc : copy_kbest[copy_last];
            ++copy_runs;
        }
    }
    if (prep)
        prep(arg);
    return timed(run, arg);
}

/* Best time of `n_reps` runs of `run` after one warm-up (copied_run). */
static double best_of(bench_fn prep, bench_fn run, void *arg, int n_reps)
{
    double best = 1e30;
    for (int r = 0; r <= n_reps; ++r) {
        double t = copied_run(prep, run, arg, r == 0, NULL);
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
    uint32_t *keys, *vals, *tmp_k, *out;
    uint32_t *flags, *cellk; /* compaction's flags; sorted cell keys */
    float *f, *fout;
    sluice_stream *s_in, *s_out, *s_out2, *s_keys, *s_vals, *s_flags;
    sluice_stream *s_fin, *s_cells, *s_route, *s_over; /* float records, cell keys,
                                                          bucket keys, overflow counts */
    sluice_stream *copy_in, *copy_out; /* the copy's own: it warms no primitive's data */
    sluice_kernel *copy[3], *chain;    /* copy: per record, 16 per step, 4 per record */
    unsigned copy_turn, copy_kernels;  /* taken in turn: 2, or 3 in the GPU layout */
    sluice_stream *chain_a, *chain_b;
    sluice_counters *trip; /* the round trip's counters */
    int trip_counters;     /* 1: the round trip resets and reads them */
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
                              "__kernel void copy16(SLUICE_PARAMS, global const uint *in,"
                              " global uint *out)\n"
                              "{\n"
                              "    SLUICE_FOR_EACH_RANGE(b, e) {\n"
                              "        uint i = b;\n"
                              "        for (; i + 16u <= e; i += 16u)\n"
                              "            *(global sluice_uint16_unaligned_ *)(out + i) =\n"
                              "                SLUICE_LOAD16(in + i);\n"
                              "        for (; i < e; ++i)\n"
                              "            out[i] = in[i];\n"
                              "    }\n"
                              "}\n"
                              "__kernel void copy4(SLUICE_PARAMS, global const uint4 *in,"
                              " global uint4 *out)\n"
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
    copy_last = b->copy_turn++ % b->copy_kernels;
    sluice_kernel *k = b->copy[copy_last];
    if (k == b->copy[2])
        TRY(sluice_kernel_launch_count(k, b->n / 4));
    else
        TRY(sluice_kernel_launch(k));
}

/* The OpenCL implementation's own copy of the same streams
 * (clEnqueueCopyBuffer), for the record beside the copy kernels. */
static void run_vendor_copy(void *a)
{
    bench *b = a;
    cl_int err = clEnqueueCopyBuffer(
        (cl_command_queue)sluice_context_cl_queue(ctx), (cl_mem)sluice_stream_cl_mem(b->copy_in),
        (cl_mem)sluice_stream_cl_mem(b->copy_out), 0, 0, b->n * 4, 0, NULL, NULL);
    if (err != CL_SUCCESS) {
        fprintf(stderr, "bench_streams: clEnqueueCopyBuffer failed (%d)\n", (int)err);
        exit(1);
    }
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

/* The splits' threshold: half the records (uniform in [0, 1)) go each way;
 * 2 sends all of them below, leaving the other output empty. */
static void set_ordered(void *a)
{
    ((bench *)a)->mode = SLUICE_ORDERED;
    ((bench *)a)->threshold = 0.5f;
}

static void set_unordered(void *a)
{
    ((bench *)a)->mode = SLUICE_UNORDERED;
    ((bench *)a)->threshold = 0.5f;
}

static void set_ordered_one_way(void *a)
{
    ((bench *)a)->mode = SLUICE_ORDERED;
    ((bench *)a)->threshold = 2.0f;
}

static void run_partition(void *a)
{
    bench *b = a;
    TRY(sluice_partition(ctx, b->s_fin, SLUICE_F32, &b->threshold, b->s_out, b->s_out2, b->mode));
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
        k += b->flags[i] != 0;
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
    kv *p = (kv *)b->tmp_k; /* n key-value pairs */
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
    /* Ping-pongs with b->out (room for n pairs), kept between runs as the
     * device sort's scratch is. */
    kv *src = (kv *)b->tmp_k, *dst = (kv *)b->out;
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
}

static void run_cell_search(void *a)
{
    bench *b = a;
    TRY(sluice_cell_index_search(ctx, b->s_cells, b->cells, b->s_out));
}

static void run_cell_count(void *a)
{
    bench *b = a;
    TRY(sluice_cell_index_count(ctx, b->s_cells, b->cells, b->s_out));
}

static void c_cell_count(void *a)
{
    bench *b = a;
    memset(b->out, 0, (b->cells + 1) * sizeof *b->out);
    for (size_t i = 0; i < b->n; ++i)
        if (b->cellk[i] < b->cells)
            b->out[b->cellk[i] + 1]++;
    for (uint32_t c = 0; c < b->cells; ++c)
        b->out[c + 1] += b->out[c];
}

static void run_route(void *a)
{
    bench *b = a;
    TRY(sluice_route_bounded(ctx, b->s_route, b->s_vals, b->cells, 8, b->s_out, b->s_out2,
                             b->s_over));
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

/* 100 frames of the smallest round trips a renderer makes: one launch and
 * a wait for it (trip_counters 0), a counters reset, one launch and the
 * counters read back (blocking; 1), or one launch and the counters read and
 * restarted (sluice_counters_read_restart, no reset command; 2: a fused
 * frame's commands now). Against the chain above, what waiting for the
 * device, and a reset and a read, add to a frame. */
static void run_round_trip(void *a)
{
    bench *b = a;
    uint32_t c;
    for (int i = 0; i < 100; ++i) {
        if (b->trip_counters == 1)
            TRY(sluice_counters_reset(b->trip));
        TRY(sluice_kernel_set_input(b->chain, 0, i % 2 ? b->chain_b : b->chain_a));
        TRY(sluice_kernel_set_stream(b->chain, 1, i % 2 ? b->chain_a : b->chain_b, 1));
        TRY(sluice_kernel_launch(b->chain));
        if (b->trip_counters == 1)
            TRY(sluice_counters_read(b->trip, &c));
        else if (b->trip_counters == 2)
            TRY(sluice_counters_read_restart(b->trip, &c));
        else
            TRY(sluice_context_finish(ctx));
    }
}

static void usage(FILE *f)
{
    fprintf(f, "usage: bench_streams [--n N] [--reps R] [--out FILE] [--skip-bitonic]\n"
               "Measures every stream primitive on N records (default 2^24) against a copy\n"
               "kernel (the bandwidth bound, timed before every run of a primitive) and plain\n"
               "single-thread C. Prints a table; --out FILE also writes it as JSON.\n");
}

int main(int argc, char **argv)
{
    size_t n = (size_t)1 << 24;
    const char *out_path = NULL;
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
    /* Opened first, so that a path that cannot be written fails before the
     * minutes of measuring; without --out the JSON goes to a scratch file. */
    FILE *f = out_path ? fopen(out_path, "w") : tmpfile();
    if (!f) {
        fprintf(stderr, "bench_streams: cannot write %s\n",
                out_path ? out_path : "a temporary file");
        return 1;
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
            "device: %s, n = %zu, best of %d interleaved rounds\nCPU: %s (%s), kernels' block "
            "emission: %s\n",
            info.name, n, reps, mach.cpu, mach.isa, mach.block);

    bench b = {0};
    b.n = n;
    b.cells = (uint32_t)(n / 16);
    b.keys = malloc(n * 4);
    b.vals = malloc(n * 4);
    b.tmp_k = malloc(n * 8); /* also holds n key-value pairs */
    b.flags = malloc(n * 4);
    b.cellk = malloc(n * 4);
    b.out = malloc((n + 1) * 8);
    b.f = malloc(n * 4);
    b.fout = malloc(n * 4);
    if (!b.keys || !b.vals || !b.tmp_k || !b.flags || !b.cellk || !b.out || !b.f || !b.fout) {
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
    TRY(sluice_stream_create(ctx, 4, n, &b.copy_in));
    TRY(sluice_stream_create(ctx, 4, n, &b.copy_out));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_keys));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_vals));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_flags));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_fin));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_cells));
    TRY(sluice_stream_create(ctx, 4, n, &b.s_route));
    TRY(sluice_stream_create(ctx, 4, b.cells, &b.s_over));
    sluice_program *prog;
    TRY(sluice_program_create_source(ctx, "bench_copy.cl", copy_src, NULL, &prog));
    TRY(sluice_kernel_create(prog, "copy", &b.copy[0]));
    TRY(sluice_kernel_create(prog, "copy16", &b.copy[1]));
    TRY(sluice_kernel_create(prog, "copy4", &b.copy[2]));
    TRY(sluice_kernel_create(prog, "increment", &b.chain));

    /* The device side: every primitive has its own input streams, filled
     * once, so that the rounds below can take the primitives in turn. */
    for (size_t i = 0; i < n; ++i) {
        b.flags[i] = b.keys[i] & 1u;                        /* compaction keeps half */
        b.cellk[i] = (uint32_t)((uint64_t)i * b.cells / n); /* n/16 cells, sorted */
        b.out[i] = b.keys[i] % b.cells;                     /* n/16 buckets of 8 slots */
    }
    TRY(sluice_stream_upload(b.copy_in, b.keys, n));
    TRY(sluice_stream_upload(b.s_in, b.keys, n));
    TRY(sluice_stream_upload(b.s_fin, b.f, n));
    TRY(sluice_stream_upload(b.s_flags, b.flags, n));
    TRY(sluice_stream_upload(b.s_cells, b.cellk, n));
    TRY(sluice_stream_upload(b.s_route, b.out, n));
    TRY(sluice_stream_upload(b.s_vals, b.vals, n));
    for (int k = 0; k < 2; ++k) {
        TRY(sluice_kernel_set_input(b.copy[k], 0, b.copy_in));
        TRY(sluice_kernel_set_stream(b.copy[k], 1, b.copy_out, 1));
    }
    /* On devices other than CPUs (the GPU layout) also 16-byte records, n/4 of them: a GPU's
     * work-item keeps one load in flight per record, and 4-byte records one
     * at a time leave its memory half idle (bench/README.md). On a CPU the
     * 16-per-step kernel is the vector copy. */
    b.copy_kernels = info.is_cpu || n % 4 ? 2 : 3;
    TRY(sluice_kernel_set_stream(b.copy[2], 0, b.copy_in, 0));
    TRY(sluice_kernel_set_stream(b.copy[2], 1, b.copy_out, 0));
    copy_run = run_copy;

    typedef struct primitive {
        const char *name;
        double bytes; /* effective bytes per run */
        bench_fn prep, run, c_prep, c_run;
        const char *c_name;
        int rounds;           /* of `reps` (the sorts take fewer) */
        int scratch;          /* record the context's scratch after it */
        bench_fn mode_setter; /* NULL, or sets b.mode before prep */
    } primitive;
    double dn = (double)n;
    int sort_reps = reps < 3 ? reps : 3;
    primitive prims[] = {
        {"scan_u32_exclusive", 8 * dn, NULL, run_scan, NULL, c_scan, "serial loop", reps, 0, NULL},
        {"reduce_u32_sum", 4 * dn, NULL, run_reduce, NULL, c_reduce, "serial loop", reps, 0, NULL},
        {"split_f32_ordered", 8 * dn, NULL, run_partition, NULL, c_partition,
         "branch-free serial loop", reps, 1, set_ordered},
        {"split_f32_unordered", 8 * dn, NULL, run_partition, NULL, c_partition,
         "branch-free serial loop", reps, 1, set_unordered},
        {"split_f32_one_way", 8 * dn, NULL, run_partition, NULL, c_partition,
         "branch-free serial loop", reps, 1, set_ordered_one_way},
        {"compact_ordered", 10 * dn, NULL, run_compact, NULL, c_compact, "branch-free serial loop",
         reps, 1, set_ordered},
        {"compact_unordered", 10 * dn, NULL, run_compact, NULL, c_compact,
         "branch-free serial loop", reps, 1, set_unordered},
        {"sort_radix_kv", 16 * dn, prep_sort, run_radix, prep_c_sort, c_radix,
         "single-thread LSD radix sort", sort_reps, 0, NULL},
        {"sort_bitonic_kv", 16 * dn, prep_sort, run_bitonic, prep_c_sort, c_qsort, "qsort", 1, 0,
         NULL},
        {"cell_index_search", 4 * dn + 4.0 * b.cells, NULL, run_cell_search, NULL, c_cell_count,
         "serial counting", reps, 0, NULL},
        {"cell_index_count", 4 * dn + 4.0 * b.cells, NULL, run_cell_count, NULL, c_cell_count,
         "serial counting", reps, 0, NULL},
        {"route_bounded_8", 8 * dn, NULL, run_route, NULL, c_route, "serial loop", reps, 0, NULL},
    };
    enum { n_prims = sizeof prims / sizeof *prims, i_radix = 7, i_bitonic = 8 };
    int active[n_prims];
    for (int i = 0; i < n_prims; ++i)
        active[i] = !(skip_bitonic && i == i_bitonic);

    /* Rounds: each takes every primitive once, each run preceded by a timed
     * copy (the bound, best_of's comment), so that a stretch of noise on a
     * shared machine costs one round of every primitive rather than all the
     * runs of one. A primitive's first run is a warm-up (its kernels' first
     * launch, its scratch). The best run of each is kept. */
    double best[n_prims], scratch[n_prims], own_copy[n_prims];
    for (int i = 0; i < n_prims; ++i)
        best[i] = 1e30, scratch[i] = -1, own_copy[i] = 1e30;
    for (int r = 0; r <= reps; ++r) {
        for (int i = 0; i < n_prims; ++i) {
            if (!active[i] || r > prims[i].rounds)
                continue;
            if (prims[i].mode_setter)
                prims[i].mode_setter(&b);
            double tc = 1e30;
            double t = copied_run(prims[i].prep, prims[i].run, &b, r == 0, &tc);
            if (r > 0 && t < best[i])
                best[i] = t;
            if (r > 0 && tc < own_copy[i])
                own_copy[i] = tc;
            if (prims[i].scratch && r == 0) /* before the sorts take theirs */
                scratch[i] = (double)sluice_context_scratch_bytes(ctx);
        }
    }
    /* The C peers, on the host, after the device's rounds. */
    result res[n_prims];
    int nr = 0;
    double t_qsort = 0, t_cradix = 0;
    for (int i = 0; i < n_prims; ++i) {
        if (!active[i] && i != i_bitonic)
            continue;
        if (prims[i].mode_setter)
            prims[i].mode_setter(&b);
        double tc =
            best_of_c(prims[i].c_prep, prims[i].c_run, &b, i == i_bitonic ? 1 : prims[i].rounds);
        if (i == i_radix)
            t_cradix = tc;
        if (i == i_bitonic) {
            t_qsort = tc;
            if (!active[i])
                continue;
        }
        res[nr++] = (result){prims[i].name,   dn,         prims[i].bytes, best[i], tc,
                             prims[i].c_name, scratch[i], own_copy[i]};
    }
    double t_radix = best[i_radix];
    /* Launch overhead: 100 dependent launches over 1024 records. */
    TRY(sluice_stream_create(ctx, 4, 1024, &b.chain_a));
    TRY(sluice_stream_create(ctx, 4, 1024, &b.chain_b));
    TRY(sluice_stream_upload(b.chain_a, b.keys, 1024));
    copy_run = NULL; /* the chain's small streams stay in cache, as in a renderer */
    double t_vendor = best_of(NULL, run_vendor_copy, &b, reps);
    double t_chain = best_of(NULL, run_chain, &b, reps);
    const char *trip_name[] = {"trip"};
    TRY(sluice_counters_create(ctx, 1, trip_name, &b.trip));
    b.trip_counters = 0;
    double t_sync = best_of(NULL, run_round_trip, &b, reps);
    b.trip_counters = 1;
    double t_trip = best_of(NULL, run_round_trip, &b, reps);
    b.trip_counters = 2;
    double t_restart = best_of(NULL, run_round_trip, &b, reps);
    uint32_t check[1024];
    TRY(sluice_stream_download(b.chain_a, check, 1024, NULL));
    if (check[0] != b.keys[0] + 400u * (uint32_t)(reps + 1)) {
        fprintf(stderr, "bench_streams: the launch chain computed a wrong result\n");
        return 1;
    }

    /* Report. With SLUICE_PROFILE=1, the kernels' times first (every run,
     * the copies and warm-ups included). */
    if (sluice_profile_enabled(ctx))
        TRY(sluice_profile_print(ctx, stdout));
    double copy_gbs = 8.0 * (double)n / copy_best / 1e9;
    double copy_gbs_worst = 8.0 * (double)n / copy_worst / 1e9;
    printf("copy: %.2f GB/s (best of %d runs of %u copy kernels, interleaved with the primitives' "
           "runs; worst %.2f GB/s)\n",
           copy_gbs, copy_runs, b.copy_kernels, copy_gbs_worst);
    double kgbs[3];
    for (unsigned k = 0; k < 3; ++k)
        kgbs[k] = k < b.copy_kernels ? 8.0 * (double)n / copy_kbest[k] / 1e9 : 0.0;
    printf("copy kernels: per record %.2f, 16 per step %.2f", kgbs[0], kgbs[1]);
    if (b.copy_kernels > 2)
        printf(", 16-byte records %.2f", kgbs[2]);
    printf(" GB/s\n");
    double vendor_gbs = 8.0 * (double)n / t_vendor / 1e9;
    printf("clEnqueueCopyBuffer: %.2f GB/s (the OpenCL implementation's own copy, best of %d)\n",
           vendor_gbs, reps);
    fprintf(f,
            "{\n  \"device\": \"%s\",\n  \"cpu\": \"%s\",\n  \"cpu_isa\": \"%s\",\n  "
            "\"kernel_block_path\": \"%s\",\n  \"records\": %zu,\n  \"runs\": %d,\n",
            info.name, mach.cpu, mach.isa, mach.block, n, reps);
    fprintf(f, "  \"copy_gb_per_s\": %.3f,\n  \"copy_gb_per_s_worst\": %.3f,\n", copy_gbs,
            copy_gbs_worst);
    fprintf(f, "  \"copy_runs\": %d,\n  \"copy_kernels_gb_per_s\": [%.3f, %.3f", copy_runs, kgbs[0],
            kgbs[1]);
    if (b.copy_kernels > 2)
        fprintf(f, ", %.3f", kgbs[2]);
    fprintf(f, "],\n");
    fprintf(f, "  \"cl_copy_buffer_gb_per_s\": %.3f,\n  \"primitives\": [\n", vendor_gbs);
    printf("%-22s %12s %10s %9s %9s %10s %12s\n", "primitive", "Mrecords/s", "GB/s", "of copy",
           "of own", "vs C", "scratch %");
    for (int i = 0; i < nr; ++i) {
        const result *r = &res[i];
        double gbs = r->bytes / r->seconds / 1e9;
        double scratch_pct = r->scratch_bytes / (4.0 * (double)n) * 100.0;
        char scratch[32] = "-";
        if (r->scratch_bytes >= 0)
            snprintf(scratch, sizeof scratch, "%.3f%%", scratch_pct);
        double own = gbs / (8.0 * (double)n / r->own_copy_s / 1e9);
        printf("%-22s %12.1f %10.2f %8.0f%% %8.0f%% %9.2fx %12s\n", r->name,
               r->records / r->seconds / 1e6, gbs, 100.0 * gbs / copy_gbs, 100.0 * own,
               r->c_seconds / r->seconds, scratch);
        char scratch_json[64] = "null";
        if (r->scratch_bytes >= 0)
            snprintf(scratch_json, sizeof scratch_json, "%.0f", r->scratch_bytes);
        fprintf(f,
                "    {\"name\": \"%s\", \"seconds\": %.6f, \"records_per_s\": %.1f, "
                "\"gb_per_s\": %.3f, \"fraction_of_copy\": %.3f, \"fraction_of_own_copies\": "
                "%.3f, \"c_peer\": \"%s\", "
                "\"c_seconds\": %.6f, \"speedup_vs_c\": %.3f, \"scratch_bytes\": %s}%s\n",
                r->name, r->seconds, r->records / r->seconds, gbs, gbs / copy_gbs, own, r->c_name,
                r->c_seconds, r->c_seconds / r->seconds, scratch_json, i + 1 < nr ? "," : "");
    }
    double per_launch_us = t_chain / 100.0 * 1e6;
    printf(
        "qsort of %zu pairs: %.3f s; radix sort is %.1fx faster than qsort, %.2fx than C radix\n",
        n, t_qsort, t_qsort / t_radix, t_cradix / t_radix);
    printf("chain of 100 dependent launches: %.2f us per launch\n", per_launch_us);
    double sync_us = t_sync / 100.0 * 1e6, trip_us = t_trip / 100.0 * 1e6,
           restart_us = t_restart / 100.0 * 1e6;
    printf("a launch and a wait for it: %.2f us; counters reset, a launch, the counters read: "
           "%.2f us; a launch, the counters read and restarted: %.2f us\n",
           sync_us, trip_us, restart_us);
    fprintf(f, "  ],\n  \"qsort_seconds\": %.6f,\n", t_qsort);
    fprintf(f, "  \"launch_chain_us_per_launch\": %.3f,\n", per_launch_us);
    fprintf(f, "  \"launch_and_wait_us\": %.3f,\n  \"round_trip_us\": %.3f,\n", sync_us, trip_us);
    fprintf(f, "  \"restart_trip_us\": %.3f,\n", restart_us);
    fprintf(f, "  \"targets\": {\n");
    const result *sp_o = &res[2], *sp_u = &res[3], *scan = &res[0];
    double frac_o = sp_o->bytes / sp_o->seconds / 1e9 / copy_gbs;
    double frac_u = sp_u->bytes / sp_u->seconds / 1e9 / copy_gbs;
    double frac_s = scan->bytes / scan->seconds / 1e9 / copy_gbs;
    fprintf(f, "    \"split_ordered_ge_50pct_copy\": %s,\n", frac_o >= 0.5 ? "true" : "false");
    fprintf(f, "    \"split_unordered_ge_50pct_copy\": %s,\n", frac_u >= 0.5 ? "true" : "false");
    const result *sp_1 = &res[4];
    double frac_1 = sp_1->bytes / sp_1->seconds / 1e9 / copy_gbs;
    fprintf(f, "    \"split_one_way_ge_50pct_copy\": %s,\n", frac_1 >= 0.5 ? "true" : "false");
    fprintf(f, "    \"scan_ge_50pct_copy\": %s,\n", frac_s >= 0.5 ? "true" : "false");
    fprintf(f, "    \"radix_ge_5x_qsort\": %s,\n", t_qsort / t_radix >= 5 ? "true" : "false");
    fprintf(f, "    \"radix_ge_1.5x_c_radix\": %s,\n",
            t_cradix / res[i_radix].seconds >= 1.5 ? "true" : "false");
    fprintf(f, "    \"launch_le_10us\": %s,\n", per_launch_us <= 10 ? "true" : "false");
    fprintf(f, "    \"split_scratch_le_1pct\": %s\n",
            res[2].scratch_bytes <= 0.01 * 4.0 * (double)n ? "true" : "false");
    fprintf(f, "  }\n}\n");
    fclose(f);

    sluice_kernel_destroy(b.copy[0]);
    sluice_kernel_destroy(b.copy[1]);
    sluice_kernel_destroy(b.copy[2]);
    sluice_kernel_destroy(b.chain);
    sluice_counters_destroy(b.trip);
    sluice_program_destroy(prog);
    sluice_stream *all[] = {b.s_in,    b.s_out,   b.s_out2,  b.s_keys,  b.s_vals,
                            b.s_flags, b.s_fin,   b.s_cells, b.s_route, b.s_over,
                            b.chain_a, b.chain_b, b.copy_in, b.copy_out};
    for (size_t i = 0; i < sizeof all / sizeof *all; ++i)
        sluice_stream_destroy(all[i]);
    sluice_context_destroy(ctx);
    free(b.keys);
    free(b.vals);
    free(b.tmp_k);
    free(b.flags);
    free(b.cellk);
    free(b.out);
    free(b.f);
    free(b.fout);
    return 0;
}
