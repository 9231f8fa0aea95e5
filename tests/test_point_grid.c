/* Tests of the uniform point grid (apps/render/point_grid.h; Purcell 6.2.2):
 * the counting, bitonic and stencil builds against a plain C reference
 * (cell ranges and the ascending list of each cell) on random and
 * adversarial inputs, stencil overflow (counts, which points are kept,
 * determinism), stencil with enough slots equal to the other builds,
 * non-finite points, rebuilds with kept scratch, the grid helpers and the
 * error paths; the hashed layout (Purcell 6.4.4) the same way, with tables
 * small enough that every cell collides, its descriptions and the choice
 * between the layouts. */
#include "check.h"
#include "point_grid.h"

#include "../kernels/render/rt_types.h"
#include "../kernels/photonmap/pm_types.h"

#include "../kernels/render/pg_types.h"

#include <math.h>
#include <string.h>

static const char *kind_name[3] = {"count", "bitonic", "stencil"};

/* The grid as downloaded (or as the reference makes it). */
typedef struct grid_data {
    uint32_t *order, *start, *count, *arrived;
    size_t order_len;
} grid_data;

static void grid_data_free(grid_data *d)
{
    free(d->order);
    free(d->start);
    free(d->count);
    free(d->arrived);
    memset(d, 0, sizeof *d);
}

/* Reference: each cell's points in ascending index, the first `slots` of
 * them stored when slots > 0. A hashed layout (`hash` not NULL): the same
 * over buckets. */
static void reference(const rt_grid_desc *desc, const sr_point_hash_desc *hash, const float *pts,
                      size_t stride_f, size_t n, uint32_t slots, grid_data *r, size_t *dropped)
{
    size_t cells = hash ? hash->buckets : (size_t)desc->dims[0] * desc->dims[1] * desc->dims[2];
    uint32_t *key = malloc((n + 1) * sizeof *key);
    r->arrived = calloc(cells + 1, sizeof *r->arrived);
    r->count = calloc(cells + 1, sizeof *r->count);
    r->start = calloc(cells + 1, sizeof *r->start);
    *dropped = 0;
    for (size_t i = 0; i < n; ++i) {
        key[i] = hash ? sr_point_grid_bucket_of(hash, pts + i * stride_f, NULL)
                      : sr_point_grid_cell_of(desc, pts + i * stride_f);
        if (key[i] < cells)
            r->arrived[key[i]]++;
        else
            ++*dropped;
    }
    size_t total = 0;
    for (size_t c = 0; c < cells; ++c) {
        r->count[c] = slots && r->arrived[c] > slots ? slots : r->arrived[c];
        r->start[c] = (uint32_t)total;
        total += r->count[c];
    }
    r->order = malloc((total + 1) * sizeof *r->order);
    r->order_len = total;
    uint32_t *fillp = calloc(cells + 1, sizeof *fillp);
    for (size_t i = 0; i < n; ++i) {
        uint32_t c = key[i];
        if (c < cells && fillp[c] < r->count[c])
            r->order[r->start[c] + fillp[c]++] = (uint32_t)i;
    }
    free(fillp);
    free(key);
}

static int download(sr_point_grid *g, sluice_context *ctx, grid_data *d)
{
    sr_point_grid_view v;
    CHECK_OK(ctx, sr_point_grid_get(g, &v));
    size_t cells = v.cells, len = 0;
    d->start = malloc((cells + 1) * sizeof *d->start);
    d->count = malloc((cells + 1) * sizeof *d->count);
    d->arrived = malloc((cells + 1) * sizeof *d->arrived);
    int ok = 1;
    ok &= sluice_stream_download(v.cell_start, d->start, cells, NULL) == SLUICE_OK;
    ok &= sluice_stream_download(v.cell_count, d->count, cells, NULL) == SLUICE_OK;
    ok &= sluice_stream_download(v.cell_arrived, d->arrived, cells, NULL) == SLUICE_OK;
    ok &= sluice_stream_length(v.order, &len) == SLUICE_OK;
    d->order = malloc((len + 1) * sizeof *d->order);
    ok &= sluice_stream_download(v.order, d->order, len, &d->order_len) == SLUICE_OK;
    CHECK(ok, "download failed: %s", sluice_context_error(ctx));
    return ok;
}

/* Builds with `kind` and compares with the reference; returns the grid's
 * data in *keep when it is not NULL. */
