/*
 * bench_raytrace: rays per second of the ray tracer against its peers,
 * measured in one run on the same rays, the same mesh and the same pixel
 * count, for two ray sets per scene:
 *   primary rays: one per pixel, through the pixel centre, from the scene's
 *     own camera (coherent);
 *   diffuse bounce rays: the incoherent rays a path tracer traces next, one
 *     per pixel whose primary ray hit (by the C tracer below, the
 *     reference): from the hit point offset along the geometric normal
 *     (facing the incoming ray) by the renderer's scene_eps
 *     (sr_scene_epsilon), in a cosine-weighted direction about that normal
 *     drawn from a hash of the pixel (fixed seed), tmin 0, tmax infinity,
 *     flagged as the renderer's path rays; in the primary rays' order (8x8
 *     tiles), compacted to the pixels that have one.
 * The peers:
 *   (a) Sluice, fused mode (one kernel takes a ray through the whole grid);
 *   (b) Sluice, stream mode (Purcell's multipass traverse / intersect);
 *   (c) a plain single-thread C tracer written here: the same uniform grid
 *       (rt_grid_build_host), the same 3D-DDA and Moller-Trumbore test in
 *       the same order, so it finds the same hits;
 *   (d) Intel Embree 3 (when built with it: HAVE_EMBREE), its BVH over the
 *       same triangles, rtcIntersect16 on 4x4 pixel tiles and rtcIntersect1,
 *       with 1 and 2 threads (a pthread split of the tile rows: Embree does
 *       not spawn threads for traversal); the fastest of the four is
 *       "Embree's best" (normally 2 threads, but a busy machine can make
 *       the second core worth nothing). The context is COHERENT for primary
 *       rays and INCOHERENT for bounce rays; pixels without a bounce ray are
 *       inactive lanes of rtcIntersect16 (valid 0; a tile with none active
 *       is skipped) and are skipped by rtcIntersect1.
 * Sluice times are trace time only: rays already in a device stream, hits
 * left in one, after a warm-up; grid build and program compilation are
 * reported apart. The peers run in interleaved rounds (each round times
 * every peer for a few frames back to back, round 0 a warm-up) and every
 * time is the best frame of --reps rounds, so the ratios are taken under
 * the same conditions; one function (time_peers) does this for either ray
 * set. Rates count the rays of the set (for bounce rays: the pixels that
 * have one). Hit agreement (the fraction of a set's rays for which two peers
 * name the same triangle, or both miss) keeps the comparison honest.
 *
 * Then Purcell's statistics (thesis Fig. 5.2, Table 5.2) for ray casting at
 * 1024x1024 in stream mode, with grid minimum dimension 64 (his setting for
 * the bunny) and the default, beside his published bunny figures.
 *
 *   bench_raytrace [--size N] [--reps R] [--scene NAME]... [--out FILE]
 *                  [--purcell-size N] [--skip-purcell] [--quick]
 *                  [--embree-isa ISA] [--grid-min-dim N] [--fused-walk W]
 *
 * Embree picks its code path at run time; when the kernels were built for
 * AVX2 on an AVX-512 machine (POCL_KERNELLIB_NAME=avx2), Embree is held to
 * AVX2 as well (max_isa), so the run stands for an AVX2 CPU on both sides.
 *
 * Exit status 1 when a Sluice mode or the C tracer disagrees with another on
 * more than 1% of the rays of either set (a broken tracer), 2 on setup
 * errors.
 */
#include "clock.h"
#include "bench_args.h"
#include "bench_machine.h"
#include "bench_rays.h"
#include "device_scene.h"
#include "grid.h"
#include "mt_ref.h"
#include "render.h"
#include "scene.h"
#include "tracer.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifdef HAVE_EMBREE
#include <embree3/rtcore.h>
#include <pmmintrin.h>
#include <pthread.h>
#include <xmmintrin.h>
#endif

#define PROG "bench_raytrace"
#define MAX_SCENES 8
#define BUNNY_PATH "/usr/share/glmark2/models/bunny.obj"

static sluice_context *ctx;
/* Embree's device configuration (rtcNewDevice): "max_isa=avx2" when the
 * kernels were built for AVX2, so that both sides of the comparison use the
 * instruction set an AVX2 CPU has (see --embree-isa). */
static char embree_config[64];
/* --grid-min-dim: 0 for the tracer's automatic resolution */
static unsigned grid_min_dim;
/* --fused-walk: how the fused tracer crosses the grid (tracer.h) */
static rt_fused_walk fused_walk = RT_WALK_AUTO;
static const char *const walk_names[] = {"auto", "voxel", "walk", "slices"};

#define TRY(call)                                                                                  \
    do {                                                                                           \
        sluice_status st_ = (call);                                                                \
        if (st_ != SLUICE_OK) {                                                                    \
            fprintf(stderr, PROG ": %s failed: %s\n", #call, sluice_context_error(ctx));           \
            exit(2);                                                                               \
        }                                                                                          \
    } while (0)

static void *xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p) {
        fprintf(stderr, PROG ": out of memory\n");
        exit(2);
    }
    return p;
}

/* ------------------------------------------------------------------ */
/* Eye rays                                                            */
/* ------------------------------------------------------------------ */

/* bench_eye_rays (bench_rays.h), or exit when out of memory. */
static rt_ray *eye_rays(const sr_scene *sc, unsigned w, unsigned h)
{
    rt_ray *rays = bench_eye_rays(sc, w, h);
    if (!rays) {
        fprintf(stderr, PROG ": out of memory\n");
        exit(2);
    }
    return rays;
}

/* A set of rays that every peer traces: in stream order (the primary
 * rays' 8x8 tiles), compacted to the pixels that have one, and by pixel for
 * Embree's 4x4 tiles. */
typedef struct ray_set {
    rt_ray *rays; /* stream order */
    size_t n;
    rt_ray *by_pixel;      /* w * h rays; a harmless ray where not active */
    unsigned char *active; /* by pixel: the pixel has a ray; NULL: every pixel */
    int coherent;          /* Embree's context flag: COHERENT, else INCOHERENT */
} ray_set;

static ray_set primary_set(const sr_scene *sc, unsigned w, unsigned h)
{
    ray_set s = {0};
    s.n = (size_t)w * h;
    s.rays = eye_rays(sc, w, h);
    s.by_pixel = xmalloc(s.n * sizeof *s.by_pixel);
    for (size_t i = 0; i < s.n; ++i)
        s.by_pixel[s.rays[i].pixel] = s.rays[i];
    s.coherent = 1;
    return s;
}

static void ray_set_free(ray_set *s)
{
    free(s->rays);
    free(s->by_pixel);
    free(s->active);
    memset(s, 0, sizeof *s);
}

/* ------------------------------------------------------------------ */
/* The plain C tracer: the grid, DDA and test of kernels/raytrace/     */
/* rt_trace.cl and rt_fused.cl, one ray at a time, one thread          */
/* ------------------------------------------------------------------ */

typedef struct cgrid {
    float lo[3], hi[3], cell[3], inv_cell[3];
    int dims[3];
    const uint32_t *start, *tris;
    float *tv; /* 9 floats per triangle */
} cgrid;

typedef struct cbest {
    uint32_t tri;
    float t, u, v;
} cbest;

__attribute__((always_inline)) static inline void c_intersect(const float *tv, uint32_t tri,
                                                              const float o[3], const float d[3],
                                                              float tmin, float limit, cbest *best)
{
    const float *p = tv + 9 * (size_t)tri;
    float e1[3] = {p[3] - p[0], p[4] - p[1], p[5] - p[2]};
    float e2[3] = {p[6] - p[0], p[7] - p[1], p[8] - p[2]};
    float t, u, v;
    if (rt_mt_ref(p, e1, e2, o, d, &t, &u, &v) && t >= tmin && t <= limit && t < best->t) {
        best->tri = tri;
        best->t = t;
        best->u = u;
        best->v = v;
    }
}

