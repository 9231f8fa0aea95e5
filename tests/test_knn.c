/* Tests of the kNN-grid search (apps/photonmap/knn.h; Purcell 6.2.3)
 * against FLANN's exact searches (FLANN_INDEX_KDTREE_SINGLE with eps 0; the
 * default randomized kd-trees are approximate), for every build of the point
 * grid (the stencil with slots enough for the fullest cell), on random
 * photons, all photons in one cell, many photons at one point (ties),
 * photons on cell faces and corners, a planar map on 250x1x250, fewer
 * photons than k, an empty map and queries outside the grid:
 *
 *   atleast  every photon FLANN finds within the final radius is in the
 *            estimate, every photon of the estimate is within it, and there
 *            are at least min(k, photons within the maximum radius). Float
 *            rounding differs between FLANN and the kernel (summation
 *            order), so "within" allows a relative band of 1e-5 of r^2 at
 *            the boundary: photons inside the band may be in or out.
 *   exact    the same multiset of squared distances as FLANN's k nearest
 *            within the maximum radius (sorted, compared with a relative
 *            tolerance of 1e-5: ties make the indices ambiguous).
 *
 * Also: the three builds give the same results bit for bit, the summed
 * power matches the photons listed, the normal filter, exact mode in
 * several batches, statistics and the error paths; and the radius search
 * (PM_KNN_RADIUS) over the dense grid and the hashed one (Purcell 6.4.4)
 * against brute force and FLANN's radius search, photon set by photon set
 * (test_radius), with what a hashed grid refuses. */
#include "check.h"
#include "knn.h"

#include <flann/flann.h>
#include <math.h>
#include <string.h>

#define BAND 1e-5

static float frand(uint32_t *s)
{
    return (float)(check_rand(s) >> 8) * (1.0f / 16777216.0f);
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* The kernels' squared distance and normal-filter dot product (PM_D2_ and
 * PM_DOT_ in pm_knn.cl), the same fused operations, so that radii agree
 * bit for bit. */
static float fused_d2(float dx, float dy, float dz)
{
    return fmaf(dz, dz, fmaf(dy, dy, dx * dx));
}

static float fused_dot(const pm_query *q, const pm_photon *p)
{
    return fmaf(q->nz, p->dz, fmaf(q->ny, p->dy, q->nx * p->dx));
}

static float dist2(const pm_photon *p, const pm_query *q)
{
    return fused_d2(p->px - q->px, p->py - q->py, p->pz - q->pz);
}

typedef struct fixture {
    sluice_context *ctx;
    sr_point_grid *grid;
    pm_knn *knn;
} fixture;

typedef struct flann_ref {
    flann_index_t index;
    struct FLANNParameters params;
    float *pos;
    int *idx;
    float *d;
    size_t np;
} flann_ref;

static void flann_ref_init(flann_ref *f, const pm_photon *ph, size_t np)
{
    memset(f, 0, sizeof *f);
    f->np = np;
    f->params = DEFAULT_FLANN_PARAMETERS;
    f->params.algorithm = FLANN_INDEX_KDTREE_SINGLE;
    f->params.checks = FLANN_CHECKS_UNLIMITED;
    f->params.eps = 0.0f;
    f->params.sorted = 1;
    f->params.max_neighbors = -1;
    f->params.log_level = FLANN_LOG_NONE;
    f->params.leaf_max_size = 10;
    f->params.cores = 1;
    f->pos = malloc((np * 3 + 3) * sizeof *f->pos);
    f->idx = malloc((np + 1) * sizeof *f->idx);
    f->d = malloc((np + 1) * sizeof *f->d);
    for (size_t i = 0; i < np; ++i) {
        f->pos[3 * i] = ph[i].px;
        f->pos[3 * i + 1] = ph[i].py;
        f->pos[3 * i + 2] = ph[i].pz;
    }
    if (np) {
        float speedup;
        f->index = flann_build_index_float(f->pos, (int)np, 3, &speedup, &f->params);
        CHECK(f->index != NULL, "FLANN index");
    }
}

static void flann_ref_free(flann_ref *f)
{
    if (f->index)
        flann_free_index_float(f->index, &f->params);
    free(f->pos);
    free(f->idx);
    free(f->d);
}

/* Photons FLANN finds within squared radius r2 of q (into f->idx, f->d). */
static int flann_within(flann_ref *f, const pm_query *q, float r2)
{
    if (!f->np || !(r2 >= 0.0f))
        return 0;
    float qp[3] = {q->px, q->py, q->pz};
    if (isinf(r2))
        r2 = 3.0e38f;
    return flann_radius_search_float(f->index, qp, f->idx, f->d, (int)f->np, r2, &f->params);
}

/* Checks the results of one query call of either mode against FLANN. */
static void check_against_flann(const char *name, pm_knn_mode mode, flann_ref *f,
                                const pm_photon *ph, const pm_query *qs, size_t nq,
                                const pm_knn_result *res, const uint32_t *ind, uint32_t cap,
                                uint32_t k, float max_r)
{
    const char *mname = mode == PM_KNN_EXACT ? "exact" : "atleast";
    float max_r2 = max_r * max_r;
    char *in = calloc(f->np + 1, 1);
    float *mine = malloc(((size_t)cap + 1) * sizeof *mine);
    size_t bad = 0, cut = 0;
    for (size_t q = 0; q < nq && bad < 8; ++q) {
        const pm_knn_result *r = &res[q];
        if (r->flags & PM_KNN_INDICES_CUT) {
            ++cut;
            continue;
        }
        uint32_t m = r->count;
        int ok = (r->flags & PM_KNN_DONE) != 0;
        /* the list, its power and its radius */
        double sr = 0.0;
        float far = 0.0f;
        for (uint32_t j = 0; j < m; ++j) {
            uint32_t id = ind[q * cap + j];
            if (id >= f->np) {
                ok = 0;
                break;
            }
            in[id] = 1;
            sr += ph[id].pr;
            mine[j] = dist2(&ph[id], &qs[q]);
            far = fmaxf(far, mine[j]);
        }
        ok = ok && fabs(sr - r->sr) <= 1e-4 * fabs(sr) + 1e-6;
        ok = ok && (m == 0 ? r->r2 == 0.0f : far == r->r2);
        ok = ok && r->r2 <= max_r2 * (1.0f + (float)BAND);
        int within_max = flann_within(f, &qs[q], max_r2 * (float)(1.0 - BAND));
        uint32_t want = within_max < (int)k ? (uint32_t)within_max : k;
        if (mode == PM_KNN_ATLEAST) {
            ok = ok && m >= want;
            /* all of FLANN's photons inside the radius are listed */
            int inner = flann_within(f, &qs[q], r->r2 * (float)(1.0 - BAND));
            for (int j = 0; ok && j < inner; ++j)
                ok = in[f->idx[j]];
            /* and nothing beyond it: the list is the photons within r */
            int outer = flann_within(f, &qs[q], r->r2 * (float)(1.0 + BAND));
            ok = ok && (int)m <= outer && (int)m >= inner;
        } else {
            /* FLANN's k nearest within the maximum radius */
            int nn = f->np < k ? (int)f->np : (int)k, got = 0;
            if (nn > 0) {
                float qp[3] = {qs[q].px, qs[q].py, qs[q].pz};
                flann_find_nearest_neighbors_index_float(f->index, qp, 1, f->idx, f->d, nn,
                                                         &f->params);
                for (int j = 0; j < nn; ++j)
                    got += f->d[j] <= max_r2;
            }
            qsort(f->d, (size_t)got, sizeof *f->d, cmp_float);
            qsort(mine, m, sizeof *mine, cmp_float);
            /* a photon right at the maximum radius may fall either way */
            int extra = (int)m - got;
            if (extra != 0) {
                float edge = extra > 0 ? mine[m - 1] : f->d[got - 1];
                ok = ok && abs(extra) == 1 && fabsf(edge - max_r2) <= (float)BAND * max_r2;
            }
            int common = got < (int)m ? got : (int)m;
            for (int j = 0; ok && j < common; ++j)
                ok = fabsf(mine[j] - f->d[j]) <= (float)BAND * fmaxf(f->d[j], 1e-30f);
        }
        for (uint32_t j = 0; j < m && ind[q * cap + j] < f->np; ++j)
            in[ind[q * cap + j]] = 0;
        if (!ok) {
            ++bad;
            CHECK(0,
                  "%s/%s: query %zu at (%g %g %g): count %u r2 %g flags %u shells %u, FLANN "
                  "within max %d",
                  name, mname, q, (double)qs[q].px, (double)qs[q].py, (double)qs[q].pz, m,
                  (double)r->r2, r->flags, r->shells, within_max);
        }
    }
    CHECK(bad == 0, "%s/%s: %zu queries differ from FLANN", name, mname, bad);
    CHECK(cut * 10 <= nq, "%s/%s: %zu of %zu index lists were cut", name, mname, cut, nq);
    free(in);
    free(mine);
}

