/* The uniform point grid (point_grid.h; Purcell 6.2.2), kernels in
 * kernels/render/point_grid.cl. Every build starts with pg_key (the cell of
 * each point, the index as value) and ends with the same representation:
 *
 *   COUNT    sluice_cell_index_count (atomic histogram + scan) gives the
 *            starts, pg_scatter puts each point at its cell's next place
 *            (atomic cursor), pg_finish sorts each cell's indices.
 *   BITONIC  sluice_sort_bitonic of (cell, index) (any length: the primitive
 *            pads to a power of two itself), sluice_cell_index_search for the
 *            starts (Purcell Fig. 6.4), pg_finish sorts each cell (bitonic
 *            sort is not stable).
 *   STENCIL  sluice_route_bounded into cells * slots places, then
 *            pg_finish_stencil. Which points an overfull bucket keeps is up
 *            to the atomics there, so such cells are refilled: pg_pick lists
 *            the points of overfull cells in index order, a stable radix
 *            sort groups them by cell, and pg_place writes each cell's first
 *            `slots`: its lowest indices, what Purcell's stencil keeps when
 *            photons are drawn in index order. Only the overflowing cells'
 *            points pay for this; a map without overflow skips it.
 *
 * Sorting each cell after the scatter costs little (cells are short) and
 * makes every build's `order` the same array, so the renderer's image does
 * not depend on timing.
 *
 * The hashed layout (Purcell 6.4.4) differs only in the first step:
 * pg_hash_key gives each point its bucket instead of its cell, and the
 * count and bitonic builds then run over buckets as they run over cells. */
#include "point_grid.h"

#include "app_error.h"
#include "kernels.h"
#include "sluice/streams.h"

#include "../../kernels/render/rt_types.h"
#include "../../kernels/render/pg_types.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct sr_point_grid {
    sluice_context *ctx;
    sluice_program *prog;
    sluice_kernel *k_key, *k_hash_key, *k_fill, *k_scatter, *k_finish, *k_finish_stencil, *k_pick,
        *k_place;
    sluice_counters *counters;
    /* scratch and result streams, kept and grown between builds */
    sluice_stream *keys, *values, *order, *start, *count, *arrived, *cursor;
    sluice_stream *sub_keys, *sub_values, *sub_start;
    sr_point_grid_view view;
    sr_point_grid_stats stats;
    int built;
    uint64_t builds; /* build calls so far (sr_point_grid_view.build) */
    char message[512];
};

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Records why a call failed in g->message and evaluates to `st`. */
#define FAIL(g, st, ...) (sr_set_error((g)->message, sizeof(g)->message, __VA_ARGS__), (st))

void sr_point_grid_destroy(sr_point_grid *g)
{
    if (!g)
        return;
    sluice_kernel_destroy(g->k_key);
    sluice_kernel_destroy(g->k_hash_key);
    sluice_kernel_destroy(g->k_fill);
    sluice_kernel_destroy(g->k_scatter);
    sluice_kernel_destroy(g->k_finish);
    sluice_kernel_destroy(g->k_finish_stencil);
    sluice_kernel_destroy(g->k_pick);
    sluice_kernel_destroy(g->k_place);
    sluice_program_destroy(g->prog);
    sluice_counters_destroy(g->counters);
    sluice_stream *s[] = {g->keys,    g->values, g->order,    g->start,      g->count,
                          g->arrived, g->cursor, g->sub_keys, g->sub_values, g->sub_start};
    for (size_t i = 0; i < sizeof s / sizeof *s; ++i)
        sluice_stream_destroy(s[i]);
    free(g);
}

sluice_status sr_point_grid_create(sluice_context *ctx, sr_point_grid **out)
{
    if (!out)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sr_point_grid *g = calloc(1, sizeof *g);
    if (!g)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    g->ctx = ctx;
    sluice_status st = sr_shared_program_create(
        ctx, (const char *[]){"rt_types.h", "pg_types.h", "point_grid.cl"}, 3, NULL, &g->prog);
    struct {
        sluice_kernel **k;
        const char *name;
    } ks[] = {{&g->k_key, "pg_key"},       {&g->k_hash_key, "pg_hash_key"},
              {&g->k_fill, "pg_fill"},     {&g->k_scatter, "pg_scatter"},
              {&g->k_finish, "pg_finish"}, {&g->k_finish_stencil, "pg_finish_stencil"},
              {&g->k_pick, "pg_pick"},     {&g->k_place, "pg_place"}};
    for (size_t i = 0; st == SLUICE_OK && i < sizeof ks / sizeof *ks; ++i)
        st = sluice_kernel_create(g->prog, ks[i].name, ks[i].k);
    if (st == SLUICE_OK)
        st = sluice_counters_create(ctx, 3, NULL, &g->counters);
    if (st != SLUICE_OK) {
        sr_point_grid_destroy(g);
        return st;
    }
    *out = g;
    return SLUICE_OK;
}

