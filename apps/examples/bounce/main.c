/*
 * bounce: a multipass loop stopped by what the device counted.
 *
 * N particles bounce in a box whose floor has a hole (see bounce.cl). Each
 * pass of a sluice_loop launches one kernel that moves the live particles a
 * few steps and emits the survivors into a second stream; the host swaps the
 * two streams (ping-pong) and the loop reads the new live length and the
 * counters of escaped and stopped particles after every pass. The loop ends
 * when no particle is left. The whole run is then replayed in plain C and
 * compared pass by pass and particle by particle; the integer arithmetic makes
 * the comparison exact.
 *
 * The kernel is loaded at run time from the path given with --kernel, else
 * found by find_kernel() below (next to the program, in the installed data
 * folder, or in the source tree).
 */
#include <sluice/sluice.h>

#include "data_path.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef EXAMPLE_KERNEL_DIR
#define EXAMPLE_KERNEL_DIR "."
#endif

/* The same constants, record and step function as in bounce.cl. */
#define BOX_WIDTH 1000000
#define GRAVITY 1000
#define HOLE_BEGIN 400000
#define HOLE_END 600000
#define STOP_SPEED 2000
#define FATE_MOVING 0u
#define FATE_ESCAPED 1u
#define FATE_STOPPED 2u

typedef struct particle {
    int32_t x, y;
    int32_t vx, vy;
    uint32_t id;
    uint32_t fate; /* FATE_* in the low byte, the pass it left in above it */
} particle;

static uint32_t step(particle *p)
{
    p->vy -= GRAVITY;
    p->x += p->vx;
    p->y += p->vy;
    if (p->x < 0) {
        p->x = -p->x;
        p->vx = -p->vx;
    } else if (p->x >= BOX_WIDTH) {
        p->x = 2 * (BOX_WIDTH - 1) - p->x;
        p->vx = -p->vx;
    }
    if (p->y < 0) {
        if (p->x >= HOLE_BEGIN && p->x < HOLE_END)
            return FATE_ESCAPED;
        p->y = 0; /* back on the floor */
        p->vy = -p->vy * 3 / 4;
        if (p->vy < STOP_SPEED) {
            p->vy = 0;
            return FATE_STOPPED;
        }
    }
    return FATE_MOVING;
}

/* Kernel arguments (after SLUICE_PARAMS), output slots and counters. */
enum { ARG_LIVE = 0, ARG_NEXT = 1, ARG_DEPARTED = 2, ARG_STEPS = 3, ARG_PASS = 4 };
enum { SLOT_NEXT = 0, SLOT_DEPARTED = 1 };
enum { CTR_ESCAPED, CTR_STOPPED, CTR_COUNT };
/* What the loop watches, in the order of sluice_pass_stats.values: the
 * stream lengths first, then the counters. */
enum { VAL_LIVE, VAL_ESCAPED, VAL_STOPPED };

typedef struct options {
    size_t count;
    uint32_t seed;
    int steps;
    unsigned max_passes;
    unsigned every;
    const char *kernel;
    const char *device;
    int profile;
} options;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: sluice-example-bounce [--count N] [--seed S] [--steps K] [--max-passes P]\n"
            "                             [--every E] [--kernel PATH] [--device NAME] [--profile]\n"
            "                             [--help]\n"
            "Bounces N particles in a box with a hole in the floor, K steps per pass of a\n"
            "Sluice multipass loop, until every particle has escaped or come to rest;\n"
            "then checks every pass against plain C.\n"
            "  --count N       number of particles (default 100000)\n"
            "  --seed S        seed of the random start positions (default 1)\n"
            "  --steps K       time steps per pass (default 4)\n"
            "  --max-passes P  give up after P passes (default 10000)\n"
            "  --every E       print the statistics of every E-th pass (default 10;\n"
            "                  0: only the summary)\n"
            "  --kernel PATH   the kernel file (default: bounce.cl next to the program,\n"
            "                  else in <datadir>/sluice/examples, else in the source tree)\n"
            "  --device NAME   OpenCL device whose \"platform / name\" contains NAME\n"
            "                  (default: SLUICE_DEVICE, else the first CPU device)\n"
            "  --profile       print the per-kernel profiling table\n");
}

