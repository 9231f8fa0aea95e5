/*
 * split_sign: a complete Sluice program, meant to be copied.
 *
 * Generates N random floats in [-1, 1) (every 1000th one a NaN), splits them
 * with one kernel into three conditional output streams (negative, small,
 * large), counts the values close to zero and the values kept with two
 * counters, downloads everything, checks it against a plain C loop and prints
 * a short summary with the throughput.
 *
 * The kernel lives in split_sign.cl, loaded from disk at run time: from the
 * path given with --kernel, else found by find_kernel() below (next to the
 * program, in the installed data folder, or in the source tree).
 */
#include <sluice/sluice.h>

#include "data_path.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef EXAMPLE_KERNEL_DIR
#define EXAMPLE_KERNEL_DIR "."
#endif

#define THRESHOLD 0.5f /* small: 0 <= x < THRESHOLD, large: x >= THRESHOLD */
#define EPSILON 0.001f /* near zero: |x| < EPSILON */
#define NAN_EVERY 1000 /* record i is a NaN when i % NAN_EVERY == NAN_EVERY - 1 */

/* The three outputs: their slot in the kernel, their argument index (counted
 * after SLUICE_PARAMS) and how each one is written. */
enum { OUT_NEGATIVE, OUT_SMALL, OUT_LARGE, OUT_COUNT };
static const char *const out_names[OUT_COUNT] = {"negative", "small", "large"};
static const sluice_output_mode out_modes[OUT_COUNT] = {SLUICE_ORDERED, SLUICE_UNORDERED,
                                                        SLUICE_ORDERED};
enum { ARG_IN = 0, ARG_FIRST_OUT = 1, ARG_THRESHOLD = 4, ARG_EPSILON = 5 };
enum { CTR_NEAR_ZERO, CTR_KEPT, CTR_COUNT };

typedef struct options {
    size_t count;
    uint32_t seed;
    unsigned repeat;
    const char *kernel;
    const char *device;
    int profile;
} options;

static void usage(FILE *f)
{
    fprintf(f, "usage: sluice-example-split-sign [--count N] [--seed S] [--repeat R]\n"
               "                                 [--kernel PATH] [--device NAME] [--profile]\n"
               "                                 [--help]\n"
               "Splits N random floats into three streams (negative, small, large) with one\n"
               "Sluice kernel, checks the result against plain C and prints the throughput.\n"
               "  --count N      number of floats (default 1000000)\n"
               "  --seed S       seed of the random numbers (default 1)\n"
               "  --repeat R     launches to time; the best one is reported (default 3)\n"
               "  --kernel PATH  the kernel file (default: split_sign.cl next to the program,\n"
               "                 else in <datadir>/sluice/examples, else in the source tree)\n"
               "  --device NAME  OpenCL device whose \"platform / name\" contains NAME\n"
               "                 (default: SLUICE_DEVICE, else the first CPU device)\n"
               "  --profile      print the per-kernel profiling table\n");
}

/* Parses a non-negative decimal integer no larger than `max`. */
static int parse_size(const char *s, unsigned long long max, unsigned long long *out)
{
    if (!s || *s < '0' || *s > '9')
        return 0;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (errno || *end || v > max)
        return 0;
    *out = v;
    return 1;
}

/* Returns 0 on success, 2 on a usage error (message printed), 1 for --help. */
static int parse_args(int argc, char **argv, options *o)
{
    o->count = 1000000;
    o->seed = 1;
    o->repeat = 3;
    o->kernel = NULL; /* find_kernel() */
    o->device = NULL;
    o->profile = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        unsigned long long n;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return 1;
        } else if (strcmp(a, "--profile") == 0) {
            o->profile = 1;
            continue;
        } else if (strcmp(a, "--count") == 0) {
            if (!parse_size(v, UINT32_MAX - 1u, &n)) {
                fprintf(stderr, "split_sign: --count needs a number from 0 to %u\n",
                        UINT32_MAX - 1u);
                return 2;
            }
            o->count = (size_t)n;
        } else if (strcmp(a, "--seed") == 0) {
            if (!parse_size(v, UINT32_MAX, &n)) {
                fprintf(stderr, "split_sign: --seed needs a number from 0 to %u\n", UINT32_MAX);
                return 2;
            }
            o->seed = (uint32_t)n;
        } else if (strcmp(a, "--repeat") == 0) {
            if (!parse_size(v, 1000, &n) || n == 0) {
                fprintf(stderr, "split_sign: --repeat needs a number from 1 to 1000\n");
                return 2;
            }
            o->repeat = (unsigned)n;
        } else if (strcmp(a, "--kernel") == 0) {
            if (!v) {
                fprintf(stderr, "split_sign: --kernel needs a path\n");
                return 2;
            }
            o->kernel = v;
        } else if (strcmp(a, "--device") == 0) {
            if (!v) {
                fprintf(stderr, "split_sign: --device needs a name\n");
                return 2;
            }
            o->device = v;
        } else {
            fprintf(stderr, "split_sign: unknown argument '%s' (try --help)\n", a);
            return 2;
        }
        ++i; /* the option's value */
    }
    return 0;
}