/* Whether two calls' results agree in everything but the order in which
 * the power was summed: count, radius, shells and flags bit for bit, the
 * sums to a relative 1e-5. */
static int same_but_sums(const pm_knn_result *a, const pm_knn_result *b, size_t nq)
{
    for (size_t q = 0; q < nq; ++q) {
        float x[3] = {a[q].sr, a[q].sg, a[q].sb}, y[3] = {b[q].sr, b[q].sg, b[q].sb};
        if (a[q].count != b[q].count || memcmp(&a[q].r2, &b[q].r2, sizeof a[q].r2) != 0 ||
            a[q].shells != b[q].shells || a[q].flags != b[q].flags)
            return 0;
        for (int c = 0; c < 3; ++c)
            if (!(fabsf(x[c] - y[c]) <= 1e-5f * fabsf(x[c]) + 1e-30f))
                return 0;
    }
    return 1;
}

/* Runs both modes on every build, checks against FLANN and that the builds
 * agree bit for bit. */
static void run_case(fixture *fx, const char *name, const rt_grid_desc *desc, const pm_photon *ph,
                     size_t np, const pm_query *qs, size_t nq, uint32_t k, float max_r)
{
    sluice_context *ctx = fx->ctx;
    sluice_stream *sp = NULL, *sq = NULL, *sr = NULL, *si = NULL;
    /* room for every photon of the map when that fits 64 MiB */
    uint32_t cap = np < 8192 ? (uint32_t)(np ? np : 1) : 8192u;
    if ((size_t)cap * nq > ((size_t)16 << 20))
        cap = (uint32_t)(((size_t)16 << 20) / nq);
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_photon), np ? np : 1, &sp));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_query), nq, &sq));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_knn_result), nq, &sr));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, (size_t)cap * nq, &si));
    CHECK_OK(ctx, sluice_stream_upload(sp, ph, np));
    CHECK_OK(ctx, sluice_stream_upload(sq, qs, nq));
    pm_knn_result *res = malloc(nq * sizeof *res), *first[2] = {NULL, NULL};
    uint32_t *ind = malloc((size_t)cap * nq * sizeof *ind);
    flann_ref f;
    flann_ref_init(&f, ph, np);
    for (int b = 0; b < 3; ++b) {
        sr_point_grid_build_kind kind = (sr_point_grid_build_kind)b;
        uint32_t slots = 0;
        if (kind == SR_POINT_GRID_STENCIL) {
            sr_point_grid_stats st;
            sr_point_grid_statistics(fx->grid, &st);
            slots = st.max_per_cell ? st.max_per_cell : 1;
        }
        sluice_status s =
            sr_point_grid_build(fx->grid, desc, sp, sizeof(pm_photon), np, kind, slots);
        CHECK(s == SLUICE_OK, "%s: build %d: %s", name, b, sr_point_grid_error(fx->grid));
        if (s != SLUICE_OK)
            continue;
        for (int m = 0; m < 2; ++m) {
            pm_knn_options o = {k, max_r, (pm_knn_mode)m, 0, NULL, NULL, 0};
            pm_knn_stats stats;
            s = pm_knn_query_indices(fx->knn, fx->grid, sp, sq, nq, sr, &o, si, cap, &stats);
            CHECK(s == SLUICE_OK, "%s: query: %s", name, pm_knn_error(fx->knn));
            if (s != SLUICE_OK)
                continue;
            CHECK_OK(ctx, sluice_stream_download(sr, res, nq, NULL));
            CHECK_OK(ctx, sluice_stream_download(si, ind, (size_t)cap * nq, NULL));
            CHECK(stats.queries == nq && stats.passes >= 1 && stats.live[0] <= nq, "%s: statistics",
                  name);
            char full[128];
            snprintf(full, sizeof full, "%s/build %d", name, b);
            if (b == 0) {
                check_against_flann(full, (pm_knn_mode)m, &f, ph, qs, nq, res, ind, cap, k, max_r);
                first[m] = malloc(nq * sizeof *res);
                memcpy(first[m], res, nq * sizeof *res);
                /* more shells per pass: the same shells in the same order,
                 * so the same results, in fewer passes; all of them in one
                 * pass in at-least mode sums the photons within the radius
                 * 8 queries at a time (pm_knn_sum): the same photons, the
                 * same radius, the sums in another order */
                static const uint32_t spp[2] = {3, PM_KNN_ALL_SHELLS};
                for (int v = 0; v < 2; ++v) {
                    pm_knn_stats more;
                    o.shells_per_pass = spp[v];
                    int summed = spp[v] == PM_KNN_ALL_SHELLS && m == PM_KNN_ATLEAST;
                    if (summed) {
                        CHECK_OK(ctx, pm_knn_query_indices(fx->knn, fx->grid, sp, sq, nq, sr, &o,
                                                           si, cap, &more));
                        CHECK_OK(ctx, sluice_stream_download(si, ind, (size_t)cap * nq, NULL));
                    } else {
                        CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, nq, sr, &o, &more));
                    }
                    CHECK_OK(ctx, sluice_stream_download(sr, res, nq, NULL));
                    int same = summed ? same_but_sums(first[m], res, nq)
                                      : memcmp(first[m], res, nq * sizeof *res) == 0;
                    CHECK(same && more.passes <= stats.passes &&
                              (spp[v] != PM_KNN_ALL_SHELLS || more.passes == more.batches),
                          "%s: mode %d: %u shells per pass: other results or %u passes (one "
                          "shell: %u)",
                          full, m, spp[v], more.passes, stats.passes);
                    if (summed) {
                        char all[160];
                        snprintf(all, sizeof all, "%s/all shells", full);
                        check_against_flann(all, (pm_knn_mode)m, &f, ph, qs, nq, res, ind, cap, k,
                                            max_r);
                    }
                }
            } else {
                CHECK(memcmp(first[m], res, nq * sizeof *res) == 0,
                      "%s: mode %d: build %d differs from the counting build", name, m, b);
            }
        }
    }
    flann_ref_free(&f);
    free(first[0]);
    free(first[1]);
    free(res);
    free(ind);
    sluice_stream_destroy(sp);
    sluice_stream_destroy(sq);
    sluice_stream_destroy(sr);
    sluice_stream_destroy(si);
}