RT_MT_REF_FAST static void c_trace(const cgrid *g, const rt_ray *ray, rt_hit *hit)
{
    float o[3] = {ray->ox, ray->oy, ray->oz}, d[3] = {ray->dx, ray->dy, ray->dz}, inv[3];
    for (int k = 0; k < 3; ++k)
        inv[k] = d[k] != 0.0f ? 1.0f / d[k] : 0.0f;
    float tmin = ray->tmin, tmax = ray->tmax;
    int any_hit = (ray->flags & RT_FLAG_ANY_HIT) != 0;
    cbest best = {RT_NO_HIT, tmax, 0.0f, 0.0f};
    uint32_t steps = 0, tests = 0;
    float t0 = tmin, t1 = tmax;
    int inside = 1;
    for (int k = 0; k < 3 && inside; ++k) {
        if (d[k] == 0.0f) {
            inside = !(o[k] < g->lo[k] || o[k] > g->hi[k]);
            continue;
        }
        float ta = (g->lo[k] - o[k]) * inv[k], tb = (g->hi[k] - o[k]) * inv[k];
        t0 = fmaxf(t0, fminf(ta, tb));
        t1 = fminf(t1, fmaxf(ta, tb));
    }
    if (inside && t0 <= t1) {
        int c[3];
        for (int k = 0; k < 3; ++k) {
            float p = o[k] + d[k] * t0;
            int v = (int)floorf((p - g->lo[k]) * g->inv_cell[k]);
            c[k] = v < 0 ? 0 : (v > g->dims[k] - 1 ? g->dims[k] - 1 : v);
        }
        for (;;) {
            ++steps;
            uint32_t ci =
                (uint32_t)c[0] +
                (uint32_t)g->dims[0] * ((uint32_t)c[1] + (uint32_t)g->dims[1] * (uint32_t)c[2]);
            uint32_t a = g->start[ci], b = g->start[ci + 1];
            /* where the ray leaves the voxel, and through which face */
            float te = INFINITY;
            int axis = 0;
            for (int k = 0; k < 3; ++k) {
                float bnd = g->lo[k] + (float)(c[k] + (d[k] > 0.0f)) * g->cell[k];
                float tk = d[k] != 0.0f ? (bnd - o[k]) * inv[k] : INFINITY;
                if (k == 0 || tk < te) {
                    te = tk;
                    axis = k;
                }
            }
            if (a < b) {
                tests += b - a;
                float limit = any_hit ? tmax : fminf(te + fabsf(te) * 1e-6f, tmax);
                for (uint32_t i = a; i < b; ++i)
                    c_intersect(g->tv, g->tris[i], o, d, tmin, limit, &best);
                if (best.tri != RT_NO_HIT)
                    break;
            }
            if (te >= tmax)
                break;
            c[axis] += d[axis] > 0.0f ? 1 : -1;
            if (c[axis] < 0 || c[axis] >= g->dims[axis])
                break;
        }
    }
    hit->tri = best.tri;
    hit->t = best.t;
    hit->u = best.u;
    hit->v = best.v;
    hit->steps = steps;
    hit->tests = tests;
}

static void cgrid_init(cgrid *g, const rt_grid_host *h, const sr_scene *sc)
{
    for (int k = 0; k < 3; ++k) {
        g->lo[k] = h->desc.lo[k];
        g->hi[k] = h->desc.hi[k];
        g->cell[k] = h->desc.cell[k];
        g->inv_cell[k] = 1.0f / h->desc.cell[k];
        g->dims[k] = (int)h->desc.dims[k];
    }
    g->start = h->cell_start;
    g->tris = h->cell_tris;
    size_t nt = sr_scene_triangle_count(sc);
    const float *pos = sr_scene_positions(sc);
    const uint32_t *idx = sr_scene_indices(sc);
    g->tv = xmalloc(9 * nt * sizeof *g->tv);
    for (size_t i = 0; i < nt; ++i)
        for (int j = 0; j < 3; ++j)
            memcpy(g->tv + 9 * i + 3 * j, pos + 3 * (size_t)idx[3 * i + j], 3 * sizeof(float));
}

/* ------------------------------------------------------------------ */
/* Diffuse bounce rays                                                 */
/* ------------------------------------------------------------------ */

/* The renderer's counter-based random numbers (kernels/render/rng.cl:
 * rt_hash, rt_key, rt_rand), on the host. */
static uint32_t h_hash(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

static uint32_t h_key(uint32_t a, uint32_t b)
{
    return h_hash(a ^ h_hash(b + 0x9e3779b9u));
}

static float h_rand(uint32_t key, uint32_t dim)
{
    return (float)(h_key(key, dim) >> 8) * (1.0f / 16777216.0f);
}

/* A cosine-weighted direction about the unit normal `n` from two uniform
 * numbers, as kernels/render/surface.cl's rt_cosine_dir (Duff et al.'s
 * tangent frame). */
static void cosine_dir(const float n[3], float r1, float r2, float out[3])
{
    float phi = 2.0f * 3.14159265358979323846f * r1, st = sqrtf(r2),
          ct = sqrtf(fmaxf(0.0f, 1.0f - r2));
    float sign = n[2] >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n[2]), b = n[0] * n[1] * a;
    float t1[3] = {1.0f + sign * n[0] * n[0] * a, sign * b, -sign * n[0]};
    float t2[3] = {b, sign + n[1] * n[1] * a, -n[1]};
    float cp = cosf(phi) * st, sp = sinf(phi) * st, len = 0.0f;
    for (int k = 0; k < 3; ++k) {
        out[k] = t1[k] * cp + t2[k] * sp + n[k] * ct;
        len += out[k] * out[k];
    }
    len = sqrtf(len);
    for (int k = 0; k < 3; ++k)
        out[k] /= len;
}

/* The seed of the bounce directions (each pixel's are a hash of it and the
 * pixel). */
#define BOUNCE_SEED 0x5eedb0u

/* The diffuse bounce rays of the primary rays `prim` from their hits `hits`
 * (the C tracer's, in stream order): one per ray that hit, in the same
 * order, as the renderer's path mode spawns them (kernels/raytrace/
 * rt_shade.cl, rt_spawn): from the hit point offset along the geometric
 * normal facing the incoming ray by `eps` (sr_scene_epsilon), a
 * cosine-weighted direction about that normal, tmin 0, tmax infinity, kind
 * RT_KIND_PATH at depth 1. `tv`: 9 floats (the vertices) per triangle. */
static ray_set bounce_set(const ray_set *prim, const rt_hit *hits, const float *tv, float eps,
                          unsigned w, unsigned h)
{
    ray_set s = {0};
    size_t npix = (size_t)w * h;
    s.rays = xmalloc(prim->n * sizeof *s.rays);
    s.by_pixel = xmalloc(npix * sizeof *s.by_pixel);
    memcpy(s.by_pixel, prim->by_pixel, npix * sizeof *s.by_pixel);
    s.active = xmalloc(npix);
    memset(s.active, 0, npix);
    s.coherent = 0;
    for (size_t i = 0; i < prim->n; ++i) {
        const rt_ray *r = &prim->rays[i];
        if (hits[i].tri == RT_NO_HIT)
            continue;
        const float *v = tv + 9 * (size_t)hits[i].tri;
        float o[3] = {r->ox, r->oy, r->oz}, d[3] = {r->dx, r->dy, r->dz};
        float e1[3], e2[3], p[3], ng[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = v[3 + k] - v[k];
            e2[k] = v[6 + k] - v[k];
            p[k] = o[k] + d[k] * hits[i].t;
        }
        ng[0] = e1[1] * e2[2] - e1[2] * e2[1];
        ng[1] = e1[2] * e2[0] - e1[0] * e2[2];
        ng[2] = e1[0] * e2[1] - e1[1] * e2[0];
        float len = sqrtf(ng[0] * ng[0] + ng[1] * ng[1] + ng[2] * ng[2]);
        float side = ng[0] * d[0] + ng[1] * d[1] + ng[2] * d[2] < 0.0f ? 1.0f : -1.0f;
        for (int k = 0; k < 3; ++k)
            ng[k] = len > 0.0f ? side * ng[k] / len : -d[k]; /* facing the incoming ray */
        uint32_t key = h_key(BOUNCE_SEED, r->pixel);
        float dir[3];
        cosine_dir(ng, h_rand(key, 0u), h_rand(key, 1u), dir);
        rt_ray *b = &s.rays[s.n++];
        memset(b, 0, sizeof *b);
        b->ox = p[0] + ng[0] * eps;
        b->oy = p[1] + ng[1] * eps;
        b->oz = p[2] + ng[2] * eps;
        b->dx = dir[0];
        b->dy = dir[1];
        b->dz = dir[2];
        b->tmin = 0.0f;
        b->tmax = INFINITY;
        b->wr = b->wg = b->wb = 1.0f;
        b->pixel = r->pixel;
        b->key = key;
        b->flags = RT_KIND_PATH | (1u << RT_DEPTH_SHIFT);
        s.by_pixel[r->pixel] = *b;
        s.active[r->pixel] = 1;
    }
    return s;
}

