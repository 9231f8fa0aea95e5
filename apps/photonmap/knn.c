/* The kNN-grid search (knn.h; Purcell 6.2.3), kernels in
 * kernels/photonmap/pm_knn.cl. Per batch of queries:
 *
 *   pm_knn_gather  (once per call) the photons copied in cell order, power
 *                  redistribution applied, so a cell is one contiguous run;
 *                  planes of x, y, z, ... (structure of arrays), which the
 *                  search reads in blocks of PM_MAP_BLOCK
 *   pm_knn_bounds  (once per call) the photons' bounding box, a lower bound
 *                  on every distance beside the shells'
 *   pm_knn_sat_*   (once per call) the summed-count table over the cells,
 *                  with which a pass jumps over shells without photons
 *   pm_knn_order_keys + radix sort
 *                  (once per call) the search order: the queries by cell,
 *                  so that consecutive queries share cached photons
 *   pm_knn_init    live = the batch's places in that order (results zeroed
 *                  once per call, all of them)
 *   loop           while the live stream is not empty (sluice_loop watching
 *                  its length: Purcell's occlusion query, 6.3.3):
 *                    pm_knn_pass  one more shell per live query; or, in
 *                                 at-least mode with all shells in one pass
 *                                 (one pass), pm_knn_reach: the search up to
 *                                 the k-th photon, the queries of one cell
 *                                 in lockstep, PM_KNN_SUM_QUERIES at most
 *                    pm_knn_sum   (the same one pass) the estimates of the
 *                                 queries that reached k photons,
 *                                 PM_KNN_SUM_QUERIES side by side
 *                    pm_knn_live  the ids not done into `next`; swap
 *
 * The per-query state between passes is the result record itself (sums,
 * count, r^2, shells, flags) and, in exact mode, the heap. Atleast mode runs
 * all queries in one batch; exact mode in batches whose heaps fit
 * PM_KNN_EXACT_HEAP_BYTES.
 *
 * A hashed grid (Purcell 6.4.4; radius mode only) shares the gather and the
 * bounds (buckets for cells) and then needs no summed counts and no loop:
 * pm_knn_hash answers every query in one launch, one pass. */
#include "knn.h"

#include "app_error.h"
#include "kernels.h"
#include "sluice/streams.h"

#include "../../kernels/render/pg_types.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Arguments of pm_knn_pass after SLUICE_PARAMS. */
enum {
    PASS_LIVE,
    PASS_ORDER,
    PASS_QUERIES,
    PASS_MAP,
    PASS_MAP_START,
    PASS_COUNT,
    PASS_SAT,
    PASS_GRID,
    PASS_PARAMS,
    PASS_EXACT,
    PASS_BASE,
    PASS_RESULTS,
    PASS_HEAP_D2,
    PASS_HEAP_ID,
    PASS_INDICES
};

struct pm_knn {
    sluice_context *ctx;
    sluice_program *prog;
    sluice_kernel *k_gather, *k_bounds, *k_sat[3], *k_order, *k_sortq, *k_unsort, *k_init, *k_pass,
        *k_live, *k_hash, *k_sum, *k_reach;
    int sum_after; /* this call is one pass: pm_knn_reach, then pm_knn_sum */
    sluice_loop *loop;
    /* scratch kept between calls; streams only grow */
    sluice_stream *live, *next, *heap_d2, *heap_id, *dummy;
    sluice_stream *map, *map_start; /* the cell-ordered copy of the photons */
    sluice_stream *box;             /* its bounding box: lo xyz, hi xyz */
    sluice_stream *sat;             /* summed counts: skips shells without photons */
    /* what the copy, its box and the summed counts were made from: a call
     * with the same grid build and photons reuses them (copy_made) */
    int copy_made;
    const sr_point_grid *copy_grid;
    uint64_t copy_build;
    sluice_stream *copy_photons;
    float copy_box[6];
    sluice_stream *order_keys, *order; /* the search order: queries by cell */
    sluice_stream *qsorted, *rsorted;  /* queries and results in that order */
    /* the current call's pass hook */
    pm_knn_pass_fn on_pass;
    void *on_pass_user;
    unsigned passes_before; /* passes of the earlier batches */
    size_t answered;        /* results current: all of the call's (zeroed first) */
    char message[512];
};

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Records why a call failed in knn->message and evaluates to `st`. */
#define FAIL(knn, st, ...) (sr_set_error((knn)->message, sizeof(knn)->message, __VA_ARGS__), (st))

