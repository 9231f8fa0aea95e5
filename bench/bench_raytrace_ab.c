/*
 * bench_raytrace_ab: one ray tracer against a variant of itself, to tell a
 * change of a few percent from the noise of a shared machine.
 *
 * Two tracers of one mode trace the same eye rays (one per pixel centre,
 * 8x8-tile order, as bench_raytrace's primary rays), each in its own context:
 * variant A with the build options --a appended to every kernel build (the
 * context option build_options), variant B with --b, and each with its own
 * stream-mode budgets. They alternate frame by frame, A B then B A, so that
 * drift in the machine's speed falls on both alike. The result is the median
 * over frame pairs of B's speed over A's, with its quartiles, beside each
 * variant's best and median frame. A kernel change goes behind an #ifdef
 * and is measured as, e.g., --b -DMY_CHANGE; an A/A run (no options) gives
 * the noise, within a few percent of 1.
 *
 *   bench_raytrace_ab [--scene NAME|FILE] [--exec stream|fused] [--size N]
 *                     [--pairs N] [--a OPTIONS] [--b OPTIONS]
 *                     [--a-steps K] [--b-steps K] [--a-tests M] [--b-tests M]
 *                     [--allow-diff]
 *
 * Exit status 0 when both traced every ray to the same hit record (1 when
 * some differ, unless --allow-diff), 2 on bad arguments or setup errors.
 */
#include "bench_ab.h"
#include "bench_args.h"
#include "bench_machine.h"
#include "bench_rays.h"
#include "clock.h"
#include "scene.h"
#include "tracer.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PROG "bench_raytrace_ab"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: " PROG " [options]\n"
            "Times a ray tracer against a variant of itself on the same eye rays, the two\n"
            "alternating frame by frame, and prints the median over frame pairs of B's\n"
            "speed over A's with its quartiles.\n\n"
            "  --scene NAME|FILE  scene (default bunny-close: the bunny filling the frame)\n"
            "  --exec E           stream | fused (default stream)\n"
            "  --size N           image side, rays = N*N (default 512)\n"
            "  --pairs N          timed frame pairs, after 4 warm-up pairs (default 160)\n"
            "  --a OPTIONS        build options appended for variant A (default none)\n"
            "  --b OPTIONS        build options appended for variant B (default none)\n"
            "  --a-steps K        stream mode: voxels per traverse pass of A (default: the\n"
            "                     tracer's); --b-steps for B\n"
            "  --a-tests M        stream mode: tests per intersect pass of A (default: the\n"
            "                     tracer's); --b-tests for B\n"
            "  --allow-diff       exit 0 even when some hit records differ\n"
            "  --help             this text\n\n"
            "example: a kernel change behind #ifdef MY_CHANGE, on the bunny filling the frame:\n"
            "  " PROG " --b -DMY_CHANGE\n");
}

typedef struct variant {
    const char *options;
    unsigned steps, tests; /* 0: the tracer's defaults */
    sluice_context *ctx;
    rt_tracer *tracer;
    sluice_stream *rays, *hits;
    double *seconds; /* per timed frame */
} variant;

static void variant_free(variant *v)
{
    sluice_stream_destroy(v->rays);
    sluice_stream_destroy(v->hits);
    rt_tracer_destroy(v->tracer);
    if (v->ctx)
        sluice_context_destroy(v->ctx);
    free(v->seconds);
}

static int variant_create(variant *v, char name, const sr_scene *sc, rt_exec exec,
                          const rt_ray *rays, size_t n, unsigned pairs)
{
    if (!bench_ab_context(PROG, name, v->options, &v->ctx))
        return 0;
    char err[512];
    rt_tracer_options o = rt_tracer_options_default();
    o.exec = exec;
    if (v->steps)
        o.unroll_steps = v->steps;
    if (v->tests)
        o.unroll_tests = v->tests;
    if (rt_tracer_create(v->ctx, sc, &o, &v->tracer, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, PROG ": variant %c: %s\n", name, err);
        return 0;
    }
    v->seconds = malloc(pairs * sizeof *v->seconds);
    if (!v->seconds || sluice_stream_create(v->ctx, sizeof(rt_ray), n, &v->rays) != SLUICE_OK ||
        sluice_stream_create(v->ctx, sizeof(rt_hit), n, &v->hits) != SLUICE_OK ||
        sluice_stream_upload(v->rays, rays, n) != SLUICE_OK) {
        fprintf(stderr, PROG ": variant %c: %s\n", name,
                v->seconds ? sluice_context_error(v->ctx) : "out of memory");
        return 0;
    }
    return 1;
}

/* One timed trace of all rays; a negative time on failure. */
static double frame(variant *v, size_t n)
{
    if (sluice_context_finish(v->ctx) != SLUICE_OK)
        return -1.0;
    double t0 = sr_clock_seconds();
    if (rt_tracer_trace_stream(v->tracer, v->rays, n, v->hits) != SLUICE_OK ||
        sluice_context_finish(v->ctx) != SLUICE_OK)
        return -1.0;
    return sr_clock_seconds() - t0;
}