/* ------------------------------------------------------------------ */
/* Embree 3                                                            */
/* ------------------------------------------------------------------ */

#ifdef HAVE_EMBREE
typedef struct emb_job {
    RTCScene scene;
    const ray_set *set;
    unsigned w, h;
    uint32_t *tri; /* by pixel */
    float *t;
    int packet; /* 16: rtcIntersect16 on 4x4 tiles; 1: rtcIntersect1 */
    unsigned thread, threads;
} emb_job;

static void *emb_worker(void *arg)
{
    emb_job *j = arg;
    const rt_ray *rays = j->set->by_pixel;
    const unsigned char *active = j->set->active;
    /* Embree's recommended floating-point mode for its threads */
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    struct RTCIntersectContext ic;
    rtcInitIntersectContext(&ic);
    ic.flags = j->set->coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT
                                : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    unsigned tiles_x = (j->w + 3) / 4, tiles_y = (j->h + 3) / 4;
    for (unsigned ty = j->thread; ty < tiles_y; ty += j->threads)
        for (unsigned tx = 0; tx < tiles_x; ++tx) {
            if (j->packet == 16) {
                struct RTCRayHit16 rh;
                _Alignas(64) int valid[16];
                int any = 0;
                for (unsigned k = 0; k < 16; ++k) {
                    unsigned x = tx * 4 + k % 4, y = ty * 4 + k / 4;
                    int in = x < j->w && y < j->h;
                    size_t p = in ? (size_t)y * j->w + x : 0;
                    /* a pixel without a ray of this set: an inactive lane
                     * (its record holds a harmless ray) */
                    valid[k] = in && (!active || active[p]) ? -1 : 0;
                    any |= valid[k];
                    const rt_ray *r = &rays[p];
                    rh.ray.org_x[k] = r->ox;
                    rh.ray.org_y[k] = r->oy;
                    rh.ray.org_z[k] = r->oz;
                    rh.ray.dir_x[k] = r->dx;
                    rh.ray.dir_y[k] = r->dy;
                    rh.ray.dir_z[k] = r->dz;
                    rh.ray.tnear[k] = r->tmin;
                    rh.ray.tfar[k] = r->tmax;
                    rh.ray.time[k] = 0.0f;
                    rh.ray.mask[k] = 0xffffffffu;
                    rh.ray.id[k] = k;
                    rh.ray.flags[k] = 0;
                    rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                    rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
                }
                if (!any)
                    continue;
                rtcIntersect16(valid, j->scene, &ic, &rh);
                for (unsigned k = 0; k < 16; ++k) {
                    unsigned x = tx * 4 + k % 4, y = ty * 4 + k / 4;
                    if (valid[k]) {
                        size_t p = (size_t)y * j->w + x;
                        int hit = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
                        j->tri[p] = hit ? rh.hit.primID[k] : RT_NO_HIT;
                        j->t[p] = rh.ray.tfar[k];
                    }
                }
            } else {
                for (unsigned k = 0; k < 16; ++k) {
                    unsigned x = tx * 4 + k % 4, y = ty * 4 + k / 4;
                    if (x >= j->w || y >= j->h)
                        continue;
                    size_t p = (size_t)y * j->w + x;
                    if (active && !active[p])
                        continue;
                    const rt_ray *r = &rays[p];
                    struct RTCRayHit rh;
                    rh.ray.org_x = r->ox;
                    rh.ray.org_y = r->oy;
                    rh.ray.org_z = r->oz;
                    rh.ray.dir_x = r->dx;
                    rh.ray.dir_y = r->dy;
                    rh.ray.dir_z = r->dz;
                    rh.ray.tnear = r->tmin;
                    rh.ray.tfar = r->tmax;
                    rh.ray.time = 0.0f;
                    rh.ray.mask = 0xffffffffu;
                    rh.ray.id = 0;
                    rh.ray.flags = 0;
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(j->scene, &ic, &rh);
                    j->tri[p] =
                        rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? rh.hit.primID : RT_NO_HIT;
                    j->t[p] = rh.ray.tfar;
                }
            }
        }
    return NULL;
}

/* One frame of the ray set with `threads` threads; returns the seconds it
 * took. */
static double emb_frame(RTCScene scene, const ray_set *set, unsigned w, unsigned h, uint32_t *tri,
                        float *t, int packet, unsigned threads)
{
    emb_job jobs[2];
    pthread_t th[2];
    double t0 = sr_clock_seconds();
    for (unsigned i = 0; i < threads; ++i) {
        jobs[i] = (emb_job){scene, set, w, h, tri, t, packet, i, threads};
        if (i > 0 && pthread_create(&th[i], NULL, emb_worker, &jobs[i]) != 0) {
            fprintf(stderr, PROG ": pthread_create failed\n");
            exit(2);
        }
    }
    emb_worker(&jobs[0]);
    for (unsigned i = 1; i < threads; ++i)
        pthread_join(th[i], NULL);
    return sr_clock_seconds() - t0;
}
#endif

/* ------------------------------------------------------------------ */
/* One scene                                                           */
/* ------------------------------------------------------------------ */

typedef struct peer_hits {
    uint32_t *tri; /* by pixel */
    float *t;
} peer_hits;

/* What the peers measured on one ray set. */
typedef struct set_result {
    size_t rays;
    double hit_fraction; /* of the set's rays, by fused */
    double fused_s, stream_s, c_s;
    double emb_s[2][2]; /* [packet 1 / 16][1 / 2 threads] */
    const char *emb_best_name;
    double emb_best_s;
    unsigned emb_best_threads;
    /* hit agreement over the set's rays: same triangle (or both miss); and
     * same t within 1e-4 */
    double agree_stream, agree_c, agree_emb_tri, agree_emb_t;
    /* the ratios of each timed round's best frames (stream over fused, fused
     * over Embree's best): the lowest, the median and the highest, so that
     * a ratio near its bound shows how far the rounds spread around it */
    double sf_round[3], fe_round[3];
} set_result;

typedef struct scene_result {
    const char *name;
    size_t triangles;
    unsigned w, h;
    unsigned min_dim; /* the tracer's automatic choice */
    uint32_t dims[3];
    size_t grid_entries;
    double grid_host_s, grid_device_s, tracer_create_s[2];
    char fused_path[192]; /* rt_tracer_fused_path */
    int embree;
    double emb_build_s;
    set_result primary, bounce;
} scene_result;

static peer_hits hits_alloc(size_t n)
{
    peer_hits p = {xmalloc(n * sizeof(uint32_t)), xmalloc(n * sizeof(float))};
    return p;
}

static void hits_free(peer_hits *p)
{
    free(p->tri);
    free(p->t);
}

static void hits_from_rt(const rt_ray *rays, const rt_hit *h, size_t n, peer_hits *out)
{
    for (size_t i = 0; i < n; ++i) {
        out->tri[rays[i].pixel] = h[i].tri;
        out->t[rays[i].pixel] = h[i].t;
    }
}

/* Over the rays of `set` (by their pixels). */
static double agree_tri(const peer_hits *a, const peer_hits *b, const ray_set *set)
{
    size_t same = 0;
    for (size_t i = 0; i < set->n; ++i) {
        uint32_t p = set->rays[i].pixel;
        same += a->tri[p] == b->tri[p];
    }
    return set->n ? (double)same / (double)set->n : 1.0;
}

#ifdef HAVE_EMBREE
static double agree_t(const peer_hits *a, const peer_hits *b, const ray_set *set)
{
    size_t same = 0;
    for (size_t i = 0; i < set->n; ++i) {
        uint32_t p = set->rays[i].pixel;
        int ha = a->tri[p] != RT_NO_HIT, hb = b->tri[p] != RT_NO_HIT;
        if (!ha && !hb)
            ++same;
        else if (ha && hb && fabsf(a->t[p] - b->t[p]) <= 1e-4f * fmaxf(1.0f, fabsf(a->t[p])))
            ++same;
    }
    return set->n ? (double)same / (double)set->n : 1.0;
}
#endif