static void run_build_layout(sluice_context *ctx, sr_point_grid *g, const char *name,
                             const rt_grid_desc *desc, const sr_point_hash_desc *hash,
                             sluice_stream *s, const float *pts, size_t stride, size_t n,
                             sr_point_grid_build_kind kind, uint32_t slots, grid_data *keep)
{
    sluice_status st = hash ? sr_point_grid_build_hashed(g, hash, s, stride, n, kind)
                            : sr_point_grid_build(g, desc, s, stride, n, kind, slots);
    CHECK(st == SLUICE_OK, "%s/%s: build: %s", name, kind_name[kind], sr_point_grid_error(g));
    if (st != SLUICE_OK)
        return;
    uint32_t ref_slots = kind == SR_POINT_GRID_STENCIL ? slots : 0;
    grid_data r = {0}, d = {0};
    size_t dropped = 0;
    reference(desc, hash, pts, stride / 4, n, ref_slots, &r, &dropped);
    size_t cells = hash ? hash->buckets : (size_t)desc->dims[0] * desc->dims[1] * desc->dims[2];
    sr_point_grid_view view;
    CHECK_OK(ctx, sr_point_grid_get(g, &view));
    CHECK(view.layout == (hash ? SR_POINT_GRID_HASHED : SR_POINT_GRID_DENSE) &&
              view.cells == cells && view.points == n &&
              (hash ? view.hash.buckets == hash->buckets && view.hash.cell == hash->cell &&
                          view.desc.dims[0] == 0
                    : view.desc.dims[0] == desc->dims[0] && view.hash.buckets == 0),
          "%s/%s: the view", name, kind_name[kind]);
    if (download(g, ctx, &d)) {
        size_t bad = 0, overfull = 0, over_pts = 0, occupied = 0;
        uint32_t largest = 0;
        for (size_t c = 0; c < cells && bad < 5; ++c) {
            int ok = d.count[c] == r.count[c] && d.arrived[c] == r.arrived[c];
            if (kind == SR_POINT_GRID_STENCIL)
                ok = ok && d.start[c] == c * slots;
            else
                ok = ok && d.start[c] == r.start[c];
            for (uint32_t j = 0; ok && j < r.count[c]; ++j)
                ok = (size_t)d.start[c] + j < d.order_len &&
                     d.order[d.start[c] + j] == r.order[r.start[c] + j];
            if (!ok) {
                ++bad;
                CHECK(0, "%s/%s: cell %zu: count %u/%u arrived %u/%u start %u", name,
                      kind_name[kind], c, d.count[c], r.count[c], d.arrived[c], r.arrived[c],
                      d.start[c]);
            }
            occupied += r.arrived[c] > 0;
            overfull += r.arrived[c] > r.count[c];
            over_pts += r.arrived[c] - r.count[c];
            largest = r.arrived[c] > largest ? r.arrived[c] : largest;
        }
        CHECK(bad == 0, "%s/%s: cells differ", name, kind_name[kind]);
        sr_point_grid_stats stt;
        CHECK_OK(ctx, sr_point_grid_statistics(g, &stt));
        CHECK(stt.points == n && stt.cells == cells && stt.dropped_nonfinite == dropped &&
                  stt.occupied_cells == occupied && stt.max_per_cell == largest &&
                  stt.overfull_cells == overfull && stt.overflow_points == over_pts &&
                  stt.stored == r.order_len,
              "%s/%s: statistics (occupied %zu/%zu, max %u/%u, overfull %zu/%zu, over %zu/%zu, "
              "dropped %zu/%zu, stored %zu/%zu)",
              name, kind_name[kind], stt.occupied_cells, occupied, stt.max_per_cell, largest,
              stt.overfull_cells, overfull, stt.overflow_points, over_pts, stt.dropped_nonfinite,
              dropped, stt.stored, r.order_len);
    }
    grid_data_free(&r);
    if (keep)
        *keep = d;
    else
        grid_data_free(&d);
}

static void run_build(sluice_context *ctx, sr_point_grid *g, const char *name,
                      const rt_grid_desc *desc, sluice_stream *s, const float *pts, size_t stride,
                      size_t n, sr_point_grid_build_kind kind, uint32_t slots, grid_data *keep)
{
    run_build_layout(ctx, g, name, desc, NULL, s, pts, stride, n, kind, slots, keep);
}

/* The hashed layout on one point set: both compact builds against the
 * reference and each other; the stencil build is refused. */
static void run_hashed(sluice_context *ctx, sr_point_grid *g, const char *name,
                       const sr_point_hash_desc *hash, const float *pts, size_t stride, size_t n)
{
    sluice_stream *s = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, stride, n ? n : 1, &s));
    CHECK_OK(ctx, sluice_stream_upload(s, pts, n));
    grid_data a = {0}, b = {0};
    run_build_layout(ctx, g, name, NULL, hash, s, pts, stride, n, SR_POINT_GRID_COUNT, 0, &a);
    run_build_layout(ctx, g, name, NULL, hash, s, pts, stride, n, SR_POINT_GRID_BITONIC, 0, &b);
    CHECK(a.order_len == b.order_len &&
              (a.order_len == 0 || memcmp(a.order, b.order, a.order_len * 4) == 0),
          "%s: hashed count and bitonic orders differ", name);
    CHECK(sr_point_grid_build_hashed(g, hash, s, stride, n, SR_POINT_GRID_STENCIL) ==
                  SLUICE_ERROR_INVALID_ARGUMENT &&
              strstr(sr_point_grid_error(g), "stencil"),
          "%s: a hashed stencil build is refused", name);
    grid_data_free(&a);
    grid_data_free(&b);
    sluice_stream_destroy(s);
}