/* One pass of the loop. */
static sluice_status knn_pass(void *user, unsigned pass, unsigned choice)
{
    (void)choice;
    pm_knn *knn = user;
    sluice_status st = sluice_stream_clear(knn->next);
    if (st == SLUICE_OK)
        st = knn->sum_after
                 ? sluice_kernel_launch_count(
                       knn->k_reach, (knn->answered + PM_KNN_SUM_QUERIES - 1) / PM_KNN_SUM_QUERIES)
                 : sluice_kernel_launch(knn->k_pass);
    if (st == SLUICE_OK && knn->sum_after)
        st = sluice_kernel_launch_count(knn->k_sum, (knn->answered + PM_KNN_SUM_QUERIES - 1) /
                                                        PM_KNN_SUM_QUERIES);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(knn->k_live);
    if (st == SLUICE_OK)
        st = sluice_stream_swap(knn->live, knn->next);
    /* the hook reads the results in the queries' order */
    if (st == SLUICE_OK && knn->on_pass)
        st = sluice_kernel_launch_count(knn->k_unsort, knn->answered);
    if (st == SLUICE_OK && knn->on_pass)
        st = knn->on_pass(knn->on_pass_user, knn->passes_before + pass, knn->answered);
    return st;
}

/* Goes on while queries are live. */
static unsigned knn_oracle(void *user, unsigned pass, const uint32_t *values, size_t count)
{
    (void)user;
    (void)pass;
    (void)count;
    return values[0] ? 0u : SLUICE_LOOP_STOP;
}

void pm_knn_destroy(pm_knn *knn)
{
    if (!knn)
        return;
    sluice_loop_destroy(knn->loop);
    sluice_kernel_destroy(knn->k_gather);
    sluice_kernel_destroy(knn->k_bounds);
    for (int a = 0; a < 3; ++a)
        sluice_kernel_destroy(knn->k_sat[a]);
    sluice_kernel_destroy(knn->k_order);
    sluice_kernel_destroy(knn->k_sortq);
    sluice_kernel_destroy(knn->k_unsort);
    sluice_kernel_destroy(knn->k_init);
    sluice_kernel_destroy(knn->k_pass);
    sluice_kernel_destroy(knn->k_live);
    sluice_kernel_destroy(knn->k_hash);
    sluice_kernel_destroy(knn->k_sum);
    sluice_kernel_destroy(knn->k_reach);
    sluice_program_destroy(knn->prog);
    sluice_stream_destroy(knn->live);
    sluice_stream_destroy(knn->next);
    sluice_stream_destroy(knn->heap_d2);
    sluice_stream_destroy(knn->heap_id);
    sluice_stream_destroy(knn->dummy);
    sluice_stream_destroy(knn->map);
    sluice_stream_destroy(knn->map_start);
    sluice_stream_destroy(knn->box);
    sluice_stream_destroy(knn->sat);
    sluice_stream_destroy(knn->order_keys);
    sluice_stream_destroy(knn->order);
    sluice_stream_destroy(knn->qsorted);
    sluice_stream_destroy(knn->rsorted);
    free(knn);
}