static sr_scene *load_scene(const char *name)
{
    return bench_load_scene(PROG, name);
}

static rt_tracer *make_tracer(const sr_scene *sc, rt_exec exec, unsigned min_dim, unsigned unroll,
                              double *seconds)
{
    char err[512];
    rt_tracer_options o = rt_tracer_options_default();
    o.exec = exec;
    if (unroll) {
        o.unroll_steps = unroll;
        o.unroll_tests = unroll;
    }
    o.grid_min_dim = min_dim;
    o.fused_walk = fused_walk;
    rt_tracer *t = NULL;
    double t0 = sr_clock_seconds();
    if (rt_tracer_create(ctx, sc, &o, &t, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, PROG ": rt_tracer_create: %s\n", err);
        exit(2);
    }
    TRY(sluice_context_finish(ctx));
    if (seconds)
        *seconds = sr_clock_seconds() - t0;
    return t;
}

/* Frames per peer and round (see time_peers). */
#define BENCH_BURST 8u

/* Keeps the best frame of the timed rounds: frame f of round `round`, where
 * round 0 is a warm-up. */
static void keep_best(double *best, unsigned round, unsigned f, double s)
{
    if (round > 0 && ((round == 1 && f == 0) || s < *best))
        *best = s;
}

/* The lowest, median and highest of x[0 .. n) (n > 0) into out; sorts x. */
static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void spread3(double *x, unsigned n, double *out)
{
    qsort(x, n, sizeof *x, cmp_double);
    out[0] = x[0];
    out[1] = n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
    out[2] = x[n - 1];
}

/* One trace of the device ray stream, timed. */
static double sluice_frame(rt_tracer *t, sluice_stream *rays_s, size_t n, sluice_stream *hits_s)
{
    TRY(sluice_context_finish(ctx));
    double t0 = sr_clock_seconds();
    TRY(rt_tracer_trace_stream(t, rays_s, n, hits_s));
    TRY(sluice_context_finish(ctx));
    return sr_clock_seconds() - t0;
}

/* The hits a Sluice run left in hits_s, by pixel. */
static void sluice_hits(sluice_stream *hits_s, const rt_ray *rays, size_t n, peer_hits *out)
{
    rt_hit *h = xmalloc(n * sizeof *h);
    size_t got = 0;
    TRY(sluice_stream_download(hits_s, h, n, &got));
    if (got != n) {
        fprintf(stderr, PROG ": %zu hits for %zu rays\n", got, n);
        exit(2);
    }
    hits_from_rt(rays, h, n, out);
    free(h);
}

/* One frame of the plain C tracer, one thread, timed. */
static double c_frame(const cgrid *cg, const rt_ray *rays, size_t n, rt_hit *out)
{
    double t0 = sr_clock_seconds();
    for (size_t i = 0; i < n; ++i)
        c_trace(cg, &rays[i], &out[i]);
    return sr_clock_seconds() - t0;
}

/* The peers of one scene, set up once and timed on each ray set. */
typedef struct peers {
    unsigned w, h;
    rt_tracer *tf, *ts; /* Sluice, fused and stream */
    cgrid cg;
#ifdef HAVE_EMBREE
    RTCScene es;
#endif
} peers;

#ifdef HAVE_EMBREE
static const int emb_packets[2] = {1, 16};
#endif

/* Times every peer on the ray set `set` and compares their hits. `c_hits`
 * (set->n records) receives the C tracer's hits in stream order. */
static void time_peers(const peers *pe, const ray_set *set, unsigned reps, set_result *res,
                       rt_hit *c_hits)
{
    size_t n = set->n, npix = (size_t)pe->w * pe->h;
    memset(res, 0, sizeof *res);
    res->rays = n;
    if (n == 0)
        return;
    sluice_stream *rays_s = NULL, *hits_f = NULL, *hits_s = NULL;
    TRY(sluice_stream_create(ctx, sizeof(rt_ray), n, &rays_s));
    TRY(sluice_stream_create(ctx, sizeof(rt_hit), n, &hits_f));
    TRY(sluice_stream_create(ctx, sizeof(rt_hit), n, &hits_s));
    TRY(sluice_stream_upload(rays_s, set->rays, n));
    peer_hits fused = hits_alloc(npix), stream = hits_alloc(npix), cref = hits_alloc(npix);
#ifdef HAVE_EMBREE
    peer_hits emb = hits_alloc(npix);
#endif

    /* Interleaved rounds: each round times every peer in a burst of
     * BENCH_BURST frames back to back, so that each is measured warm (its
     * data in cache, its threads awake: on these shared 2-core machines a
     * frame after an idle or single-threaded spell was up to 50% slower, for
     * every peer), and a slow spell of the machine falls on all peers alike
     * rather than on whichever ran then. The bursts are 8 frames because
     * Sluice's frames (bunny, fused) came down gradually over the first 5-8
     * of a burst, after the C tracer's frames as after 200 ms of sleep (from
     * about 7.5 to 5 ms), where Embree's were flat from the first. Round 0
     * is a warm-up; every time is the best frame of the other `reps`
     * rounds. */
    double *sf = xmalloc(reps * sizeof *sf), *fe = xmalloc(reps * sizeof *fe);
    for (unsigned r = 0; r <= reps; ++r) {
        /* this round's best frames (keep_best's round 1 starts afresh) */
        double rf = 0, rs = 0, re = 1e30;
        for (unsigned f = 0; f < BENCH_BURST; ++f) {
            double s = sluice_frame(pe->tf, rays_s, n, hits_f);
            keep_best(&res->fused_s, r, f, s);
            keep_best(&rf, 1, f, s);
        }
        for (unsigned f = 0; f < BENCH_BURST; ++f) {
            double s = sluice_frame(pe->ts, rays_s, n, hits_s);
            keep_best(&res->stream_s, r, f, s);
            keep_best(&rs, 1, f, s);
        }
        for (unsigned f = 0; f < BENCH_BURST; ++f)
            keep_best(&res->c_s, r, f, c_frame(&pe->cg, set->rays, n, c_hits));
#ifdef HAVE_EMBREE
        for (int p = 0; p < 2; ++p)
            for (unsigned th = 1; th <= 2; ++th)
                for (unsigned f = 0; f < BENCH_BURST; ++f) {
                    double s =
                        emb_frame(pe->es, set, pe->w, pe->h, emb.tri, emb.t, emb_packets[p], th);
                    keep_best(&res->emb_s[p][th - 1], r, f, s);
                    re = s < re ? s : re;
                }
#endif
        if (r > 0) {
            sf[r - 1] = rf / rs;
            fe[r - 1] = re / rf;
        }
    }
    spread3(sf, reps, res->sf_round);
    spread3(fe, reps, res->fe_round);
    free(sf);
    free(fe);
    sluice_hits(hits_f, set->rays, n, &fused);
    sluice_hits(hits_s, set->rays, n, &stream);
    hits_from_rt(set->rays, c_hits, n, &cref);
    sluice_stream_destroy(rays_s);
    sluice_stream_destroy(hits_f);
    sluice_stream_destroy(hits_s);

    size_t hit = 0;
    for (size_t i = 0; i < n; ++i)
        hit += fused.tri[set->rays[i].pixel] != RT_NO_HIT;
    res->hit_fraction = (double)hit / (double)n;
    res->agree_stream = agree_tri(&fused, &stream, set);
    res->agree_c = agree_tri(&fused, &cref, set);

#ifdef HAVE_EMBREE
    /* Embree's best on the cores Sluice has: 2 threads normally, 1 when the
     * other core is busy and 2 threads lose */
    res->emb_best_s = 1e30;
    for (int p = 0; p < 2; ++p)
        for (unsigned th = 1; th <= 2; ++th)
            if (res->emb_s[p][th - 1] < res->emb_best_s) {
                res->emb_best_s = res->emb_s[p][th - 1];
                res->emb_best_threads = th;
                res->emb_best_name = emb_packets[p] == 16 ? "rtcIntersect16" : "rtcIntersect1";
            }
    /* the hits of the last run (rtcIntersect16, 2 threads) */
    res->agree_emb_tri = agree_tri(&fused, &emb, set);
    res->agree_emb_t = agree_t(&fused, &emb, set);
    hits_free(&emb);
#endif
    hits_free(&fused);
    hits_free(&stream);
    hits_free(&cref);
}