static int parse_number(const char *s, unsigned long long max, unsigned long long *out)
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
    o->count = 100000;
    o->seed = 1;
    o->steps = 4;
    o->max_passes = 10000;
    o->every = 10;
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
            if (!parse_number(v, 100000000, &n)) {
                fprintf(stderr, "bounce: --count needs a number from 0 to 100000000\n");
                return 2;
            }
            o->count = (size_t)n;
        } else if (strcmp(a, "--seed") == 0) {
            if (!parse_number(v, UINT32_MAX, &n)) {
                fprintf(stderr, "bounce: --seed needs a number from 0 to %u\n", UINT32_MAX);
                return 2;
            }
            o->seed = (uint32_t)n;
        } else if (strcmp(a, "--steps") == 0) {
            if (!parse_number(v, 100000, &n) || n == 0) {
                fprintf(stderr, "bounce: --steps needs a number from 1 to 100000\n");
                return 2;
            }
            o->steps = (int)n;
        } else if (strcmp(a, "--max-passes") == 0) {
            if (!parse_number(v, 1000000, &n) || n == 0) {
                fprintf(stderr, "bounce: --max-passes needs a number from 1 to 1000000\n");
                return 2;
            }
            o->max_passes = (unsigned)n;
        } else if (strcmp(a, "--every") == 0) {
            if (!parse_number(v, UINT32_MAX, &n)) {
                fprintf(stderr, "bounce: --every needs a number\n");
                return 2;
            }
            o->every = (unsigned)n;
        } else if (strcmp(a, "--kernel") == 0) {
            if (!v) {
                fprintf(stderr, "bounce: --kernel needs a path\n");
                return 2;
            }
            o->kernel = v;
        } else if (strcmp(a, "--device") == 0) {
            if (!v) {
                fprintf(stderr, "bounce: --device needs a name\n");
                return 2;
            }
            o->device = v;
        } else {
            fprintf(stderr, "bounce: unknown argument '%s' (try --help)\n", a);
            return 2;
        }
        ++i; /* the option's value */
    }
    return 0;
}

static uint32_t next_random(uint32_t *state)
{
    uint32_t x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *state = x;
}

/* A random integer in [lo, hi]. */
static int32_t random_between(uint32_t *state, int32_t lo, int32_t hi)
{
    return lo + (int32_t)(next_random(state) % (uint32_t)(hi - lo + 1));
}

static double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

/* Everything one pass needs, handed to the pass function by the loop. */
typedef struct bounce_state {
    sluice_kernel *kernel;
    sluice_stream *live, *next;
} bounce_state;

/* One pass: move the live particles into `next`, then swap the streams so
 * that `live` holds the survivors. The kernel bound `live` and `next` once;
 * after a swap it sees the exchanged buffers at its next launch. Called by
 * sluice_loop_run, which has already restarted the counters from zero. */
static sluice_status bounce_pass(void *user, unsigned pass, unsigned choice)
{
    (void)choice;
    bounce_state *b = user;
    uint32_t pass_arg = pass;
    sluice_status st = sluice_kernel_set_arg(b->kernel, ARG_PASS, sizeof pass_arg, &pass_arg);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(b->next); /* outputs append after the length */
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(b->kernel);
    if (st == SLUICE_OK)
        st = sluice_stream_swap(b->live, b->next);
    return st;
}

/* Goes on while particles are left. Without an oracle the loop would also
 * run while the escaped or stopped counters are non-zero, which costs one
 * empty pass at the end. */
static unsigned until_empty(void *user, unsigned pass, const uint32_t *values, size_t count)
{
    (void)user;
    (void)pass;
    (void)count;
    return values[VAL_LIVE] ? 0u : SLUICE_LOOP_STOP;
}

/* The reference: the same passes in plain C. Fills per-pass live, escaped and
 * stopped counts (arrays of max_passes entries) and the final state of every
 * particle by id; returns the number of passes, or max_passes + 1 if the
 * particles did not all leave in time. */
static unsigned simulate(const particle *start, size_t n, int steps, unsigned max_passes,
                         uint32_t *live_after, uint32_t *escaped, uint32_t *stopped,
                         particle *final_state)
{
    particle *live = malloc((n ? n : 1) * sizeof *live);
    if (!live)
        return max_passes + 1;
    memcpy(live, start, n * sizeof *live);
    size_t live_n = n;
    unsigned pass = 0;
    for (; live_n > 0; ++pass) {
        if (pass == max_passes) {
            free(live);
            return max_passes + 1;
        }
        size_t kept = 0;
        escaped[pass] = stopped[pass] = 0;
        for (size_t i = 0; i < live_n; ++i) {
            particle p = live[i];
            uint32_t fate = FATE_MOVING;
            for (int s = 0; s < steps && fate == FATE_MOVING; ++s)
                fate = step(&p);
            p.fate = fate | (pass << 8);
            if (fate == FATE_MOVING) {
                live[kept++] = p;
            } else {
                final_state[p.id] = p;
                escaped[pass] += fate == FATE_ESCAPED;
                stopped[pass] += fate == FATE_STOPPED;
            }
        }
        live_n = kept;
        live_after[pass] = (uint32_t)kept;
    }
    free(live);
    return pass;
}