static void random_queries(pm_query *qs, size_t nq, float lo, float hi, uint32_t *seed)
{
    for (size_t i = 0; i < nq; ++i) {
        qs[i].px = lo + (hi - lo) * frand(seed);
        qs[i].py = lo + (hi - lo) * frand(seed);
        qs[i].pz = lo + (hi - lo) * frand(seed);
        qs[i].nx = 0.0f, qs[i].ny = 1.0f, qs[i].nz = 0.0f;
        qs[i].id = (uint32_t)i;
    }
}

static void set_photon(pm_photon *p, float x, float y, float z, uint32_t *seed)
{
    memset(p, 0, sizeof *p);
    p->px = x, p->py = y, p->pz = z;
    p->pr = 0.5f + frand(seed), p->pg = 1.0f, p->pb = 0.25f;
    p->dy = frand(seed) < 0.5f ? -1.0f : 1.0f;
}

static rt_grid_desc desc_of(const float lo[3], const float hi[3], uint32_t nx, uint32_t ny,
                            uint32_t nz)
{
    rt_grid_desc d;
    char err[256];
    const uint32_t dims[3] = {nx, ny, nz};
    CHECK(sr_point_grid_desc_dims(lo, hi, dims, &d, err, sizeof err) == SLUICE_OK, "%s", err);
    return d;
}

static void test_cases(fixture *fx)
{
    uint32_t seed = 2024;
    size_t np_max = 40000, nq = 2000;
    pm_photon *ph = malloc(np_max * sizeof *ph);
    pm_query *qs = malloc(nq * sizeof *qs);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    char err[256];

    /* random photons, an automatic grid, queries partly outside it */
    for (size_t i = 0; i < 20000; ++i)
        set_photon(&ph[i], frand(&seed), frand(&seed), frand(&seed), &seed);
    rt_grid_desc d;
    CHECK(sr_point_grid_desc_auto(lo, hi, 20000, 0.05f, &d, err, sizeof err) == SLUICE_OK, "%s",
          err);
    random_queries(qs, nq, -0.2f, 1.2f, &seed);
    run_case(fx, "random k=16", &d, ph, 20000, qs, nq, 16, 0.2137f);
    run_case(fx, "random k=100", &d, ph, 20000, qs, nq, 100, 0.3137f);
    rt_grid_desc coarse = desc_of(lo, hi, 5, 3, 4);
    run_case(fx, "random coarse k=40 r=inf", &coarse, ph, 20000, qs, nq, 40, INFINITY);

    /* all photons in one cell of a 10^3 grid */
    for (size_t i = 0; i < 5000; ++i)
        set_photon(&ph[i], 0.42f + 0.05f * frand(&seed), 0.51f + 0.05f * frand(&seed),
                   0.33f + 0.05f * frand(&seed), &seed);
    rt_grid_desc ten = desc_of(lo, hi, 10, 10, 10);
    random_queries(qs, nq, 0.0f, 1.0f, &seed);
    run_case(fx, "one cell", &ten, ph, 5000, qs, nq, 50, 0.4137f);

    /* many photons at one point (ties), among random ones */
    for (size_t i = 0; i < 5000; ++i) {
        if (i % 5 < 3)
            set_photon(&ph[i], 0.5f, 0.25f, 0.75f, &seed);
        else
            set_photon(&ph[i], frand(&seed), frand(&seed), frand(&seed), &seed);
    }
    for (size_t i = 0; i < nq / 2; ++i)
        qs[i].px = 0.5f + 0.02f * frand(&seed), qs[i].py = 0.25f, qs[i].pz = 0.75f;
    run_case(fx, "ties", &ten, ph, 5000, qs, nq, 32, 0.1537f);

    /* photons on cell faces, edges and corners; queries on them too */
    size_t n = 0;
    for (int x = 0; x <= 10; ++x)
        for (int y = 0; y <= 10; ++y)
            for (int z = 0; z <= 10; ++z) {
                set_photon(&ph[n++], ten.lo[0] + (float)x * ten.cell[0],
                           ten.lo[1] + (float)y * ten.cell[1], ten.lo[2] + (float)z * ten.cell[2],
                           &seed);
                set_photon(&ph[n++], ten.lo[0] + ((float)x + 0.5f) * ten.cell[0],
                           ten.lo[1] + (float)y * ten.cell[1], ten.lo[2] + (float)z * ten.cell[2],
                           &seed);
            }
    random_queries(qs, nq, 0.0f, 1.0f, &seed);
    for (size_t i = 0; i < nq / 2; ++i)
        qs[i] = (pm_query){ph[(i * 7) % n].px, ph[(i * 7) % n].py, ph[(i * 7) % n].pz, 0, 1, 0,
                           (uint32_t)i};
    run_case(fx, "lattice", &ten, ph, n, qs, nq, 20, 0.2537f);

    /* a planar map on Purcell's 250x1x250 grid, queries on the plane */
    for (size_t i = 0; i < 30000; ++i)
        set_photon(&ph[i], frand(&seed), 0.5f, frand(&seed) * frand(&seed), &seed);
    const float plo[3] = {0, 0.5f, 0}, phi[3] = {1, 0.5f, 1};
    rt_grid_desc planar = desc_of(plo, phi, 250, 1, 250);
    random_queries(qs, nq, 0.0f, 1.0f, &seed);
    for (size_t i = 0; i < nq; ++i)
        qs[i].py = i % 4 ? 0.5f : qs[i].py;
    run_case(fx, "planar 250x1x250", &planar, ph, 30000, qs, nq, 64, 0.1037f);

    /* fewer photons than k; an empty map */
    for (size_t i = 0; i < 10; ++i)
        set_photon(&ph[i], frand(&seed), frand(&seed), frand(&seed), &seed);
    run_case(fx, "fewer than k", &ten, ph, 10, qs, nq, 32, INFINITY);
    run_case(fx, "fewer than k, max radius", &ten, ph, 10, qs, nq, 32, 0.3f);
    run_case(fx, "empty", &ten, ph, 0, qs, nq, 8, 0.5f);
    free(ph);
    free(qs);
}

/* The radius search (PM_KNN_RADIUS, progressive photon mapping's) over the
 * dense grid and over the hashed one (Purcell 6.4.4) against brute force by
 * the kernel's own arithmetic and against FLANN's radius search: the same
 * photon sets exactly, compared as sorted index lists. FLANN keeps
 * d2 < radius where the kernel keeps d2 <= r^2, and computes d2 in the same
 * order ((dx^2 + dy^2) + dz^2, no fused multiply-adds): asked for the next
 * float above r^2, its set is the kernel's to the last photon. */
typedef struct radius_ref {
    uint32_t *start; /* nq + 1: query q's photons are ids[start[q] .. start[q + 1]) */
    uint32_t *ids;   /* ascending within a query */
    float *r2;       /* the farthest one's squared distance (0 when none) */
    double *sr;      /* summed red power */
    uint32_t most;   /* largest count */
} radius_ref;

static void radius_ref_free(radius_ref *r)
{
    free(r->start);
    free(r->ids);
    free(r->r2);
    free(r->sr);
    memset(r, 0, sizeof *r);
}

