/*
 * bench_knn_ab: the kNN-grid search (apps/photonmap/knn.h) against a variant
 * of itself, to tell a change of a few percent from the noise of a shared
 * machine (bench_raytrace_ab does the same for the ray tracer).
 *
 * Two searches run the same queries over the same photons (bench_knn's
 * Cornell-box-like surfaces, bench_knn_scene.h), each in its own context:
 * variant A with the build options --a appended to every kernel build (the
 * context option build_options), variant B with --b. They alternate call by
 * call, A B then B A, so that drift in the machine's speed falls on both
 * alike. The result is the median over call pairs of B's speed over A's,
 * with its quartiles. --grid sets the grid's dimensions (Purcell's cornell
 * ran 25x25x50 cells for k = 500, cells a fraction of the search radius);
 * by default the grid is the one sr_point_grid_desc_auto makes.
 *
 *   bench_knn_ab [--photons N] [--queries N] [--k K]
 *                [--mode atleast|exact|radius] [--grid XxYxZ | --hashed]
 *                [--shells-per-pass N|all] [--pairs N] [--a OPTIONS] [--b OPTIONS]
 *
 * --hashed runs the radius search over the hashed grid (Purcell 6.4.4,
 * sr_point_hash_desc_auto for the maximum radius), as the progressive
 * photon mapper does.
 *
 * Exit status 0 when both found the same photon counts and radii for every
 * query and power sums as near as summing the same photons in another order
 * allows, 1 when not, 2 on bad arguments or setup errors.
 */
#include "bench_ab.h"
#include "bench_args.h"
#include "bench_knn_scene.h"
#include "bench_machine.h"
#include "clock.h"
#include "knn.h"
#include "point_grid.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PROG "bench_knn_ab"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: " PROG " [options]\n"
            "Times the kNN-grid search against a variant of itself on the same photons and\n"
            "queries, the two alternating call by call, and prints the median over call\n"
            "pairs of B's speed over A's with its quartiles.\n\n"
            "  --photons N        photons on the surfaces (default 65000)\n"
            "  --queries N        query points on the surfaces (default 262144)\n"
            "  --k K              photons per estimate (default 500)\n"
            "  --mode M           atleast | exact | radius (default atleast; radius: every\n"
            "                     photon within the maximum radius)\n"
            "  --hashed           the radius search over the hashed grid (implies --mode\n"
            "                     radius)\n"
            "  --grid XxYxZ       the grid's cells (default: sr_point_grid_desc_auto's for the\n"
            "                     mean k-photon radius)\n"
            "  --shells-per-pass N|all\n"
            "                     kNN shells each pass explores (default 1, Purcell's;\n"
            "                     all: one pass, as sluice-photonmap --shells-per-pass all)\n"
            "  --pairs N          timed call pairs, after 2 warm-up pairs (default 20)\n"
            "  --a OPTIONS        build options appended for variant A (default none)\n"
            "  --b OPTIONS        build options appended for variant B (default none)\n"
            "  --help             this text\n\n"
            "example: Purcell's cornell settings, a change behind #ifdef MY_CHANGE:\n"
            "  " PROG " --k 500 --grid 25x25x50 --b -DMY_CHANGE\n");
}

typedef struct variant {
    const char *options;
    sluice_context *ctx;
    sr_point_grid *grid;
    pm_knn *knn;
    sluice_stream *photons, *queries, *results;
    double *seconds; /* per timed call */
} variant;

static void variant_free(variant *v)
{
    sluice_stream_destroy(v->photons);
    sluice_stream_destroy(v->queries);
    sluice_stream_destroy(v->results);
    pm_knn_destroy(v->knn);
    sr_point_grid_destroy(v->grid);
    if (v->ctx)
        sluice_context_destroy(v->ctx);
    free(v->seconds);
}

static int variant_create(variant *v, char name, const rt_grid_desc *d,
                          const sr_point_hash_desc *hd, const pm_photon *ph, size_t np,
                          const pm_query *qs, size_t nq, unsigned pairs)
{
    if (!bench_ab_context(PROG, name, v->options, &v->ctx))
        return 0;
    v->seconds = malloc(pairs * sizeof *v->seconds);
    if (!v->seconds || sr_point_grid_create(v->ctx, &v->grid) != SLUICE_OK ||
        pm_knn_create(v->ctx, &v->knn) != SLUICE_OK ||
        sluice_stream_create(v->ctx, sizeof *ph, np, &v->photons) != SLUICE_OK ||
        sluice_stream_create(v->ctx, sizeof *qs, nq, &v->queries) != SLUICE_OK ||
        sluice_stream_create(v->ctx, sizeof(pm_knn_result), nq, &v->results) != SLUICE_OK ||
        sluice_stream_upload(v->photons, ph, np) != SLUICE_OK ||
        sluice_stream_upload(v->queries, qs, nq) != SLUICE_OK) {
        fprintf(stderr, PROG ": variant %c: %s\n", name,
                v->seconds ? sluice_context_error(v->ctx) : "out of memory");
        return 0;
    }
    if ((hd ? sr_point_grid_build_hashed(v->grid, hd, v->photons, sizeof(pm_photon), np,
                                         SR_POINT_GRID_COUNT)
            : sr_point_grid_build(v->grid, d, v->photons, sizeof(pm_photon), np,
                                  SR_POINT_GRID_COUNT, 0)) != SLUICE_OK) {
        fprintf(stderr, PROG ": variant %c: %s\n", name, sr_point_grid_error(v->grid));
        return 0;
    }
    return 1;
}