static int compare_ids(const void *a, const void *b)
{
    uint32_t x = ((const particle *)a)->id, y = ((const particle *)b)->id;
    return x < y ? -1 : x > y;
}

/* The kernel file when --kernel is not given: next to the program (a
 * copy of the example with its kernel beside it), else in the installed data
 * folder <datadir>/sluice/examples (found relative to the program, so that a
 * moved install or one staged with --destdir finds its own copy), else in
 * the source tree (EXAMPLE_KERNEL_DIR, recorded at build time). */
static int find_kernel(char *path, size_t size)
{
    char tried[8192];
    if (sr_find_data_file("examples", "bounce.cl", 1, EXAMPLE_KERNEL_DIR, path, size, tried,
                          sizeof tried) == 0)
        return 0;
    fprintf(
        stderr,
        "bounce: cannot find the kernel bounce.cl; tried %s (give its path with --kernel PATH)\n",
        tried);
    return -1;
}

#define TRY(call)                                                                                  \
    do {                                                                                           \
        sluice_status st_ = (call);                                                                \
        if (st_ != SLUICE_OK) {                                                                    \
            fprintf(stderr, "bounce: %s failed (%s): %s\n", #call, sluice_status_string(st_),      \
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
    sluice_stream *live = NULL, *next = NULL, *departed = NULL;
    sluice_loop *loop = NULL;
    particle *start = calloc(n ? n : 1, sizeof *start);
    particle *got = calloc(n ? n : 1, sizeof *got);
    particle *want = calloc(n ? n : 1, sizeof *want);
    uint32_t *want_live = calloc(opt.max_passes, sizeof *want_live);
    uint32_t *want_escaped = calloc(opt.max_passes, sizeof *want_escaped);
    uint32_t *want_stopped = calloc(opt.max_passes, sizeof *want_stopped);
    if (!start || !got || !want || !want_live || !want_escaped || !want_stopped) {
        fprintf(stderr, "bounce: out of host memory for %zu particles\n", n);
        goto done;
    }

    /* Random start states: anywhere in the lower half of the box, moving. */
    uint32_t state = opt.seed ? opt.seed : 0x9e3779b9u;
    for (size_t i = 0; i < n; ++i) {
        start[i].x = random_between(&state, 0, BOX_WIDTH - 1);
        start[i].y = random_between(&state, 0, 500000);
        start[i].vx = random_between(&state, -30000, 30000);
        start[i].vy = random_between(&state, -20000, 20000);
        start[i].id = (uint32_t)i;
        start[i].fate = FATE_MOVING;
    }

    sluice_context_options copt = {0};
    copt.device = opt.device;
    copt.profile = opt.profile;
    char error[512];
    if (sluice_context_create(&copt, &ctx, error, sizeof error) != SLUICE_OK) {
        fprintf(stderr, "bounce: cannot create an OpenCL context: %s\n", error);
        goto done;
    }
    sluice_device_info info;
    TRY(sluice_context_device(ctx, &info));
    TRY(sluice_program_create_file(ctx, opt.kernel, NULL, &program));
    TRY(sluice_kernel_create(program, "bounce", &kernel));

    /* Two live streams for the ping-pong, and one that collects the departed
     * particles of all passes (every particle departs exactly once). */
    TRY(sluice_stream_create(ctx, sizeof(particle), n, &live));
    TRY(sluice_stream_create(ctx, sizeof(particle), n, &next));
    TRY(sluice_stream_create(ctx, sizeof(particle), n, &departed));
    TRY(sluice_stream_upload(live, start, n));
    const char *counter_names[CTR_COUNT] = {"escaped", "stopped"};
    TRY(sluice_counters_create(ctx, CTR_COUNT, counter_names, &counters));

    TRY(sluice_kernel_set_input(kernel, ARG_LIVE, live));
    TRY(sluice_kernel_set_output(kernel, ARG_NEXT, SLOT_NEXT, next, SLUICE_ORDERED));
    TRY(sluice_kernel_set_output(kernel, ARG_DEPARTED, SLOT_DEPARTED, departed, SLUICE_UNORDERED));
    TRY(sluice_kernel_set_arg(kernel, ARG_STEPS, sizeof opt.steps, &opt.steps));
    TRY(sluice_kernel_set_counters(kernel, counters));

    /* The loop watches the live stream's length and both counters, zeroes
     * the counters before every pass and asks the oracle whether to go on. */
    bounce_state b = {kernel, live, next};
    sluice_stream *watched[] = {live};
    sluice_loop_desc desc = {0};
    desc.pass = bounce_pass;
    desc.oracle = until_empty;
    desc.user = &b;
    desc.streams = watched;
    desc.stream_count = 1;
    desc.counters = counters;
    desc.reset_counters = 1;
    desc.max_passes = opt.max_passes;
    TRY(sluice_loop_create(ctx, &desc, &loop));

    double t0 = now_seconds();
    sluice_status run = sluice_loop_run(loop);
    double seconds = now_seconds() - t0;
    if (run == SLUICE_ERROR_LIMIT) {
        fprintf(stderr, "bounce: particles were still moving after %u passes (--max-passes): %s\n",
                opt.max_passes, sluice_context_error(ctx));
        goto done;
    }
    TRY(run);
    unsigned passes = sluice_loop_pass_count(loop);

    /* Per-pass statistics, kept by the loop. */
    printf("bounce: %zu particles, %d steps per pass, on %s\n", n, opt.steps, info.name);
    printf("  kernel %s\n", opt.kernel);
    if (opt.every)
        printf("  %6s %10s %10s %10s %9s\n", "pass", "live", "escaped", "stopped", "ms");
    uint64_t moved = n; /* particle-passes: the records all launches read */
    uint64_t total_escaped = 0, total_stopped = 0;
    for (unsigned p = 0; p < passes; ++p) {
        const sluice_pass_stats *s = sluice_loop_pass(loop, p);
        total_escaped += s->values[VAL_ESCAPED];
        total_stopped += s->values[VAL_STOPPED];
        if (p + 1 < passes)
            moved += s->values[VAL_LIVE];
        if (opt.every && (p % opt.every == 0 || p + 1 == passes))
            printf("  %6u %10u %10u %10u %9.3f\n", p, s->values[VAL_LIVE], s->values[VAL_ESCAPED],
                   s->values[VAL_STOPPED], s->seconds * 1e3);
    }

    /* The reference, pass by pass. */
    int ok = 1;
    unsigned want_passes =
        simulate(start, n, opt.steps, opt.max_passes, want_live, want_escaped, want_stopped, want);
    if (want_passes != passes) {
        fprintf(stderr, "bounce: %u passes, the C reference needs %u\n", passes, want_passes);
        ok = 0;
    }
    for (unsigned p = 0; ok && p < passes; ++p) {
        const sluice_pass_stats *s = sluice_loop_pass(loop, p);
        if (s->values[VAL_LIVE] != want_live[p] || s->values[VAL_ESCAPED] != want_escaped[p] ||
            s->values[VAL_STOPPED] != want_stopped[p]) {
            fprintf(stderr,
                    "bounce: pass %u: live %u escaped %u stopped %u, the C reference has "
                    "%u %u %u\n",
                    p, s->values[VAL_LIVE], s->values[VAL_ESCAPED], s->values[VAL_STOPPED],
                    want_live[p], want_escaped[p], want_stopped[p]);
            ok = 0;
        }
    }
    size_t got_n = 0;
    TRY(sluice_stream_download(departed, got, n, &got_n));
    qsort(got, got_n, sizeof *got, compare_ids); /* unordered output: any order */
    if (got_n != n) {
        fprintf(stderr, "bounce: %zu particles departed, expected %zu\n", got_n, n);
        ok = 0;
    } else {
        size_t bad = 0;
        for (size_t i = 0; i < n; ++i)
            bad += memcmp(&got[i], &want[i], sizeof *got) != 0;
        if (bad) {
            fprintf(stderr, "bounce: %zu particles end differently from the C reference\n", bad);
            ok = 0;
        }
    }

    printf("  %u passes in %.3f ms, %.1f M particle-passes/s\n", passes, seconds * 1e3,
           seconds > 0 ? (double)moved / seconds * 1e-6 : 0.0);
    printf("  escaped %llu, stopped %llu\n", (unsigned long long)total_escaped,
           (unsigned long long)total_stopped);
    printf("  check against plain C: %s\n", ok ? "ok" : "FAILED");
    if (opt.profile)
        TRY(sluice_profile_print(ctx, stdout));
    rc = ok ? 0 : 1;

done:
    sluice_loop_destroy(loop);
    sluice_kernel_destroy(kernel);
    sluice_program_destroy(program);
    sluice_counters_destroy(counters);
    sluice_stream_destroy(live);
    sluice_stream_destroy(next);
    sluice_stream_destroy(departed);
    sluice_context_destroy(ctx);
    free(start);
    free(got);
    free(want);
    free(want_live);
    free(want_escaped);
    free(want_stopped);
    return rc;
}