/* Brute force with the kernel's float arithmetic (-ffp-contract=off). */
static void radius_brute(const pm_photon *ph, size_t np, const pm_query *qs, size_t nq, float r,
                         int normal_filter, radius_ref *out)
{
    const float r2 = r * r;
    size_t cap = 1024, len = 0;
    out->start = malloc((nq + 1) * sizeof *out->start);
    out->ids = malloc(cap * sizeof *out->ids);
    out->r2 = calloc(nq ? nq : 1, sizeof *out->r2);
    out->sr = calloc(nq ? nq : 1, sizeof *out->sr);
    out->most = 0;
    for (size_t q = 0; q < nq; ++q) {
        out->start[q] = (uint32_t)len;
        for (size_t i = 0; i < np && isfinite(qs[q].px) && isfinite(qs[q].py) && isfinite(qs[q].pz);
             ++i) {
            float d2 = dist2(&ph[i], &qs[q]);
            if (!(d2 <= r2))
                continue;
            if (normal_filter && !(fused_dot(&qs[q], &ph[i]) < 0.0f))
                continue;
            if (len == cap) {
                cap *= 2;
                out->ids = realloc(out->ids, cap * sizeof *out->ids);
            }
            out->ids[len++] = (uint32_t)i;
            out->r2[q] = fmaxf(out->r2[q], d2);
            out->sr[q] += ph[i].pr;
        }
        uint32_t c = (uint32_t)len - out->start[q];
        out->most = c > out->most ? c : out->most;
    }
    out->start[nq] = (uint32_t)len;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* One radius search over the grid as it is built; the results and each
 * query's index list sorted. */
static int radius_search(fixture *fx, const char *name, sluice_stream *sp, sluice_stream *sq,
                         size_t nq, sluice_stream *sr, sluice_stream *si, uint32_t cap, float r,
                         int normal_filter, pm_knn_result *res, uint32_t *ind)
{
    pm_knn_options o = {1, r, PM_KNN_RADIUS, normal_filter, NULL, NULL, 0};
    pm_knn_stats stats;
    sluice_status s = pm_knn_query_indices(fx->knn, fx->grid, sp, sq, nq, sr, &o, si, cap, &stats);
    CHECK(s == SLUICE_OK, "%s: query: %s", name, pm_knn_error(fx->knn));
    if (s != SLUICE_OK)
        return 0;
    CHECK_OK(fx->ctx, sluice_stream_download(sr, res, nq, NULL));
    CHECK_OK(fx->ctx, sluice_stream_download(si, ind, (size_t)cap * nq, NULL));
    CHECK(stats.queries == nq && stats.passes >= 1, "%s: statistics", name);
    for (size_t q = 0; q < nq; ++q)
        qsort(ind + q * cap, res[q].count < cap ? res[q].count : cap, sizeof *ind, cmp_u32);
    return 1;
}

/* Checks one search's results against the brute force: the same sorted
 * photon lists, r2 the farthest one's bit for bit, the power summed. */
static void radius_check(const char *name, const radius_ref *ref, size_t nq,
                         const pm_knn_result *res, const uint32_t *ind, uint32_t cap)
{
    size_t bad = 0;
    for (size_t q = 0; q < nq; ++q) {
        uint32_t want = ref->start[q + 1] - ref->start[q];
        int ok = res[q].count == want && (res[q].flags & PM_KNN_DONE) &&
                 !(res[q].flags & PM_KNN_INDICES_CUT) && res[q].r2 == ref->r2[q] &&
                 fabs(res[q].sr - ref->sr[q]) <= 1e-5 * ref->sr[q] + 1e-6;
        ok = ok && (want == 0 ||
                    memcmp(ind + q * cap, ref->ids + ref->start[q], want * sizeof *ind) == 0);
        if (!ok && ++bad <= 5)
            CHECK(0,
                  "%s: query %zu: count %u (want %u) r2 %.9g (want %.9g) sr %g (want %g) flags %u",
                  name, q, res[q].count, want, (double)res[q].r2, (double)ref->r2[q],
                  (double)res[q].sr, ref->sr[q], res[q].flags);
    }
    CHECK(bad == 0, "%s: %zu of %zu queries differ from brute force", name, bad, nq);
}

/* Runs the radius search over the dense grid `dense` and the hashed layout
 * `hash` (count and bitonic builds); checks both against brute force and
 * FLANN, and that the two layouts find the same photons, bit for bit in
 * count and r2. */
static void radius_case(fixture *fx, const char *name, const rt_grid_desc *dense,
                        const sr_point_hash_desc *hash, const pm_photon *ph, size_t np,
                        const pm_query *qs, size_t nq, float r, int normal_filter)
{
    sluice_context *ctx = fx->ctx;
    radius_ref ref;
    radius_brute(ph, np, qs, nq, r, normal_filter, &ref);
    uint32_t cap = ref.most ? ref.most : 1;
    CHECK((size_t)cap * nq <= ((size_t)64 << 20), "%s: %u photons per query is too many to list",
          name, cap);
    sluice_stream *sp = NULL, *sq = NULL, *sr = NULL, *si = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_photon), np ? np : 1, &sp));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_query), nq, &sq));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_knn_result), nq, &sr));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, (size_t)cap * nq, &si));
    CHECK_OK(ctx, sluice_stream_upload(sp, ph, np));
    CHECK_OK(ctx, sluice_stream_upload(sq, qs, nq));
    pm_knn_result *res[3];
    uint32_t *ind[3];
    for (int i = 0; i < 3; ++i) {
        res[i] = calloc(nq, sizeof **res);
        ind[i] = calloc((size_t)cap * nq, sizeof **ind);
    }
    char full[160];
    /* 0: dense (count build), 1: hashed (count), 2: hashed (bitonic) */
    int have[3] = {0, 0, 0};
    for (int v = 0; v < 3; ++v) {
        sr_point_grid_build_kind kind = v == 2 ? SR_POINT_GRID_BITONIC : SR_POINT_GRID_COUNT;
        sluice_status s =
            v == 0 ? sr_point_grid_build(fx->grid, dense, sp, sizeof(pm_photon), np, kind, 0)
                   : sr_point_grid_build_hashed(fx->grid, hash, sp, sizeof(pm_photon), np, kind);
        snprintf(full, sizeof full, "%s/%s", name,
                 v == 0 ? "dense" : (v == 1 ? "hash" : "hash bitonic"));
        CHECK(s == SLUICE_OK, "%s: build: %s", full, sr_point_grid_error(fx->grid));
        if (s != SLUICE_OK)
            continue;
        have[v] =
            radius_search(fx, full, sp, sq, nq, sr, si, cap, r, normal_filter, res[v], ind[v]);
        if (have[v])
            radius_check(full, &ref, nq, res[v], ind[v], cap);
    }
    /* the layouts agree: the same photons, the same r2 (the same float
     * distances); only the order of the power sums differs */
    size_t differ = 0;
    for (size_t q = 0; have[0] && have[1] && q < nq; ++q)
        differ += res[0][q].count != res[1][q].count || res[0][q].r2 != res[1][q].r2 ||
                  memcmp(ind[0] + q * cap, ind[1] + q * cap,
                         (res[0][q].count < cap ? res[0][q].count : cap) * sizeof(uint32_t)) != 0;
    CHECK(differ == 0, "%s: hash and dense differ on %zu queries", name, differ);
    CHECK(!have[1] || !have[2] || memcmp(res[1], res[2], nq * sizeof **res) == 0,
          "%s: the hashed count and bitonic builds differ", name);
    /* FLANN, asked for d2 < nextafter(r^2): the kernel's d2 <= r^2 */
    if (!normal_filter && np) {
        flann_ref f;
        flann_ref_init(&f, ph, np);
        size_t bad = 0;
        float r2 = nextafterf(r * r, INFINITY);
        uint32_t *got = malloc((np + 1) * sizeof *got);
        for (size_t q = 0; q < nq; ++q) {
            if (!isfinite(qs[q].px) || !isfinite(qs[q].py) || !isfinite(qs[q].pz))
                continue;
            float qp[3] = {qs[q].px, qs[q].py, qs[q].pz};
            int m = flann_radius_search_float(f.index, qp, f.idx, f.d, (int)np, r2, &f.params);
            for (int j = 0; j < m; ++j)
                got[j] = (uint32_t)f.idx[j];
            qsort(got, (size_t)(m > 0 ? m : 0), sizeof *got, cmp_u32);
            uint32_t want = ref.start[q + 1] - ref.start[q];
            int ok = m == (int)want &&
                     (want == 0 || memcmp(got, ref.ids + ref.start[q], want * sizeof *got) == 0);
            if (!ok && ++bad <= 5)
                CHECK(0, "%s: query %zu at (%g %g %g): FLANN finds %d photons, brute force %u",
                      name, q, (double)qs[q].px, (double)qs[q].py, (double)qs[q].pz, m, want);
        }
        CHECK(bad == 0, "%s: %zu queries differ from FLANN's radius search", name, bad);
        free(got);
        flann_ref_free(&f);
    }
    for (int i = 0; i < 3; ++i) {
        free(res[i]);
        free(ind[i]);
    }
    radius_ref_free(&ref);
    sluice_stream_destroy(sp);
    sluice_stream_destroy(sq);
    sluice_stream_destroy(sr);
    sluice_stream_destroy(si);
}