/* Every build on one point set; the stencil with slots enough for the
 * fullest cell must equal the others. */
static void run_all(sluice_context *ctx, sr_point_grid *g, const char *name,
                    const rt_grid_desc *desc, const float *pts, size_t stride, size_t n)
{
    sluice_stream *s = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, stride, n ? n : 1, &s));
    CHECK_OK(ctx, sluice_stream_upload(s, pts, n));
    grid_data a = {0}, b = {0};
    run_build(ctx, g, name, desc, s, pts, stride, n, SR_POINT_GRID_COUNT, 0, &a);
    run_build(ctx, g, name, desc, s, pts, stride, n, SR_POINT_GRID_BITONIC, 0, &b);
    CHECK(a.order_len == b.order_len &&
              (a.order_len == 0 || memcmp(a.order, b.order, a.order_len * 4) == 0),
          "%s: count and bitonic orders differ", name);
    sr_point_grid_stats stt;
    CHECK_OK(ctx, sr_point_grid_statistics(g, &stt));
    size_t cells = (size_t)desc->dims[0] * desc->dims[1] * desc->dims[2];
    uint32_t slots = stt.max_per_cell ? stt.max_per_cell : 1;
    if ((size_t)slots * cells <= ((size_t)1 << 24))
        run_build(ctx, g, name, desc, s, pts, stride, n, SR_POINT_GRID_STENCIL, slots, NULL);
    /* a stencil that overflows (when anything can) */
    if (stt.max_per_cell > 1 && cells * (stt.max_per_cell / 2) <= ((size_t)1 << 24))
        run_build(ctx, g, name, desc, s, pts, stride, n, SR_POINT_GRID_STENCIL,
                  stt.max_per_cell / 2, NULL);
    grid_data_free(&a);
    grid_data_free(&b);
    sluice_stream_destroy(s);
}

static float frand(uint32_t *s)
{
    return (float)(check_rand(s) >> 8) * (1.0f / 16777216.0f);
}

static rt_grid_desc make_desc(float lo, float hi, uint32_t nx, uint32_t ny, uint32_t nz)
{
    rt_grid_desc d;
    char err[256];
    const float l[3] = {lo, lo, lo}, h[3] = {hi, hi, hi};
    const uint32_t dims[3] = {nx, ny, nz};
    CHECK(sr_point_grid_desc_dims(l, h, dims, &d, err, sizeof err) == SLUICE_OK, "desc: %s", err);
    return d;
}

static void test_cases(sluice_context *ctx, sr_point_grid *g)
{
    uint32_t seed = 12345;
    size_t nmax = 200000;
    float *p = malloc(nmax * 3 * sizeof *p);
    rt_grid_desc d = make_desc(-1.0f, 1.0f, 13, 7, 11);

    run_all(ctx, g, "empty", &d, p, 12, 0);
    p[0] = 0.1f, p[1] = 0.2f, p[2] = 0.3f;
    run_all(ctx, g, "one point", &d, p, 12, 1);
    for (size_t i = 0; i < 3 * 12345; ++i)
        p[i] = frand(&seed) * 2.0f - 1.0f;
    run_all(ctx, g, "random 12345", &d, p, 12, 12345);
    run_all(ctx, g, "random 1000", &d, p, 12, 1000);
    /* all points in one cell, and many at one position */
    for (size_t i = 0; i < 5000; ++i) {
        p[3 * i] = 0.01f + 0.001f * frand(&seed);
        p[3 * i + 1] = 0.02f;
        p[3 * i + 2] = 0.03f;
    }
    run_all(ctx, g, "one cell", &d, p, 12, 5000);
    for (size_t i = 0; i < 3000; ++i)
        p[3 * i] = 0.5f, p[3 * i + 1] = -0.5f, p[3 * i + 2] = 0.25f;
    run_all(ctx, g, "same position", &d, p, 12, 3000);
    /* lattice points: on cell faces, edges and corners, the box boundary
     * and beyond it */
    size_t n = 0;
    for (int x = -1; x <= 14; ++x)
        for (int y = -1; y <= 8; ++y)
            for (int z = -1; z <= 12; ++z) {
                p[3 * n] = d.lo[0] + (float)x * d.cell[0];
                p[3 * n + 1] = d.lo[1] + (float)y * d.cell[1];
                p[3 * n + 2] = d.lo[2] + (float)z * d.cell[2];
                ++n;
            }
    p[3 * n] = d.hi[0], p[3 * n + 1] = d.hi[1], p[3 * n + 2] = d.hi[2], ++n;
    p[3 * n] = -1e30f, p[3 * n + 1] = 1e30f, p[3 * n + 2] = 0.0f, ++n;
    run_all(ctx, g, "lattice", &d, p, 12, n);
    /* non-finite points are dropped and counted */
    for (size_t i = 0; i < 3 * 999; ++i)
        p[i] = frand(&seed) * 2.0f - 1.0f;
    p[3 * 10] = NAN;
    p[3 * 20 + 1] = INFINITY;
    p[3 * 30 + 2] = -INFINITY;
    run_all(ctx, g, "non-finite", &d, p, 12, 999);
    /* one cell for the whole grid */
    rt_grid_desc one = make_desc(0.0f, 1.0f, 1, 1, 1);
    run_all(ctx, g, "one-cell grid", &one, p, 12, 999);
    /* a planar photon map on Purcell's 250x1x250 grid */
    {
        const float l[3] = {0, 0.5f, 0}, h[3] = {1, 0.5f, 1};
        const uint32_t dims[3] = {250, 1, 250};
        rt_grid_desc pd;
        char err[256];
        CHECK(sr_point_grid_desc_dims(l, h, dims, &pd, err, sizeof err) == SLUICE_OK, "%s", err);
        for (size_t i = 0; i < 100000; ++i) {
            p[3 * i] = frand(&seed);
            p[3 * i + 1] = 0.5f;
            p[3 * i + 2] = frand(&seed) * frand(&seed); /* denser near z = 0 */
        }
        run_all(ctx, g, "planar 250x1x250", &pd, p, 12, 100000);
    }
    free(p);
}

