/* Tests of the ray tracer's uniform grid (apps/render/grid.h; Purcell 3.2,
 * 5.2.1): the choice of resolution, the C build against a brute-force
 * reference (every triangle against every voxel) and against point samples
 * of the triangles (no voxel a triangle passes through may miss it), and the
 * device build against the C build, element by element, on random triangle
 * soups and on built-in scenes. */
#include "clock.h"
#include "check.h"
#include "grid.h"
#include "scene.h"

#include "../kernels/render/tri_box.h"

#include <math.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#define UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UNDER_ASAN 1
#endif
#endif
#ifndef UNDER_ASAN
#define UNDER_ASAN 0
#endif

#define BUNNY_PATH "/usr/share/glmark2/models/bunny.obj"

/* A uniform float in [a, b). */
static float frand(uint32_t *s, float a, float b)
{
    return a + (b - a) * (float)(check_rand(s) >> 8) * (1.0f / 16777216.0f);
}

/* ------------------------------------------------------------------ */
/* rt_grid_choose                                                      */
/* ------------------------------------------------------------------ */

static void check_contains(const rt_grid_desc *d, const float lo[3], const float hi[3],
                           const char *what)
{
    for (int a = 0; a < 3; ++a) {
        CHECK(d->lo[a] < lo[a] && d->hi[a] > hi[a], "%s: axis %d: [%g, %g] inside [%g, %g]", what,
              a, (double)lo[a], (double)hi[a], (double)d->lo[a], (double)d->hi[a]);
        float expect = (d->hi[a] - d->lo[a]) / (float)d->dims[a];
        CHECK(d->cell[a] == expect, "%s: cell %d is (hi - lo) / dims", what, a);
    }
}