/* radius_case with the automatic grids of sr_point_grid_plan_auto (the
 * photon mapper's: dense cells for half the radius, hash cells of the
 * radius) over the photons' bounds, or over [lo, hi] when given. */
static void radius_case_auto(fixture *fx, const char *name, const pm_photon *ph, size_t np,
                             const pm_query *qs, size_t nq, float r, int normal_filter,
                             uint32_t buckets, int expect_hash)
{
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (size_t i = 0; i < np; ++i) {
        const float p[3] = {ph[i].px, ph[i].py, ph[i].pz};
        for (int a = 0; a < 3; ++a) {
            lo[a] = i ? fminf(lo[a], p[a]) : p[a];
            hi[a] = i ? fmaxf(hi[a], p[a]) : p[a];
        }
    }
    sr_point_grid_plan plan;
    char err[256];
    sluice_status s = sr_point_grid_plan_auto(lo, hi, np, r / 2, r, SR_POINT_GRID_LAYOUT_AUTO,
                                              &plan, err, sizeof err);
    CHECK(s == SLUICE_OK, "%s: plan: %s", name, err);
    if (s != SLUICE_OK)
        return;
    CHECK(expect_hash < 0 || (plan.layout == SR_POINT_GRID_HASHED) == expect_hash,
          "%s: the plan chose %s: %s", name, plan.layout ? "hash" : "dense", plan.why);
    if (buckets)
        plan.hash.buckets = buckets;
    radius_case(fx, name, &plan.dense, &plan.hash, ph, np, qs, nq, r, normal_filter);
}

static void test_radius(fixture *fx)
{
    uint32_t seed = 4711;
    const size_t np_max = 20000, nq = 1500;
    pm_photon *ph = malloc(np_max * sizeof *ph);
    pm_query *qs = malloc(nq * sizeof *qs);

    /* random photons, queries partly outside their box; with the normal
     * filter; tables of 1, 2 and 8 buckets (every cell collides) */
    for (size_t i = 0; i < np_max; ++i)
        set_photon(&ph[i], frand(&seed), frand(&seed), frand(&seed), &seed);
    random_queries(qs, nq, -0.2f, 1.2f, &seed);
    radius_case_auto(fx, "radius random", ph, np_max, qs, nq, 0.05f, 0, 0, 1);
    radius_case_auto(fx, "radius random, dense cells fit", ph, np_max, qs, nq, 0.1f, 0, 0, 1);
    radius_case_auto(fx, "radius random, normal filter", ph, np_max, qs, nq, 0.05f, 1, 0, -1);
    radius_case_auto(fx, "radius random, 1 bucket", ph, 4000, qs, 400, 0.05f, 0, 1, -1);
    radius_case_auto(fx, "radius random, 2 buckets", ph, 4000, qs, 400, 0.05f, 0, 2, -1);
    radius_case_auto(fx, "radius random, 8 buckets", ph, np_max, qs, nq, 0.03f, 0, 8, -1);
    radius_case_auto(fx, "radius random, large radius", ph, 5000, qs, 300, 0.3f, 0, 0, -1);

    /* empty; one photon (queries on it, at exactly r from it along an axis,
     * just inside and outside) */
    radius_case_auto(fx, "radius empty", ph, 0, qs, nq, 0.05f, 0, 0, -1);
    set_photon(&ph[0], 0.5f, 0.25f, 0.75f, &seed);
    for (size_t i = 0; i < 64; ++i) {
        float off[4] = {0.0f, 0.125f, nextafterf(0.125f, 0.0f), nextafterf(0.125f, 1.0f)};
        qs[i] = (pm_query){0.5f, 0.25f, 0.75f, 0, 1, 0, (uint32_t)i};
        float *c = (i / 4) % 3 == 0 ? &qs[i].px : ((i / 4) % 3 == 1 ? &qs[i].py : &qs[i].pz);
        *c += (i & 16 ? -1.0f : 1.0f) * off[i % 4];
    }
    radius_case_auto(fx, "radius one photon", ph, 1, qs, 64, 0.125f, 0, 0, -1);

    /* all photons at one point, queries around it and on it */
    for (size_t i = 0; i < 5000; ++i)
        set_photon(&ph[i], 0.3f, 0.6f, 0.9f, &seed);
    random_queries(qs, nq, 0.2f, 0.4f, &seed);
    for (size_t i = 0; i < nq; ++i)
        qs[i].py += 0.3f, qs[i].pz += 0.6f;
    qs[0] = (pm_query){0.3f, 0.6f, 0.9f, 0, 1, 0, 0};
    radius_case_auto(fx, "radius one point", ph, 5000, qs, nq, 0.04f, 0, 0, -1);

    /* photons far apart in a huge box: four clusters at corners of a box
     * 10^4 wide and scattered photons, radius 0.01; the dense grid is then
     * capped and coarse, the hash keeps cells of the radius */
    {
        const float corner[4][3] = {{0, 0, 0}, {1e4f, 0, 0}, {0, 1e4f, 1e4f}, {1e4f, 1e4f, 1e4f}};
        size_t n = 0;
        for (int c = 0; c < 4; ++c)
            for (int i = 0; i < 2000; ++i, ++n)
                set_photon(&ph[n], corner[c][0] + 0.2f * frand(&seed),
                           corner[c][1] + 0.2f * frand(&seed), corner[c][2] + 0.2f * frand(&seed),
                           &seed);
        for (int i = 0; i < 500; ++i, ++n)
            set_photon(&ph[n], 1e4f * frand(&seed), 1e4f * frand(&seed), 1e4f * frand(&seed),
                       &seed);
        for (size_t i = 0; i < nq; ++i) {
            const float *c = corner[i % 4];
            qs[i] = (pm_query){c[0] + 0.24f * frand(&seed) - 0.02f,
                               c[1] + 0.24f * frand(&seed) - 0.02f,
                               c[2] + 0.24f * frand(&seed) - 0.02f,
                               0,
                               1,
                               0,
                               (uint32_t)i};
        }
        for (size_t i = 0; i < 100; ++i) /* on the scattered ones */
            qs[i] = (pm_query){
                ph[8000 + i].px + 0.005f, ph[8000 + i].py, ph[8000 + i].pz, 0, 1, 0, (uint32_t)i};
        radius_case_auto(fx, "radius huge box", ph, n, qs, nq, 0.01f, 0, 0, 1);
    }

    /* ties on cell faces: a lattice of cells of 1/8 from 0, photons at
     * every 1/16 (on faces, edges, corners and in between), queries on the
     * same points and radius 1/8, so that distances of exactly r are
     * common (binary fractions: no rounding) */
    {
        size_t n = 0;
        for (int x = 0; x <= 16; ++x)
            for (int y = 0; y <= 16; ++y)
                for (int z = 0; z <= 4; ++z)
                    set_photon(&ph[n++], (float)x / 16, (float)y / 16, (float)z / 16, &seed);
        for (size_t i = 0; i < nq; ++i) {
            const pm_photon *p = &ph[(i * 37) % n];
            qs[i] = (pm_query){p->px, p->py, p->pz, 0, 1, 0, (uint32_t)i};
        }
        const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 0.25f};
        rt_grid_desc d = desc_of(lo, hi, 8, 8, 2);
        sr_point_hash_desc h = {{0.0f, 0.0f, 0.0f}, 0.125f, 64};
        radius_case(fx, "radius faces", &d, &h, ph, n, qs, nq, 0.125f, 0);
        h.buckets = 4;
        radius_case(fx, "radius faces, 4 buckets", &d, &h, ph, n, qs, nq, 0.125f, 0);
        /* a lattice of cells smaller than the radius: many cells per query */
        h.cell = 0.03125f;
        h.buckets = 1024;
        radius_case(fx, "radius faces, fine lattice", &d, &h, ph, n, qs, 300, 0.125f, 0);
    }

    /* a query at NaN finds nothing on both layouts (brute force: none) */
    for (size_t i = 0; i < 1000; ++i)
        set_photon(&ph[i], frand(&seed), frand(&seed), frand(&seed), &seed);
    random_queries(qs, 100, 0.0f, 1.0f, &seed);
    qs[3].py = NAN;
    radius_case_auto(fx, "radius NaN query", ph, 1000, qs, 100, 0.1f, 0, 0, -1);
    free(ph);
    free(qs);
}