/* The hashed layout (Purcell 6.4.4) against the reference: random points
 * with ordinary, tiny (every cell collides) and one-bucket tables, all
 * points in one cell or at one position, points on the lattice's faces,
 * below its origin and far beyond its last coordinate (clamped), points far
 * apart in a huge box, non-finite points, photon records; the bucket
 * function's cell coordinates. */
static void test_hashed(sluice_context *ctx, sr_point_grid *g)
{
    uint32_t seed = 2468;
    size_t nmax = 50000;
    float *p = calloc(nmax * 3, sizeof *p);
    sr_point_hash_desc h = {{-1.0f, -1.0f, -1.0f}, 0.125f, 1024};

    run_hashed(ctx, g, "hash empty", &h, p, 12, 0);
    p[0] = 0.1f, p[1] = 0.2f, p[2] = 0.3f;
    run_hashed(ctx, g, "hash one point", &h, p, 12, 1);
    for (size_t i = 0; i < 3 * 12345; ++i)
        p[i] = frand(&seed) * 2.0f - 1.0f;
    run_hashed(ctx, g, "hash random", &h, p, 12, 12345);
    h.buckets = 4;
    run_hashed(ctx, g, "hash random, 4 buckets", &h, p, 12, 12345);
    h.buckets = 1;
    run_hashed(ctx, g, "hash random, 1 bucket", &h, p, 12, 2000);
    h.buckets = 1u << 16;
    for (size_t i = 0; i < 5000; ++i) {
        p[3 * i] = 0.01f + 0.001f * frand(&seed);
        p[3 * i + 1] = 0.02f;
        p[3 * i + 2] = 0.03f;
    }
    run_hashed(ctx, g, "hash one cell", &h, p, 12, 5000);
    for (size_t i = 0; i < 3000; ++i)
        p[3 * i] = 0.5f, p[3 * i + 1] = -0.5f, p[3 * i + 2] = 0.25f;
    run_hashed(ctx, g, "hash same position", &h, p, 12, 3000);
    /* the lattice's faces, edges and corners, and below its origin */
    size_t n = 0;
    for (int x = -2; x <= 17; ++x)
        for (int y = -2; y <= 17; ++y)
            for (int z = -2; z <= 5; ++z) {
                p[3 * n] = h.lo[0] + (float)x * h.cell;
                p[3 * n + 1] = h.lo[1] + (float)y * h.cell;
                p[3 * n + 2] = h.lo[2] + (float)z * h.cell;
                ++n;
            }
    /* far beyond the last coordinate, and at the largest floats */
    p[3 * n] = 1e30f, p[3 * n + 1] = -1e30f, p[3 * n + 2] = 0.0f, ++n;
    p[3 * n] = 3e38f, p[3 * n + 1] = 3e38f, p[3 * n + 2] = -3e38f, ++n;
    p[3 * n] = 1e6f, p[3 * n + 1] = 5e5f, p[3 * n + 2] = 1e6f, ++n;
    run_hashed(ctx, g, "hash lattice", &h, p, 12, n);
    {
        uint32_t c[3];
        const float far[3] = {1e30f, -1e30f, 0.0f}, on[3] = {-0.75f, 0.0f, 0.125f};
        sr_point_grid_bucket_of(&h, far, c);
        CHECK(c[0] == PG_HASH_MAX_COORD && c[1] == 0 && c[2] == 8, "clamped coordinates %u %u %u",
              c[0], c[1], c[2]);
        sr_point_grid_bucket_of(&h, on, c);
        CHECK(c[0] == 2 && c[1] == 8 && c[2] == 9, "coordinates on faces %u %u %u", c[0], c[1],
              c[2]);
        const float bad[3] = {0.0f, NAN, 0.0f};
        CHECK(sr_point_grid_bucket_of(&h, bad, c) == h.buckets && c[0] == 0 && c[1] == 0,
              "a NaN point's bucket");
    }
    /* points far apart in a huge box, lattice of its auto layout */
    {
        const float lo[3] = {-1e4f, -1e4f, -1e4f}, hi[3] = {1e4f, 1e4f, 1e4f};
        sr_point_hash_desc ha;
        char err[256];
        CHECK(sr_point_hash_desc_auto(lo, hi, nmax, 0.01f, &ha, err, sizeof err) == SLUICE_OK, "%s",
              err);
        for (size_t i = 0; i < nmax; ++i) {
            float cx = i % 3 == 0 ? -1e4f : (i % 3 == 1 ? 1e4f : 0.0f);
            p[3 * i] = cx + 0.5f * frand(&seed);
            p[3 * i + 1] = (i % 5 == 0 ? 2e4f * frand(&seed) - 1e4f : 0.5f * frand(&seed));
            p[3 * i + 2] = 2e4f * frand(&seed) * (i % 7 == 0) - 1e4f * (i % 7 == 0);
        }
        run_hashed(ctx, g, "hash huge box", &ha, p, 12, nmax);
    }
    /* non-finite points are dropped and counted */
    for (size_t i = 0; i < 3 * 999; ++i)
        p[i] = frand(&seed) * 2.0f - 1.0f;
    p[3 * 10] = NAN;
    p[3 * 20 + 1] = INFINITY;
    p[3 * 30 + 2] = -INFINITY;
    run_hashed(ctx, g, "hash non-finite", &h, p, 12, 999);
    free(p);
    /* photon records (stride 40) */
    size_t np = 20000;
    pm_photon *ph = calloc(np, sizeof *ph);
    for (size_t i = 0; i < np; ++i) {
        ph[i].px = frand(&seed);
        ph[i].py = frand(&seed) * frand(&seed);
        ph[i].pz = frand(&seed) * 2.0f;
        ph[i].pr = 1.0f;
    }
    sr_point_hash_desc hp = {{0.0f, 0.0f, 0.0f}, 0.05f, 1u << 15};
    run_hashed(ctx, g, "hash photons", &hp, &ph[0].px, sizeof *ph, np);
    free(ph);
}