/* Makes *s a uint32 stream of at least `cap` records (length untouched when
 * it is kept). Replaced rather than grown: the old records are not needed. */
static sluice_status ensure(sluice_context *ctx, sluice_stream **s, size_t cap)
{
    if (cap == 0)
        cap = 1;
    if (*s && sluice_stream_capacity(*s) >= cap)
        return SLUICE_OK;
    sluice_stream_destroy(*s);
    *s = NULL;
    /* room to grow by a quarter before the next reallocation */
    size_t want = cap + cap / 4;
    sluice_status st = sluice_stream_create(ctx, 4, want, s);
    if (st != SLUICE_OK)
        st = sluice_stream_create(ctx, 4, cap, s);
    return st;
}

static void params_make(pg_params *p, const rt_grid_desc *d, size_t cells, size_t stride,
                        uint32_t slots)
{
    memset(p, 0, sizeof *p);
    for (int a = 0; a < 3; ++a) {
        p->lo[a] = d->lo[a];
        p->cell[a] = d->cell[a];
        p->inv_cell[a] = 1.0f / d->cell[a];
        p->dims[a] = d->dims[a];
    }
    p->cells = (rt_u32)cells;
    p->stride = (rt_u32)(stride / 4);
    p->slots = slots;
}

uint32_t sr_point_grid_cell_of(const rt_grid_desc *desc, const float p[3])
{
    pg_params g;
    params_make(&g, desc, (size_t)desc->dims[0] * desc->dims[1] * desc->dims[2], 12, 0);
    return pg_cell(p[0], p[1], p[2], &g);
}

static void hash_params_make(pg_hash_params *p, const sr_point_hash_desc *d, size_t stride)
{
    memset(p, 0, sizeof *p);
    for (int a = 0; a < 3; ++a)
        p->lo[a] = d->lo[a];
    p->cell = d->cell;
    p->inv_cell = 1.0f / d->cell;
    p->mask = d->buckets - 1u;
    p->buckets = d->buckets;
    p->stride = (rt_u32)(stride / 4);
}

uint32_t sr_point_grid_bucket_of(const sr_point_hash_desc *desc, const float p[3],
                                 uint32_t coords[3])
{
    pg_hash_params h;
    hash_params_make(&h, desc, 12);
    uint32_t b = pg_hash_point(p[0], p[1], p[2], &h);
    if (coords) {
        for (int a = 0; a < 3; ++a)
            coords[a] = b == h.buckets ? 0u : pg_hash_axis(p[a], h.lo[a], h.inv_cell);
    }
    return b;
}