/* What a hashed grid refuses, and its pass hook. */
static unsigned hash_hook_calls;
static sluice_status hash_hook(void *user, unsigned pass, size_t answered)
{
    (void)user;
    CHECK(pass == 0 && answered == 4, "hashed pass hook: pass %u, %zu answered", pass, answered);
    hash_hook_calls++;
    return SLUICE_OK;
}

static void test_hash_errors(fixture *fx)
{
    sluice_context *ctx = fx->ctx;
    sluice_stream *sp = NULL, *sq = NULL, *sr = NULL;
    pm_photon ph[4] = {{0}};
    pm_query qs[4] = {{0}};
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_photon), 4, &sp));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_query), 4, &sq));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_knn_result), 4, &sr));
    CHECK_OK(ctx, sluice_stream_upload(sp, ph, 4));
    CHECK_OK(ctx, sluice_stream_upload(sq, qs, 4));
    sr_point_hash_desc h = {{0, 0, 0}, 0.5f, 16};
    CHECK_OK(ctx, sr_point_grid_build_hashed(fx->grid, &h, sp, sizeof(pm_photon), 4,
                                             SR_POINT_GRID_COUNT));
    pm_knn_options o = {8, 1.0f, PM_KNN_ATLEAST, 0, NULL, NULL, 0};
    for (int m = 0; m < 2; ++m) {
        o.mode = (pm_knn_mode)m;
        CHECK(pm_knn_query(fx->knn, fx->grid, sp, sq, 4, sr, &o, NULL) ==
                      SLUICE_ERROR_INVALID_ARGUMENT &&
                  strstr(pm_knn_error(fx->knn), "hashed"),
              "mode %d over a hashed grid: %s", m, pm_knn_error(fx->knn));
    }
    o.mode = PM_KNN_RADIUS;
    o.max_radius = INFINITY;
    CHECK(pm_knn_query(fx->knn, fx->grid, sp, sq, 4, sr, &o, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "an infinite radius over a hashed grid");
    o.max_radius = 1.0f;
    o.on_pass = hash_hook;
    pm_knn_stats st;
    CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, 4, sr, &o, &st));
    CHECK(hash_hook_calls == 1 && st.passes == 1 && st.queries == 4 && st.mean_count == 4.0,
          "hashed: %u hook calls, %u passes, %.1f photons per query", hash_hook_calls, st.passes,
          st.mean_count);
    sluice_stream_destroy(sp);
    sluice_stream_destroy(sq);
    sluice_stream_destroy(sr);
}

/* Exact mode in batches (k large enough that the heaps of all queries do
 * not fit PM_KNN_EXACT_HEAP_BYTES), and the normal filter. */
/* np random photons in the unit cube and nq random queries in [qlo, qhi]^3,
 * uploaded into new streams (with a result stream for nq), and the grid
 * built over them with n^3 cells (a count build). */
typedef struct unit_set {
    pm_photon *ph;
    pm_query *qs;
    sluice_stream *sp, *sq, *sr;
} unit_set;

static void unit_set_make(fixture *fx, uint32_t seed, size_t np, size_t nq, float qlo, float qhi,
                          uint32_t n, unit_set *u)
{
    sluice_context *ctx = fx->ctx;
    u->ph = malloc(np * sizeof *u->ph);
    u->qs = malloc(nq * sizeof *u->qs);
    u->sp = u->sq = u->sr = NULL;
    for (size_t i = 0; i < np; ++i)
        set_photon(&u->ph[i], frand(&seed), frand(&seed), frand(&seed), &seed);
    random_queries(u->qs, nq, qlo, qhi, &seed);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    rt_grid_desc d = desc_of(lo, hi, n, n, n);
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof *u->ph, np, &u->sp));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof *u->qs, nq, &u->sq));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_knn_result), nq, &u->sr));
    CHECK_OK(ctx, sluice_stream_upload(u->sp, u->ph, np));
    CHECK_OK(ctx, sluice_stream_upload(u->sq, u->qs, nq));
    CHECK_OK(ctx,
             sr_point_grid_build(fx->grid, &d, u->sp, sizeof *u->ph, np, SR_POINT_GRID_COUNT, 0));
}

static void unit_set_free(unit_set *u)
{
    sluice_stream_destroy(u->sp);
    sluice_stream_destroy(u->sq);
    sluice_stream_destroy(u->sr);
    free(u->ph);
    free(u->qs);
}