static int run_scene(const char *name, unsigned size, unsigned reps, scene_result *res)
{
    char err[512];
    memset(res, 0, sizeof *res);
    sr_scene *sc = load_scene(name);
    if (!sc)
        return 0;
    res->name = name;
    res->triangles = sr_scene_triangle_count(sc);
    res->w = res->h = size;

    /* the grid: plain C build (also the C tracer's) and the device build */
    const sr_scene_stats *ss = sr_scene_statistics(sc);
    /* The fused tracer's resolution (its automatic choice unless
     * --grid-min-dim), for all peers that use a grid. */
    peers pe;
    memset(&pe, 0, sizeof pe);
    pe.w = pe.h = size;
    pe.tf = make_tracer(sc, RT_EXEC_FUSED, grid_min_dim, 0, &res->tracer_create_s[0]);
    snprintf(res->fused_path, sizeof res->fused_path, "%s", rt_tracer_fused_path(pe.tf));
    unsigned min_dim = rt_tracer_grid_min_dim(pe.tf);
    res->min_dim = min_dim;
    rt_grid_desc desc;
    if (rt_grid_choose(ss->bounds_min, ss->bounds_max, min_dim, &desc, err, sizeof err) !=
        SLUICE_OK) {
        fprintf(stderr, PROG ": %s: %s\n", name, err);
        exit(2);
    }
    memcpy(res->dims, desc.dims, sizeof res->dims);
    rt_grid_host gh = {0};
    for (unsigned r = 0; r <= reps; ++r) {
        rt_grid_host_free(&gh);
        double t0 = sr_clock_seconds();
        if (rt_grid_build_host(&desc, sr_scene_positions(sc), sr_scene_indices(sc), res->triangles,
                               &gh, err, sizeof err) != SLUICE_OK) {
            fprintf(stderr, PROG ": %s: grid: %s\n", name, err);
            exit(2);
        }
        double s = sr_clock_seconds() - t0;
        keep_best(&res->grid_host_s, r, 0, s);
    }
    size_t cells = (size_t)desc.dims[0] * desc.dims[1] * desc.dims[2];
    res->grid_entries = gh.cell_start[cells];
    {
        size_t nv = sr_scene_vertex_count(sc);
        sluice_stream *sp = NULL, *si = NULL;
        TRY(sluice_stream_create(ctx, 12, nv, &sp));
        TRY(sluice_stream_create(ctx, 12, res->triangles, &si));
        TRY(sluice_stream_upload(sp, sr_scene_positions(sc), nv));
        TRY(sluice_stream_upload(si, sr_scene_indices(sc), res->triangles));
        for (unsigned r = 0; r <= reps; ++r) {
            rt_grid_device g = {0};
            TRY(sluice_context_finish(ctx));
            double t0 = sr_clock_seconds();
            if (rt_grid_build_device(ctx, &desc, sp, si, res->triangles, &g) != SLUICE_OK) {
                fprintf(stderr, PROG ": %s: device grid: %s\n", name, g.message);
                exit(2);
            }
            TRY(sluice_context_finish(ctx));
            double s = sr_clock_seconds() - t0;
            rt_grid_device_free(&g);
            keep_best(&res->grid_device_s, r, 0, s);
        }
        sluice_stream_destroy(sp);
        sluice_stream_destroy(si);
    }

    /* the peers: (a), (b) Sluice, rays already on the device, (c) plain C,
     * (d) Embree */
    pe.ts = make_tracer(sc, RT_EXEC_STREAM, min_dim, 0, &res->tracer_create_s[1]);
    cgrid_init(&pe.cg, &gh, sc);
#ifdef HAVE_EMBREE
    res->embree = 1;
    RTCDevice dev = rtcNewDevice(embree_config[0] ? embree_config : NULL);
    if (!dev) {
        fprintf(stderr, PROG ": rtcNewDevice(\"%s\") failed\n", embree_config);
        exit(2);
    }
    pe.es = rtcNewScene(dev);
    rtcSetSceneBuildQuality(pe.es, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geo = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    size_t nv = sr_scene_vertex_count(sc);
    float *vb = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                        3 * sizeof(float), nv);
    uint32_t *ib = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(uint32_t), res->triangles);
    if (!vb || !ib) {
        fprintf(stderr, PROG ": Embree buffers: error %d\n", (int)rtcGetDeviceError(dev));
        exit(2);
    }
    memcpy(vb, sr_scene_positions(sc), 3 * nv * sizeof(float));
    memcpy(ib, sr_scene_indices(sc), 3 * res->triangles * sizeof(uint32_t));
    double t0 = sr_clock_seconds();
    rtcCommitGeometry(geo);
    rtcAttachGeometry(pe.es, geo);
    rtcReleaseGeometry(geo);
    rtcCommitScene(pe.es);
    res->emb_build_s = sr_clock_seconds() - t0;
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
        fprintf(stderr, PROG ": Embree scene build failed\n");
        exit(2);
    }
#endif

    /* primary rays, then the diffuse bounce rays off the C tracer's hits */
    ray_set prim = primary_set(sc, size, size);
    rt_hit *ch = xmalloc(prim.n * sizeof *ch);
    time_peers(&pe, &prim, reps, &res->primary, ch);
    ray_set bounce = bounce_set(&prim, ch, pe.cg.tv, sr_scene_epsilon(sc), size, size);
    time_peers(&pe, &bounce, reps, &res->bounce, ch);

#ifdef HAVE_EMBREE
    rtcReleaseScene(pe.es);
    rtcReleaseDevice(dev);
#endif
    rt_tracer_destroy(pe.tf);
    rt_tracer_destroy(pe.ts);
    free(ch);
    free(pe.cg.tv);
    rt_grid_host_free(&gh);
    ray_set_free(&prim);
    ray_set_free(&bounce);
    sr_scene_destroy(sc);
    return 1;
}

/* ------------------------------------------------------------------ */
/* Purcell's statistics                                                */
/* ------------------------------------------------------------------ */

typedef struct purcell_row {
    const char *scene;
    unsigned min_dim;
    uint32_t dims[3];
    double v, t, s;
    uint64_t passes, traverse_passes, intersect_passes;
    uint32_t max_steps, max_tests;
    double live_percent;   /* ours: share of the live rays each pass processed */
    double active_percent; /* Purcell's: 100 (v + t) / P, of all rays */
    double seconds;
} purcell_row;

static int purcell_run(const char *name, unsigned size, unsigned min_dim, purcell_row *row)
{
    sr_scene *sc = load_scene(name);
    if (!sc)
        return 0;
    size_t n = (size_t)size * size;
    rt_ray *rays = eye_rays(sc, size, size);
    rt_hit *hits = xmalloc(n * sizeof *hits);
    rt_tracer *t = make_tracer(sc, RT_EXEC_STREAM, min_dim, 1, NULL); /* Purcell's k = m = 1 */
    rt_tracer_reset_stats(t);
    double t0 = sr_clock_seconds();
    TRY(rt_tracer_trace(t, rays, n, hits));
    double secs = sr_clock_seconds() - t0;
    const rt_trace_stats *st = rt_tracer_stats(t);
    size_t hit = 0;
    for (size_t i = 0; i < n; ++i)
        hit += hits[i].tri != RT_NO_HIT;
    memset(row, 0, sizeof *row);
    row->scene = name;
    row->min_dim = min_dim;
    memcpy(row->dims, rt_tracer_grid(t)->desc.dims, sizeof row->dims);
    double rays_n = st->rays ? (double)st->rays : 1.0;
    row->v = (double)st->voxels / rays_n;
    row->t = (double)st->tests / rays_n;
    row->s = (double)hit / rays_n; /* ray casting: one shading per hit */
    row->passes = st->passes;
    row->traverse_passes = st->traverse_passes;
    row->intersect_passes = st->intersect_passes;
    row->max_steps = st->max_steps;
    row->max_tests = st->max_tests;
    row->live_percent = st->passes ? 100.0 * st->live_fraction_sum / (double)st->passes : 0.0;
    row->active_percent = st->passes ? 100.0 * (row->v + row->t) / (double)st->passes : 0.0;
    row->seconds = secs;
    rt_tracer_destroy(t);
    free(rays);
    free(hits);
    sr_scene_destroy(sc);
    return 1;
}

/* ------------------------------------------------------------------ */
/* Main                                                                */
/* ------------------------------------------------------------------ */