/* One timed search of all queries; a negative time on failure. */
static double call(variant *v, size_t nq, const pm_knn_options *o)
{
    if (sluice_context_finish(v->ctx) != SLUICE_OK)
        return -1.0;
    double t0 = sr_clock_seconds();
    if (pm_knn_query(v->knn, v->grid, v->photons, v->queries, nq, v->results, o, NULL) !=
            SLUICE_OK ||
        sluice_context_finish(v->ctx) != SLUICE_OK) {
        fprintf(stderr, PROG ": %s\n", pm_knn_error(v->knn));
        return -1.0;
    }
    return sr_clock_seconds() - t0;
}

/* Sums of the same n positive terms in two orders: each within (n - 1) u of
 * the exact sum (u = 2^-24, recursive summation), so within (n - 1) 2^-23 of
 * each other, relative. */
static int near(float a, float b, uint32_t n)
{
    double tol = fmax(1.0, (double)n) * 0x1p-23;
    return fabs((double)a - (double)b) <= tol * fmax(fabs((double)a), fabs((double)b));
}

/* Results that differ between the variants (count, radius, or power beyond
 * the sums' rounding); -1 on failure. Writes the mean count to *mean. */
static long count_diff(variant *v, size_t nq, double *mean)
{
    pm_knn_result *r[2] = {malloc(nq * sizeof(pm_knn_result) + 1),
                           malloc(nq * sizeof(pm_knn_result) + 1)};
    long diff = -1;
    size_t got[2] = {0, 0};
    if (r[0] && r[1] && sluice_stream_download(v[0].results, r[0], nq, &got[0]) == SLUICE_OK &&
        sluice_stream_download(v[1].results, r[1], nq, &got[1]) == SLUICE_OK && got[0] == nq &&
        got[1] == nq) {
        diff = 0;
        double sum = 0.0;
        for (size_t i = 0; i < nq; ++i) {
            const pm_knn_result *a = &r[0][i], *b = &r[1][i];
            sum += a->count;
            diff += a->count != b->count || a->r2 != b->r2 || !near(a->sr, b->sr, a->count) ||
                    !near(a->sg, b->sg, a->count) || !near(a->sb, b->sb, a->count);
        }
        *mean = sum / (double)nq;
    }
    free(r[0]);
    free(r[1]);
    return diff;
}