static void test_batches_and_filter(fixture *fx)
{
    sluice_context *ctx = fx->ctx;
    size_t np = 3000, nq = 700;
    unit_set u;
    unit_set_make(fx, 77, np, nq, 0.0f, 1.0f, 8, &u);
    pm_photon *ph = u.ph;
    pm_query *qs = u.qs;
    sluice_stream *sp = u.sp, *sq = u.sq, *sr = u.sr;
    pm_knn_result *a = malloc(nq * sizeof *a), *b = malloc(nq * sizeof *b);
    /* k = 2^18: 2 MiB of heap per query, 32 queries per batch */
    pm_knn_options o = {1u << 18, 0.3f, PM_KNN_EXACT, 0, NULL, NULL, 0};
    pm_knn_stats st;
    CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, nq, sr, &o, &st));
    CHECK(st.batches == (nq + 31) / 32, "batches %u", st.batches);
    CHECK_OK(ctx, sluice_stream_download(sr, a, nq, NULL));
    o.mode = PM_KNN_ATLEAST; /* with k above the photons, both find all within 0.3 */
    CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, nq, sr, &o, &st));
    CHECK(st.batches == 1 && st.hit_max_radius == nq, "atleast: %u batches, %zu at max radius",
          st.batches, st.hit_max_radius);
    CHECK_OK(ctx, sluice_stream_download(sr, b, nq, NULL));
    size_t bad = 0;
    for (size_t q = 0; q < nq; ++q) {
        uint32_t want = 0;
        for (size_t i = 0; i < np; ++i)
            want += dist2(&ph[i], &qs[q]) <= 0.09f;
        bad += a[q].count != want || b[q].count != want || a[q].r2 != b[q].r2 ||
               fabsf(a[q].sr - b[q].sr) > 1e-4f * b[q].sr;
    }
    CHECK(bad == 0, "batched exact and atleast disagree with brute force on %zu queries", bad);
    /* normal filter: only photons travelling against the normal (dy < 0
     * for normal +y) */
    o = (pm_knn_options){16, 0.25f, PM_KNN_ATLEAST, 1, NULL, NULL, 0};
    for (int m = 0; m < 2; ++m) {
        o.mode = (pm_knn_mode)m;
        CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, nq, sr, &o, NULL));
        CHECK_OK(ctx, sluice_stream_download(sr, b, nq, NULL));
        bad = 0;
        for (size_t q = 0; q < nq; ++q) {
            uint32_t inside = 0, all = 0;
            for (size_t i = 0; i < np; ++i) {
                if (ph[i].dy >= 0.0f)
                    continue;
                float d2 = dist2(&ph[i], &qs[q]);
                all += d2 <= 0.0625f;
                inside += d2 <= b[q].r2;
            }
            uint32_t want = all < 16 ? all : 16;
            bad += b[q].count < want || (m == 0 && b[q].count != inside) ||
                   (m == 1 && b[q].count != want);
        }
        CHECK(bad == 0, "normal filter, mode %d: %zu queries wrong", m, bad);
    }
    unit_set_free(&u);
    free(a);
    free(b);
}

/* The cell-ordered copy is made once per build of the grid: a second call
 * on the same build answers as the first, and photons changed in place and
 * built again are answered as a fresh search answers them. No queries: no
 * work, an empty result. */
static void test_copy_reuse(fixture *fx)
{
    sluice_context *ctx = fx->ctx;
    size_t np = 2000, nq = 300;
    unit_set u;
    unit_set_make(fx, 91, np, nq, 0.0f, 1.0f, 6, &u);
    pm_photon *ph = u.ph;
    sluice_stream *sp = u.sp, *sq = u.sq, *sr = u.sr;
    pm_knn_result *a = malloc(nq * sizeof *a), *b = malloc(nq * sizeof *b),
                  *c = malloc(nq * sizeof *c);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    rt_grid_desc d = desc_of(lo, hi, 6, 6, 6);
    pm_knn_options o = {24, 0.4f, PM_KNN_ATLEAST, 0, NULL, NULL, 0};
    CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, nq, sr, &o, NULL));
    CHECK_OK(ctx, sluice_stream_download(sr, a, nq, NULL));
    CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, nq, sr, &o, NULL));
    CHECK_OK(ctx, sluice_stream_download(sr, b, nq, NULL));
    CHECK(memcmp(a, b, nq * sizeof *a) == 0, "the same build answered twice differs");
    /* the photons moved and their power changed, in place, then built again */
    for (size_t i = 0; i < np; ++i) {
        ph[i].px = 1.0f - ph[i].px;
        ph[i].pr *= 2.0f;
    }
    CHECK_OK(ctx, sluice_stream_upload(sp, ph, np));
    CHECK_OK(ctx, sr_point_grid_build(fx->grid, &d, sp, sizeof *ph, np, SR_POINT_GRID_COUNT, 0));
    CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, nq, sr, &o, NULL));
    CHECK_OK(ctx, sluice_stream_download(sr, b, nq, NULL));
    pm_knn *fresh = NULL;
    CHECK_OK(ctx, pm_knn_create(ctx, &fresh));
    if (fresh) {
        CHECK_OK(ctx, pm_knn_query(fresh, fx->grid, sp, sq, nq, sr, &o, NULL));
        CHECK_OK(ctx, sluice_stream_download(sr, c, nq, NULL));
        CHECK(memcmp(b, c, nq * sizeof *b) == 0,
              "after a new build the search answers otherwise than a fresh one");
    }
    CHECK(memcmp(a, b, nq * sizeof *a) != 0, "moved photons, the same answers");
    pm_knn_stats st;
    size_t len = 1;
    CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, 0, sr, &o, &st));
    CHECK_OK(ctx, sluice_stream_length(sr, &len));
    CHECK(len == 0 && st.queries == 0 && st.passes == 0,
          "no queries: length %zu, %zu queries, %u passes", len, st.queries, st.passes);
    pm_knn_destroy(fresh);
    unit_set_free(&u);
    free(a);
    free(b);
    free(c);
}

/* The pass hook: one call per pass, each query's count never falls from
 * one pass to the next and ends at the final result; batches of the exact
 * mode say how many results are current; a failing hook stops the search
 * with its status. */
typedef struct hook_state {
    sluice_stream *results;
    size_t n;
    pm_knn_result *prev, *now;
    unsigned calls, fail_at;
    size_t last_answered, shrank, answered_bad;
} hook_state;

static sluice_status count_hook(void *user, unsigned pass, size_t answered)
{
    hook_state *h = user;
    if (pass != h->calls)
        h->answered_bad++;
    h->calls++;
    if (answered < h->last_answered || answered > h->n)
        h->answered_bad++;
    h->last_answered = answered;
    sluice_status st = sluice_stream_download(h->results, h->now, h->n, NULL);
    for (size_t q = 0; st == SLUICE_OK && q < answered; ++q) {
        if (h->now[q].count < h->prev[q].count && q < answered)
            h->shrank++;
        h->prev[q] = h->now[q];
    }
    if (st != SLUICE_OK)
        return st;
    return h->calls == h->fail_at ? SLUICE_ERROR_LIMIT : SLUICE_OK;
}