/* pm_photon records (stride 40), a grid of Purcell's 25x25x50. */
static void test_photons(sluice_context *ctx, sr_point_grid *g)
{
    size_t n = 65000;
    pm_photon *ph = calloc(n, sizeof *ph);
    uint32_t seed = 99;
    for (size_t i = 0; i < n; ++i) {
        ph[i].px = frand(&seed);
        ph[i].py = frand(&seed) * frand(&seed);
        ph[i].pz = frand(&seed) * 2.0f;
        ph[i].pr = 1.0f;
        ph[i].flags = (uint32_t)i & 0xffu;
    }
    const float l[3] = {0, 0, 0}, h[3] = {1, 1, 2};
    const uint32_t dims[3] = {25, 25, 50};
    rt_grid_desc d;
    char err[256];
    CHECK(sr_point_grid_desc_dims(l, h, dims, &d, err, sizeof err) == SLUICE_OK, "%s", err);
    run_all(ctx, g, "photons 25x25x50", &d, &ph[0].px, sizeof *ph, n);
    free(ph);
}

/* Overflowing stencil builds are the same bit for bit every time. */
static void test_determinism(sluice_context *ctx, sr_point_grid *g)
{
    size_t n = 300000;
    float *p = malloc(n * 3 * sizeof *p);
    uint32_t seed = 7;
    for (size_t i = 0; i < 3 * n; ++i) {
        float u = frand(&seed);
        p[i] = u * u; /* dense near 0: many overfull cells */
    }
    rt_grid_desc d = make_desc(0.0f, 1.0f, 20, 20, 20);
    sluice_stream *s = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 12, n, &s));
    CHECK_OK(ctx, sluice_stream_upload(s, p, n));
    grid_data first = {0};
    for (int rep = 0; rep < 3; ++rep) {
        grid_data cur = {0};
        run_build(ctx, g, "determinism", &d, s, p, 12, n, SR_POINT_GRID_STENCIL, 16, &cur);
        sr_point_grid_stats stt;
        CHECK_OK(ctx, sr_point_grid_statistics(g, &stt));
        CHECK(stt.overfull_cells > 100 && stt.overflow_points > 10000,
              "determinism: expected heavy overflow (%zu cells, %zu points)", stt.overfull_cells,
              stt.overflow_points);
        if (rep == 0) {
            first = cur;
            continue;
        }
        CHECK(cur.order_len == first.order_len &&
                  memcmp(cur.order, first.order, cur.order_len * 4) == 0 &&
                  memcmp(cur.count, first.count, 8000 * 4) == 0 &&
                  memcmp(cur.arrived, first.arrived, 8000 * 4) == 0,
              "stencil build %d differs from the first", rep);
        grid_data_free(&cur);
    }
    grid_data_free(&first);
    sluice_stream_destroy(s);
    free(p);
}