sluice_status pm_knn_create(sluice_context *ctx, pm_knn **out)
{
    if (!out)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    pm_knn *knn = calloc(1, sizeof *knn);
    if (!knn)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    knn->ctx = ctx;
    sluice_status st = sr_shared_program_create(
        ctx, (const char *[]){"rt_types.h", "pg_types.h", "pm_types.h", "pm_knn.cl"}, 4, NULL,
        &knn->prog);
    /* the scans of the cell counts and the sort of the queries by cell,
     * built now rather than in the first estimate */
    if (st == SLUICE_OK)
        st = sluice_streams_prepare(ctx, SLUICE_ALG_SCAN | SLUICE_ALG_SORT_RADIX);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_gather", &knn->k_gather);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_bounds", &knn->k_bounds);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(float), 6, &knn->box);
    static const char *const sat_names[3] = {"pm_knn_sat_x", "pm_knn_sat_y", "pm_knn_sat_z"};
    for (int a = 0; st == SLUICE_OK && a < 3; ++a)
        st = sluice_kernel_create(knn->prog, sat_names[a], &knn->k_sat[a]);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_order_keys", &knn->k_order);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_sort_queries", &knn->k_sortq);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_unsort_results", &knn->k_unsort);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_init", &knn->k_init);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_pass", &knn->k_pass);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_live", &knn->k_live);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_hash", &knn->k_hash);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_sum", &knn->k_sum);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(knn->prog, "pm_knn_reach", &knn->k_reach);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, 4, 1, &knn->live);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, 4, 1, &knn->next);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, 4, 1, &knn->dummy);
    if (st == SLUICE_OK) {
        sluice_loop_desc d = {0};
        d.pass = knn_pass;
        d.oracle = knn_oracle;
        d.user = knn;
        d.streams = &knn->live;
        d.stream_count = 1;
        /* each pass adds a shell: a grid has fewer than 2^21 cells a side */
        d.max_passes = 1u << 21;
        st = sluice_loop_create(ctx, &d, &knn->loop);
    }
    if (st != SLUICE_OK) {
        pm_knn_destroy(knn);
        return st;
    }
    *out = knn;
    return SLUICE_OK;
}

const char *pm_knn_error(const pm_knn *knn)
{
    return knn ? knn->message : "NULL kNN search";
}

/* Makes *s a stream of records of `size` with at least `cap` records. */
static sluice_status ensure(sluice_context *ctx, sluice_stream **s, size_t size, size_t cap)
{
    if (cap == 0)
        cap = 1;
    if (*s && sluice_stream_capacity(*s) >= cap)
        return SLUICE_OK;
    sluice_stream_destroy(*s);
    *s = NULL;
    return sluice_stream_create(ctx, size, cap, s);
}

/* Checks a stream argument: record size and at least `n` records. */
static sluice_status check_stream(pm_knn *knn, sluice_stream *s, const char *what, size_t size,
                                  size_t n, int need_length)
{
    if (!s)
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT, "kNN: NULL %s stream", what);
    if (sluice_stream_record_size(s) != size)
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT,
                    "kNN: %s records are %zu bytes, %zu expected", what,
                    sluice_stream_record_size(s), size);
    size_t have = sluice_stream_capacity(s);
    if (need_length) {
        sluice_status st = sluice_stream_length(s, &have);
        if (st != SLUICE_OK)
            return FAIL(knn, st, "kNN: %s", sluice_context_error(knn->ctx));
    }
    if (have < n)
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT, "kNN: %s holds %zu records, %zu needed",
                    what, have, n);
    return SLUICE_OK;
}

/* Fills the kernels' description of the search. The margin bounds how far
 * the float cell function can misplace a point across a cell face: a few
 * ulps of (x - lo) / cell, which is at most dims, in cell units, plus the
 * rounding of the coordinates themselves. */
static void params_make(const sr_point_grid_view *v, const pm_knn_options *o, uint32_t cap,
                        uint32_t map_stride, pg_params *g, pm_knn_params *p)
{
    memset(g, 0, sizeof *g);
    memset(p, 0, sizeof *p);
    for (int a = 0; a < 3 && v->layout == SR_POINT_GRID_HASHED; ++a) {
        /* only pm_box_d2 reads it there (a bound that holds without it:
         * the box's faces are photons' own coordinates) */
        double mag = fabs((double)v->hash.lo[a]);
        p->margin[a] = (float)((double)v->hash.cell * 0x1p-12 + mag * 0x1p-20);
    }
    for (int a = 0; a < 3 && v->layout == SR_POINT_GRID_DENSE; ++a) {
        g->lo[a] = v->desc.lo[a];
        g->cell[a] = v->desc.cell[a];
        g->inv_cell[a] = 1.0f / v->desc.cell[a];
        g->dims[a] = v->desc.dims[a];
        double mag = fmax(fabs((double)v->desc.lo[a]), fabs((double)v->desc.hi[a]));
        p->margin[a] =
            (float)((double)v->desc.cell[a] * ((double)v->desc.dims[a] * 0x1p-20 + 0x1p-12) +
                    mag * 0x1p-20);
    }
    g->cells = v->layout == SR_POINT_GRID_DENSE ? v->cells : 0u;
    g->stride = sizeof(pm_photon) / 4;
    g->slots = v->slots;
    /* radius mode: the at-least search never full, so every photon within
     * the maximum radius */
    p->k = o->mode == PM_KNN_RADIUS ? UINT32_MAX : o->k;
    p->max_r2 = o->max_radius * o->max_radius;
    p->normal_filter = o->normal_filter ? 1u : 0u;
    p->index_cap = cap;
    p->map_stride = map_stride;
    p->shells_per_pass = o->shells_per_pass == PM_KNN_ALL_SHELLS
                             ? 0u
                             : (o->shells_per_pass ? o->shells_per_pass : 1u);
}

