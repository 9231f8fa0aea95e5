/*
 * bench_knn: k-nearest-neighbour queries per second of the kNN-grid
 * (apps/photonmap/knn.h, Purcell 6.2.3: point-grid build by counting sort +
 * query) against FLANN's exact single kd-tree (FLANN_INDEX_KDTREE_SINGLE:
 * build + k-nearest search), in one run, on the same photons, queries and k.
 * The photons lie on the surfaces of a Cornell-box-like scene (five walls of
 * the unit box, two boxes, a bright caustic-like spot on the floor); the
 * queries are points on the same surfaces (what eye rays would hit).
 *
 * Times are the best of --reps runs after a warm-up (which also compiles
 * the kernels). The kNN-grid runs both of its modes; "qps" is queries /
 * (build + query) seconds. Its max radius is twice the radius that holds k
 * photons at the mean density, and its grid cells are that mean radius
 * (sr_point_grid_desc_auto). FLANN searches without a radius limit (its
 * k-nearest search has none), with `cores` threads. The exact mode's k-th
 * distance is checked against FLANN's for every query whose k-th neighbour
 * lies within the max radius; the exit status is 1 on a mismatch.
 *
 *   bench_knn [--photons N] [--queries N] [--k K]... [--reps R] [--quick]
 *             [--edge F] [--out FILE]
 *
 * --edge scales the radius given to sr_point_grid_desc_auto (cells of F
 * times the mean k-photon radius; default 1), to measure the grid choice.
 */
#include "bench_args.h"
#include "bench_knn_scene.h"
#include "bench_machine.h"
#include "knn.h"

#include <flann/flann.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_K 8

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct result {
    unsigned k;
    float radius, max_radius;
    double build_s, atleast_s, exact_s, flann_build_s, flann_query_s;
    double mean_count, mean_count_exact;
    unsigned passes;
    uint32_t dims[3];
    size_t mismatches, checked;
} result;

static double edge_scale = 1.0;

static int run(sr_point_grid *grid, pm_knn *knn, const float *pos, sluice_stream *sp, size_t np,
               const pm_query *qs, sluice_stream *sq, size_t nq, sluice_stream *sr, double area,
               unsigned k, unsigned reps, result *r)
{
    memset(r, 0, sizeof *r);
    r->k = k;
    /* the radius that holds k photons at the mean density */
    r->radius = (float)sqrt((double)k * area / ((double)np * 3.14159265358979323846));
    r->max_radius = 2.0f * r->radius;
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    rt_grid_desc d;
    char err[256];
    if (sr_point_grid_desc_auto(lo, hi, np, r->radius * (float)edge_scale, &d, err, sizeof err) !=
        SLUICE_OK) {
        fprintf(stderr, "bench_knn: %s\n", err);
        return 0;
    }
    memcpy(r->dims, d.dims, sizeof r->dims);
    pm_knn_options o = {k, r->max_radius, PM_KNN_ATLEAST, 0, NULL, NULL, 0};
    pm_knn_stats st;
    r->build_s = r->atleast_s = r->exact_s = 1e30;
    for (unsigned rep = 0; rep <= reps; ++rep) {
        double t0 = now();
        if (sr_point_grid_build(grid, &d, sp, sizeof(pm_photon), np, SR_POINT_GRID_COUNT, 0) !=
            SLUICE_OK) {
            fprintf(stderr, "bench_knn: %s\n", sr_point_grid_error(grid));
            return 0;
        }
        double t1 = now();
        o.mode = PM_KNN_ATLEAST;
        sluice_status s = pm_knn_query(knn, grid, sp, sq, nq, sr, &o, NULL);
        double t2 = now();
        o.mode = PM_KNN_EXACT;
        if (s == SLUICE_OK)
            s = pm_knn_query(knn, grid, sp, sq, nq, sr, &o, NULL);
        double t3 = now();
        if (s != SLUICE_OK) {
            fprintf(stderr, "bench_knn: %s\n", pm_knn_error(knn));
            return 0;
        }
        if (rep == 0)
            continue; /* warm-up */
        r->build_s = fmin(r->build_s, t1 - t0);
        r->atleast_s = fmin(r->atleast_s, t2 - t1);
        r->exact_s = fmin(r->exact_s, t3 - t2);
    }
    o.mode = PM_KNN_ATLEAST;
    if (pm_knn_query(knn, grid, sp, sq, nq, sr, &o, &st) != SLUICE_OK)
        return 0;
    r->mean_count = st.mean_count;
    r->passes = st.passes;
    o.mode = PM_KNN_EXACT;
    if (pm_knn_query(knn, grid, sp, sq, nq, sr, &o, &st) != SLUICE_OK)
        return 0;
    r->mean_count_exact = st.mean_count;
    pm_knn_result *res = malloc(nq * sizeof *res);
    if (!res || sluice_stream_download(sr, res, nq, NULL) != SLUICE_OK) {
        free(res);
        return 0;
    }

    /* FLANN: build + k nearest, same photons and queries */
    struct FLANNParameters fp = DEFAULT_FLANN_PARAMETERS;
    fp.algorithm = FLANN_INDEX_KDTREE_SINGLE;
    fp.checks = FLANN_CHECKS_UNLIMITED;
    fp.eps = 0.0f;
    fp.sorted = 1;
    fp.leaf_max_size = 10;
    fp.cores = 2;
    fp.log_level = FLANN_LOG_NONE;
    float *qp = malloc(nq * 3 * sizeof *qp);
    int *idx = malloc(nq * (size_t)k * sizeof *idx);
    float *dist = malloc(nq * (size_t)k * sizeof *dist);
    int ok = qp && idx && dist;
    for (size_t i = 0; ok && i < nq; ++i) {
        qp[3 * i] = qs[i].px;
        qp[3 * i + 1] = qs[i].py;
        qp[3 * i + 2] = qs[i].pz;
    }
    r->flann_build_s = r->flann_query_s = 1e30;
    for (unsigned rep = 0; ok && rep <= reps; ++rep) {
        float speedup;
        double t0 = now();
        flann_index_t index = flann_build_index_float((float *)pos, (int)np, 3, &speedup, &fp);
        double t1 = now();
        ok = index != NULL && flann_find_nearest_neighbors_index_float(index, qp, (int)nq, idx,
                                                                       dist, (int)k, &fp) == 0;
        double t2 = now();
        if (index)
            flann_free_index_float(index, &fp);
        if (rep == 0)
            continue;
        r->flann_build_s = fmin(r->flann_build_s, t1 - t0);
        r->flann_query_s = fmin(r->flann_query_s, t2 - t1);
    }
    /* the exact mode's radius is FLANN's k-th distance */
    float max_r2 = r->max_radius * r->max_radius;
    for (size_t i = 0; ok && i < nq; ++i) {
        float kth = dist[i * k + k - 1];
        if (!(kth <= max_r2 * (1.0f - 1e-5f)))
            continue;
        r->checked++;
        if (res[i].count != k || fabsf(res[i].r2 - kth) > 1e-5f * kth)
            r->mismatches++;
    }
    free(res);
    free(qp);
    free(idx);
    free(dist);
    return ok;
}