static void test_choose(void)
{
    char err[256];
    rt_grid_desc d;
    {
        float lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
        CHECK(rt_grid_choose(lo, hi, 4, &d, err, sizeof err) == SLUICE_OK, "%s", err);
        CHECK(d.dims[0] == 4 && d.dims[1] == 8 && d.dims[2] == 12, "1x2x3/4 -> %ux%ux%u", d.dims[0],
              d.dims[1], d.dims[2]);
        check_contains(&d, lo, hi, "1x2x3");
        for (int a = 1; a < 3; ++a)
            CHECK(fabsf(d.cell[a] - d.cell[0]) <= 1e-6f * d.cell[0], "cubic voxels (%g, %g)",
                  (double)d.cell[0], (double)d.cell[a]);
    }
    {
        /* The same box shifted and scaled: the rule only sees proportions. */
        float lo[3] = {-1000, 50, 7}, hi[3] = {-997, 56, 7.75f};
        CHECK(rt_grid_choose(lo, hi, 8, &d, err, sizeof err) == SLUICE_OK, "%s", err);
        CHECK(d.dims[0] == 32 && d.dims[1] == 64 && d.dims[2] == 8, "-> %ux%ux%u", d.dims[0],
              d.dims[1], d.dims[2]);
        check_contains(&d, lo, hi, "shifted");
    }
    {
        /* A cube: min_dim on every axis, up to the cell limit exactly. */
        float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
        CHECK(rt_grid_choose(lo, hi, 512, &d, err, sizeof err) == SLUICE_OK, "%s", err);
        CHECK(d.dims[0] == 512 && d.dims[1] == 512 && d.dims[2] == 512, "cube 512");
        CHECK(rt_grid_choose(lo, hi, 513, &d, err, sizeof err) == SLUICE_ERROR_LIMIT,
              "cube 513: limit");
        CHECK(d.dims[0] == 0, "zeroed on failure");
        CHECK(strstr(err, "limit") != NULL, "message: %s", err);
        CHECK(rt_grid_choose(lo, hi, 4000000u, &d, err, sizeof err) == SLUICE_ERROR_LIMIT,
              "absurd min_dim: limit");
        CHECK(rt_grid_choose(lo, hi, 1, &d, err, sizeof err) == SLUICE_OK && d.dims[0] == 1 &&
                  d.dims[1] == 1 && d.dims[2] == 1,
              "min_dim 1");
    }
    {
        /* Flat box (a planar scene): the flat axis gets one voxel around the
         * plane, the others follow the shortest non-flat axis. */
        float lo[3] = {0, 0, 5}, hi[3] = {2, 1, 5};
        CHECK(rt_grid_choose(lo, hi, 8, &d, err, sizeof err) == SLUICE_OK, "%s", err);
        CHECK(d.dims[0] == 16 && d.dims[1] == 8 && d.dims[2] == 1, "flat z -> %ux%ux%u", d.dims[0],
              d.dims[1], d.dims[2]);
        check_contains(&d, lo, hi, "flat z");
        CHECK(fabsf(0.5f * (d.lo[2] + d.hi[2]) - 5.0f) < 1e-5f, "plane centred in its voxel");
        /* Flat up to rounding noise. */
        float lo2[3] = {0, 0, 0}, hi2[3] = {1e-7f, 1, 1};
        CHECK(rt_grid_choose(lo2, hi2, 8, &d, err, sizeof err) == SLUICE_OK, "%s", err);
        CHECK(d.dims[0] == 1 && d.dims[1] == 8 && d.dims[2] == 8, "near-flat x -> %ux%ux%u",
              d.dims[0], d.dims[1], d.dims[2]);
        check_contains(&d, lo2, hi2, "near-flat");
        /* A segment: two flat axes. */
        float lo3[3] = {0, 3, 3}, hi3[3] = {4, 3, 3};
        CHECK(rt_grid_choose(lo3, hi3, 8, &d, err, sizeof err) == SLUICE_OK, "%s", err);
        CHECK(d.dims[0] == 8 && d.dims[1] == 1 && d.dims[2] == 1, "segment -> %ux%ux%u", d.dims[0],
              d.dims[1], d.dims[2]);
        /* A point, and the origin. */
        float p[3] = {3, -2, 1}, o[3] = {0, 0, 0};
        CHECK(rt_grid_choose(p, p, 32, &d, err, sizeof err) == SLUICE_OK && d.dims[0] == 1 &&
                  d.dims[1] == 1 && d.dims[2] == 1,
              "point -> one voxel");
        check_contains(&d, p, p, "point");
        CHECK(rt_grid_choose(o, o, 32, &d, err, sizeof err) == SLUICE_OK && d.dims[0] == 1,
              "origin -> one voxel");
        check_contains(&d, o, o, "origin");
    }
    {
        /* Bad input. */
        float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, bad[3] = {0, NAN, 1}, inf[3] = {0, 1, INFINITY};
        float rev[3] = {1, -1, 1};
        CHECK(rt_grid_choose(lo, hi, 0, &d, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
              "min_dim 0");
        CHECK(rt_grid_choose(lo, bad, 4, &d, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
              "NaN");
        CHECK(rt_grid_choose(lo, inf, 4, &d, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
              "infinity");
        CHECK(rt_grid_choose(lo, rev, 4, &d, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
              "lo > hi: %s", err);
        CHECK(rt_grid_choose(lo, hi, 4, NULL, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
              "NULL out");
        CHECK(rt_grid_choose(NULL, hi, 4, &d, NULL, 0) == SLUICE_ERROR_INVALID_ARGUMENT,
              "NULL lo, no message buffer");
        float far_lo[3] = {-3e38f, 0, 0}, far_hi[3] = {3e38f, 1, 1};
        CHECK(rt_grid_choose(far_lo, far_hi, 4, &d, err, sizeof err) ==
                  SLUICE_ERROR_INVALID_ARGUMENT,
              "bounds beyond float: %s", err);
    }
    {
        /* Description checks. */
        rt_grid_desc g = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {0.5f, 0.5f, 0.5f}};
        size_t cells = 0;
        CHECK(rt_grid_desc_check(&g, &cells, err, sizeof err) == SLUICE_OK && cells == 8, "ok");
        g.dims[1] = 0;
        CHECK(rt_grid_desc_check(&g, &cells, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
              "dims 0");
        g.dims[1] = 2;
        g.cell[2] = -1.0f;
        CHECK(rt_grid_desc_check(&g, &cells, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
              "negative cell");
        g.cell[2] = 0.5f;
        g.dims[0] = g.dims[1] = g.dims[2] = 1024;
        CHECK(rt_grid_desc_check(&g, &cells, err, sizeof err) == SLUICE_ERROR_LIMIT,
              "too many cells");
    }
}

/* ------------------------------------------------------------------ */
/* Triangle soups and references                                       */
/* ------------------------------------------------------------------ */

typedef struct soup {
    float *pos;
    uint32_t *idx;
    size_t nv, nt;
} soup;

static void soup_alloc(soup *s, size_t nt)
{
    s->nt = nt;
    s->nv = 3 * nt;
    s->pos = malloc(s->nv * 3 * sizeof *s->pos);
    s->idx = malloc(nt * 3 * sizeof *s->idx);
    if (!s->pos || !s->idx) {
        fprintf(stderr, "out of memory\n");
        exit(2);
    }
    for (size_t i = 0; i < 3 * nt; ++i)
        s->idx[i] = (uint32_t)i;
}

static void soup_free(soup *s)
{
    free(s->pos);
    free(s->idx);
    memset(s, 0, sizeof *s);
}

/* A coordinate on the grid's lattice of half voxels (faces, edges, corners,
 * centres), sometimes just off it, or anywhere. */
static float lattice(uint32_t *r, const rt_grid_desc *d, int a)
{
    uint32_t k = check_rand(r) % (2 * d->dims[a] + 1);
    float x = d->lo[a] + 0.5f * (float)k * d->cell[a];
    switch (check_rand(r) % 4) {
    case 0:
        return x + d->cell[a] * 1e-4f * frand(r, -1.0f, 1.0f);
    case 1:
        return frand(r, d->lo[a], d->hi[a]);
    default:
        return x;
    }
}

/* Fills a soup with triangles of every kind the grid must handle. */
static void soup_random(soup *s, const rt_grid_desc *d, uint32_t seed)
{
    uint32_t r = seed | 1u;
    for (size_t t = 0; t < s->nt; ++t) {
        float *p = s->pos + 9 * t;
        unsigned kind = check_rand(&r) % 7;
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a)
                p[3 * k + a] = lattice(&r, d, a);
        switch (kind) {
        case 0: /* axis-aligned: one coordinate shared by all corners */
        {
            int a = (int)(check_rand(&r) % 3);
            p[3 + a] = p[6 + a] = p[a];
            break;
        }
        case 1: /* tiny, around a lattice point */
        {
            float size = d->cell[0] * (check_rand(&r) % 2 ? 1e-3f : 1e-5f);
            for (int k = 1; k < 3; ++k)
                for (int a = 0; a < 3; ++a)
                    p[3 * k + a] = p[a] + size * frand(&r, -1.0f, 1.0f);
            break;
        }
        case 2: /* huge, reaching far out of the grid */
            for (int k = 0; k < 3; ++k)
                for (int a = 0; a < 3; ++a) {
                    float ext = d->hi[a] - d->lo[a];
                    p[3 * k + a] = frand(&r, d->lo[a] - 2 * ext, d->hi[a] + 2 * ext);
                }
            break;
        case 3: /* degenerate: collinear, or two equal corners */
        {
            int same = (int)(check_rand(&r) % 2);
            for (int a = 0; a < 3; ++a)
                p[6 + a] = same ? p[a] : 0.5f * (p[a] + p[3 + a]);
            break;
        }
        default: /* anything, corners on the lattice */
            break;
        }
    }
}

/* The brute-force grid: every voxel against every triangle, with the same
 * test. Lists in the layout of grid.h. */
static void brute_force(const rt_grid_desc *d, const soup *s, uint32_t **start_out,
                        uint32_t **tris_out)
{
    rt_grid_params g;
    rt_grid_params_make(&g, d->lo, d->cell, d->dims);
    size_t cells = (size_t)d->dims[0] * d->dims[1] * d->dims[2];
    uint32_t *start = calloc(cells + 1, sizeof *start);
    size_t cap = 1024, n = 0;
    uint32_t *tris = malloc(cap * sizeof *tris);
    rt_tri *prep = malloc((s->nt ? s->nt : 1) * sizeof *prep);
    for (size_t t = 0; t < s->nt; ++t) {
        const uint32_t *ix = s->idx + 3 * t;
        rt_tri_setup(&prep[t], s->pos + 3 * ix[0], s->pos + 3 * ix[1], s->pos + 3 * ix[2]);
    }
    const float h[3] = {rt_voxel_half(g.cell[0]), rt_voxel_half(g.cell[1]),
                        rt_voxel_half(g.cell[2])};
    for (uint32_t z = 0; z < d->dims[2]; ++z)
        for (uint32_t y = 0; y < d->dims[1]; ++y)
            for (uint32_t x = 0; x < d->dims[0]; ++x) {
                size_t c = x + (size_t)d->dims[0] * (y + (size_t)d->dims[1] * z);
                float ctr[3] = {rt_voxel_center(g.lo[0], g.cell[0], x),
                                rt_voxel_center(g.lo[1], g.cell[1], y),
                                rt_voxel_center(g.lo[2], g.cell[2], z)};
                start[c] = (uint32_t)n;
                for (size_t t = 0; t < s->nt; ++t) {
                    if (!rt_tri_box_overlap(&prep[t], ctr, h))
                        continue;
                    if (n == cap)
                        tris = realloc(tris, (cap *= 2) * sizeof *tris);
                    tris[n++] = (uint32_t)t;
                }
            }
    start[cells] = (uint32_t)n;
    free(prep);
    *start_out = start;
    *tris_out = tris;
}

/* Element-by-element comparison of two grids' arrays. */
static int same_lists(size_t cells, const uint32_t *s1, const uint32_t *t1, const uint32_t *s2,
                      const uint32_t *t2, const char *what)
{
    for (size_t c = 0; c <= cells; ++c)
        if (s1[c] != s2[c]) {
            CHECK(0, "%s: cell_start[%zu] %u != %u", what, c, s1[c], s2[c]);
            return 0;
        }
    for (size_t i = 0; i < s1[cells]; ++i)
        if (t1[i] != t2[i]) {
            CHECK(0, "%s: cell_tris[%zu] %u != %u", what, i, t1[i], t2[i]);
            return 0;
        }
    CHECK(1, "%s", what);
    return 1;
}

/* Non-zero when voxel c lists triangle t. */
static int lists(const rt_grid_host *g, size_t c, uint32_t t)
{
    for (uint32_t i = g->cell_start[c]; i < g->cell_start[c + 1]; ++i)
        if (g->cell_tris[i] == t)
            return 1;
    return 0;
}

/* Point samples of every triangle (corners, edges, inside, in double): the
 * voxel holding each sample must list the triangle. Independent of the
 * separating axis code, so it checks the test itself for false negatives. */
static void check_samples(const rt_grid_host *g, const soup *s, const char *what)
{
    const rt_grid_desc *d = &g->desc;
    const int steps = 6;
    size_t misses = 0, samples = 0;
    for (size_t t = 0; t < s->nt; ++t) {
        const float *p[3];
        for (int k = 0; k < 3; ++k)
            p[k] = s->pos + 3 * s->idx[3 * t + k];
        for (int i = 0; i <= steps; ++i)
            for (int j = 0; i + j <= steps; ++j) {
                double u = (double)i / steps, v = (double)j / steps, vox[3];
                int inside = 1;
                for (int a = 0; a < 3 && inside; ++a) {
                    double x = (1 - u - v) * p[0][a] + u * p[1][a] + v * p[2][a];
                    vox[a] = floor((x - d->lo[a]) / d->cell[a]);
                    inside = vox[a] >= 0 && vox[a] < d->dims[a];
                }
                if (!inside)
                    continue;
                size_t c =
                    (size_t)vox[0] + d->dims[0] * ((size_t)vox[1] + d->dims[1] * (size_t)vox[2]);
                ++samples;
                if (!lists(g, c, (uint32_t)t) && misses++ < 1)
                    fprintf(stderr,
                            "%s: triangle %zu missing from voxel %zu (%a %a %a | %a %a %a | %a %a "
                            "%a) u=%g v=%g lo %a %a %a cell %a %a %a\n",
                            what, t, c, p[0][0], p[0][1], p[0][2], p[1][0], p[1][1], p[1][2],
                            p[2][0], p[2][1], p[2][2], u, v, d->lo[0], d->lo[1], d->lo[2],
                            d->cell[0], d->cell[1], d->cell[2]);
            }
    }
    CHECK(misses == 0, "%s: %zu of %zu samples in voxels that miss their triangle", what, misses,
          samples);
}

/* ------------------------------------------------------------------ */
/* Host build                                                          */
/* ------------------------------------------------------------------ */

static void test_host_known(void)
{
    /* The triangle x + y <= 4 in the plane z = 0 on a 4 x 4 x 1 grid of unit
     * voxels centred on the plane: it touches voxel (i, j) exactly when
     * i + j <= 4 (at i + j == 4 only in a corner). Its bounding box would
     * take all 16. */
    rt_grid_desc d = {{0, 0, -0.5f}, {4, 4, 0.5f}, {4, 4, 1}, {1, 1, 1}};
    float pos[9] = {0, 0, 0, 4, 0, 0, 0, 4, 0};
    uint32_t idx[3] = {0, 1, 2};
    rt_grid_host g;
    char err[256];
    CHECK(rt_grid_build_host(&d, pos, idx, 1, &g, err, sizeof err) == SLUICE_OK, "%s", err);
    for (uint32_t j = 0; j < 4; ++j)
        for (uint32_t i = 0; i < 4; ++i) {
            size_t c = i + 4 * j;
            CHECK((g.cell_start[c + 1] - g.cell_start[c] == 1) == (i + j <= 4),
                  "voxel (%u, %u): %u entries", i, j, g.cell_start[c + 1] - g.cell_start[c]);
        }
    CHECK(g.cell_start[16] == 13, "13 voxels (%u)", g.cell_start[16]);
    rt_grid_host_free(&g);

    /* A triangle in the shared face z = 1 of a 1 x 1 x 2 grid is in both
     * voxels; one on the outer face z = 0 in the first. */
    rt_grid_desc d2 = {{0, 0, 0}, {1, 1, 2}, {1, 1, 2}, {1, 1, 1}};
    float pos2[18] = {0, 0, 1, 1, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 0, 1, 0};
    uint32_t idx2[6] = {0, 1, 2, 3, 4, 5};
    CHECK(rt_grid_build_host(&d2, pos2, idx2, 2, &g, err, sizeof err) == SLUICE_OK, "%s", err);
    CHECK(g.cell_start[1] == 2 && g.cell_start[2] == 3 && g.cell_tris[0] == 0 &&
              g.cell_tris[1] == 1 && g.cell_tris[2] == 0,
          "shared face: %u %u", g.cell_start[1], g.cell_start[2]);
    rt_grid_host_free(&g);

    /* Errors: a non-finite corner, bad descriptions, NULL. */
    pos[4] = NAN;
    CHECK(rt_grid_build_host(&d, pos, idx, 1, &g, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NaN corner");
    CHECK(g.cell_start == NULL && strstr(err, "triangle 0") != NULL, "message: %s", err);
    pos[4] = 0;
    d.dims[2] = 0;
    CHECK(rt_grid_build_host(&d, pos, idx, 1, &g, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "dims 0");
    d.dims[2] = 1;
    CHECK(rt_grid_build_host(&d, NULL, idx, 1, &g, err, sizeof err) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL positions");
    CHECK(rt_grid_build_host(&d, pos, idx, 1, NULL, err, sizeof err) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL out");
    /* No triangles: an empty grid. */
    CHECK(rt_grid_build_host(&d, NULL, NULL, 0, &g, err, sizeof err) == SLUICE_OK &&
              g.cell_start[16] == 0,
          "no triangles");
    rt_grid_host_free(&g);
    /* Too many entries: the limit is checked (with a small limit here; the
     * default one takes 2^27 entries to reach). */
    d.dims[2] = 1;
    CHECK(rt_grid_build_host_limit(&d, pos, idx, 1, 13, &g, err, sizeof err) == SLUICE_OK &&
              g.cell_start[16] == 13,
          "13 entries within a limit of 13: %s", err);
    rt_grid_host_free(&g);
    CHECK(rt_grid_build_host_limit(&d, pos, idx, 1, 12, &g, err, sizeof err) == SLUICE_ERROR_LIMIT,
          "13 entries over a limit of 12");
    CHECK(g.cell_start == NULL && strstr(err, "limit of 12") != NULL, "message: %s", err);
}

/* ------------------------------------------------------------------ */
/* Device build                                                        */
/* ------------------------------------------------------------------ */

/* Builds on the device from host arrays and compares with the host grid. */
static void device_vs_host(sluice_context *ctx, const rt_grid_desc *d, const float *pos, size_t nv,
                           const uint32_t *idx, size_t nt, const rt_grid_host *host,
                           const char *what, double *seconds, size_t *bytes)
{
    sluice_stream *sp = NULL, *si = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 12, nv, &sp));
    CHECK_OK(ctx, sluice_stream_create(ctx, 12, nt, &si));
    CHECK_OK(ctx, sluice_stream_upload(sp, pos, nv));
    CHECK_OK(ctx, sluice_stream_upload(si, idx, nt));
    CHECK_OK(ctx, sluice_context_finish(ctx));
    rt_grid_device g;
    double t0 = sr_clock_seconds();
    sluice_status st = rt_grid_build_device(ctx, d, sp, si, nt, &g);
    sluice_context_finish(ctx);
    double t1 = sr_clock_seconds();
    if (seconds)
        *seconds = t1 - t0;
    CHECK(st == SLUICE_OK, "%s: device build: %s: %s", what, sluice_status_string(st), g.message);
    if (st == SLUICE_OK) {
        size_t cells = (size_t)d->dims[0] * d->dims[1] * d->dims[2], n1 = 0, n2 = 0;
        uint32_t *start = malloc((cells + 1) * sizeof *start);
        uint32_t *tris = malloc((g.cell_tri_count + 1) * sizeof *tris);
        CHECK_OK(ctx, sluice_stream_download(g.cell_start, start, cells + 1, &n1));
        CHECK_OK(ctx, sluice_stream_download(g.cell_tris, tris, g.cell_tri_count, &n2));
        CHECK(n1 == cells + 1 && n2 == g.cell_tri_count &&
                  g.cell_tri_count == host->cell_start[cells],
              "%s: lengths %zu %zu, %zu entries (host %u)", what, n1, n2, g.cell_tri_count,
              host->cell_start[cells]);
        CHECK(g.message[0] == 0, "no message after success");
        CHECK(g.bytes >= (cells + 1 + g.cell_tri_count) * 4, "bytes %zu", g.bytes);
        if (n1 == cells + 1 && n2 == host->cell_start[cells])
            same_lists(cells, host->cell_start, host->cell_tris, start, tris, what);
        if (bytes)
            *bytes = g.bytes;
        free(start);
        free(tris);
    }
    rt_grid_device_free(&g);
    sluice_stream_destroy(sp);
    sluice_stream_destroy(si);
}

static void test_soups(sluice_context *ctx)
{
    const float boxes[][6] = {
        {0, 0, 0, 1, 1, 1}, {-3, 0.5f, 2, 4, 1.25f, 9}, {100, 100, 100, 103, 101, 100.5f}};
    const unsigned mins[] = {3, 4, 2};
    for (size_t b = 0; b < sizeof mins / sizeof *mins; ++b) {
        rt_grid_desc d;
        char err[256], what[64];
        CHECK(rt_grid_choose(boxes[b], boxes[b] + 3, mins[b], &d, err, sizeof err) == SLUICE_OK,
              "%s", err);
        for (uint32_t seed = 1; seed <= 3; ++seed) {
            soup s;
            soup_alloc(&s, 300);
            soup_random(&s, &d, seed * 7919u + (uint32_t)b);
            snprintf(what, sizeof what, "soup %zu/%u (%ux%ux%u)", b, seed, d.dims[0], d.dims[1],
                     d.dims[2]);
            rt_grid_host g;
            CHECK(rt_grid_build_host(&d, s.pos, s.idx, s.nt, &g, err, sizeof err) == SLUICE_OK,
                  "%s: %s", what, err);
            uint32_t *bs, *bt;
            brute_force(&d, &s, &bs, &bt);
            size_t cells = (size_t)d.dims[0] * d.dims[1] * d.dims[2];
            same_lists(cells, bs, bt, g.cell_start, g.cell_tris, what);
            check_samples(&g, &s, what);
            device_vs_host(ctx, &d, s.pos, s.nv, s.idx, s.nt, &g, what, NULL, NULL);
            free(bs);
            free(bt);
            rt_grid_host_free(&g);
            soup_free(&s);
        }
    }
    /* A fixed grid of unit voxels, so that lattice points are exact faces,
     * edges and corners. */
    rt_grid_desc d = {{-2, -2, -2}, {3, 2, 4}, {5, 4, 6}, {1, 1, 1}};
    soup s;
    soup_alloc(&s, 400);
    soup_random(&s, &d, 12345u);
    rt_grid_host g;
    char err[256];
    CHECK(rt_grid_build_host(&d, s.pos, s.idx, s.nt, &g, err, sizeof err) == SLUICE_OK, "%s", err);
    uint32_t *bs, *bt;
    brute_force(&d, &s, &bs, &bt);
    same_lists(120, bs, bt, g.cell_start, g.cell_tris, "unit lattice");
    check_samples(&g, &s, "unit lattice");
    device_vs_host(ctx, &d, s.pos, s.nv, s.idx, s.nt, &g, "unit lattice", NULL, NULL);
    free(bs);
    free(bt);
    rt_grid_host_free(&g);
    soup_free(&s);
}

static void test_device_errors(sluice_context *ctx)
{
    rt_grid_desc d = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {0.5f, 0.5f, 0.5f}};
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t idx[6] = {0, 1, 2, 0, 1, 3};
    sluice_stream *sp = NULL, *si = NULL, *s4 = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 12, 3, &sp));
    CHECK_OK(ctx, sluice_stream_create(ctx, 12, 2, &si));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 2, &s4));
    CHECK_OK(ctx, sluice_stream_upload(sp, pos, 3));
    CHECK_OK(ctx, sluice_stream_upload(si, idx, 2));
    rt_grid_device g;
    CHECK(rt_grid_build_device(ctx, &d, sp, si, 2, &g) == SLUICE_ERROR_INVALID_ARGUMENT,
          "index past the vertices");
    CHECK(g.cell_start == NULL && strstr(g.message, "index") != NULL, "message: %s", g.message);
    CHECK(rt_grid_build_device(ctx, &d, sp, si, 3, &g) == SLUICE_ERROR_INVALID_ARGUMENT,
          "more triangles than indices: %s", g.message);
    CHECK(rt_grid_build_device(ctx, &d, s4, si, 1, &g) == SLUICE_ERROR_INVALID_ARGUMENT,
          "4-byte positions: %s", g.message);
    CHECK(rt_grid_build_device(NULL, &d, sp, si, 1, &g) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL context");
    CHECK(rt_grid_build_device(ctx, &d, sp, si, 1, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL out");
    rt_grid_desc bad = d;
    bad.cell[0] = NAN;
    CHECK(rt_grid_build_device(ctx, &bad, sp, si, 1, &g) == SLUICE_ERROR_INVALID_ARGUMENT,
          "bad description: %s", g.message);
    /* A non-finite corner. */
    pos[1] = INFINITY;
    CHECK_OK(ctx, sluice_stream_upload(sp, pos, 3));
    CHECK(rt_grid_build_device(ctx, &d, sp, si, 1, &g) == SLUICE_ERROR_INVALID_ARGUMENT,
          "infinite corner: %s", g.message);
    pos[1] = 0;
    CHECK_OK(ctx, sluice_stream_upload(sp, pos, 3));
    /* No triangles: every voxel empty. */
    CHECK(rt_grid_build_device(ctx, &d, sp, si, 0, &g) == SLUICE_OK, "no triangles: %s", g.message);
    uint32_t start[9];
    size_t n = 0;
    memset(start, 0xff, sizeof start);
    if (g.cell_start)
        CHECK_OK(ctx, sluice_stream_download(g.cell_start, start, 9, &n));
    CHECK(n == 9 && start[0] == 0 && start[8] == 0 && g.cell_tri_count == 0, "empty grid");
    rt_grid_device_free(&g);
    /* The pair limit: 13 entries (see test_host_known) over limits of 12
     * and 13. */
    rt_grid_desc known = {{0, 0, -0.5f}, {4, 4, 0.5f}, {4, 4, 1}, {1, 1, 1}};
    float big[9] = {0, 0, 0, 4, 0, 0, 0, 4, 0};
    CHECK_OK(ctx, sluice_stream_upload(sp, big, 3));
    CHECK(rt_grid_build_device_limit(ctx, &known, sp, si, 1, 12, &g) == SLUICE_ERROR_LIMIT,
          "pair limit: %s", g.message);
    CHECK(strstr(g.message, "13 (voxel, triangle) entries") != NULL && g.cell_start == NULL,
          "message: %s", g.message);
    CHECK(rt_grid_build_device_limit(ctx, &known, sp, si, 1, 13, &g) == SLUICE_OK &&
              g.cell_tri_count == 13,
          "pair limit 13: %s", g.message);
    rt_grid_device_free(&g);
    CHECK_OK(ctx, sluice_stream_upload(sp, pos, 3));
    /* Upload of a host grid. */
    rt_grid_host h;
    char err[256];
    CHECK(rt_grid_build_host(&d, pos, idx, 1, &h, err, sizeof err) == SLUICE_OK, "%s", err);
    CHECK(rt_grid_upload(ctx, &h, &g) == SLUICE_OK, "upload: %s", g.message);
    uint32_t tris[16];
    size_t nt = 0;
    CHECK_OK(ctx, sluice_stream_download(g.cell_start, start, 9, &n));
    CHECK_OK(ctx, sluice_stream_download(g.cell_tris, tris, 16, &nt));
    CHECK(n == 9 && nt == g.cell_tri_count && nt == h.cell_start[8] &&
              memcmp(start, h.cell_start, sizeof start) == 0 &&
              memcmp(tris, h.cell_tris, nt * 4) == 0,
          "upload matches");
    CHECK(g.bytes == (9 + 1 + nt + 1) * 4, "upload bytes %zu", g.bytes);
    rt_grid_device_free(&g);
    rt_grid_device_free(NULL);
    rt_grid_host_free(&h);
    rt_grid_host_free(NULL);
    CHECK(rt_grid_upload(ctx, NULL, &g) == SLUICE_ERROR_INVALID_ARGUMENT, "upload NULL");
    sluice_stream_destroy(sp);
    sluice_stream_destroy(si);
    sluice_stream_destroy(s4);
}

/* 2^20 copies of a tiny triangle and one triangle across 64 x 64 voxels:
 * triangles x (largest count) reaches 2^32, where the device build no longer
 * trusts the 32-bit scan total and sums the counts in 64 bits. */
static void test_many(sluice_context *ctx)
{
    const size_t nt = ((size_t)1 << 20) + 1;
    rt_grid_desc d = {{0, 0, -0.5f}, {64, 64, 63.5f}, {64, 64, 64}, {1, 1, 1}};
    float pos[18] = {0.25f, 0.25f, 10, 0.5f, 0.25f, 10, 0.25f, 0.5f, 10,
                     -1,    -1,    0,  200,  -1,    0,  -1,    200,  0};
    uint32_t *idx = malloc(nt * 3 * sizeof *idx);
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k)
            idx[3 * t + k] = (uint32_t)(t == nt / 2 ? 3 + k : k);
    rt_grid_host h;
    char err[256];
    CHECK(rt_grid_build_host(&d, pos, idx, nt, &h, err, sizeof err) == SLUICE_OK, "%s", err);
    CHECK(h.cell_start[(size_t)64 * 64 * 64] == (nt - 1) + 64 * 64, "%u entries",
          h.cell_start[(size_t)64 * 64 * 64]);
    device_vs_host(ctx, &d, pos, 6, idx, nt, &h, "2^20 + 1 triangles", NULL, NULL);
    rt_grid_host_free(&h);
    free(idx);
}

/* A scene: grid dims at the default and at 64, host and device builds
 * compared (compare_host > 0), or the device build alone (0), or timed: the
 * device build five times, then the C build (< 0). Times and memory are
 * printed. */
static void test_scene(sluice_context *ctx, const char *name, int compare_host)
{
    char err[512];
    sr_scene_load_options o = {0};
    o.flags = SR_SCENE_ALLOW_NO_LIGHT;
    sr_scene *sc = NULL;
    double t0 = sr_clock_seconds();
    sluice_status st = sr_scene_load(name, &o, &sc, err, sizeof err);
    double t_load = sr_clock_seconds() - t0;
    CHECK(st == SLUICE_OK, "loading %s: %s", name, err);
    if (st != SLUICE_OK)
        return;
    const sr_scene_stats *stats = sr_scene_statistics(sc);
    rt_grid_desc d, d64;
    CHECK(rt_grid_choose(stats->bounds_min, stats->bounds_max, RT_GRID_DEFAULT_MIN_DIM, &d, err,
                         sizeof err) == SLUICE_OK,
          "%s: %s", name, err);
    CHECK(rt_grid_choose(stats->bounds_min, stats->bounds_max, 64, &d64, err, sizeof err) ==
              SLUICE_OK,
          "%s: %s", name, err);
    size_t nt = sr_scene_triangle_count(sc), nv = sr_scene_vertex_count(sc);
    const float *pos = sr_scene_positions(sc);
    const uint32_t *idx = sr_scene_indices(sc);
    rt_grid_host h = {0};
    double t_host = 0, t_dev = 0;
    size_t bytes = 0, entries = 0;
    if (compare_host > 0) {
        t0 = sr_clock_seconds();
        CHECK(rt_grid_build_host(&d, pos, idx, nt, &h, err, sizeof err) == SLUICE_OK, "%s: %s",
              name, err);
        t_host = sr_clock_seconds() - t0;
        device_vs_host(ctx, &d, pos, nv, idx, nt, &h, name, &t_dev, &bytes);
        if (h.cell_start)
            entries = h.cell_start[(size_t)d.dims[0] * d.dims[1] * d.dims[2]];
    } else {
        /* Device only (the C build is too slow here): build and check the
         * structure's invariants instead. */
        sluice_stream *sp = NULL, *si = NULL;
        CHECK_OK(ctx, sluice_stream_create(ctx, 12, nv, &sp));
        CHECK_OK(ctx, sluice_stream_create(ctx, 12, nt, &si));
        CHECK_OK(ctx, sluice_stream_upload(sp, pos, nv));
        CHECK_OK(ctx, sluice_stream_upload(si, idx, nt));
        CHECK_OK(ctx, sluice_context_finish(ctx));
        /* The first build also loads the kernels: report the best of a few. */
        for (int rep = 0; rep < (compare_host < 0 ? 5 : 1); ++rep) {
            rt_grid_device g;
            t0 = sr_clock_seconds();
            st = rt_grid_build_device(ctx, &d, sp, si, nt, &g);
            sluice_context_finish(ctx);
            double t = sr_clock_seconds() - t0;
            if (rep == 0 || t < t_dev)
                t_dev = t;
            if (compare_host < 0)
                printf("  device build %d: %.3f s\n", rep, t);
            CHECK(st == SLUICE_OK, "%s: %s", name, g.message);
            bytes = g.bytes;
            entries = g.cell_tri_count;
            rt_grid_device_free(&g);
        }
        if (compare_host < 0) {
            rt_grid_host h2;
            t0 = sr_clock_seconds();
            CHECK(rt_grid_build_host(&d, pos, idx, nt, &h2, err, sizeof err) == SLUICE_OK, "%s: %s",
                  name, err);
            t_host = sr_clock_seconds() - t0;
            printf("  C build: %.3f s\n", t_host);
            rt_grid_host_free(&h2);
        }
        sluice_stream_destroy(sp);
        sluice_stream_destroy(si);
    }
    printf("%-10s %8zu triangles (load %.2f s): grid %ux%ux%u (min_dim 64: %ux%ux%u), "
           "%zu entries, %.1f MB; build device %.3f s",
           name, nt, t_load, d.dims[0], d.dims[1], d.dims[2], d64.dims[0], d64.dims[1], d64.dims[2],
           entries, bytes / 1e6, t_dev);
    if (compare_host > 0)
        printf(", C %.3f s", t_host);
    printf("\n");
    if (strcmp(name, "million") == 0) {
        size_t total = bytes + 24 * nt; /* grid + positions and indices (<= 12 B each) */
        CHECK(total < 200u * 1000 * 1000, "million: grid + triangles %zu bytes", total);
    }
    rt_grid_host_free(&h);
    sr_scene_destroy(sc);
}

/* A scene of one triangle, built with the scene builder. */
static void test_one_triangle(sluice_context *ctx)
{
    char err[256];
    sr_scene_builder *b = NULL;
    sr_scene *sc = NULL;
    sr_material m = sr_material_make(SR_MATERIAL_DIFFUSE, "grey");
    float pos[9] = {0.25f, -1, 3, 2, 0.5f, 3.5f, -1, 1, 2};
    uint32_t idx[3] = {0, 1, 2};
    sr_mesh_desc mesh = {0};
    mesh.source = "one";
    mesh.positions = pos;
    mesh.vertex_count = 3;
    mesh.indices = idx;
    mesh.triangle_count = 1;
    CHECK(sr_scene_builder_create("one triangle", &b) == SLUICE_OK, "builder");
    CHECK(sr_scene_builder_add_material(b, &m, NULL, err, sizeof err) == SLUICE_OK, "%s", err);
    CHECK(sr_scene_builder_add_mesh(b, &mesh, err, sizeof err) == SLUICE_OK, "%s", err);
    CHECK(sr_scene_builder_finish(b, SR_SCENE_ALLOW_NO_LIGHT, &sc, err, sizeof err) == SLUICE_OK,
          "%s", err);
    sr_scene_builder_destroy(b);
    if (!sc)
        return;
    const sr_scene_stats *st = sr_scene_statistics(sc);
    rt_grid_desc d;
    CHECK(rt_grid_choose(st->bounds_min, st->bounds_max, RT_GRID_DEFAULT_MIN_DIM, &d, err,
                         sizeof err) == SLUICE_OK,
          "%s", err);
    rt_grid_host h;
    CHECK(rt_grid_build_host(&d, sr_scene_positions(sc), sr_scene_indices(sc), 1, &h, err,
                             sizeof err) == SLUICE_OK,
          "%s", err);
    soup s = {(float *)sr_scene_positions(sc), (uint32_t *)sr_scene_indices(sc), 3, 1};
    check_samples(&h, &s, "one triangle");
    device_vs_host(ctx, &d, sr_scene_positions(sc), 3, sr_scene_indices(sc), 1, &h, "one triangle",
                   NULL, NULL);
    printf("one triangle: grid %ux%ux%u, %u entries\n", d.dims[0], d.dims[1], d.dims[2],
           h.cell_start[(size_t)d.dims[0] * d.dims[1] * d.dims[2]]);
    rt_grid_host_free(&h);
    sr_scene_destroy(sc);
}

/* rt_grid_auto_min_dim: about RT_GRID_AUTO_DENSITY voxels per triangle. */
static void test_auto_min_dim(void)
{
    const float lo[3] = {0, 0, 0}, cube[3] = {1, 1, 1}, slab[3] = {4, 2, 0}, box[3] = {2, 1, 4};
    /* a unit cube, 1000 triangles: 5000 voxels, edge 5000^(-1/3), 17 per axis */
    unsigned d = rt_grid_auto_min_dim(lo, cube, 1000);
    CHECK(d == 17, "cube: min dim %u, expected 17", d);
    /* a box 2 x 1 x 4 and 1000 triangles: edge (8 / 5000)^(1/3), 1 / edge = 8.55 */
    d = rt_grid_auto_min_dim(lo, box, 1000);
    CHECK(d == 9, "box: min dim %u, expected 9", d);
    /* flat (z = 0): an area 4 x 2 cut into about 5000 squares: edge 0.04, 50 */
    d = rt_grid_auto_min_dim(lo, slab, 1000);
    CHECK(d == 50, "slab: min dim %u, expected 50", d);
    /* few triangles: at least one voxel */
    d = rt_grid_auto_min_dim(lo, cube, 1);
    CHECK(d == 2, "one triangle: min dim %u, expected 2", d);
    /* many: capped at RT_GRID_AUTO_MAX_CELLS, and the grid is valid */
    d = rt_grid_auto_min_dim(lo, box, (size_t)1 << 30);
    rt_grid_desc desc;
    char err[256];
    CHECK(rt_grid_choose(lo, box, d, &desc, err, sizeof err) == SLUICE_OK, "capped: %s", err);
    CHECK((double)desc.dims[0] * desc.dims[1] * desc.dims[2] <= (double)RT_GRID_AUTO_MAX_CELLS,
          "capped: %u x %u x %u voxels", desc.dims[0], desc.dims[1], desc.dims[2]);
    /* a point, bad bounds, no triangles */
    CHECK(rt_grid_auto_min_dim(lo, lo, 100) == 1, "point");
    const float bad[3] = {1, NAN, 1};
    CHECK(rt_grid_auto_min_dim(lo, bad, 100) == RT_GRID_DEFAULT_MIN_DIM, "NaN bounds");
    CHECK(rt_grid_auto_min_dim(lo, cube, 0) == RT_GRID_DEFAULT_MIN_DIM, "no triangles");

    /* a floor on the voxel edge: big triangles coarsen the grid, small ones
     * leave the density rule alone */
    d = rt_grid_auto_min_dim_edge(lo, cube, 1000, 0.25);
    CHECK(d == 4, "edge floor 0.25: min dim %u, expected 4", d);
    d = rt_grid_auto_min_dim_edge(lo, cube, 1000, 0.01);
    CHECK(d == 17, "edge floor 0.01: min dim %u, expected 17", d);
    d = rt_grid_auto_min_dim_edge(lo, cube, 1000, 0.0);
    CHECK(d == 17, "no edge floor: min dim %u, expected 17", d);
    d = rt_grid_auto_min_dim_edge(lo, cube, 1000, NAN);
    CHECK(d == 17, "NaN edge floor: min dim %u, expected 17", d);

    /* another density: 1.5 voxels per triangle, 1500 voxels, 11.4 per axis;
     * a density that is not positive and finite is the default one */
    d = rt_grid_auto_min_dim_density(lo, cube, 1000, 0.0, 1.5);
    CHECK(d == 11, "density 1.5: min dim %u, expected 11", d);
    d = rt_grid_auto_min_dim_density(lo, cube, 1000, 0.0, RT_GRID_AUTO_DENSITY);
    CHECK(d == 17, "default density: min dim %u, expected 17", d);
    d = rt_grid_auto_min_dim_density(lo, cube, 1000, 0.25, 1.5);
    CHECK(d == 4, "density 1.5, edge floor 0.25: min dim %u, expected 4", d);
    const double bad_density[] = {0.0, -1.0, NAN, INFINITY};
    for (size_t k = 0; k < sizeof bad_density / sizeof *bad_density; ++k) {
        d = rt_grid_auto_min_dim_density(lo, cube, 1000, 0.0, bad_density[k]);
        CHECK(d == 17, "density %g: min dim %u, expected 17", bad_density[k], d);
    }

    /* edge quartile: right triangles with legs 1 and 2 (edges 1, 2, sqrt 5):
     * the lower quartile of {1, 2, 2.24} x N is 1; a non-finite vertex's
     * edges are left out; no triangles give 0 */
    const float pos[] = {0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 5, 1, 0, 5, 0, 2, 5, 0, 0, INFINITY};
    const uint32_t idx[] = {0, 1, 2, 3, 4, 5, 6, 6, 6};
    double q = rt_grid_edge_quartile(pos, idx, 2);
    CHECK(q == 1.0, "edge quartile %g, expected 1", q);
    q = rt_grid_edge_quartile(pos, idx, 3);
    CHECK(q == 1.0, "edge quartile with a non-finite triangle %g, expected 1", q);
    CHECK(rt_grid_edge_quartile(pos, idx, 0) == 0.0, "no triangles");
    CHECK(rt_grid_edge_quartile(pos, idx + 6, 1) == 0.0, "only non-finite edges");
}

int main(int argc, char **argv)
{
    /* --scene NAME: one scene only, timed (measurements by hand; with
     * SLUICE_PROFILE=1 the per-kernel table follows). */
    if (argc >= 3 && strcmp(argv[1], "--scene") == 0) {
        sluice_context *ctx = check_context(0);
        test_scene(ctx, argv[2], -1);
        if (sluice_profile_enabled(ctx))
            sluice_profile_print(ctx, stdout);
        sluice_context_destroy(ctx);
        return check_summary();
    }
    test_choose();
    test_auto_min_dim();
    test_host_known();
    sluice_context *ctx = check_context(0);
    test_soups(ctx);
    test_device_errors(ctx);
    test_one_triangle(ctx);
    test_many(ctx);
    test_scene(ctx, "cornell", 1);
    test_scene(ctx, "spheres:50", 1);
    if (access(BUNNY_PATH, R_OK) == 0)
        test_scene(ctx, "bunny", 1);
    else
        printf("skipping bunny: %s is missing (Debian package glmark2-data)\n", BUNNY_PATH);
    /* The million-triangle scene: device build only, and not under the
     * sanitizers (minutes there); the memory bound is checked. */
    if (!UNDER_ASAN)
        test_scene(ctx, "million", 0);
    else
        printf("skipping million under AddressSanitizer\n");
    sluice_context_destroy(ctx);
    return check_summary();
}