static void test_pass_hook(fixture *fx)
{
    sluice_context *ctx = fx->ctx;
    uint32_t seed = 99;
    const size_t np = 3000, nq = 400;
    pm_photon *ph = malloc(np * sizeof *ph);
    pm_query *qs = malloc(nq * sizeof *qs);
    pm_knn_result *fin = malloc(nq * sizeof *fin);
    hook_state h = {0};
    h.n = nq;
    h.prev = calloc(nq, sizeof *h.prev);
    h.now = calloc(nq, sizeof *h.now);
    for (size_t i = 0; i < np; ++i)
        set_photon(&ph[i], frand(&seed), frand(&seed), frand(&seed), &seed);
    random_queries(qs, nq, -0.2f, 1.2f, &seed);
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    rt_grid_desc d = desc_of(lo, hi, 16, 16, 16);
    sluice_stream *sp = NULL, *sq = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof *ph, np, &sp));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof *qs, nq, &sq));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof *fin, nq, &h.results));
    CHECK_OK(ctx, sluice_stream_upload(sp, ph, np));
    CHECK_OK(ctx, sluice_stream_upload(sq, qs, nq));
    CHECK_OK(ctx, sr_point_grid_build(fx->grid, &d, sp, sizeof *ph, np, SR_POINT_GRID_COUNT, 0));
    /* atleast, then exact in batches of 64 MiB / (8 k) = 16 queries */
    const uint32_t ks[2] = {40, 1u << 19};
    for (int m = 0; m < 2; ++m) {
        pm_knn_options o = {ks[m], 0.5f, (pm_knn_mode)m, 0, count_hook, &h, 0};
        pm_knn_stats st;
        memset(h.prev, 0, nq * sizeof *h.prev);
        h.calls = 0;
        h.fail_at = 0;
        h.last_answered = 0;
        h.shrank = h.answered_bad = 0;
        CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, nq, h.results, &o, &st));
        CHECK(h.calls == st.passes && st.passes > 1, "mode %d: %u hook calls for %u passes", m,
              h.calls, st.passes);
        CHECK(h.answered_bad == 0 && h.last_answered == nq, "mode %d: answered %zu, %zu bad", m,
              h.last_answered, h.answered_bad);
        CHECK(h.shrank == 0, "mode %d: %zu counts fell between passes", m, h.shrank);
        CHECK_OK(ctx, sluice_stream_download(h.results, fin, nq, NULL));
        CHECK(memcmp(fin, h.prev, nq * sizeof *fin) == 0,
              "mode %d: the last pass's results are the final ones", m);
        /* a hook that fails on its third call ends the search with its status */
        h.calls = 0;
        h.fail_at = 3;
        h.last_answered = 0;
        CHECK(pm_knn_query(fx->knn, fx->grid, sp, sq, nq, h.results, &o, NULL) ==
                      SLUICE_ERROR_LIMIT &&
                  h.calls == 3,
              "mode %d: failing hook: %u calls", m, h.calls);
    }
    /* the search runs again normally after a failed hook */
    pm_knn_options plain = {40, 0.5f, PM_KNN_ATLEAST, 0, NULL, NULL, 0};
    CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, nq, h.results, &plain, NULL));
    CHECK_OK(ctx, sluice_stream_download(h.results, h.now, nq, NULL));
    size_t differ = 0;
    CHECK_OK(ctx,
             pm_knn_query(fx->knn, fx->grid, sp, sq, nq, h.results,
                          &(pm_knn_options){40, 0.5f, PM_KNN_ATLEAST, 0, count_hook, &h, 0}, NULL));
    CHECK_OK(ctx, sluice_stream_download(h.results, fin, nq, NULL));
    for (size_t q = 0; q < nq; ++q)
        differ += memcmp(&fin[q], &h.now[q], sizeof *fin) != 0;
    CHECK(differ == 0, "a hook changes %zu results", differ);
    sluice_stream_destroy(sp);
    sluice_stream_destroy(sq);
    sluice_stream_destroy(h.results);
    free(ph);
    free(qs);
    free(fin);
    free(h.prev);
    free(h.now);
}

static void test_errors(fixture *fx)
{
    sluice_context *ctx = fx->ctx;
    sluice_stream *sp = NULL, *sq = NULL, *sr = NULL, *s12 = NULL;
    pm_photon ph[4] = {{0}};
    pm_query qs[4] = {{0}};
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_photon), 4, &sp));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_query), 4, &sq));
    CHECK_OK(ctx, sluice_stream_create(ctx, sizeof(pm_knn_result), 4, &sr));
    CHECK_OK(ctx, sluice_stream_create(ctx, 12, 4, &s12));
    CHECK_OK(ctx, sluice_stream_upload(sp, ph, 4));
    CHECK_OK(ctx, sluice_stream_upload(sq, qs, 4));
    sr_point_grid *fresh = NULL;
    CHECK_OK(ctx, sr_point_grid_create(ctx, &fresh));
    pm_knn_options o = {8, 1.0f, PM_KNN_ATLEAST, 0, NULL, NULL, 0};
    CHECK(pm_knn_query(fx->knn, fresh, sp, sq, 4, sr, &o, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "grid not built");
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    rt_grid_desc d = desc_of(lo, hi, 2, 2, 2);
    CHECK_OK(ctx, sr_point_grid_build(fx->grid, &d, sp, sizeof(pm_photon), 4, 0, 0));
    CHECK(pm_knn_create(ctx, NULL) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL out");
    CHECK(pm_knn_query(NULL, fx->grid, sp, sq, 4, sr, &o, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL knn");
    CHECK(pm_knn_query(fx->knn, fx->grid, s12, sq, 4, sr, &o, NULL) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "photon record size");
    CHECK(pm_knn_query(fx->knn, fx->grid, sp, sq, 5, sr, &o, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "n above the queries");
    CHECK(pm_knn_query(fx->knn, fx->grid, sp, sq, 4, s12, &o, NULL) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "result record size");
    pm_knn_options bad = o;
    bad.k = 0;
    CHECK(pm_knn_query(fx->knn, fx->grid, sp, sq, 4, sr, &bad, NULL) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "k = 0");
    bad = o;
    bad.max_radius = NAN;
    CHECK(pm_knn_query(fx->knn, fx->grid, sp, sq, 4, sr, &bad, NULL) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "NaN radius");
    bad = o;
    bad.mode = (pm_knn_mode)5;
    CHECK(pm_knn_query(fx->knn, fx->grid, sp, sq, 4, sr, &bad, NULL) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "mode");
    CHECK(pm_knn_query_indices(fx->knn, fx->grid, sp, sq, 4, sr, &o, s12, 0, NULL) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "cap 0");
    CHECK(*pm_knn_error(fx->knn) != '\0', "a message");
    /* a query at NaN finds nothing and says so */
    qs[1].px = NAN;
    CHECK_OK(ctx, sluice_stream_upload(sq, qs, 4));
    CHECK_OK(ctx, pm_knn_query(fx->knn, fx->grid, sp, sq, 4, sr, &o, NULL));
    pm_knn_result r[4];
    CHECK_OK(ctx, sluice_stream_download(sr, r, 4, NULL));
    CHECK(r[1].count == 0 && (r[1].flags & PM_KNN_BAD_QUERY) && r[0].count == 4,
          "NaN query: count %u flags %u; others %u", r[1].count, r[1].flags, r[0].count);
    sr_point_grid_destroy(fresh);
    sluice_stream_destroy(sp);
    sluice_stream_destroy(sq);
    sluice_stream_destroy(sr);
    sluice_stream_destroy(s12);
}

int main(void)
{
    fixture fx = {0};
    fx.ctx = check_context(0);
    CHECK_OK(fx.ctx, sr_point_grid_create(fx.ctx, &fx.grid));
    CHECK_OK(fx.ctx, pm_knn_create(fx.ctx, &fx.knn));
    if (fx.grid && fx.knn) {
        test_errors(&fx);
        test_hash_errors(&fx);
        test_radius(&fx);
        test_batches_and_filter(&fx);
        test_copy_reuse(&fx);
        test_pass_hook(&fx);
        test_cases(&fx);
    }
    pm_knn_destroy(fx.knn);
    sr_point_grid_destroy(fx.grid);
    sluice_context_destroy(fx.ctx);
    return check_summary();
}