/* Hit records that differ between the variants; -1 on failure. */
static long count_diff(variant *v, size_t n)
{
    rt_hit *h[2] = {malloc(n * sizeof(rt_hit) + 1), malloc(n * sizeof(rt_hit) + 1)};
    long diff = -1;
    size_t got[2] = {0, 0};
    if (h[0] && h[1] && sluice_stream_download(v[0].hits, h[0], n, &got[0]) == SLUICE_OK &&
        sluice_stream_download(v[1].hits, h[1], n, &got[1]) == SLUICE_OK && got[0] == n &&
        got[1] == n) {
        diff = 0;
        for (size_t i = 0; i < n; ++i)
            diff += memcmp(&h[0][i], &h[1][i], sizeof(rt_hit)) != 0;
    }
    free(h[0]);
    free(h[1]);
    return diff;
}

int main(int argc, char **argv)
{
    const char *scene = "bunny-close", *exec_name = "stream";
    unsigned size = 512, pairs = 160;
    int allow_diff = 0;
    variant v[2];
    memset(v, 0, sizeof v);
    v[0].options = v[1].options = "";
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        int ok = 1;
        if (strcmp(a, "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--allow-diff") == 0) {
            allow_diff = 1;
            continue;
        } else if (!val) {
            fprintf(stderr, PROG ": %s: unknown option or missing value (try --help)\n", a);
            return 2;
        } else if (strcmp(a, "--scene") == 0)
            scene = val;
        else if (strcmp(a, "--exec") == 0)
            exec_name = val;
        else if (strcmp(a, "--size") == 0)
            ok = bench_parse_uint(val, 4096, &size) && size > 0;
        else if (strcmp(a, "--pairs") == 0)
            ok = bench_parse_uint(val, 100000, &pairs) && pairs > 0;
        else if (strcmp(a, "--a") == 0 || strcmp(a, "--b") == 0)
            v[a[2] - 'a'].options = val;
        else if (strcmp(a, "--a-steps") == 0 || strcmp(a, "--b-steps") == 0)
            ok = bench_parse_uint(val, 4096, &v[a[2] - 'a'].steps) && v[a[2] - 'a'].steps > 0;
        else if (strcmp(a, "--a-tests") == 0 || strcmp(a, "--b-tests") == 0)
            ok = bench_parse_uint(val, 4096, &v[a[2] - 'a'].tests) && v[a[2] - 'a'].tests > 0;
        else {
            fprintf(stderr, PROG ": unknown option %s (try --help)\n", a);
            return 2;
        }
        if (!ok) {
            fprintf(stderr, PROG ": %s: bad value '%s' (try --help)\n", a, val);
            return 2;
        }
        ++i;
    }
    rt_exec exec;
    if (strcmp(exec_name, "stream") == 0)
        exec = RT_EXEC_STREAM;
    else if (strcmp(exec_name, "fused") == 0)
        exec = RT_EXEC_FUSED;
    else {
        fprintf(stderr, PROG ": --exec: '%s' is neither stream nor fused\n", exec_name);
        return 2;
    }

    sr_scene *sc = bench_load_scene(PROG, scene);
    if (!sc)
        return 2;
    size_t n = (size_t)size * size;
    rt_ray *rays = bench_eye_rays(sc, size, size);
    int status = 2;
    if (!rays) {
        fprintf(stderr, PROG ": out of memory\n");
        goto done;
    }
    if (!variant_create(&v[0], 'A', sc, exec, rays, n, pairs) ||
        !variant_create(&v[1], 'B', sc, exec, rays, n, pairs))
        goto done;

    sluice_device_info info;
    bench_machine mach;
    if (sluice_context_device(v[0].ctx, &info) != SLUICE_OK)
        goto done;
    bench_machine_probe(v[0].ctx, &mach);
    printf("device: %s / %s, %u compute units\nCPU: %s (%s), kernels' block emission: %s\n",
           info.platform, info.name, info.compute_units, mach.cpu, mach.isa, mach.block);
    printf("%s, %s mode, %ux%u eye rays; A: '%s', B: '%s'; %u frame pairs (A B, B A)\n", scene,
           exec_name, size, size, v[0].options, v[1].options, pairs);
    fflush(stdout);

    for (int f = -4; f < (int)pairs; ++f) {
        for (int k = 0; k < 2; ++k) {
            int w = (f & 1) ? 1 - k : k;
            double s = frame(&v[w], n);
            if (s < 0.0) {
                fprintf(stderr, PROG ": variant %c: %s\n", "AB"[w], sluice_context_error(v[w].ctx));
                goto done;
            }
            if (f >= 0)
                v[w].seconds[f] = s;
        }
        if (f >= 0 && (f + 1) % 32 == 0)
            fprintf(stderr, PROG ": %d of %u pairs\n", f + 1, pairs);
    }
    double q[3];
    if (!bench_ab_ratio(v[0].seconds, v[1].seconds, pairs, q)) {
        fprintf(stderr, PROG ": out of memory\n");
        goto done;
    }
    for (int k = 0; k < 2; ++k)
        printf("%c: best %.2f, median %.2f M rays/s\n", "AB"[k], (double)n / v[k].seconds[0] / 1e6,
               (double)n / v[k].seconds[pairs / 2] / 1e6);
    printf("B over A, median over frame pairs: %.3f (quartiles %.3f, %.3f)\n", q[1], q[0], q[2]);
    long diff = count_diff(v, n);
    if (diff < 0) {
        fprintf(stderr, PROG ": reading the hits: %s\n", sluice_context_error(v[0].ctx));
        goto done;
    }
    printf("hit records that differ: %ld of %zu\n", diff, n);
    status = diff && !allow_diff ? 1 : 0;
done:
    variant_free(&v[1]);
    variant_free(&v[0]);
    free(rays);
    sr_scene_destroy(sc);
    return status;
}