/* Checks a hashed layout as the builds need it. */
static sluice_status hash_desc_check(const sr_point_hash_desc *d, char *err, size_t err_size)
{
    for (int a = 0; a < 3; ++a)
        if (!isfinite(d->lo[a])) {
            sr_set_error(err, err_size, "point grid: the hash lattice's origin is not finite");
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
    /* 1 / cell must be finite too: the cell function multiplies by it */
    if (!isfinite(d->cell) || !(d->cell > 0.0f) || !isfinite(1.0f / d->cell)) {
        sr_set_error(err, err_size, "point grid: a hash cell of %g (positive and finite needed)",
                     (double)d->cell);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (d->buckets == 0 || (d->buckets & (d->buckets - 1u)) ||
        d->buckets > SR_POINT_HASH_MAX_BUCKETS) {
        sr_set_error(err, err_size,
                     "point grid: %u hash buckets (a power of two from 1 to %u needed)", d->buckets,
                     SR_POINT_HASH_MAX_BUCKETS);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    return SLUICE_OK;
}

/* Launches a generator kernel over `count` records. */
static sluice_status launch(sluice_kernel *k, size_t count)
{
    return count ? sluice_kernel_launch_count(k, count) : SLUICE_OK;
}

/* Launches a generator kernel over `count` records with the counters bound,
 * and reads what it counted (waits) into c[0 .. 2]: the counters are
 * restarted by each read, not reset before each launch (one command less;
 * only these launches count into them). */
static sluice_status launch_counted(sr_point_grid *g, sluice_kernel *k, size_t count, uint32_t c[3])
{
    c[0] = c[1] = c[2] = 0;
    sluice_status st = sluice_kernel_set_counters(k, g->counters);
    if (st == SLUICE_OK)
        st = launch(k, count);
    if (st == SLUICE_OK)
        st = sluice_counters_read_restart(g->counters, c);
    return st;
}

static sluice_status fill(sr_point_grid *g, sluice_stream *s, size_t n, uint32_t value)
{
    sluice_status st = sluice_kernel_set_stream(g->k_fill, 0, s, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(g->k_fill, 1, sizeof value, &value);
    if (st == SLUICE_OK)
        st = launch(g->k_fill, n);
    return st;
}

/* COUNT: histogram and scan, scatter, per-cell sort. */
static sluice_status build_count(sr_point_grid *g, size_t n, uint32_t cells)
{
    sluice_status st = sluice_cell_index_count(g->ctx, g->keys, cells, g->start);
    if (st == SLUICE_OK)
        st = fill(g, g->cursor, cells, 0u);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(g->k_scatter, 0, g->keys, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(g->k_scatter, 1, g->start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(g->k_scatter, 2, g->cursor, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(g->k_scatter, 3, g->order, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(g->k_scatter, 4, sizeof cells, &cells);
    if (st == SLUICE_OK)
        st = launch(g->k_scatter, n);
    g->view.order = g->order;
    return st;
}

/* BITONIC: sort the pairs, search the starts (Purcell Fig. 6.4). */
static sluice_status build_bitonic(sr_point_grid *g, uint32_t cells)
{
    sluice_status st = sluice_sort_bitonic(g->ctx, g->keys, g->values);
    if (st == SLUICE_OK)
        st = sluice_cell_index_search(g->ctx, g->keys, cells, g->start);
    g->view.order = g->values;
    return st;
}

/* The compact builds' last step (both): counts, arrivals, sorted cells. */
static sluice_status finish_compact(sr_point_grid *g, uint32_t cells)
{
    sluice_kernel *k = g->k_finish;
    sluice_status st = sluice_kernel_set_stream(k, 0, g->start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, g->view.order, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 2, g->count, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 3, g->arrived, 0);
    uint32_t c[3] = {0, 0, 0};
    if (st == SLUICE_OK)
        st = launch_counted(g, k, cells, c);
    g->stats.occupied_cells = c[0];
    return st;
}

/* STENCIL: bounded routing, then the deterministic refill of overfull
 * cells. A cell's places past its count are never read: the routing leaves
 * them unwritten (sparse), so that the footprint of the empty cells, most
 * of a photon map's, costs nothing. */
static sluice_status build_stencil(sr_point_grid *g, size_t n, uint32_t cells, uint32_t slots)
{
    /* fill goes to count and overflow to arrived; pg_finish_stencil turns
     * them into stored and arrived counts in place */
    sluice_status st = sluice_route_bounded_sparse(g->ctx, g->keys, g->values, cells, slots,
                                                   g->order, g->count, g->arrived);
    sluice_kernel *k = g->k_finish_stencil;
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 0, g->order, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, g->start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 2, g->count, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 3, g->arrived, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 4, sizeof slots, &slots);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 5, sizeof cells, &cells);
    uint32_t c[3] = {0, 0, 0};
    if (st == SLUICE_OK)
        st = launch_counted(g, k, cells, c);
    g->view.order = g->order;
    g->stats.occupied_cells = c[0];
    g->stats.overfull_cells = c[1];
    g->stats.overflow_points = c[2];
    if (st != SLUICE_OK || c[1] == 0)
        return st;

    /* Refill the overfull cells with their lowest indices. */
    size_t picked = 0;
    st = ensure(g->ctx, &g->sub_keys, n);
    if (st == SLUICE_OK)
        st = ensure(g->ctx, &g->sub_values, n);
    if (st == SLUICE_OK)
        st = ensure(g->ctx, &g->sub_start, (size_t)cells + 1);
    k = g->k_pick;
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 0, g->keys, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, g->count, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 2, g->arrived, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 3, sizeof cells, &cells);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 4, 0, g->sub_keys, SLUICE_ORDERED);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 5, 1, g->sub_values, SLUICE_ORDERED);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(g->sub_keys);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(g->sub_values);
    if (st == SLUICE_OK)
        st = launch(k, n);
    if (st == SLUICE_OK)
        st = sluice_sort_radix(g->ctx, g->sub_keys, g->sub_values);
    if (st == SLUICE_OK)
        st = sluice_cell_index_search(g->ctx, g->sub_keys, cells, g->sub_start);
    if (st == SLUICE_OK)
        st = sluice_stream_length(g->sub_keys, &picked);
    k = g->k_place;
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(k, 0, g->sub_keys);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, g->sub_values, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 2, g->sub_start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 3, sizeof slots, &slots);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 4, g->order, 0);
    if (st == SLUICE_OK && picked)
        st = sluice_kernel_launch(k);
    return st;
}

/* Both layouts' builds: a dense grid (`desc`) or a hashed one (`hdesc`). */
static sluice_status build(sr_point_grid *g, const rt_grid_desc *desc,
                           const sr_point_hash_desc *hdesc, sluice_stream *points, size_t stride,
                           size_t n, sr_point_grid_build_kind kind, uint32_t slots)
{
    double t0 = now();
    g->message[0] = '\0';
    g->built = 0;
    memset(&g->view, 0, sizeof g->view);
    memset(&g->stats, 0, sizeof g->stats);
    if ((!desc && !hdesc) || !points)
        return FAIL(g, SLUICE_ERROR_INVALID_ARGUMENT, "point grid: NULL argument");
    size_t cells = 0;
    sluice_status st;
    if (desc) {
        st = rt_grid_desc_check(desc, &cells, g->message, sizeof g->message);
    } else {
        st = hash_desc_check(hdesc, g->message, sizeof g->message);
        cells = hdesc->buckets;
        if (st == SLUICE_OK && kind == SR_POINT_GRID_STENCIL)
            return FAIL(g, SLUICE_ERROR_INVALID_ARGUMENT,
                        "point grid: no stencil build of a hashed grid (its power "
                        "redistribution is per cell, and a bucket mixes cells: Purcell 6.4.4)");
    }
    if (st != SLUICE_OK)
        return st;
    if (stride < 12 || stride % 4 || stride != sluice_stream_record_size(points))
        return FAIL(g, SLUICE_ERROR_INVALID_ARGUMENT,
                    "point grid: a stride of %zu bytes for records of %zu (it must be the "
                    "record size, a multiple of 4 and at least 12)",
                    stride, sluice_stream_record_size(points));
    if (kind != SR_POINT_GRID_COUNT && kind != SR_POINT_GRID_BITONIC &&
        kind != SR_POINT_GRID_STENCIL)
        return FAIL(g, SLUICE_ERROR_INVALID_ARGUMENT, "point grid: unknown build %d", (int)kind);
    if (kind != SR_POINT_GRID_STENCIL)
        slots = 0;
    else if (slots == 0 || slots > SR_POINT_GRID_MAX_SLOTS)
        return FAIL(g, SLUICE_ERROR_INVALID_ARGUMENT,
                    "point grid: %u slots per cell (1 .. %u allowed)", slots,
                    SR_POINT_GRID_MAX_SLOTS);
    else if ((size_t)slots * cells > SR_POINT_GRID_MAX_FOOTPRINT)
        return FAIL(g, SLUICE_ERROR_LIMIT,
                    "point grid: %zu cells x %u slots exceed the limit of %zu places", cells, slots,
                    SR_POINT_GRID_MAX_FOOTPRINT);
    if (n > SR_POINT_GRID_MAX_POINTS)
        return FAIL(g, SLUICE_ERROR_LIMIT, "point grid: %zu points exceed the limit of %zu", n,
                    SR_POINT_GRID_MAX_POINTS);
    size_t len = 0;
    st = sluice_stream_length(points, &len);
    if (st != SLUICE_OK)
        return FAIL(g, st, "point grid: %s", sluice_context_error(g->ctx));
    if (n > len)
        return FAIL(g, SLUICE_ERROR_INVALID_ARGUMENT,
                    "point grid: %zu points asked for, the stream holds %zu", n, len);

    const uint32_t nc = (uint32_t)cells;
    pg_params p;
    pg_hash_params hp;
    if (desc)
        params_make(&p, desc, cells, stride, slots);
    else
        hash_params_make(&hp, hdesc, stride);
    const char *step = "allocating streams";
    size_t order_cap = kind == SR_POINT_GRID_STENCIL ? cells * slots : n;
    st = ensure(g->ctx, &g->keys, n);
    if (st == SLUICE_OK)
        st = ensure(g->ctx, &g->values, n);
    if (st == SLUICE_OK && kind != SR_POINT_GRID_BITONIC)
        st = ensure(g->ctx, &g->order, order_cap);
    if (st == SLUICE_OK)
        st = ensure(g->ctx, &g->start, cells + 1);
    if (st == SLUICE_OK)
        st = ensure(g->ctx, &g->count, cells);
    if (st == SLUICE_OK)
        st = ensure(g->ctx, &g->arrived, cells);
    if (st == SLUICE_OK && kind == SR_POINT_GRID_COUNT)
        st = ensure(g->ctx, &g->cursor, cells);
    if (st != SLUICE_OK)
        goto runtime_fail;

    step = "keying the points";
    uint32_t c[3] = {0, 0, 0};
    sluice_kernel *kk = desc ? g->k_key : g->k_hash_key;
    st = sluice_kernel_set_stream(kk, 0, points, 0);
    if (st == SLUICE_OK)
        st = desc ? sluice_kernel_set_arg(kk, 1, sizeof p, &p)
                  : sluice_kernel_set_arg(kk, 1, sizeof hp, &hp);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(kk, 2, g->keys, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(kk, 3, g->values, 0);
    if (st == SLUICE_OK)
        st = launch_counted(g, kk, n, c);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(g->keys, n);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(g->values, n);
    if (st != SLUICE_OK)
        goto runtime_fail;
    const uint32_t bad = c[0];

    step = kind == SR_POINT_GRID_COUNT     ? "counting sort"
           : kind == SR_POINT_GRID_BITONIC ? "bitonic sort"
                                           : "stencil routing";
    if (kind == SR_POINT_GRID_COUNT)
        st = build_count(g, n, nc);
    else if (kind == SR_POINT_GRID_BITONIC)
        st = build_bitonic(g, nc);
    else
        st = build_stencil(g, n, nc, slots);
    if (st == SLUICE_OK && kind != SR_POINT_GRID_STENCIL)
        st = finish_compact(g, nc);
    /* lengths, so that downloads and reductions see whole streams */
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(g->start, cells + 1);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(g->count, cells);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(g->arrived, cells);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(g->view.order,
                                      kind == SR_POINT_GRID_STENCIL ? cells * slots : n - bad);
    uint32_t largest = 0;
    if (st == SLUICE_OK && cells)
        st = sluice_reduce(g->ctx, g->arrived, SLUICE_U32, SLUICE_MAX, &largest);
    if (st != SLUICE_OK)
        goto runtime_fail;

    if (desc) {
        g->view.layout = SR_POINT_GRID_DENSE;
        g->view.desc = *desc;
    } else {
        g->view.layout = SR_POINT_GRID_HASHED;
        g->view.hash = *hdesc;
    }
    g->view.cells = nc;
    g->view.kind = kind;
    g->view.slots = slots;
    g->view.points = n;
    g->view.cell_start = g->start;
    g->view.cell_count = g->count;
    g->view.cell_arrived = g->arrived;
    sr_point_grid_stats *s = &g->stats;
    s->points = n;
    s->cells = cells;
    s->dropped_nonfinite = bad;
    s->stored = n - bad - s->overflow_points;
    s->max_per_cell = largest;
    s->mean_per_occupied = s->occupied_cells ? (double)(n - bad) / (double)s->occupied_cells : 0.0;
    s->build_seconds = now() - t0;
    g->built = 1;
    return SLUICE_OK;

runtime_fail:
    memset(&g->view, 0, sizeof g->view);
    memset(&g->stats, 0, sizeof g->stats);
    if (st == SLUICE_ERROR_OUT_OF_MEMORY && !*sluice_context_error(g->ctx))
        return FAIL(g, st, "point grid: %s: out of memory", step);
    return FAIL(g, st, "point grid: %s: %s", step, sluice_context_error(g->ctx));
}

sluice_status sr_point_grid_prepare(sr_point_grid *g, sr_point_grid_build_kind kind)
{
    if (!g)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    /* the statistics' reduction, then each build's sort or routing and the
     * cell index (the stencil build sorts the cells it redistributes) */
    unsigned alg = SLUICE_ALG_REDUCE | SLUICE_ALG_CELL_INDEX;
    if (kind == SR_POINT_GRID_BITONIC)
        alg |= SLUICE_ALG_SORT_BITONIC;
    else if (kind == SR_POINT_GRID_STENCIL)
        alg |= SLUICE_ALG_ROUTE | SLUICE_ALG_SORT_RADIX;
    else if (kind != SR_POINT_GRID_COUNT)
        return FAIL(g, SLUICE_ERROR_INVALID_ARGUMENT, "point grid: unknown build %d", (int)kind);
    sluice_status st = sluice_streams_prepare(g->ctx, alg);
    return st == SLUICE_OK ? st : FAIL(g, st, "point grid: %s", sluice_context_error(g->ctx));
}

sluice_status sr_point_grid_build(sr_point_grid *g, const rt_grid_desc *desc, sluice_stream *points,
                                  size_t stride, size_t n, sr_point_grid_build_kind kind,
                                  uint32_t slots)
{
    if (!g)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    g->builds++;
    if (!desc) {
        memset(&g->view, 0, sizeof g->view);
        memset(&g->stats, 0, sizeof g->stats);
        g->built = 0;
        return FAIL(g, SLUICE_ERROR_INVALID_ARGUMENT, "point grid: NULL argument");
    }
    return build(g, desc, NULL, points, stride, n, kind, slots);
}

sluice_status sr_point_grid_build_hashed(sr_point_grid *g, const sr_point_hash_desc *desc,
                                         sluice_stream *points, size_t stride, size_t n,
                                         sr_point_grid_build_kind kind)
{
    if (!g)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    g->builds++;
    if (!desc) {
        memset(&g->view, 0, sizeof g->view);
        memset(&g->stats, 0, sizeof g->stats);
        g->built = 0;
        return FAIL(g, SLUICE_ERROR_INVALID_ARGUMENT, "point grid: NULL argument");
    }
    return build(g, NULL, desc, points, stride, n, kind, 0);
}

sluice_status sr_point_grid_get(const sr_point_grid *g, sr_point_grid_view *view)
{
    if (!g || !view)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    *view = g->view;
    view->build = g->builds;
    return SLUICE_OK;
}

sluice_status sr_point_grid_statistics(const sr_point_grid *g, sr_point_grid_stats *stats)
{
    if (!g || !stats)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    *stats = g->stats;
    return SLUICE_OK;
}

const char *sr_point_grid_error(const sr_point_grid *g)
{
    return g ? g->message : "NULL point grid";
}

/* Checks bounds for both desc helpers; fills the extents, the largest one
 * and the largest coordinate magnitude. */
static sluice_status check_bounds(const float lo[3], const float hi[3], double ext[3],
                                  double *max_ext, double *mag, char *err, size_t err_size)
{
    *max_ext = 0.0;
    *mag = 0.0;
    for (int a = 0; a < 3; ++a) {
        if (!isfinite(lo[a]) || !isfinite(hi[a]) || lo[a] > hi[a]) {
            sr_set_error(err, err_size, "point grid: bad bounds on axis %d (%g .. %g)", a,
                         (double)lo[a], (double)hi[a]);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
        ext[a] = (double)hi[a] - (double)lo[a];
        *max_ext = fmax(*max_ext, ext[a]);
        *mag = fmax(*mag, fmax(fabs((double)lo[a]), fabs((double)hi[a])));
    }
    return SLUICE_OK;
}

/* Stores the box lo .. hi cut into dims as out, checked. */
static sluice_status desc_finish(const double lo[3], const double hi[3], const uint32_t dims[3],
                                 rt_grid_desc *out, char *err, size_t err_size)
{
    for (int a = 0; a < 3; ++a) {
        out->lo[a] = (float)lo[a];
        out->hi[a] = (float)hi[a];
        out->dims[a] = dims[a];
        out->cell[a] = dims[a] ? (out->hi[a] - out->lo[a]) / (float)dims[a] : 0.0f;
    }
    sluice_status st = rt_grid_desc_check(out, NULL, err, err_size);
    if (st != SLUICE_OK)
        memset(out, 0, sizeof *out);
    return st;
}

sluice_status sr_point_grid_desc_dims(const float lo[3], const float hi[3], const uint32_t dims[3],
                                      rt_grid_desc *out, char *err, size_t err_size)
{
    if (!lo || !hi || !dims || !out) {
        sr_set_error(err, err_size, "sr_point_grid_desc_dims: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    memset(out, 0, sizeof *out);
    double ext[3], max_ext, mag, l[3], h[3];
    sluice_status st = check_bounds(lo, hi, ext, &max_ext, &mag, err, err_size);
    if (st != SLUICE_OK)
        return st;
    /* a flat axis (a planar photon map) gets the same padding as
     * rt_grid_choose gives it */
    double pad = max_ext * 0x1p-12 + mag * 0x1p-20;
    if (pad == 0.0)
        pad = 1.0;
    for (int a = 0; a < 3; ++a) {
        double p = ext[a] > 0.0 ? 0.0 : pad;
        l[a] = (double)lo[a] - p;
        h[a] = (double)hi[a] + p;
    }
    return desc_finish(l, h, dims, out, err, err_size);
}

/* sr_point_grid_desc_auto; also the cells a grid at the edge aimed at would
 * have (*wanted) and the edge over the one aimed at (*coarsening). */
static sluice_status desc_auto(const float lo[3], const float hi[3], size_t points, float radius,
                               rt_grid_desc *out, double *wanted, double *coarsening, char *err,
                               size_t err_size)
{
    memset(out, 0, sizeof *out);
    if (!isfinite(radius) || !(radius > 0.0f)) {
        sr_set_error(err, err_size, "point grid: the search radius must be positive, not %g",
                     (double)radius);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    double ext[3], max_ext, mag;
    sluice_status st = check_bounds(lo, hi, ext, &max_ext, &mag, err, err_size);
    if (st != SLUICE_OK)
        return st;
    double pad = max_ext * 0x1p-12 + mag * 0x1p-20;
    if (pad == 0.0)
        pad = 1.0;
    double cap = (double)points * SR_POINT_GRID_AUTO_CELLS_PER_POINT;
    if (cap < 64.0)
        cap = 64.0;
    if (cap > (double)SR_POINT_GRID_AUTO_MAX_CELLS)
        cap = (double)SR_POINT_GRID_AUTO_MAX_CELLS;
    const double aim = SR_POINT_GRID_AUTO_EDGE * (double)radius;
    double edge = aim, padded[3];
    for (int a = 0; a < 3; ++a)
        padded[a] = ext[a] + 2.0 * pad;
    *wanted = 1.0;
    for (int a = 0; a < 3; ++a)
        if (ext[a] > max_ext * RT_GRID_FLAT_RATIO)
            *wanted *= fmax(ceil(padded[a] / aim), 1.0);
    uint32_t dims[3];
    for (;;) {
        double cells = 1.0;
        for (int a = 0; a < 3; ++a) {
            /* a flat axis (as rt_grid_choose defines it) gets one cell */
            double d = ext[a] > max_ext * RT_GRID_FLAT_RATIO ? ceil(padded[a] / edge) : 1.0;
            if (d < 1.0)
                d = 1.0;
            if (d > (double)RT_GRID_MAX_SIDE)
                d = (double)RT_GRID_MAX_SIDE;
            dims[a] = (uint32_t)d;
            cells *= d;
        }
        if (cells <= cap)
            break;
        edge *= 1.0905; /* 2^(1/8): a few percent coarser per step */
    }
    double l[3], h[3];
    for (int a = 0; a < 3; ++a) {
        double centre = 0.5 * ((double)lo[a] + (double)hi[a]);
        double half =
            ext[a] > max_ext * RT_GRID_FLAT_RATIO ? 0.5 * edge * dims[a] : 0.5 * padded[a];
        if (half < 0.5 * padded[a])
            half = 0.5 * padded[a];
        l[a] = centre - half;
        h[a] = centre + half;
    }
    *coarsening = edge / aim;
    return desc_finish(l, h, dims, out, err, err_size);
}

sluice_status sr_point_grid_desc_auto(const float lo[3], const float hi[3], size_t points,
                                      float radius, rt_grid_desc *out, char *err, size_t err_size)
{
    if (!lo || !hi || !out) {
        sr_set_error(err, err_size, "sr_point_grid_desc_auto: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    double wanted, coarsening;
    return desc_auto(lo, hi, points, radius, out, &wanted, &coarsening, err, err_size);
}

sluice_status sr_point_hash_desc_auto(const float lo[3], const float hi[3], size_t points,
                                      float radius, sr_point_hash_desc *out, char *err,
                                      size_t err_size)
{
    if (!lo || !hi || !out) {
        sr_set_error(err, err_size, "sr_point_hash_desc_auto: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    memset(out, 0, sizeof *out);
    if (!isfinite(radius) || !(radius > 0.0f)) {
        sr_set_error(err, err_size, "point grid: the search radius must be positive, not %g",
                     (double)radius);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    double ext[3], max_ext, mag;
    sluice_status st = check_bounds(lo, hi, ext, &max_ext, &mag, err, err_size);
    if (st != SLUICE_OK)
        return st;
    /* cells no finer than the box cut into SR_POINT_HASH_MAX_SIDE, nor than
     * float tells apart near the box (coordinates of magnitude mag are
     * 2^-24 mag apart: at 2^-20 mag the cell function's rounding stays
     * within a sixteenth of a cell). Finer cells would still be correct,
     * the cell function being monotone, only wasteful. */
    double edge = SR_POINT_HASH_EDGE * (double)radius;
    edge = fmax(edge, max_ext / (double)SR_POINT_HASH_MAX_SIDE);
    edge = fmax(edge, mag * 0x1p-20);
    if (!(edge <= 0x1p100))
        edge = 0x1p100;
    double want = (double)points * SR_POINT_HASH_BUCKETS_PER_POINT;
    uint32_t buckets = 64;
    while ((double)buckets < want && buckets < SR_POINT_HASH_MAX_BUCKETS)
        buckets <<= 1;
    for (int a = 0; a < 3; ++a)
        out->lo[a] = lo[a];
    out->cell = (float)edge;
    out->buckets = buckets;
    return hash_desc_check(out, err, err_size);
}

sluice_status sr_point_grid_plan_auto(const float lo[3], const float hi[3], size_t points,
                                      float dense_radius, float search_radius,
                                      sr_point_grid_layout request, sr_point_grid_plan *out,
                                      char *err, size_t err_size)
{
    if (!lo || !hi || !out) {
        sr_set_error(err, err_size, "sr_point_grid_plan_auto: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    memset(out, 0, sizeof *out);
    if (request != SR_POINT_GRID_DENSE && request != SR_POINT_GRID_HASHED &&
        request != SR_POINT_GRID_LAYOUT_AUTO) {
        sr_set_error(err, err_size, "point grid: unknown layout %d", (int)request);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sluice_status st = desc_auto(lo, hi, points, dense_radius, &out->dense, &out->wanted_cells,
                                 &out->coarsening, err, err_size);
    if (st == SLUICE_OK)
        st = sr_point_hash_desc_auto(lo, hi, points, search_radius, &out->hash, err, err_size);
    if (st != SLUICE_OK) {
        memset(out, 0, sizeof *out);
        return st;
    }
    const rt_grid_desc *d = &out->dense;
    size_t cells = (size_t)d->dims[0] * d->dims[1] * d->dims[2];
    double aim = SR_POINT_GRID_AUTO_EDGE * (double)dense_radius;
    int hashed = request != SR_POINT_GRID_DENSE;
    out->layout = hashed ? SR_POINT_GRID_HASHED : SR_POINT_GRID_DENSE;
    const char *how =
        request == SR_POINT_GRID_LAYOUT_AUTO ? " (auto: the faster search)" : " (asked for)";
    const char *name = hashed ? "hash" : "dense";
    if (out->coarsening > 1.0)
        snprintf(out->why, sizeof out->why,
                 "%s%s: a dense grid at cells of %.3g would need %.3g cells; capped at %zu "
                 "(%ux%ux%u) its cells are %.3gx coarser",
                 name, how, aim, out->wanted_cells, cells, d->dims[0], d->dims[1], d->dims[2],
                 out->coarsening);
    else
        snprintf(out->why, sizeof out->why, "%s%s: a dense grid's cells of %.3g fit in %ux%ux%u",
                 name, how, aim, d->dims[0], d->dims[1], d->dims[2]);
    return SLUICE_OK;
}