/* Reads the results back into the statistics' means and counts. */
static sluice_status results_stats(pm_knn *knn, sluice_stream *results, size_t n,
                                   pm_knn_stats *stats)
{
    pm_knn_result *r = malloc((n ? n : 1) * sizeof *r);
    if (!r)
        return FAIL(knn, SLUICE_ERROR_OUT_OF_MEMORY, "kNN: statistics: out of host memory");
    sluice_status st = sluice_stream_download(results, r, n, NULL);
    double sum_count = 0.0, sum_radius = 0.0;
    size_t with = 0;
    for (size_t i = 0; st == SLUICE_OK && i < n; ++i) {
        sum_count += r[i].count;
        if (r[i].count) {
            sum_radius += sqrt((double)r[i].r2);
            ++with;
        } else {
            stats->empty++;
        }
        if (r[i].flags & PM_KNN_HIT_MAX_RADIUS)
            stats->hit_max_radius++;
    }
    free(r);
    if (st != SLUICE_OK)
        return FAIL(knn, st, "kNN: statistics: %s", sluice_context_error(knn->ctx));
    stats->queries = n;
    stats->mean_count = n ? sum_count / (double)n : 0.0;
    stats->mean_radius = with ? sum_radius / (double)with : 0.0;
    return SLUICE_OK;
}

/* The radius search over a hashed grid (the map already gathered): one
 * launch of pm_knn_hash, one pass; n > 0. */
static sluice_status query_hashed(pm_knn *knn, const sr_point_grid_view *v,
                                  sluice_stream *map_start, sluice_stream *queries, size_t n,
                                  sluice_stream *results, const pm_knn_options *o,
                                  const pm_knn_params *p, sluice_stream *indices, uint32_t cap,
                                  pm_knn_stats *stats, double t0)
{
    pg_hash_params h;
    memset(&h, 0, sizeof h);
    for (int a = 0; a < 3; ++a)
        h.lo[a] = v->hash.lo[a];
    h.cell = v->hash.cell;
    h.inv_cell = 1.0f / v->hash.cell;
    h.mask = v->hash.buckets - 1u;
    h.buckets = v->hash.buckets;
    h.stride = sizeof(pm_photon) / 4;
    sluice_kernel *k = knn->k_hash;
    sluice_status st = sluice_kernel_set_stream(k, 0, queries, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, knn->map, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 2, map_start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 3, v->cell_count, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 4, sizeof h, &h);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 5, sizeof *p, p);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 6, results, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 7, indices ? indices : knn->dummy, 0);
    /* the length first: a pass hook may read the results */
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(results, n);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, n);
    if (st == SLUICE_OK && indices)
        st = sluice_stream_set_length(indices, n * cap);
    if (st == SLUICE_OK)
        st = sluice_context_finish(knn->ctx);
    if (st != SLUICE_OK) {
        if (st == SLUICE_ERROR_OUT_OF_MEMORY && !*sluice_context_error(knn->ctx))
            return FAIL(knn, st, "kNN: searching the hashed grid: out of memory");
        return FAIL(knn, st, "kNN: searching the hashed grid: %s", sluice_context_error(knn->ctx));
    }
    /* one pass: the hook sees every result final */
    if (o->on_pass) {
        st = o->on_pass(o->on_pass_user, 0, n);
        if (st != SLUICE_OK)
            return FAIL(knn, st, "kNN: the pass hook failed (%s)", sluice_status_string(st));
    }
    if (stats) {
        stats->passes = 1;
        stats->batches = 1;
        st = results_stats(knn, results, n, stats);
        if (st != SLUICE_OK)
            return st;
        stats->seconds = now() - t0;
    }
    return SLUICE_OK;
}