static int embree_isa_known(const char *s)
{
    static const char *const known[] = {"auto", "native", "sse2",  "sse4.2",
                                        "avx",  "avx2",   "avx512"};
    for (size_t i = 0; i < sizeof known / sizeof *known; ++i)
        if (strcmp(s, known[i]) == 0)
            return 1;
    return 0;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: " PROG " [--size N] [--reps R] [--scene NAME]... [--out FILE]\n"
               "                      [--purcell-size N] [--skip-purcell] [--quick]\n"
               "                      [--embree-isa ISA] [--grid-min-dim N] [--fused-walk W]\n"
               "  --size N          image side for the rays/s comparison (default 512)\n"
               "  --reps R          timed rounds, each running every peer for 8 frames;\n"
               "                    the best frame of each peer is kept (default 10)\n"
               "  --scene NAME      scene (default cornell, bunny and bunny-close: the bunny\n"
               "                    filling most of the frame); repeatable\n"
               "  --out FILE        write the results as JSON\n"
               "  --purcell-size N  image side for Purcell's statistics (default 1024)\n"
               "  --skip-purcell    no Purcell statistics\n"
               "  --quick           smoke test: 64x64, 1 rep, Purcell at 64x64\n"
               "  --embree-isa ISA  the widest instruction set Embree may use: sse2, sse4.2,\n"
               "                    avx, avx2, avx512, native (its own choice), or auto\n"
               "                    (default: avx2 when the kernels were built for AVX2,\n"
               "                    as with POCL_KERNELLIB_NAME=avx2, else native)\n"
               "  --grid-min-dim N  voxels along the grid's shortest axis, 1 .. 1024 (default:\n"
               "                    the tracer's automatic resolution per scene)\n"
               "  --fused-walk W    how `fused` crosses the grid: auto (default), voxel (a\n"
               "                    voxel at a time), walk (walk ahead) or slices (coherent\n"
               "                    packets slice by slice, the others walking ahead)\n");
}

static double rate(size_t n, double s)
{
    return s > 0 ? (double)n / s : 0.0;
}

static void table_header(const char *count)
{
    printf("%-11s %9s %8s %8s %8s %8s %8s %8s %8s %8s %8s %8s\n", "scene", count, "fused", "stream",
           "C 1t", "Emb 1t", "Emb 2t", "f/Emb", "s/f", "f/C", "=stream", "=Embree");
}

static void table_legend(void)
{
    printf("(Emb 1t, 2t: Embree's faster of rtcIntersect1 and rtcIntersect16 on 1 and 2 threads; "
           "f/Emb: fused over Embree's best; s/f: stream over fused; f/C: fused "
           "over 1-thread C; =: same hit triangle as fused; per round: the ratios of each "
           "round's best frames, median (lowest-highest))\n");
}

/* One row of a rays/s table: the set `s` of scene `r`, `count` in the
 * second column. */
static void table_row(const scene_result *r, const set_result *s, size_t count)
{
    size_t n = s->rays;
    if (n == 0)
        printf("%-11s %9zu (no rays)\n", r->name, count);
    else if (r->embree)
        printf("%-11s %9zu %8.2f %8.2f %8.2f %8.2f %8.2f %8.3f %8.3f %8.2f %7.2f%% %7.2f%%\n",
               r->name, count, rate(n, s->fused_s) / 1e6, rate(n, s->stream_s) / 1e6,
               rate(n, s->c_s) / 1e6, rate(n, fmin(s->emb_s[0][0], s->emb_s[1][0])) / 1e6,
               rate(n, fmin(s->emb_s[0][1], s->emb_s[1][1])) / 1e6, s->emb_best_s / s->fused_s,
               s->fused_s / s->stream_s, s->c_s / s->fused_s, 100 * s->agree_stream,
               100 * s->agree_emb_tri);
    else
        printf("%-11s %9zu %8.2f %8.2f %8.2f %8s %8s %8s %8.3f %8.2f %7.2f%% %8s\n", r->name, count,
               rate(n, s->fused_s) / 1e6, rate(n, s->stream_s) / 1e6, rate(n, s->c_s) / 1e6, "-",
               "-", "-", s->fused_s / s->stream_s, s->c_s / s->fused_s, 100 * s->agree_stream, "-");
}

/* Embree's four variants on the set `s` and its agreement in t. */
/* The per-round ratios (set_result.sf_round, fe_round), for the detail
 * lines. */
static void round_detail(const scene_result *r, const set_result *s)
{
    printf("; per round: s/f %.3f (%.3f-%.3f)", s->sf_round[1], s->sf_round[0], s->sf_round[2]);
    if (r->embree)
        printf(", f/Emb %.3f (%.3f-%.3f)", s->fe_round[1], s->fe_round[0], s->fe_round[2]);
}

static void embree_detail(const scene_result *r, const set_result *s)
{
    if (!r->embree)
        return;
    size_t n = s->rays;
    printf("; Embree 1/16-wide 1t %.2f/%.2f, 2t %.2f/%.2f M rays/s, same t %.2f%%",
           rate(n, s->emb_s[0][0]) / 1e6, rate(n, s->emb_s[1][0]) / 1e6,
           rate(n, s->emb_s[0][1]) / 1e6, rate(n, s->emb_s[1][1]) / 1e6, 100 * s->agree_emb_t);
}

/* 0 when a Sluice mode or the C tracer disagrees with fused on more than 1%
 * of the set's rays (`what`); warns when Embree does. */
static int check_agreement(const scene_result *r, const set_result *s, const char *what)
{
    int ok = 1;
    if (s->agree_stream < 0.99 || s->agree_c < 0.99) {
        fprintf(stderr, PROG ": %s: hits disagree (stream %.4f, C %.4f of %s)\n", r->name,
                s->agree_stream, s->agree_c, what);
        ok = 0;
    }
    if (r->embree && s->agree_emb_tri < 0.99)
        fprintf(stderr, PROG ": warning: %s: Embree agrees on %.2f%% of %s only\n", r->name,
                100 * s->agree_emb_tri, what);
    return ok;
}

/* The JSON of one ray set's figures: rays_per_second, seconds, ratios and
 * hit_agreement, each on a line of its own after `indent`; `bvh_s` (the
 * primary set's Embree build time) is added to seconds when >= 0. */
static void json_set(FILE *f, const char *indent, const scene_result *r, const set_result *s,
                     double bvh_s)
{
    size_t n = s->rays;
    fprintf(f,
            "%s\"rays_per_second\": {\"sluice_fused\": %.1f, \"sluice_stream\": %.1f, "
            "\"c_grid_1thread\": %.1f",
            indent, rate(n, s->fused_s), rate(n, s->stream_s), rate(n, s->c_s));
    if (r->embree)
        fprintf(f,
                ", \"embree_best\": %.1f, \"embree_intersect1_1thread\": %.1f, "
                "\"embree_intersect1_2threads\": "
                "%.1f, \"embree_intersect16_1thread\": %.1f, "
                "\"embree_intersect16_2threads\": %.1f",
                rate(n, s->emb_best_s), rate(n, s->emb_s[0][0]), rate(n, s->emb_s[0][1]),
                rate(n, s->emb_s[1][0]), rate(n, s->emb_s[1][1]));
    else
        fprintf(f, ", \"embree_best\": null");
    fprintf(f, "},\n");
    fprintf(f,
            "%s\"seconds\": {\"sluice_fused\": %.6f, \"sluice_stream\": %.6f, "
            "\"c_grid_1thread\": %.6f",
            indent, s->fused_s, s->stream_s, s->c_s);
    if (r->embree) {
        fprintf(f, ", \"embree_best\": %.6f", s->emb_best_s);
        if (bvh_s >= 0)
            fprintf(f, ", \"embree_bvh_build\": %.6f", bvh_s);
    }
    fprintf(f, "},\n");
    fprintf(f, "%s\"ratios\": {\"fused_over_embree\": ", indent);
    if (r->embree)
        fprintf(f, "%.4f", s->emb_best_s / s->fused_s);
    else
        fprintf(f, "null");
    fprintf(f,
            ", \"stream_over_fused\": %.4f, \"fused_over_c\": %.4f, "
            "\"embree_best_is\": ",
            s->fused_s / s->stream_s, s->c_s / s->fused_s);
    if (r->embree)
        fprintf(f, "\"%s, %u thread%s\"", s->emb_best_name, s->emb_best_threads,
                s->emb_best_threads > 1 ? "s" : "");
    else
        fprintf(f, "null");
    fprintf(f, ", \"stream_over_fused_rounds\": [%.4f, %.4f, %.4f]", s->sf_round[0], s->sf_round[1],
            s->sf_round[2]);
    if (r->embree)
        fprintf(f, ", \"fused_over_embree_rounds\": [%.4f, %.4f, %.4f]", s->fe_round[0],
                s->fe_round[1], s->fe_round[2]);
    else
        fprintf(f, ", \"fused_over_embree_rounds\": null");
    fprintf(f, "},\n");
    fprintf(f,
            "%s\"hit_agreement\": {\"fused_vs_stream\": %.6f, \"fused_vs_c\": %.6f, "
            "\"fused_vs_embree_triangle\": ",
            indent, s->agree_stream, s->agree_c);
    if (r->embree)
        fprintf(f, "%.6f, \"fused_vs_embree_t\": %.6f}", s->agree_emb_tri, s->agree_emb_t);
    else
        fprintf(f, "null, \"fused_vs_embree_t\": null}");
}