/* xorshift32: the same numbers on every machine. */
static uint32_t next_random(uint32_t *state)
{
    uint32_t x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *state = x;
}

static double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

/* Reports a failed Sluice call with the context's message and jumps to the
 * clean-up code. Every Sluice call returns a status; SLUICE_OK is 0. */
/* The kernel file when --kernel is not given: next to the program (a
 * copy of the example with its kernel beside it), else in the installed data
 * folder <datadir>/sluice/examples (found relative to the program, so that a
 * moved install or one staged with --destdir finds its own copy), else in
 * the source tree (EXAMPLE_KERNEL_DIR, recorded at build time). */
static int find_kernel(char *path, size_t size)
{
    char tried[8192];
    if (sr_find_data_file("examples", "split_sign.cl", 1, EXAMPLE_KERNEL_DIR, path, size, tried,
                          sizeof tried) == 0)
        return 0;
    fprintf(stderr,
            "split_sign: cannot find the kernel split_sign.cl; tried %s (give its path with "
            "--kernel PATH)\n",
            tried);
    return -1;
}

#define TRY(call)                                                                                  \
    do {                                                                                           \
        sluice_status st_ = (call);                                                                \
        if (st_ != SLUICE_OK) {                                                                    \
            fprintf(stderr, "split_sign: %s failed (%s): %s\n", #call, sluice_status_string(st_),  \
                    sluice_context_error(ctx));                                                    \
            goto done;                                                                             \
        }                                                                                          \
    } while (0)