/* A million points, each build once (scratch grows, then a small rebuild
 * reuses it). */
static void test_large(sluice_context *ctx, sr_point_grid *g)
{
    size_t n = (size_t)1 << 20;
    float *p = malloc(n * 3 * sizeof *p);
    uint32_t seed = 31337;
    for (size_t i = 0; i < 3 * n; ++i)
        p[i] = frand(&seed) * 10.0f - 5.0f;
    rt_grid_desc d = make_desc(-5.0f, 5.0f, 64, 64, 64);
    sluice_stream *s = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 12, n, &s));
    CHECK_OK(ctx, sluice_stream_upload(s, p, n));
    run_build(ctx, g, "1M", &d, s, p, 12, n, SR_POINT_GRID_COUNT, 0, NULL);
    run_build(ctx, g, "1M", &d, s, p, 12, n, SR_POINT_GRID_BITONIC, 0, NULL);
    run_build(ctx, g, "1M", &d, s, p, 12, n, SR_POINT_GRID_STENCIL, 8, NULL);
    run_build(ctx, g, "1M then 1000", &d, s, p, 12, 1000, SR_POINT_GRID_COUNT, 0, NULL);
    /* a million points in one cell */
    for (size_t i = 0; i < n; ++i)
        p[3 * i] = 0.01f, p[3 * i + 1] = 0.01f, p[3 * i + 2] = 0.01f * frand(&seed);
    CHECK_OK(ctx, sluice_stream_upload(s, p, n));
    run_build(ctx, g, "1M one cell", &d, s, p, 12, n, SR_POINT_GRID_COUNT, 0, NULL);
    run_build(ctx, g, "1M one cell", &d, s, p, 12, n, SR_POINT_GRID_STENCIL, 256, NULL);
    sluice_stream_destroy(s);
    free(p);
}