int main(int argc, char **argv)
{
    const char *scenes[MAX_SCENES], *out = NULL;
    size_t nscenes = 0;
    unsigned size = 512, reps = 10, psize = 1024;
    int skip_purcell = 0, quick = 0;
    const char *embree_isa = "auto";
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--scene") == 0 && i + 1 < argc && nscenes < MAX_SCENES)
            scenes[nscenes++] = argv[++i];
        else if (strcmp(argv[i], "--size") == 0 && i + 1 < argc &&
                 bench_parse_uint(argv[i + 1], 8192, &size) && size > 0)
            ++i;
        else if (strcmp(argv[i], "--purcell-size") == 0 && i + 1 < argc &&
                 bench_parse_uint(argv[i + 1], 8192, &psize) && psize > 0)
            ++i;
        else if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc &&
                 bench_parse_uint(argv[i + 1], 1000, &reps) && reps > 0)
            ++i;
        else if (strcmp(argv[i], "--out") == 0 && i + 1 < argc)
            out = argv[++i];
        else if (strcmp(argv[i], "--skip-purcell") == 0)
            skip_purcell = 1;
        else if (strcmp(argv[i], "--grid-min-dim") == 0 && i + 1 < argc &&
                 bench_parse_uint(argv[i + 1], 1024, &grid_min_dim) && grid_min_dim > 0)
            ++i;
        else if (strcmp(argv[i], "--fused-walk") == 0 && i + 1 < argc) {
            unsigned k = 0;
            while (k < 4 && strcmp(argv[i + 1], walk_names[k]) != 0)
                ++k;
            if (k == 4) {
                fprintf(stderr, PROG ": --fused-walk: unknown \"%s\" (auto, voxel, walk, slices)\n",
                        argv[i + 1]);
                return 2;
            }
            fused_walk = (rt_fused_walk)k;
            ++i;
        } else if (strcmp(argv[i], "--embree-isa") == 0 && i + 1 < argc &&
                   embree_isa_known(argv[i + 1]))
            embree_isa = argv[++i];
        else if (strcmp(argv[i], "--quick") == 0) {
            quick = 1;
            size = 64;
            reps = 1;
            psize = 64;
        } else if (strcmp(argv[i], "--help") == 0) {
            usage(stdout);
            return 0;
        } else {
            usage(stderr);
            return 2;
        }
    }
    FILE *probe = fopen(BUNNY_PATH, "rb");
    int have_bunny = probe != NULL;
    if (probe)
        fclose(probe);
    if (nscenes == 0) {
        scenes[nscenes++] = "cornell";
        if (have_bunny) {
            scenes[nscenes++] = "bunny";
            scenes[nscenes++] = "bunny-close";
        } else
            fprintf(stderr, PROG ": no " BUNNY_PATH " (glmark2-data): bunny skipped\n");
    }

    char err[512];
    if (sluice_context_create(NULL, &ctx, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, PROG ": %s\n", err);
        return 2;
    }
    sluice_device_info info;
    TRY(sluice_context_device(ctx, &info));
    bench_machine mach;
    bench_machine_probe(ctx, &mach);
    printf("device: %s / %s, %u compute units\nCPU: %s (%s), kernels' block emission: %s\n",
           info.platform, info.name, info.compute_units, mach.cpu, mach.isa, mach.block);
    if (strcmp(embree_isa, "auto") == 0)
        embree_isa = strcmp(mach.block, "avx2") == 0 ? "avx2" : "native";
    if (strcmp(embree_isa, "native") != 0)
        snprintf(embree_config, sizeof embree_config, "max_isa=%s", embree_isa);
#ifdef HAVE_EMBREE
    printf("Embree %s, BVH build quality high, 1 and 2 threads, ISA: %s\n", RTC_VERSION_STRING,
           strcmp(embree_isa, "native") == 0 ? "its own choice" : embree_config);
#else
    printf("Embree: not built in (install libembree-dev: sh tools/install-deps.sh --bench)\n");