int main(int argc, char **argv)
{
    options opt;
    int parsed = parse_args(argc, argv, &opt);
    if (parsed)
        return parsed == 1 ? 0 : 2;
    char kernel_path[4096];
    if (!opt.kernel) {
        if (find_kernel(kernel_path, sizeof kernel_path) != 0)
            return 1;
        opt.kernel = kernel_path;
    }

    const size_t n = opt.count;
    int rc = 1;
    sluice_context *ctx = NULL;
    sluice_program *program = NULL;
    sluice_kernel *kernel = NULL;
    sluice_counters *counters = NULL;
    sluice_stream *in = NULL, *out[OUT_COUNT] = {NULL, NULL, NULL};
    float *values = NULL, *got[OUT_COUNT] = {NULL, NULL, NULL},
          *want[OUT_COUNT] = {NULL, NULL, NULL};

    /* Input data: uniform in [-1, 1), exactly representable, plus some NaNs. */
    values = malloc((n ? n : 1) * sizeof *values);
    for (int k = 0; k < OUT_COUNT; ++k) {
        got[k] = malloc((n ? n : 1) * sizeof *got[k]);
        want[k] = malloc((n ? n : 1) * sizeof *want[k]);
    }
    if (!values || !got[0] || !got[1] || !got[2] || !want[0] || !want[1] || !want[2]) {
        fprintf(stderr, "split_sign: out of host memory for %zu floats\n", n);
        goto done;
    }
    uint32_t state = opt.seed ? opt.seed : 0x9e3779b9u; /* xorshift must not start at 0 */
    for (size_t i = 0; i < n; ++i) {
        uint32_t r = next_random(&state);
        values[i] =
            i % NAN_EVERY == NAN_EVERY - 1 ? NAN : (float)(r >> 8) * (2.0f / 16777216.0f) - 1.0f;
    }

    /* 1. A context on one OpenCL device. */
    sluice_context_options copt = {0};
    copt.device = opt.device;
    copt.profile = opt.profile;
    char error[512];
    if (sluice_context_create(&copt, &ctx, error, sizeof error) != SLUICE_OK) {
        fprintf(stderr, "split_sign: cannot create an OpenCL context: %s\n", error);
        goto done;
    }
    sluice_device_info info;
    TRY(sluice_context_device(ctx, &info));

    /* 2. The program (compiled on first use) and its kernel. */
    TRY(sluice_program_create_file(ctx, opt.kernel, NULL, &program));
    TRY(sluice_kernel_create(program, "split_sign", &kernel));

    /* 3. Streams of 4-byte records. Each output could receive every record,
     *    so each gets the input's length as capacity. */
    TRY(sluice_stream_create(ctx, sizeof(float), n, &in));
    TRY(sluice_stream_upload(in, values, n));
    for (int k = 0; k < OUT_COUNT; ++k)
        TRY(sluice_stream_create(ctx, sizeof(float), n, &out[k]));

    /* 4. Counters, named so they can be looked up. */
    const char *counter_names[CTR_COUNT] = {"near_zero", "kept"};
    TRY(sluice_counters_create(ctx, CTR_COUNT, counter_names, &counters));

    /* 5. Bind everything. Argument indices count the kernel's parameters
     *    after SLUICE_PARAMS; slots are the first argument of SLUICE_EMIT_IF. */
    const float threshold = THRESHOLD, epsilon = EPSILON;
    TRY(sluice_kernel_set_input(kernel, ARG_IN, in));
    for (int k = 0; k < OUT_COUNT; ++k)
        TRY(sluice_kernel_set_output(kernel, ARG_FIRST_OUT + k, (unsigned)k, out[k], out_modes[k]));
    TRY(sluice_kernel_set_arg(kernel, ARG_THRESHOLD, sizeof threshold, &threshold));
    TRY(sluice_kernel_set_arg(kernel, ARG_EPSILON, sizeof epsilon, &epsilon));
    TRY(sluice_kernel_set_counters(kernel, counters));

    /* 6. Launch. Outputs are appended after their current length, and
     *    counters add up, so both are cleared before every run. The first
     *    run also pays for compiling; the best of the runs is reported. */
    double best = 0.0;
    for (unsigned r = 0; r < opt.repeat; ++r) {
        for (int k = 0; k < OUT_COUNT; ++k)
            TRY(sluice_stream_clear(out[k]));
        TRY(sluice_counters_reset(counters));
        double t0 = now_seconds();
        TRY(sluice_kernel_launch(kernel));
        TRY(sluice_context_finish(ctx));
        double t = now_seconds() - t0;
        if (r == 0 || t < best)
            best = t;
    }

    /* 7. Download the results. */
    size_t got_len[OUT_COUNT];
    uint32_t counts[CTR_COUNT];
    for (int k = 0; k < OUT_COUNT; ++k)
        TRY(sluice_stream_download(out[k], got[k], n, &got_len[k]));
    TRY(sluice_counters_read(counters, counts));

    /* 8. The same computation in plain C. */
    size_t want_len[OUT_COUNT] = {0, 0, 0};
    uint32_t want_counts[CTR_COUNT] = {0, 0};
    for (size_t i = 0; i < n; ++i) {
        float x = values[i];
        if (isnan(x))
            continue;
        int k = x < 0.0f ? OUT_NEGATIVE : x < THRESHOLD ? OUT_SMALL : OUT_LARGE;
        want[k][want_len[k]++] = x;
        want_counts[CTR_NEAR_ZERO] += fabsf(x) < EPSILON;
        want_counts[CTR_KEPT] += 1;
    }
    int ok = 1;
    for (int k = 0; k < OUT_COUNT; ++k) {
        if (got_len[k] != want_len[k]) {
            fprintf(stderr, "split_sign: stream %s has %zu records, expected %zu\n", out_names[k],
                    got_len[k], want_len[k]);
            ok = 0;
            continue;
        }
        if (out_modes[k] == SLUICE_UNORDERED) { /* same records, any order */
            qsort(got[k], got_len[k], sizeof(float), compare_floats);
            qsort(want[k], want_len[k], sizeof(float), compare_floats);
        }
        if (got_len[k] && memcmp(got[k], want[k], got_len[k] * sizeof(float)) != 0) {
            fprintf(stderr, "split_sign: stream %s differs from the C reference\n", out_names[k]);
            ok = 0;
        }
    }
    for (int c = 0; c < CTR_COUNT; ++c)
        if (counts[c] != want_counts[c]) {
            fprintf(stderr, "split_sign: counter %s is %u, expected %u\n", counter_names[c],
                    counts[c], want_counts[c]);
            ok = 0;
        }

    /* 9. Summary. */
    size_t emitted = got_len[0] + got_len[1] + got_len[2];
    double bytes = (double)(n + emitted) * sizeof(float);
    printf("split_sign: %zu floats on %s\n", n, info.name);
    printf("  kernel    %s\n", opt.kernel);
    for (int k = 0; k < OUT_COUNT; ++k)
        printf("  %-9s %10zu records  (%s)\n", out_names[k], got_len[k],
               out_modes[k] == SLUICE_ORDERED ? "ordered" : "unordered");
    printf("  %-9s %10u records  (|x| < %g)\n", counter_names[CTR_NEAR_ZERO], counts[CTR_NEAR_ZERO],
           (double)EPSILON);
    printf("  %-9s %10u records  (not NaN)\n", counter_names[CTR_KEPT], counts[CTR_KEPT]);
    if (n > 0 && best > 0.0)
        printf("  best of %u launches: %.3f ms, %.1f M records/s, %.2f GB/s\n", opt.repeat,
               best * 1e3, (double)n / best * 1e-6, bytes / best * 1e-9);
    printf("  check against plain C: %s\n", ok ? "ok" : "FAILED");
    if (opt.profile)
        TRY(sluice_profile_print(ctx, stdout));
    rc = ok ? 0 : 1;

done:
    /* Destroy in reverse order: kernels before programs, everything before
     * the context. Destroy functions accept NULL. */
    sluice_kernel_destroy(kernel);
    sluice_program_destroy(program);
    sluice_counters_destroy(counters);
    for (int k = 0; k < OUT_COUNT; ++k)
        sluice_stream_destroy(out[k]);
    sluice_stream_destroy(in);
    sluice_context_destroy(ctx);
    free(values);
    for (int k = 0; k < OUT_COUNT; ++k) {
        free(got[k]);
        free(want[k]);
    }
    return rc;
}