static void test_errors(sluice_context *ctx, sr_point_grid *g)
{
    rt_grid_desc d = make_desc(0.0f, 1.0f, 4, 4, 4);
    sluice_stream *s = NULL, *s40 = NULL;
    float p[12] = {0};
    CHECK_OK(ctx, sluice_stream_create(ctx, 12, 4, &s));
    CHECK_OK(ctx, sluice_stream_create(ctx, 40, 4, &s40));
    CHECK_OK(ctx, sluice_stream_upload(s, p, 4));
    CHECK(sr_point_grid_create(NULL, NULL) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL out");
    CHECK(sr_point_grid_build(NULL, &d, s, 12, 4, 0, 0) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL");
    CHECK(sr_point_grid_build(g, NULL, s, 12, 4, 0, 0) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL d");
    CHECK(sr_point_grid_build(g, &d, NULL, 12, 4, 0, 0) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL s");
    CHECK(sr_point_grid_build(g, &d, s, 16, 4, 0, 0) == SLUICE_ERROR_INVALID_ARGUMENT, "stride");
    CHECK(sr_point_grid_build(g, &d, s40, 40, 4, 0, 0) == SLUICE_ERROR_INVALID_ARGUMENT,
          "n above the length");
    CHECK(sr_point_grid_build(g, &d, s, 12, 5, 0, 0) == SLUICE_ERROR_INVALID_ARGUMENT, "n > len");
    CHECK(sr_point_grid_build(g, &d, s, 12, 4, (sr_point_grid_build_kind)7, 0) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "kind");
    CHECK(sr_point_grid_build(g, &d, s, 12, 4, SR_POINT_GRID_STENCIL, 0) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "0 slots");
    CHECK(*sr_point_grid_error(g) != '\0', "an error message");
    rt_grid_desc bad = d;
    bad.dims[1] = 0;
    CHECK(sr_point_grid_build(g, &bad, s, 12, 4, 0, 0) == SLUICE_ERROR_INVALID_ARGUMENT, "dims");
    rt_grid_desc big = make_desc(0.0f, 1.0f, 1024, 1024, 64);
    CHECK(sr_point_grid_build(g, &big, s, 12, 4, SR_POINT_GRID_STENCIL, 256) == SLUICE_ERROR_LIMIT,
          "footprint limit");
    sr_point_grid_view v;
    CHECK_OK(ctx, sr_point_grid_get(g, &v));
    CHECK(v.order == NULL && v.cells == 0, "a failed build leaves no grid");
    CHECK_OK(ctx, sr_point_grid_build(g, &d, s, 12, 4, SR_POINT_GRID_COUNT, 0));
    CHECK(*sr_point_grid_error(g) == '\0', "no error after success");
    /* hashed layouts: bad descriptions */
    sr_point_hash_desc h = {{0, 0, 0}, 0.5f, 64};
    CHECK(sr_point_grid_build_hashed(NULL, &h, s, 12, 4, 0) == SLUICE_ERROR_INVALID_ARGUMENT,
          "hash: NULL grid");
    CHECK(sr_point_grid_build_hashed(g, NULL, s, 12, 4, 0) == SLUICE_ERROR_INVALID_ARGUMENT,
          "hash: NULL desc");
    const sr_point_hash_desc bad_h[] = {{{0, 0, 0}, 0.5f, 0},        {{0, 0, 0}, 0.5f, 48},
                                        {{0, 0, 0}, 0.5f, 1u << 28}, {{0, 0, 0}, 0.0f, 64},
                                        {{0, 0, 0}, -1.0f, 64},      {{0, 0, 0}, NAN, 64},
                                        {{0, 0, 0}, 1e-45f, 64},     {{0, INFINITY, 0}, 0.5f, 64}};
    for (size_t i = 0; i < sizeof bad_h / sizeof *bad_h; ++i)
        CHECK(sr_point_grid_build_hashed(g, &bad_h[i], s, 12, 4, SR_POINT_GRID_COUNT) ==
                      SLUICE_ERROR_INVALID_ARGUMENT &&
                  *sr_point_grid_error(g),
              "hash: bad description %zu", i);
    CHECK(sr_point_grid_build_hashed(g, &h, s, 16, 4, 0) == SLUICE_ERROR_INVALID_ARGUMENT,
          "hash: stride");
    CHECK(sr_point_grid_build_hashed(g, &h, s, 12, 5, 0) == SLUICE_ERROR_INVALID_ARGUMENT,
          "hash: n > len");
    CHECK(sr_point_grid_build_hashed(g, &h, s, 12, 4, (sr_point_grid_build_kind)7) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "hash: kind");
    CHECK_OK(ctx, sr_point_grid_get(g, &v));
    CHECK(v.order == NULL && v.cells == 0, "a failed hashed build leaves no grid");
    CHECK_OK(ctx, sr_point_grid_build_hashed(g, &h, s, 12, 4, SR_POINT_GRID_COUNT));
    CHECK(*sr_point_grid_error(g) == '\0', "no error after a hashed build");
    sluice_stream_destroy(s);
    sluice_stream_destroy(s40);
}

static void test_desc(void)
{
    char err[256];
    rt_grid_desc d;
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 2};
    CHECK(sr_point_grid_desc_auto(lo, hi, 65000, 0.05f, &d, err, sizeof err) == SLUICE_OK, "%s",
          err);
    CHECK(d.dims[0] == 27 && d.dims[1] == 27 && d.dims[2] == 54, "auto dims %u %u %u", d.dims[0],
          d.dims[1], d.dims[2]);
    CHECK(fabsf(d.cell[0] - 0.0375f) < 1e-3f && d.lo[0] <= 0.0f && d.hi[2] >= 2.0f, "auto cell %g",
          (double)d.cell[0]);
    /* capped by the point count */
    CHECK(sr_point_grid_desc_auto(lo, hi, 100, 0.001f, &d, err, sizeof err) == SLUICE_OK, "%s",
          err);
    size_t cells = (size_t)d.dims[0] * d.dims[1] * d.dims[2];
    CHECK(cells <= 400 && cells >= 100, "capped cells %zu", cells);
    /* flat: one cell along y */
    const float flo[3] = {0, 3, 0}, fhi[3] = {1, 3, 1};
    CHECK(sr_point_grid_desc_auto(flo, fhi, 65000, 0.1f, &d, err, sizeof err) == SLUICE_OK, "%s",
          err);
    CHECK(d.dims[1] == 1 && d.dims[0] == 14 && d.lo[1] < 3.0f && d.hi[1] > 3.0f, "flat %u %u %u",
          d.dims[0], d.dims[1], d.dims[2]);
    CHECK(sr_point_grid_desc_auto(lo, hi, 10, 0.0f, &d, err, sizeof err) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "radius 0");
    const float nan_hi[3] = {1, NAN, 1};
    CHECK(sr_point_grid_desc_auto(lo, nan_hi, 10, 1.0f, &d, err, sizeof err) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "NaN bounds");
    const uint32_t dims[3] = {250, 1, 250}, zero[3] = {250, 0, 250};
    CHECK(sr_point_grid_desc_dims(flo, fhi, dims, &d, err, sizeof err) == SLUICE_OK, "%s", err);
    CHECK(d.dims[0] == 250 && d.dims[1] == 1 && d.cell[1] > 0.0f, "250x1x250");
    CHECK(sr_point_grid_desc_dims(flo, fhi, zero, &d, err, sizeof err) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "zero dims");

    /* the hashed layout: cells of the radius, two to four buckets per
     * point, coarser cells past SR_POINT_HASH_MAX_SIDE across the box */
    sr_point_hash_desc h;
    CHECK(sr_point_hash_desc_auto(lo, hi, 1000, 0.05f, &h, err, sizeof err) == SLUICE_OK, "%s",
          err);
    CHECK(h.cell == (float)(SR_POINT_HASH_EDGE * 0.05) && h.buckets == 2048 && h.lo[2] == 0.0f,
          "hash auto: cell %g, %u buckets", (double)h.cell, h.buckets);
    CHECK(sr_point_hash_desc_auto(lo, hi, 0, 0.05f, &h, err, sizeof err) == SLUICE_OK &&
              h.buckets == 64,
          "hash auto, no points: %u buckets", h.buckets);
    const float blo[3] = {-1e4f, 0, 0}, bhi[3] = {1e4f, 1, 1};
    CHECK(sr_point_hash_desc_auto(blo, bhi, 1000, 1e-5f, &h, err, sizeof err) == SLUICE_OK &&
              h.cell >= 2e4f / (float)SR_POINT_HASH_MAX_SIDE,
          "hash auto, huge box: cell %g", (double)h.cell);
    CHECK(sr_point_hash_desc_auto(lo, hi, 10, 0.0f, &h, err, sizeof err) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "hash auto: radius 0");
    CHECK(sr_point_hash_desc_auto(lo, nan_hi, 10, 1.0f, &h, err, sizeof err) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "hash auto: NaN bounds");

    /* the plan: auto takes the hash, whether the dense cells fit or the cap
     * makes them coarser (the why says which); a request decides */
    sr_point_grid_plan plan;
    CHECK(sr_point_grid_plan_auto(lo, hi, 65000, 0.05f, 0.1f, SR_POINT_GRID_LAYOUT_AUTO, &plan, err,
                                  sizeof err) == SLUICE_OK,
          "%s", err);
    CHECK(plan.layout == SR_POINT_GRID_HASHED && plan.coarsening == 1.0 &&
              plan.dense.dims[0] == 27 && plan.hash.cell == (float)(SR_POINT_HASH_EDGE * 0.1) &&
              strstr(plan.why, "hash (auto") && strstr(plan.why, "fit"),
          "plan, cells that fit: %d, %g: %s", (int)plan.layout, plan.coarsening, plan.why);
    const float wlo[3] = {-1000, -1000, -1000}, whi[3] = {1000, 1000, 1000};
    CHECK(sr_point_grid_plan_auto(wlo, whi, 65000, 0.05f, 0.1f, SR_POINT_GRID_LAYOUT_AUTO, &plan,
                                  err, sizeof err) == SLUICE_OK,
          "%s", err);
    CHECK(plan.layout == SR_POINT_GRID_HASHED && plan.coarsening > 1.0 &&
              plan.wanted_cells > 1e14 && strstr(plan.why, "hash (auto") &&
              strstr(plan.why, "coarser"),
          "plan, a huge box: %d, %g: %s", (int)plan.layout, plan.coarsening, plan.why);
    CHECK(sr_point_grid_plan_auto(wlo, whi, 65000, 0.05f, 0.1f, SR_POINT_GRID_DENSE, &plan, err,
                                  sizeof err) == SLUICE_OK &&
              plan.layout == SR_POINT_GRID_DENSE && strstr(plan.why, "asked"),
          "plan, dense asked for: %s", plan.why);
    CHECK(sr_point_grid_plan_auto(lo, hi, 65000, 0.05f, 0.1f, SR_POINT_GRID_HASHED, &plan, err,
                                  sizeof err) == SLUICE_OK &&
              plan.layout == SR_POINT_GRID_HASHED && strstr(plan.why, "asked"),
          "plan, hash asked for: %s", plan.why);
    CHECK(sr_point_grid_plan_auto(lo, hi, 65000, 0.05f, 0.1f, (sr_point_grid_layout)9, &plan, err,
                                  sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "plan: unknown layout");
    CHECK(sr_point_grid_plan_auto(lo, hi, 65000, 0.05f, -1.0f, SR_POINT_GRID_LAYOUT_AUTO, &plan,
                                  err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "plan: bad search radius");
}

int main(void)
{
    sluice_context *ctx = check_context(0);
    sr_point_grid *g = NULL;
    CHECK_OK(ctx, sr_point_grid_create(ctx, &g));
    if (!g) {
        sluice_context_destroy(ctx);
        return check_summary();
    }
    test_desc();
    test_errors(ctx, g);
    test_cases(ctx, g);
    test_photons(ctx, g);
    test_hashed(ctx, g);
    test_determinism(ctx, g);
    test_large(ctx, g);
    sr_point_grid_destroy(g);
    sluice_context_destroy(ctx);
    return check_summary();
}