int main(int argc, char **argv)
{
    unsigned np = 65000, nq = 262144, reps = 3, ks[MAX_K], nk = 0;
    const char *out = NULL;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--quick") == 0) {
            np = 8000;
            nq = 8192;
            reps = 1;
        } else if (strcmp(a, "--photons") == 0 && bench_parse_uint(v, 1u << 26, &np) && np) {
            ++i;
        } else if (strcmp(a, "--queries") == 0 && bench_parse_uint(v, 1u << 26, &nq) && nq) {
            ++i;
        } else if (strcmp(a, "--reps") == 0 && bench_parse_uint(v, 1000, &reps) && reps) {
            ++i;
        } else if (strcmp(a, "--k") == 0 && nk < MAX_K && bench_parse_uint(v, 4096, &ks[nk]) &&
                   ks[nk]) {
            ++nk;
            ++i;
        } else if (strcmp(a, "--edge") == 0 && v && atof(v) > 0.0) {
            edge_scale = atof(v);
            ++i;
        } else if (strcmp(a, "--out") == 0 && v) {
            out = v;
            ++i;
        } else {
            fprintf(stderr, "usage: bench_knn [--photons N] [--queries N] [--k K]... [--reps R] "
                            "[--quick] [--edge F] [--out FILE]\n");
            return 2;
        }
    }
    if (nk == 0) {
        ks[nk++] = 32;
        ks[nk++] = 64;
        ks[nk++] = 500;
    }
    for (unsigned i = 0; i < nk; ++i)
        if (ks[i] > np) {
            fprintf(stderr, "bench_knn: k = %u is above the %u photons\n", ks[i], np);
            return 2;
        }

    pm_photon *ph = calloc(np, sizeof *ph);
    float *pos = malloc((size_t)np * 3 * sizeof *pos);
    pm_query *qs = calloc(nq, sizeof *qs);
    if (!ph || !pos || !qs) {
        fprintf(stderr, "bench_knn: out of memory\n");
        return 1;
    }
    double area = bench_knn_scene(ph, pos, np, qs, nq);

    char err[512];
    sluice_context *ctx = NULL;
    if (sluice_context_create(NULL, &ctx, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "bench_knn: %s\n", err);
        return 1;
    }
    sluice_device_info dev;
    sluice_context_device(ctx, &dev);
    bench_machine mach;
    bench_machine_probe(ctx, &mach);
    const char *cpu = mach.cpu;
    sr_point_grid *grid = NULL;
    pm_knn *knn = NULL;
    sluice_stream *sp = NULL, *sq = NULL, *sr = NULL;
    int ok = sr_point_grid_create(ctx, &grid) == SLUICE_OK &&
             pm_knn_create(ctx, &knn) == SLUICE_OK &&
             sluice_stream_create(ctx, sizeof *ph, np, &sp) == SLUICE_OK &&
             sluice_stream_create(ctx, sizeof *qs, nq, &sq) == SLUICE_OK &&
             sluice_stream_create(ctx, sizeof(pm_knn_result), nq, &sr) == SLUICE_OK &&
             sluice_stream_upload(sp, ph, np) == SLUICE_OK &&
             sluice_stream_upload(sq, qs, nq) == SLUICE_OK;
    if (!ok)
        fprintf(stderr, "bench_knn: setup: %s\n", sluice_context_error(ctx));
    result res[MAX_K];
    size_t mismatches = 0;
    printf("bench_knn: %u photons, %u queries, CPU %s (%s, kernels: %s), device %s\n", np, nq, cpu,
           mach.isa, mach.block, dev.name);
    printf("%5s %8s %12s %10s %10s %10s %12s %12s %8s %8s\n", "k", "grid", "build ms", "atleast ms",
           "exact ms", "mean n", "FLANN b ms", "FLANN q ms", "atleast", "exact");
    for (unsigned i = 0; ok && i < nk; ++i) {
        result *r = &res[i];
        ok = run(grid, knn, pos, sp, np, qs, sq, nq, sr, area, ks[i], reps, r);
        if (!ok)
            break;
        double flann = r->flann_build_s + r->flann_query_s;
        char dims[32];
        snprintf(dims, sizeof dims, "%ux%ux%u", r->dims[0], r->dims[1], r->dims[2]);
        printf("%5u %8s %12.2f %10.2f %10.2f %10.1f %12.2f %12.2f %7.2fx %7.2fx\n", r->k, dims,
               1e3 * r->build_s, 1e3 * r->atleast_s, 1e3 * r->exact_s, r->mean_count,
               1e3 * r->flann_build_s, 1e3 * r->flann_query_s, flann / (r->build_s + r->atleast_s),
               flann / (r->build_s + r->exact_s));
        if (r->mismatches)
            fprintf(stderr, "bench_knn: k = %u: %zu of %zu exact radii differ from FLANN\n", r->k,
                    r->mismatches, r->checked);
        mismatches += r->mismatches;
    }
    if (ok && out) {
        FILE *f = fopen(out, "w");
        if (!f) {
            fprintf(stderr, "bench_knn: cannot write %s\n", out);
            ok = 0;
        } else {
            fprintf(f,
                    "{\n  \"cpu\": \"%s\",\n  \"cpu_isa\": \"%s\",\n  \"kernel_block_path\": "
                    "\"%s\",\n  \"device\": \"%s\",\n  \"photons\": %u,\n  "
                    "\"queries\": %u,\n  \"reps\": %u,\n  \"flann\": \"KDTREE_SINGLE, eps 0, "
                    "leaf 10, cores 2, no radius limit\",\n  \"results\": [\n",
                    cpu, mach.isa, mach.block, dev.name, np, nq, reps);
            for (unsigned i = 0; i < nk; ++i) {
                result *r = &res[i];
                double flann = r->flann_build_s + r->flann_query_s;
                fprintf(f,
                        "    {\"k\": %u, \"radius\": %.5f, \"max_radius\": %.5f, \"grid\": [%u, "
                        "%u, %u], \"build_s\": %.6f, \"atleast_query_s\": %.6f, "
                        "\"exact_query_s\": %.6f, \"atleast_qps\": %.0f, \"exact_qps\": %.0f, "
                        "\"mean_photons_atleast\": %.2f, \"mean_photons_exact\": %.2f, "
                        "\"passes_atleast\": %u, \"flann_build_s\": %.6f, \"flann_query_s\": "
                        "%.6f, \"flann_qps\": %.0f, \"speedup_atleast\": %.3f, "
                        "\"speedup_exact\": %.3f, \"exact_checked\": %zu, \"exact_mismatches\": "
                        "%zu}%s\n",
                        r->k, (double)r->radius, (double)r->max_radius, r->dims[0], r->dims[1],
                        r->dims[2], r->build_s, r->atleast_s, r->exact_s,
                        nq / (r->build_s + r->atleast_s), nq / (r->build_s + r->exact_s),
                        r->mean_count, r->mean_count_exact, r->passes, r->flann_build_s,
                        r->flann_query_s, nq / flann, flann / (r->build_s + r->atleast_s),
                        flann / (r->build_s + r->exact_s), r->checked, r->mismatches,
                        i + 1 < nk ? "," : "");
            }
            fprintf(f, "  ]\n}\n");
            fclose(f);
        }
    }
    sluice_stream_destroy(sp);
    sluice_stream_destroy(sq);
    sluice_stream_destroy(sr);
    pm_knn_destroy(knn);
    sr_point_grid_destroy(grid);
    sluice_context_destroy(ctx);
    free(ph);
    free(pos);
    free(qs);
    return ok && mismatches == 0 ? 0 : 1;
}