int main(int argc, char **argv)
{
    unsigned np = 65000, nq = 262144, k = 500, pairs = 20, shells = 1;
    uint32_t dims[3] = {0, 0, 0};
    const char *mode = "atleast";
    int hashed = 0;
    variant v[2];
    memset(v, 0, sizeof v);
    v[0].options = v[1].options = "";
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        int ok = 1;
        if (strcmp(a, "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--hashed") == 0) {
            hashed = 1;
            continue;
        } else if (!val) {
            fprintf(stderr, PROG ": %s: unknown option or missing value (try --help)\n", a);
            return 2;
        } else if (strcmp(a, "--photons") == 0)
            ok = bench_parse_uint(val, 1u << 26, &np) && np > 0;
        else if (strcmp(a, "--queries") == 0)
            ok = bench_parse_uint(val, 1u << 26, &nq) && nq > 0;
        else if (strcmp(a, "--k") == 0)
            ok = bench_parse_uint(val, 4096, &k) && k > 0;
        else if (strcmp(a, "--mode") == 0) {
            mode = val;
            ok = strcmp(val, "atleast") == 0 || strcmp(val, "exact") == 0 ||
                 strcmp(val, "radius") == 0;
        } else if (strcmp(a, "--grid") == 0) {
            char x1, x2, end;
            ok = sscanf(val, "%u%c%u%c%u%c", &dims[0], &x1, &dims[1], &x2, &dims[2], &end) == 5 &&
                 x1 == 'x' && x2 == 'x' && dims[0] && dims[1] && dims[2];
        } else if (strcmp(a, "--shells-per-pass") == 0) {
            if (strcmp(val, "all") == 0)
                shells = PM_KNN_ALL_SHELLS;
            else
                ok = bench_parse_uint(val, 1000000, &shells) && shells > 0;
        } else if (strcmp(a, "--pairs") == 0)
            ok = bench_parse_uint(val, 100000, &pairs) && pairs > 0;
        else if (strcmp(a, "--a") == 0 || strcmp(a, "--b") == 0)
            v[a[2] - 'a'].options = val;
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
    if (hashed && strcmp(mode, "atleast") == 0)
        mode = "radius";
    if (hashed && strcmp(mode, "radius") != 0) {
        fprintf(stderr, PROG ": --hashed serves --mode radius only\n");
        return 2;
    }
    if (k > np) {
        fprintf(stderr, PROG ": k = %u is above the %u photons\n", k, np);
        return 2;
    }

    int status = 2;
    pm_photon *ph = calloc(np, sizeof *ph);
    float *pos = malloc((size_t)np * 3 * sizeof *pos);
    pm_query *qs = calloc(nq, sizeof *qs);
    if (!ph || !pos || !qs) {
        fprintf(stderr, PROG ": out of memory\n");
        goto done;
    }
    double area = bench_knn_scene(ph, pos, np, qs, nq);
    /* as bench_knn: the radius that holds k photons at the mean density,
     * twice that the maximum radius */
    float radius = (float)sqrt((double)k * area / ((double)np * 3.14159265358979323846));
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    rt_grid_desc d;
    sr_point_hash_desc hd;
    char err[256];
    if ((hashed ? sr_point_hash_desc_auto(lo, hi, np, 2.0f * radius, &hd, err, sizeof err)
         : dims[0]
             ? sr_point_grid_desc_dims(lo, hi, dims, &d, err, sizeof err)
             : sr_point_grid_desc_auto(lo, hi, np, radius, &d, err, sizeof err)) != SLUICE_OK) {
        fprintf(stderr, PROG ": %s\n", err);
        goto done;
    }
    pm_knn_options o = {k,
                        2.0f * radius,
                        strcmp(mode, "exact") == 0    ? PM_KNN_EXACT
                        : strcmp(mode, "radius") == 0 ? PM_KNN_RADIUS
                                                      : PM_KNN_ATLEAST,
                        0,
                        NULL,
                        NULL,
                        shells};
    if (!variant_create(&v[0], 'A', &d, hashed ? &hd : NULL, ph, np, qs, nq, pairs) ||
        !variant_create(&v[1], 'B', &d, hashed ? &hd : NULL, ph, np, qs, nq, pairs))
        goto done;

    sluice_device_info info;
    bench_machine mach;
    if (sluice_context_device(v[0].ctx, &info) != SLUICE_OK)
        goto done;
    bench_machine_probe(v[0].ctx, &mach);
    printf("device: %s / %s, %u compute units\nCPU: %s (%s), kernels' block emission: %s\n",
           info.platform, info.name, info.compute_units, mach.cpu, mach.isa, mach.block);
    char grid[64];
    if (hashed)
        snprintf(grid, sizeof grid, "hashed");
    else
        snprintf(grid, sizeof grid, "%ux%ux%u", d.dims[0], d.dims[1], d.dims[2]);
    char spp[16];
    if (shells == PM_KNN_ALL_SHELLS)
        snprintf(spp, sizeof spp, "all");
    else
        snprintf(spp, sizeof spp, "%u", shells);
    printf("%u photons, %u queries, k %u, %s mode, grid %s, shells per pass %s; A: '%s', B: '%s'; "
           "%u call pairs (A B, B A)\n",
           np, nq, k, mode, grid, spp, v[0].options, v[1].options, pairs);
    fflush(stdout);

    for (int f = -2; f < (int)pairs; ++f) {
        for (int j = 0; j < 2; ++j) {
            int w = (f & 1) ? 1 - j : j;
            double s = call(&v[w], nq, &o);
            if (s < 0.0)
                goto done;
            if (f >= 0)
                v[w].seconds[f] = s;
        }
    }
    double q[3];
    if (!bench_ab_ratio(v[0].seconds, v[1].seconds, pairs, q)) {
        fprintf(stderr, PROG ": out of memory\n");
        goto done;
    }
    for (int j = 0; j < 2; ++j)
        printf("%c: best %.2f, median %.2f ms\n", "AB"[j], 1e3 * v[j].seconds[0],
               1e3 * v[j].seconds[pairs / 2]);
    printf("B over A, median over call pairs: %.3f (quartiles %.3f, %.3f)\n", q[1], q[0], q[2]);
    double mean = 0.0;
    long diff = count_diff(v, nq, &mean);
    if (diff < 0) {
        fprintf(stderr, PROG ": reading the results: %s\n", sluice_context_error(v[0].ctx));
        goto done;
    }
    printf("photons per estimate %.1f; results that differ: %ld of %u\n", mean, diff, nq);
    status = diff ? 1 : 0;
done:
    variant_free(&v[1]);
    variant_free(&v[0]);
    free(ph);
    free(pos);
    free(qs);
    return status;
}