/* The cell-ordered copy of the photons of grid view v (map, map_start)
 * and its bounding box (copy_box), `stride` floats a plane. Cells go back
 * to back in cell order, so that a run of cells along x is one run of
 * photons (the stencil build's footprints have gaps, and the bitonic
 * build's starts of empty cells are not needed to be in order). The
 * photons' box bounds every distance: queries far from all photons (on
 * the walls over glassball's floor) end at once. */
static sluice_status copy_map(pm_knn *knn, const sr_point_grid_view *v, sluice_stream *photons,
                              size_t stride, uint32_t stored)
{
    uint32_t stride32 = (uint32_t)stride;
    sluice_status st = ensure(knn->ctx, &knn->map, sizeof(float), stride * PM_MAP_PLANES);
    if (st == SLUICE_OK)
        st = ensure(knn->ctx, &knn->map_start, 4, v->cells);
    if (st == SLUICE_OK)
        st = sluice_scan(knn->ctx, v->cell_count, knn->map_start, SLUICE_U32, 0, NULL);
    sluice_stream *gather_in[] = {v->order,       v->cell_start, v->cell_count, v->cell_arrived,
                                  knn->map_start, photons,       knn->map};
    for (unsigned i = 0; st == SLUICE_OK && i < 7; ++i)
        st = sluice_kernel_set_stream(knn->k_gather, i, gather_in[i], 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(knn->k_gather, 7, sizeof stride32, &stride32);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(knn->k_gather, v->cells);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(knn->map, stride * PM_MAP_PLANES);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(knn->k_bounds, 0, knn->map, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(knn->k_bounds, 1, sizeof stride32, &stride32);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(knn->k_bounds, 2, sizeof stored, &stored);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(knn->k_bounds, 3, knn->box, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(knn->k_bounds, 6);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(knn->box, 6);
    if (st == SLUICE_OK)
        st = sluice_stream_download(knn->box, knn->copy_box, 6, NULL);
    return st;
}

/* The summed-count table of the dense grid's cells (pm_sat_at): running
 * sums along x, then y, then z. */
static sluice_status sum_counts(pm_knn *knn, const sr_point_grid_view *v, const pg_params *g)
{
    sluice_status st = ensure(knn->ctx, &knn->sat, 4, v->cells);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(knn->k_sat[0], 0, v->cell_count, 0);
    for (int a = 0; st == SLUICE_OK && a < 3; ++a) {
        sluice_kernel *ks = knn->k_sat[a];
        unsigned first = a == 0 ? 1u : 0u;
        /* lines across the axis: the product of the other two sides */
        size_t lines = (size_t)v->cells / g->dims[a];
        st = sluice_kernel_set_arg(ks, first, sizeof *g, g);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(ks, first + 1, knn->sat, 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch_count(ks, lines);
    }
    return st;
}

/* Notes what the cell-ordered copy, its box and the summed counts were
 * made from (query reuses them while these stay the same). */
static void note_copy(pm_knn *knn, const sr_point_grid *grid, const sr_point_grid_view *v,
                      sluice_stream *photons)
{
    knn->copy_made = 1;
    knn->copy_grid = grid;
    knn->copy_build = v->build;
    knn->copy_photons = photons;
}

static sluice_status query(pm_knn *knn, const sr_point_grid *grid, sluice_stream *photons,
                           sluice_stream *queries, size_t n, sluice_stream *results,
                           const pm_knn_options *o, sluice_stream *indices, uint32_t cap,
                           pm_knn_stats *stats)
{
    double t0 = now();
    knn->message[0] = '\0';
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (!grid || !o)
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT, "kNN: NULL argument");
    if (o->mode != PM_KNN_RADIUS && (o->k == 0 || o->k > PM_KNN_MAX_K))
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT, "kNN: k = %u (1 .. %u allowed)", o->k,
                    PM_KNN_MAX_K);
    if (!(o->max_radius > 0.0f)) /* also NaN; INFINITY is fine */
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT, "kNN: the maximum radius must be > 0");
    if (o->mode != PM_KNN_ATLEAST && o->mode != PM_KNN_EXACT && o->mode != PM_KNN_RADIUS)
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT, "kNN: unknown mode %d", (int)o->mode);
    if (n > UINT32_MAX / 2)
        return FAIL(knn, SLUICE_ERROR_LIMIT, "kNN: %zu queries exceed the limit of %u", n,
                    UINT32_MAX / 2);
    sr_point_grid_view v;
    sluice_status st = sr_point_grid_get(grid, &v);
    if (st != SLUICE_OK || !v.order || !v.cells)
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT, "kNN: the point grid is not built");
    const int hashed = v.layout == SR_POINT_GRID_HASHED;
    if (hashed && o->mode != PM_KNN_RADIUS)
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT,
                    "kNN: a hashed point grid answers the radius search only (the k-nearest "
                    "searches need the dense grid)");
    if (hashed && !isfinite(o->max_radius))
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT,
                    "kNN: the radius search over a hashed point grid needs a finite radius");
    st = check_stream(knn, photons, "photon", sizeof(pm_photon), v.points, 1);
    if (st == SLUICE_OK)
        st = check_stream(knn, queries, "query", sizeof(pm_query), n, 1);
    if (st == SLUICE_OK)
        st = check_stream(knn, results, "result", sizeof(pm_knn_result), n, 0);
    if (st == SLUICE_OK && indices) {
        if (cap == 0 || (uint64_t)n * cap > UINT32_MAX)
            return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT,
                        "kNN: an index list of %u places per query for %zu queries", cap, n);
        st = check_stream(knn, indices, "index", 4, n * cap, 0);
    }
    if (st != SLUICE_OK)
        return st;
    if (n == 0) {
        /* nothing to search: the map is not even copied */
        st = sluice_stream_set_length(results, 0);
        if (st == SLUICE_OK && indices)
            st = sluice_stream_set_length(indices, 0);
        if (st != SLUICE_OK)
            return FAIL(knn, st, "kNN: %s", sluice_context_error(knn->ctx));
        if (stats)
            stats->seconds = now() - t0;
        return SLUICE_OK;
    }

    uint32_t exact = o->mode == PM_KNN_EXACT;
    size_t batch = n;
    if (exact) {
        size_t per = (size_t)o->k * 8;
        size_t fit = PM_KNN_EXACT_HEAP_BYTES / per;
        if (fit < 1)
            fit = 1;
        if (batch > fit)
            batch = fit;
    }
    const char *step = "allocating scratch";
    st = ensure(knn->ctx, &knn->live, 4, batch);
    if (st == SLUICE_OK)
        st = ensure(knn->ctx, &knn->next, 4, batch);
    if (st == SLUICE_OK && exact)
        st = ensure(knn->ctx, &knn->heap_d2, 4, batch * o->k);
    if (st == SLUICE_OK && exact)
        st = ensure(knn->ctx, &knn->heap_id, 4, batch * o->k);
    if (st != SLUICE_OK)
        goto runtime_fail;

    step = "copying the map in cell order";
    const int reuse = knn->copy_made && knn->copy_grid == grid && knn->copy_build == v.build &&
                      knn->copy_photons == photons;
    knn->copy_made = reuse; /* made again below otherwise */
    sr_point_grid_stats gs;
    st = sr_point_grid_statistics(grid, &gs);
    /* room for the blocks the search reads past the last photon */
    size_t stride = (gs.stored + 2 * PM_MAP_BLOCK - 1) / PM_MAP_BLOCK * PM_MAP_BLOCK;
    uint32_t stride32 = (uint32_t)stride;
    if (st == SLUICE_OK && stride * PM_MAP_PLANES > UINT32_MAX)
        return FAIL(knn, SLUICE_ERROR_LIMIT, "kNN: %zu photons are more than the map's %u",
                    gs.stored, (unsigned)(UINT32_MAX / PM_MAP_PLANES - 2 * PM_MAP_BLOCK));
    if (st == SLUICE_OK && !reuse)
        st = copy_map(knn, &v, photons, stride, (uint32_t)gs.stored);
    if (st != SLUICE_OK)
        goto runtime_fail;
    sluice_stream *map_start = knn->map_start;
    const float *box = knn->copy_box;

    pg_params g;
    pm_knn_params p;
    params_make(&v, o, indices ? cap : 0u, stride32, &g, &p);
    memcpy(p.box_lo, box, sizeof p.box_lo);
    memcpy(p.box_hi, box + 3, sizeof p.box_hi);
    if (hashed) {
        note_copy(knn, grid, &v, photons);
        return query_hashed(knn, &v, map_start, queries, n, results, o, &p, indices, cap, stats,
                            t0);
    }

    step = "summing the cell counts";
    if (!reuse)
        st = sum_counts(knn, &v, &g);
    if (st != SLUICE_OK)
        goto runtime_fail;
    note_copy(knn, grid, &v, photons);

    step = "ordering the queries by cell";
    st = ensure(knn->ctx, &knn->order_keys, 4, n);
    if (st == SLUICE_OK)
        st = ensure(knn->ctx, &knn->order, 4, n);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(knn->k_order, 0, queries, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(knn->k_order, 1, sizeof g, &g);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(knn->k_order, 2, knn->order_keys, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(knn->k_order, 3, knn->order, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(knn->k_order, n);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(knn->order_keys, n);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(knn->order, n);
    if (st == SLUICE_OK)
        st = sluice_sort_radix(knn->ctx, knn->order_keys, knn->order);
    if (st == SLUICE_OK)
        st = ensure(knn->ctx, &knn->qsorted, sizeof(pm_query), n);
    if (st == SLUICE_OK)
        st = ensure(knn->ctx, &knn->rsorted, sizeof(pm_knn_result), n);
    sluice_stream *sortq_args[] = {knn->order, queries, knn->qsorted};
    sluice_stream *unsort_args[] = {knn->order, knn->rsorted, results};
    for (unsigned i = 0; st == SLUICE_OK && i < 3; ++i)
        st = sluice_kernel_set_stream(knn->k_sortq, i, sortq_args[i], 0);
    for (unsigned i = 0; st == SLUICE_OK && i < 3; ++i)
        st = sluice_kernel_set_stream(knn->k_unsort, i, unsort_args[i], 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(knn->k_sortq, n);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(knn->qsorted, n);
    if (st != SLUICE_OK)
        goto runtime_fail;

    step = "binding the kernels";
    sluice_kernel *k = knn->k_pass;
    st = sluice_kernel_set_input(k, PASS_LIVE, knn->live);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_ORDER, knn->order, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_QUERIES, knn->qsorted, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_MAP, knn->map, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_MAP_START, map_start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_COUNT, v.cell_count, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_SAT, knn->sat, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, PASS_GRID, sizeof g, &g);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, PASS_PARAMS, sizeof p, &p);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, PASS_EXACT, sizeof exact, &exact);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_RESULTS, knn->rsorted, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_HEAP_D2, exact ? knn->heap_d2 : knn->dummy, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_HEAP_ID, exact ? knn->heap_id : knn->dummy, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, PASS_INDICES, indices ? indices : knn->dummy, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(knn->k_live, 0, knn->live);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(knn->k_live, 1, knn->rsorted, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(knn->k_live, 2, 0, knn->next, SLUICE_UNORDERED);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(knn->k_init, 0, knn->live, 0);
    /* one pass takes every shell: pm_knn_reach searches up to the k-th
     * photon, where the at-least radius is fixed, and pm_knn_sum gathers
     * within it, PM_KNN_SUM_QUERIES at a time (the same photons; the
     * multipass search keeps Purcell's passes, whose hook shows the
     * estimates growing) */
    knn->sum_after =
        o->mode == PM_KNN_ATLEAST && p.shells_per_pass == 0u && v.layout == SR_POINT_GRID_DENSE;
    if (knn->sum_after) {
        /* pm_knn_sum and pm_knn_reach take the same arguments, but for the
         * summed counts pm_knn_reach takes after the cell counts */
        sluice_kernel *ks[2] = {knn->k_sum, knn->k_reach};
        uint32_t n32 = (uint32_t)n;
        sluice_stream *args[] = {knn->order, knn->qsorted, knn->map,
                                 map_start,  v.cell_count, knn->sat};
        for (unsigned j = 0; j < 2; ++j) {
            unsigned a = 0;
            for (; st == SLUICE_OK && a < (j ? 6u : 5u); ++a)
                st = sluice_kernel_set_stream(ks[j], a, args[a], 0);
            if (st == SLUICE_OK)
                st = sluice_kernel_set_arg(ks[j], a, sizeof g, &g);
            if (st == SLUICE_OK)
                st = sluice_kernel_set_arg(ks[j], a + 1, sizeof p, &p);
            if (st == SLUICE_OK)
                st = sluice_kernel_set_arg(ks[j], a + 2, sizeof n32, &n32);
            if (st == SLUICE_OK)
                st = sluice_kernel_set_stream(ks[j], a + 3, knn->rsorted, 0);
            if (st == SLUICE_OK)
                st = sluice_kernel_set_stream(ks[j], a + 4, indices ? indices : knn->dummy, 0);
        }
    }
    if (st != SLUICE_OK)
        goto runtime_fail;

    /* every result zeroed and the length set first: a batch takes queries
     * from all over the input (the search order), and a pass hook may read
     * any result */
    step = "clearing the results";
    const pm_knn_result zero = {0.0f, 0.0f, 0.0f, 0.0f, 0u, 0u, 0u};
    st = sluice_stream_fill(knn->rsorted, &zero, n);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(results, n);
    if (st != SLUICE_OK)
        goto runtime_fail;
    knn->on_pass = o->on_pass;
    knn->on_pass_user = o->on_pass_user;
    knn->passes_before = 0;
    knn->answered = n;
    for (size_t base = 0; base < n; base += batch) {
        size_t bn = n - base < batch ? n - base : batch;
        uint32_t b32 = (uint32_t)base;
        step = "starting a batch";
        st = sluice_kernel_set_arg(knn->k_init, 1, sizeof b32, &b32);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch_count(knn->k_init, bn);
        if (st == SLUICE_OK)
            st = sluice_stream_set_length(knn->live, bn);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_arg(k, PASS_BASE, sizeof b32, &b32);
        if (st != SLUICE_OK)
            goto runtime_fail;
        step = "searching";
        st = sluice_loop_run(knn->loop);
        knn->passes_before += sluice_loop_pass_count(knn->loop);
        if (st != SLUICE_OK) {
            knn->on_pass = NULL;
            goto runtime_fail;
        }
        if (stats) {
            unsigned passes = sluice_loop_pass_count(knn->loop);
            for (unsigned i = 0; i < passes && i < PM_KNN_STATS_PASSES; ++i)
                stats->live[i] += sluice_loop_pass(knn->loop, i)->values[0];
            stats->passes += passes;
            stats->batches++;
        }
    }
    knn->on_pass = NULL;
    step = "writing the results";
    st = sluice_kernel_launch_count(knn->k_unsort, n);
    if (st == SLUICE_OK && indices)
        st = sluice_stream_set_length(indices, n * cap);
    if (st == SLUICE_OK)
        st = sluice_context_finish(knn->ctx);
    if (st != SLUICE_OK)
        goto runtime_fail;
    if (stats) {
        st = results_stats(knn, results, n, stats);
        if (st != SLUICE_OK)
            return st;
    }
    if (stats)
        stats->seconds = now() - t0;
    return SLUICE_OK;

runtime_fail:
    if (st == SLUICE_ERROR_OUT_OF_MEMORY && !*sluice_context_error(knn->ctx))
        return FAIL(knn, st, "kNN: %s: out of memory", step);
    return FAIL(knn, st, "kNN: %s: %s", step, sluice_context_error(knn->ctx));
}

sluice_status pm_knn_query(pm_knn *knn, const sr_point_grid *grid, sluice_stream *photons,
                           sluice_stream *queries, size_t n, sluice_stream *results,
                           const pm_knn_options *options, pm_knn_stats *stats)
{
    if (!knn)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    return query(knn, grid, photons, queries, n, results, options, NULL, 0, stats);
}

sluice_status pm_knn_query_indices(pm_knn *knn, const sr_point_grid *grid, sluice_stream *photons,
                                   sluice_stream *queries, size_t n, sluice_stream *results,
                                   const pm_knn_options *options, sluice_stream *indices,
                                   uint32_t cap, pm_knn_stats *stats)
{
    if (!knn)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (!indices)
        return FAIL(knn, SLUICE_ERROR_INVALID_ARGUMENT, "kNN: NULL index stream");
    return query(knn, grid, photons, queries, n, results, options, indices, cap, stats);
}