#endif

    scene_result res[MAX_SCENES];
    int status = 0;
    printf("\nprimary rays, %ux%u, one per pixel centre, best frame of %u interleaved rounds; M "
           "rays/s\n",
           size, size, reps);
    table_header("triangles");
    for (size_t i = 0; i < nscenes; ++i) {
        scene_result *r = &res[i];
        if (!run_scene(scenes[i], size, reps, r)) {
            status = 2;
            r->name = NULL;
            continue;
        }
        table_row(r, &r->primary, r->triangles);
        if (!check_agreement(r, &r->primary, "pixels"))
            status = 1;
    }
    table_legend();
    for (size_t i = 0; i < nscenes; ++i) {
        scene_result *r = &res[i];
        if (!r->name)
            continue;
        printf("%-11s grid %ux%ux%u, %zu entries: C build %.4f s, device build %.4f s; tracer "
               "create %.3f s (fused) %.3f s (stream); hits %.1f%%; =C %.2f%%",
               r->name, r->dims[0], r->dims[1], r->dims[2], r->grid_entries, r->grid_host_s,
               r->grid_device_s, r->tracer_create_s[0], r->tracer_create_s[1],
               100 * r->primary.hit_fraction, 100 * r->primary.agree_c);
        embree_detail(r, &r->primary);
        round_detail(r, &r->primary);
        if (r->embree)
            printf("; Embree BVH %.4f s", r->emb_build_s);
        printf("\n%-11s fused traversal: %s\n", "", r->fused_path);
    }

    printf("\ndiffuse bounce rays, one per pixel whose primary ray hit (cosine-weighted about the "
           "geometric normal, from the hit offset by scene_eps), the same rounds; M rays/s\n");
    table_header("rays");
    for (size_t i = 0; i < nscenes; ++i) {
        scene_result *r = &res[i];
        if (!r->name)
            continue;
        table_row(r, &r->bounce, r->bounce.rays);
        if (!check_agreement(r, &r->bounce, "bounce rays"))
            status = 1;
    }
    table_legend();
    for (size_t i = 0; i < nscenes; ++i) {
        scene_result *r = &res[i];
        if (!r->name)
            continue;
        printf("%-11s %zu bounce rays (%.1f%% of the pixels), %.1f%% of them hit; =C %.2f%%",
               r->name, r->bounce.rays,
               100 * (double)r->bounce.rays / ((double)r->w * (double)r->h),
               100 * r->bounce.hit_fraction, 100 * r->bounce.agree_c);
        if (r->bounce.rays) {
            embree_detail(r, &r->bounce);
            round_detail(r, &r->bounce);
        }
        printf("\n");
    }

    /* Purcell's statistics */
    static const char *const purcell_scenes[] = {"cornell", "teapotahedron", "bunny"};
    purcell_row prow[6];
    size_t nprow = 0;
    if (!skip_purcell) {
        printf("\nPurcell's statistics (Fig. 5.2, Table 5.2): ray casting %ux%u, stream mode, k = "
               "m = 1\n",
               psize, psize);
        printf("%-14s %4s %12s %8s %8s %6s %6s %8s %8s %7s %9s %8s\n", "scene", "min", "grid", "v",
               "t", "s", "P", "max trv", "max isc", "live%", "active%", "seconds");
        unsigned dims[2] = {64, RT_GRID_DEFAULT_MIN_DIM};
        for (size_t i = 0; i < 3; ++i) {
            if (strcmp(purcell_scenes[i], "bunny") == 0 && !have_bunny)
                continue;
            for (int d = 0; d < 2; ++d) {
                purcell_row *p = &prow[nprow];
                if (!purcell_run(purcell_scenes[i], psize, dims[d], p)) {
                    status = 2;
                    continue;
                }
                ++nprow;
                char grid[48];
                snprintf(grid, sizeof grid, "%ux%ux%u", p->dims[0], p->dims[1], p->dims[2]);
                printf("%-14s %4u %12s %8.2f %8.2f %6.3f %6llu %8u %8u %6.1f%% %8.1f%% %8.3f\n",
                       p->scene, p->min_dim, grid, p->v, p->t, p->s, (unsigned long long)p->passes,
                       p->max_steps, p->max_tests, p->live_percent, p->active_percent, p->seconds);
            }
        }
        printf("%-14s %4u %12s %8.2f %8.2f %6.3f %6u %8u %8u %7s %8.1f%%   (Purcell 2004)\n",
               "bunny, Purcell", 64u, "98x64x163", 93.93, 13.88, 0.82, 1085u, 221u, 328u, "-",
               10.5);
        printf("(live%%: share of the live rays a pass processed, averaged over passes; active%%: "
               "100 (v + t) / P, Purcell's share of all rays active per pass)\n");
    }

    if (out) {
        FILE *f = fopen(out, "w");
        if (!f) {
            fprintf(stderr, PROG ": cannot write %s\n", out);
            sluice_context_destroy(ctx);
            return 2;
        }
        fprintf(f, "{\n  \"benchmark\": \"bench_raytrace\",\n");
        fprintf(f, "  \"cpu\": \"%s\",\n  \"cpu_isa\": \"%s\",\n  \"kernel_block_path\": \"%s\",\n",
                mach.cpu, mach.isa, mach.block);
        fprintf(f,
                "  \"device\": {\"platform\": \"%s\", \"name\": \"%s\", \"compute_units\": %u, "
                "\"opencl_c\": \"%s\"},\n",
                info.platform, info.name, info.compute_units, info.version);
        fprintf(
            f,
            "  \"setup\": {\"width\": %u, \"height\": %u, \"rays_per_pixel\": 1, \"rays\": "
            "\"primary, through the pixel centres, the scene's camera, 8x8 tiles of 4x4 blocks\", "
            "\"bounce_rays\": \"diffuse bounce: one per pixel whose primary ray hit (the C "
            "tracer's hits), from the hit point offset by scene_eps (sr_scene_epsilon) along "
            "the geometric normal facing the ray, cosine-weighted about it from a hash of the "
            "pixel (seed 0x%x), tmin 0, tmax infinity, path-ray flags; primary order, "
            "compacted; Embree: other pixels inactive, INCOHERENT context\", "
            "\"reps\": %u, \"timing\": \"interleaved rounds, each timing every peer for %u "
            "frames back to back; the best frame of reps rounds after a warm-up round; "
            "Sluice: trace only, "
            "rays and hits in device streams\", \"grid_min_dim\": \"%s\", \"fused_walk\": \"%s\", "
            "\"quick\": %s},\n",
            size, size, BOUNCE_SEED, reps, BENCH_BURST,
            grid_min_dim ? "--grid-min-dim (each scene's grid.min_dim)"
                         : "auto: the ray tracer's choice per scene (rt_tracer_grid_min_dim; "
                           "the sparse density, else the dense one)",
            walk_names[fused_walk], quick ? "true" : "false");
#ifdef HAVE_EMBREE
        fprintf(f,
                "  \"embree\": {\"available\": true, \"version\": \"%s\", \"build_quality\": "
                "\"high\", \"threads\": \"1 or 2, a pthread split of 4-pixel tile rows\", "
                "\"best\": \"the fastest of variants x threads\", \"variants\": "
                "[\"rtcIntersect1\", \"rtcIntersect16 (4x4 tiles)\"], \"max_isa\": \"%s\"},\n",
                RTC_VERSION_STRING, embree_isa);
#else
        fprintf(
            f, "  \"embree\": {\"available\": false, \"why\": \"built without Embree 3 "
               "(install libembree-dev: sh tools/install-deps.sh --bench, then reconfigure)\"},\n");
#endif
        fprintf(f, "  \"scenes\": [");
        int first = 1;
        for (size_t i = 0; i < nscenes; ++i) {
            scene_result *r = &res[i];
            if (!r->name)
                continue;
            fprintf(f, "%s\n    {\"scene\": \"%s\", \"triangles\": %zu, \"hit_fraction\": %.6f,\n",
                    first ? "" : ",", r->name, r->triangles, r->primary.hit_fraction);
            first = 0;
            fprintf(f,
                    "     \"grid\": {\"min_dim\": %u, \"dims\": [%u, %u, %u], \"entries\": %zu, "
                    "\"build_seconds_c\": %.6f, \"build_seconds_device\": %.6f, "
                    "\"tracer_create_seconds_fused\": %.6f, "
                    "\"tracer_create_seconds_stream\": %.6f},\n     \"fused_path\": \"%s\",\n",
                    r->min_dim, r->dims[0], r->dims[1], r->dims[2], r->grid_entries, r->grid_host_s,
                    r->grid_device_s, r->tracer_create_s[0], r->tracer_create_s[1], r->fused_path);
            json_set(f, "     ", r, &r->primary, r->emb_build_s);
            fprintf(f, ",\n     \"bounce\": {\"rays\": %zu, \"hit_fraction\": %.6f", r->bounce.rays,
                    r->bounce.hit_fraction);
            if (r->bounce.rays) {
                fprintf(f, ",\n");
                json_set(f, "       ", r, &r->bounce, -1.0);
            }
            fprintf(f, "}}");
        }
        fprintf(f, "\n  ],\n");
        if (skip_purcell) {
            fprintf(f, "  \"purcell\": null\n}\n");
        } else {
            fprintf(f,
                    "  \"purcell\": {\n    \"setup\": \"ray casting %ux%u, one ray per pixel "
                    "centre, stream mode (k = m = 1, threshold 0.2)\",\n"
                    "    \"notes\": \"v voxels and t triangle tests per ray, s hits (shadings) "
                    "per ray, P traverse + intersect passes (ray generation and shading passes "
                    "not counted); live_percent: share of the live rays each pass processed; "
                    "active_percent_est: 100 (v + t) / P, Purcell's share of all rays active "
                    "per pass (his bunny figures give 9.9%% by this formula for his 10.5%%)\",\n"
                    "    \"published_bunny\": {\"min_dim\": 64, \"dims\": [98, 64, 163], \"size\": "
                    "1024, \"v\": 93.93, \"t\": 13.88, \"s\": 0.82, \"P\": 1085, "
                    "\"max_traversals\": 221, \"max_intersections\": 328, "
                    "\"active_percent\": 10.5},\n    \"rows\": [",
                    psize, psize);
            for (size_t i = 0; i < nprow; ++i) {
                purcell_row *p = &prow[i];
                fprintf(f,
                        "%s\n      {\"scene\": \"%s\", \"min_dim\": %u, \"dims\": [%u, %u, %u], "
                        "\"v\": %.4f, \"t\": %.4f, \"s\": %.4f, \"P\": %llu, "
                        "\"traverse_passes\": %llu, \"intersect_passes\": %llu, "
                        "\"max_traversals\": %u, \"max_intersections\": %u, "
                        "\"live_percent\": %.3f, \"active_percent_est\": %.3f, "
                        "\"seconds\": %.4f}",
                        i ? "," : "", p->scene, p->min_dim, p->dims[0], p->dims[1], p->dims[2],
                        p->v, p->t, p->s, (unsigned long long)p->passes,
                        (unsigned long long)p->traverse_passes,
                        (unsigned long long)p->intersect_passes, p->max_steps, p->max_tests,
                        p->live_percent, p->active_percent, p->seconds);
            }
            fprintf(f, "\n    ]\n  }\n}\n");
        }
        fclose(f);
    }
    /* With SLUICE_PROFILE=1, the kernels' own times (every frame, warm-ups
     * included): against the frames' wall time, what a frame spends outside
     * its kernels. */
    if (sluice_profile_enabled(ctx))
        TRY(sluice_profile_print(ctx, stdout));
    sluice_context_destroy(ctx);
    return status;
}
