/* Tests of the ray tracer (apps/raytrace): hits against a brute-force C ray
 * caster (no grid: Moller-Trumbore over every triangle, nearest hit) in both
 * execution modes, the watertight intersector from inside closed meshes,
 * edge cases of the traversal, images of every mode against stored
 * references, determinism and the absence of NaN/Inf pixels.
 *
 * Usage: test_raytrace [--write-refs DIR] [--cli PATH-TO-sluice-raytrace]
 *   --write-refs DIR  (re)writes the reference images into DIR and exits
 *   --cli PATH        runs the command-line checks on PATH instead
 * RT_TEST_DATA (compile-time) is the directory of the stored references. */
#include "check.h"
#include "image_metrics.h"
#include "mt_ref.h"
#include "render.h"
#include "scene.h"
#include "scene_copy.h"
#include "tracer.h"

#include <math.h>
#include <signal.h>
#include <stddef.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#ifndef RT_TEST_DATA
#define RT_TEST_DATA "."
#endif

static sluice_context *ctx;

/* ------------------------------------------------------------------ */
/* Brute-force reference                                              */
/* ------------------------------------------------------------------ */

/* Nearest hit over triangles [first, last), with the kernels' arithmetic
 * (mt_ref.h), into *h (a later triangle replaces the hit only when nearer,
 * so the first of equal t wins, as over every triangle in order). */
RT_MT_REF_FAST static void bf_range(const sr_scene *s, const rt_ray *r, size_t first, size_t last,
                                    rt_hit *h)
{
    const float *p = sr_scene_positions(s);
    const uint32_t *ix = sr_scene_indices(s);
    const float o[3] = {r->ox, r->oy, r->oz}, d[3] = {r->dx, r->dy, r->dz};
    for (size_t i = first; i < last; ++i) {
        const float *v0 = p + 3 * ix[3 * i], *v1 = p + 3 * ix[3 * i + 1],
                    *v2 = p + 3 * ix[3 * i + 2];
        float e1[3] = {v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]};
        float e2[3] = {v2[0] - v0[0], v2[1] - v0[1], v2[2] - v0[2]};
        float t, u, v;
        if (rt_mt_ref(v0, e1, e2, o, d, &t, &u, &v) && t >= r->tmin && t < h->t) {
            h->tri = (uint32_t)i;
            h->t = t;
            h->u = u;
            h->v = v;
        }
    }
}

static void bf_start(const rt_ray *r, rt_hit *h)
{
    h->tri = RT_NO_HIT;
    h->t = r->tmax;
    h->u = h->v = 0;
}

/* Nearest hit over every triangle: the brute force itself. */
static void bf_trace(const sr_scene *s, const rt_ray *r, rt_hit *h)
{
    bf_start(r, h);
    bf_range(s, r, 0, sr_scene_triangle_count(s), h);
}

/* The brute force in blocks: the triangles in runs of BF_BLOCK (in their
 * own order, so no grid or tree of the tracer's is involved) and the runs
 * in groups of BF_BLOCK, each with its bounding box padded far beyond
 * rounding; a ray that misses a box, or enters it beyond its nearest hit so
 * far, skips what it holds, and the runs it meets are searched in order as
 * bf_trace searches them, so it finds the same hit (check_against_bf
 * compares the two on a share of the rays). The test spent most of its
 * time on the plain loop. */
#define BF_BLOCK 16

typedef struct bf_box {
    float lo[3], hi[3];
} bf_box;

typedef struct bf_blocks {
    size_t runs, groups;
    bf_box *run, *group;
} bf_blocks;

static void bf_box_empty(bf_box *b)
{
    for (int a = 0; a < 3; ++a) {
        b->lo[a] = INFINITY;
        b->hi[a] = -INFINITY;
    }
}

static void bf_box_add(bf_box *b, const float *lo, const float *hi)
{
    for (int a = 0; a < 3; ++a) {
        b->lo[a] = lo[a] < b->lo[a] ? lo[a] : b->lo[a];
        b->hi[a] = hi[a] > b->hi[a] ? hi[a] : b->hi[a];
    }
}

static bf_blocks bf_blocks_make(const sr_scene *s)
{
    const float *p = sr_scene_positions(s);
    const uint32_t *ix = sr_scene_indices(s);
    size_t nt = sr_scene_triangle_count(s);
    bf_blocks b = {(nt + BF_BLOCK - 1) / BF_BLOCK, 0, NULL, NULL};
    b.groups = (b.runs + BF_BLOCK - 1) / BF_BLOCK;
    b.run = malloc((b.runs + 1) * sizeof *b.run);
    b.group = malloc((b.groups + 1) * sizeof *b.group);
    CHECK(b.run && b.group, "out of memory");
    if (!b.run || !b.group) {
        b.runs = b.groups = 0;
        return b;
    }
    float span = 0.0f; /* the largest coordinate's magnitude */
    for (size_t i = 0; i < 3 * sr_scene_vertex_count(s); ++i)
        span = fmaxf(span, fabsf(p[i]));
    const float pad = 1e-3f * span + 1e-6f;
    for (size_t k = 0; k < b.runs; ++k) {
        bf_box_empty(&b.run[k]);
        for (size_t i = k * BF_BLOCK; i < nt && i < (k + 1) * BF_BLOCK; ++i)
            for (int c = 0; c < 3; ++c) {
                const float *v = p + 3 * ix[3 * i + (size_t)c];
                float lo[3] = {v[0] - pad, v[1] - pad, v[2] - pad},
                      hi[3] = {v[0] + pad, v[1] + pad, v[2] + pad};
                bf_box_add(&b.run[k], lo, hi);
            }
    }
    for (size_t g = 0; g < b.groups; ++g) {
        bf_box_empty(&b.group[g]);
        for (size_t k = g * BF_BLOCK; k < b.runs && k < (g + 1) * BF_BLOCK; ++k)
            bf_box_add(&b.group[g], b.run[k].lo, b.run[k].hi);
    }
    return b;
}

static void bf_blocks_free(bf_blocks *b)
{
    free(b->run);
    free(b->group);
}

/* Can the ray (origin o, direction d, from tmin) meet box x before t? The
 * slabs in double: no rounding here excludes a point inside the box. */
static int bf_box_meets(const bf_box *x, const float *o, const float *d, float tmin, float t)
{
    double t0 = -INFINITY, t1 = INFINITY;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0f) {
            if (o[a] < x->lo[a] || o[a] > x->hi[a])
                return 0;
            continue;
        }
        double ta = ((double)x->lo[a] - o[a]) / d[a], tb = ((double)x->hi[a] - o[a]) / d[a];
        if (ta > tb) {
            double u = ta;
            ta = tb;
            tb = u;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
    }
    return t0 <= t1 && t1 >= (double)tmin && t0 <= (double)t;
}

/* bf_trace, skipping the groups and runs the ray cannot meet nearer. Rays
 * with a coordinate that is not finite take the plain loop. */
static void bf_trace_blocks(const sr_scene *s, const bf_blocks *b, const rt_ray *r, rt_hit *h)
{
    const float o[3] = {r->ox, r->oy, r->oz}, d[3] = {r->dx, r->dy, r->dz};
    for (int a = 0; a < 3; ++a)
        if (!isfinite(o[a]) || !isfinite(d[a]) || isnan(r->tmin) || isnan(r->tmax)) {
            bf_trace(s, r, h);
            return;
        }
    size_t nt = sr_scene_triangle_count(s);
    bf_start(r, h);
    for (size_t g = 0; g < b->groups; ++g) {
        if (!bf_box_meets(&b->group[g], o, d, r->tmin, h->t))
            continue;
        for (size_t k = g * BF_BLOCK; k < b->runs && k < (g + 1) * BF_BLOCK; ++k) {
            if (!bf_box_meets(&b->run[k], o, d, r->tmin, h->t))
                continue;
            size_t last = (k + 1) * BF_BLOCK < nt ? (k + 1) * BF_BLOCK : nt;
            bf_range(s, r, k * BF_BLOCK, last, h);
        }
    }
}

static float frand(uint32_t *st)
{
    return (float)(check_rand(st) >> 8) * (1.0f / 16777216.0f);
}

static void make_ray(rt_ray *r, const float o[3], const float d[3])
{
    memset(r, 0, sizeof *r);
    r->ox = o[0];
    r->oy = o[1];
    r->oz = o[2];
    float l = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    r->dx = d[0] / l;
    r->dy = d[1] / l;
    r->dz = d[2] / l;
    r->tmin = 0;
    r->tmax = INFINITY;
    r->wr = r->wg = r->wb = 1;
}

static void random_dir(uint32_t *st, float d[3])
{
    do {
        for (int k = 0; k < 3; ++k)
            d[k] = 2 * frand(st) - 1;
    } while (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > 1 ||
             d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < 1e-4f);
}

/* A random point of the scene's box grown by 20% each way (so some rays
 * start outside the grid). */
static void random_origin(const sr_scene *s, uint32_t *st, float o[3])
{
    const sr_scene_stats *ss = sr_scene_statistics(s);
    for (int k = 0; k < 3; ++k) {
        float lo = ss->bounds_min[k], hi = ss->bounds_max[k], e = hi - lo;
        o[k] = lo - 0.2f * e + 1.4f * e * frand(st);
    }
}

/* The centroid of a random triangle. */
static void random_centroid(const sr_scene *s, uint32_t *st, float c[3])
{
    const float *p = sr_scene_positions(s);
    const uint32_t *ix = sr_scene_indices(s);
    size_t t = check_rand(st) % sr_scene_triangle_count(s);
    for (int k = 0; k < 3; ++k)
        c[k] = (p[3 * ix[3 * t] + k] + p[3 * ix[3 * t + 1] + k] + p[3 * ix[3 * t + 2] + k]) / 3.0f;
}

/* Random rays: origins by random_origin, directions uniform; every 8th ray
 * aims at a random triangle's centroid so that most rays hit. */
static rt_ray *random_rays(const sr_scene *s, size_t n, uint32_t seed)
{
    rt_ray *r = malloc(n * sizeof *r);
    uint32_t st = seed;
    for (size_t i = 0; i < n; ++i) {
        float o[3], d[3];
        random_origin(s, &st, o);
        if (i % 8 == 0) {
            random_centroid(s, &st, d);
            for (int k = 0; k < 3; ++k)
                d[k] -= o[k];
        } else {
            random_dir(&st, d);
        }
        make_ray(&r[i], o, d);
    }
    return r;
}

/* Coherent rays, in bundles of 16 (the fused mode's packets): from a random
 * origin as above to a 4x4 patch around a random triangle's centroid, a
 * patch a hundredth of the scene across; every fourth bundle instead 16
 * parallel rays along an axis (directions with two zero components) from a
 * 4x4 patch of origins. */
static rt_ray *coherent_rays(const sr_scene *s, size_t n, uint32_t seed)
{
    rt_ray *r = malloc(n * sizeof *r);
    const sr_scene_stats *ss = sr_scene_statistics(s);
    uint32_t st = seed;
    float ext = 0.0f;
    for (int k = 0; k < 3; ++k)
        ext = fmaxf(ext, ss->bounds_max[k] - ss->bounds_min[k]);
    float o[3] = {0, 0, 0}, c[3] = {0, 0, 0}, d[3];
    for (size_t i = 0; i < n; ++i) {
        size_t b = i / 16, l = i % 16;
        if (l == 0) {
            random_origin(s, &st, o);
            random_centroid(s, &st, c);
            /* some from far away, where a hit past a voxel's exit (within
             * its limit, 1e-6 of the distance) is widest */
            if (b % 8 == 5)
                for (int k = 0; k < 3; ++k)
                    o[k] = c[k] + (o[k] - c[k]) * 500.0f;
        }
        float a = 0.01f * ext * ((float)(l % 4) - 1.5f), bb = 0.01f * ext * ((float)(l / 4) - 1.5f);
        if (b % 4 == 3) {
            /* along axis K, from the far side of the box, origins spread
             * over the other two */
            int K = (int)(b / 4 % 3), U = (K + 1) % 3, V = (K + 2) % 3;
            float ro[3];
            ro[K] = ss->bounds_min[K] - 0.1f * ext;
            ro[U] = c[U] + a;
            ro[V] = c[V] + bb;
            d[K] = 1.0f;
            d[U] = d[V] = 0.0f;
            make_ray(&r[i], ro, d);
        } else {
            for (int k = 0; k < 3; ++k)
                d[k] = c[k] - o[k];
            d[(b % 3 + 1) % 3] += a;
            d[(b % 3 + 2) % 3] += bb;
            make_ray(&r[i], o, d);
        }
    }
    return r;
}

typedef struct cmp_result {
    size_t same, ties, mismatches, hits;
} cmp_result;

/* Same triangle and t within 1e-5 relative; a different triangle at the same
 * t (within 1e-5) is a tie (the ray crosses a shared edge or vertex, where
 * either triangle is the nearest hit) and counted apart. */
static void compare_hits(const rt_hit *a, const rt_hit *b, size_t n, cmp_result *c,
                         const char *what)
{
    memset(c, 0, sizeof *c);
    int shown = 0;
    for (size_t i = 0; i < n; ++i) {
        int both_miss = a[i].tri == RT_NO_HIT && b[i].tri == RT_NO_HIT;
        int t_close = a[i].tri != RT_NO_HIT && b[i].tri != RT_NO_HIT &&
                      fabsf(a[i].t - b[i].t) <= 1e-5f * fmaxf(fabsf(b[i].t), 1e-20f);
        if (b[i].tri != RT_NO_HIT)
            c->hits++;
        if (both_miss || (a[i].tri == b[i].tri && t_close))
            c->same++;
        else if (t_close)
            c->ties++;
        else {
            c->mismatches++;
            if (shown++ < 3)
                fprintf(stderr, "%s: ray %zu: got tri %u t %.9g, expected tri %u t %.9g\n", what, i,
                        a[i].tri, (double)a[i].t, b[i].tri, (double)b[i].t);
        }
    }
}

static sr_scene *load(const char *name)
{
    char err[512];
    sr_scene_load_options o = {0};
    o.flags = SR_SCENE_ALLOW_NO_LIGHT;
    sr_scene *s = NULL;
    if (sr_scene_load(name, &o, &s, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "scene %s: %s\n", name, err);
        return NULL;
    }
    return s;
}

static rt_tracer *make_tracer_walk(const sr_scene *s, rt_exec exec, rt_intersector isect,
                                   rt_fused_walk walk, size_t list_copy_max)
{
    char err[1024];
    rt_tracer_options o = rt_tracer_options_default();
    o.exec = exec;
    o.intersector = isect;
    o.fused_walk = walk;
    o.list_copy_max = list_copy_max;
    rt_tracer *t = NULL;
    sluice_status st = rt_tracer_create(ctx, s, &o, &t, err, sizeof err);
    CHECK(st == SLUICE_OK, "rt_tracer_create: %s", err);
    return t;
}

static rt_tracer *make_tracer(const sr_scene *s, rt_exec exec, rt_intersector isect)
{
    return make_tracer_walk(s, exec, isect, RT_WALK_AUTO, RT_LIST_COPY_MAX_DEFAULT);
}

static size_t total_rays_checked;

/* Slices the coherent bundles' packets crossed at once through empty macro
 * cells, over every scene (some have none). */
static uint64_t packet_slices_skipped;

/* Traces `rays` in both modes and compares with the brute force on the first
 * `nbf` of them (all when nbf == n). */
static void check_against_bf(const char *name, const sr_scene *s, rt_ray *rays, size_t n,
                             size_t nbf, int coherent)
{
    rt_hit *ref = malloc(nbf * sizeof *ref), *got = malloc(n * sizeof *got);
    bf_blocks blocks = bf_blocks_make(s);
    for (size_t i = 0; i < nbf; ++i)
        bf_trace_blocks(s, &blocks, &rays[i], &ref[i]);
    bf_blocks_free(&blocks);
    /* the blocks against the plain loop, on every 64th ray: the same hit
     * bit for bit */
    size_t bf_diff = 0;
    for (size_t i = 0; i < nbf; i += 64) {
        rt_hit plain;
        bf_trace(s, &rays[i], &plain);
        bf_diff += memcmp(&plain, &ref[i], offsetof(rt_hit, steps)) != 0; /* tri, t, u, v */
    }
    CHECK(bf_diff == 0, "%s: the blocked brute force differs from the plain one on %zu rays", name,
          bf_diff);
    rt_hit *first = malloc(n * sizeof *first);
    /* the stream mode with the list copy and without it, then every way the
     * fused mode can traverse: a voxel at a time, walking ahead with the
     * list copy, and without it, and coherent packets slice by slice (the
     * same hits; its counts are slices and culled tests, so not compared) */
    static const struct {
        const char *name;
        rt_exec exec;
        rt_fused_walk walk;
        size_t copy_max;
        const char *path; /* what rt_tracer_fused_path says */
    } paths[] = {
        {"stream", RT_EXEC_STREAM, RT_WALK_AUTO, RT_LIST_COPY_MAX_DEFAULT, ""},
        {"stream, gather", RT_EXEC_STREAM, RT_WALK_AUTO, 0, ""},
        {"fused voxel", RT_EXEC_FUSED, RT_WALK_OFF, RT_LIST_COPY_MAX_DEFAULT, "a voxel at a time"},
        {"fused walk", RT_EXEC_FUSED, RT_WALK_ON, RT_LIST_COPY_MAX_DEFAULT, "list copy"},
        {"fused walk, gather", RT_EXEC_FUSED, RT_WALK_ON, 0, "no list copy"},
        {"fused slices", RT_EXEC_FUSED, RT_WALK_SLICES, RT_LIST_COPY_MAX_DEFAULT,
         "slice by slice"}};
    for (size_t e = 0; e < sizeof paths / sizeof *paths; ++e) {
        rt_tracer *t =
            make_tracer_walk(s, paths[e].exec, RT_ISECT_MT, paths[e].walk, paths[e].copy_max);
        if (!t)
            break;
        CHECK(strstr(rt_tracer_fused_path(t), paths[e].path), "%s: fused path \"%s\"",
              paths[e].name, rt_tracer_fused_path(t));
        /* a stream tracer says when it has no list copy */
        CHECK((paths[e].exec == RT_EXEC_STREAM && paths[e].copy_max == 0) ==
                  (strstr(rt_tracer_skipped(t), "list-order copy") != NULL),
              "%s: skipped \"%s\"", paths[e].name, rt_tracer_skipped(t));
        CHECK_OK(ctx, rt_tracer_trace(t, rays, n, got));
        cmp_result c;
        char what[128];
        snprintf(what, sizeof what, "%s/%s", name, paths[e].name);
        compare_hits(got, ref, nbf, &c, what);
        printf("%-28s %8zu rays (%zu hit): %zu same, %zu ties at shared edges, %zu mismatches\n",
               what, nbf, c.hits, c.same, c.ties, c.mismatches);
        CHECK(c.mismatches == 0, "%s: %zu of %zu rays differ from the brute force", what,
              c.mismatches, nbf);
        CHECK(c.ties * 1000 <= nbf, "%s: too many ties (%zu)", what, c.ties);
        if (e == 0) {
            memcpy(first, got, n * sizeof *got);
        } else {
            /* the two modes run the same math: identical hits on every ray */
            int counts = paths[e].walk != RT_WALK_SLICES;
            size_t diff = 0, counted_apart = 0;
            uint64_t steps_dda = 0, steps_here = 0;
            for (size_t i = 0; i < n; ++i) {
                diff +=
                    first[i].tri != got[i].tri || first[i].t != got[i].t ||
                    (counts && (first[i].steps != got[i].steps || first[i].tests != got[i].tests));
                counted_apart += first[i].steps != got[i].steps || first[i].tests != got[i].tests;
                steps_dda += first[i].steps;
                steps_here += got[i].steps;
            }
            if (!counts) {
                /* the slices ran (their counts differ) on coherent bundles,
                 * and a ray crosses no more slices than voxels */
                printf("%-28s counts differ on %zu rays; %.2f slices against %.2f voxels a ray\n",
                       what, counted_apart, (double)steps_here / (double)n,
                       (double)steps_dda / (double)n);
                CHECK(!coherent || counted_apart > 0, "%s: the slices never ran", what);
                CHECK(steps_here <= steps_dda, "%s: more slices than voxels", what);
                /* packets count their slices, and those crossed at once
                 * through empty macro cells are among them */
                const rt_trace_stats *st = rt_tracer_stats(t);
                printf("%-28s %llu packet slices, %llu of them through empty blocks\n", what,
                       (unsigned long long)st->slices, (unsigned long long)st->slices_skipped);
                CHECK(!coherent || st->slices > 0, "%s: no packet slices counted", what);
                CHECK(st->slices_skipped <= st->slices, "%s: more slices skipped than crossed",
                      what);
                if (coherent)
                    packet_slices_skipped += st->slices_skipped;
            }
            CHECK(diff == 0, "%s: stream and %s differ on %zu of %zu rays", name, paths[e].name,
                  diff, n);
        }
        rt_tracer_destroy(t);
    }
    total_rays_checked += nbf;
    free(first);
    free(ref);
    free(got);
}

static void test_random_rays(void)
{
    packet_slices_skipped = 0;
    struct {
        const char *name;
        size_t n, nbf;
    } cases[] = {{"cornell", 700000, 700000},
                 {"spheres:20", 200000, 60000},
                 {"teapotahedron", 200000, 20000},
                 {"bunny", 200000, 10000},
                 {"cornell-point", 200000, 200000}};
    for (size_t c = 0; c < sizeof cases / sizeof *cases; ++c) {
        sr_scene *s = load(cases[c].name);
        if (!s) {
            if (strcmp(cases[c].name, "bunny") == 0) {
                printf("bunny not installed: skipped\n");
                continue;
            }
            CHECK(0, "cannot load %s", cases[c].name);
            continue;
        }
        rt_ray *r = random_rays(s, cases[c].n, 1234u + (uint32_t)c);
        check_against_bf(cases[c].name, s, r, cases[c].n, cases[c].nbf, 0);
        free(r);
        /* packets of coherent rays: the fused mode's slices */
        /* a quarter of the brute force of the random rays: it dominates
         * the test's time under the sanitizers */
        size_t nc = cases[c].n / 4, nbfc = cases[c].nbf / 4;
        char what[64];
        snprintf(what, sizeof what, "%s coherent", cases[c].name);
        r = coherent_rays(s, nc, 4321u + (uint32_t)c);
        check_against_bf(what, s, r, nc, nbfc, 1);
        free(r);
        sr_scene_destroy(s);
    }
    CHECK(packet_slices_skipped > 0, "no coherent packet crossed an empty macro cell");
}

/* ------------------------------------------------------------------ */
/* Small scenes built here                                             */
/* ------------------------------------------------------------------ */

static sr_scene *one_triangle(void)
{
    sr_scene_builder *b = NULL;
    sr_scene_builder_create("one triangle", &b);
    char err[256];
    sr_material m = sr_material_make(SR_MATERIAL_DIFFUSE, "d");
    uint32_t mi;
    sr_scene_builder_add_material(b, &m, &mi, err, sizeof err);
    float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 5, 5, 5, 6, 6, 6};
    uint32_t idx[] = {0, 1, 2, 3, 4, 5}; /* the second one is degenerate: dropped */
    sr_mesh_desc md = {0};
    md.source = "tri";
    md.positions = pos;
    md.vertex_count = 6;
    md.indices = idx;
    md.triangle_count = 2;
    md.material = mi;
    CHECK(sr_scene_builder_add_mesh(b, &md, err, sizeof err) == SLUICE_OK, "%s", err);
    sr_scene *s = NULL;
    CHECK(sr_scene_builder_finish(b, SR_SCENE_DEFAULT_LIGHT, &s, err, sizeof err) == SLUICE_OK,
          "%s", err);
    sr_scene_builder_destroy(b);
    return s;
}

static void test_one_triangle_and_edges(void)
{
    sr_scene *s = one_triangle();
    if (!s)
        return;
    CHECK(sr_scene_triangle_count(s) == 1, "degenerate triangle kept");
    CHECK(sr_scene_statistics(s)->degenerate_dropped == 1, "degenerate not counted");
    rt_ray *r = random_rays(s, 100000, 99);
    check_against_bf("one-triangle", s, r, 100000, 100000, 0);
    free(r);
    sr_scene_destroy(s);

    /* Axis-parallel rays and rays starting exactly on voxel faces and grid
     * corners, in cornell. */
    s = load("cornell");
    if (!s)
        return;
    rt_tracer *t = make_tracer(s, RT_EXEC_FUSED, RT_ISECT_MT);
    if (!t) {
        sr_scene_destroy(s);
        return;
    }
    const rt_grid_desc *g = &rt_tracer_grid(t)->desc;
    size_t n = 60000;
    rt_ray *rays = malloc(n * sizeof *rays);
    uint32_t st = 7;
    for (size_t i = 0; i < n; ++i) {
        float o[3], d[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k) {
            /* a voxel face (or, for every 4th ray, a grid corner) */
            unsigned c = check_rand(&st) % (g->dims[k] + 1);
            if (i % 4 == 0)
                c = (check_rand(&st) & 1) ? g->dims[k] : 0;
            o[k] = g->lo[k] + (float)c * g->cell[k];
            if (i % 3 == 1)
                o[k] += g->cell[k] * frand(&st);
        }
        if (i % 2 == 0) {
            int axis = (int)(check_rand(&st) % 3);
            d[axis] = (check_rand(&st) & 1) ? 1.0f : -1.0f;
        } else {
            random_dir(&st, d);
        }
        make_ray(&rays[i], o, d);
    }
    rt_tracer_destroy(t);
    check_against_bf("cornell-axis-and-corners", s, rays, n, n, 0);
    free(rays);
    sr_scene_destroy(s);
}

/* ------------------------------------------------------------------ */
/* Watertightness                                                      */
/* ------------------------------------------------------------------ */

static int cmp_u64(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return a < b ? -1 : a > b;
}

/* The three undirected edges of every triangle (a << 32 | b with a < b),
 * sorted, so that an edge's triangles are neighbours; 3 per triangle. */
static uint64_t *sorted_edges(const sr_scene *s)
{
    size_t nt = sr_scene_triangle_count(s);
    const uint32_t *ix = sr_scene_indices(s);
    uint64_t *e = malloc(3 * nt * sizeof *e);
    for (size_t i = 0; i < nt; ++i)
        for (int k = 0; k < 3; ++k) {
            uint64_t a = ix[3 * i + k], b = ix[3 * i + (k + 1) % 3];
            e[3 * i + k] = a < b ? (a << 32 | b) : (b << 32 | a);
        }
    qsort(e, 3 * nt, sizeof *e, cmp_u64);
    return e;
}

/* Non-zero when every undirected edge is shared by exactly two triangles. */
static int is_closed(const sr_scene *s)
{
    size_t nt = sr_scene_triangle_count(s);
    uint64_t *e = sorted_edges(s);
    int closed = 1;
    for (size_t i = 0; i < 3 * nt;) {
        size_t j = i;
        while (j < 3 * nt && e[j] == e[i])
            ++j;
        closed &= j - i == 2;
        i = j;
    }
    free(e);
    return closed;
}

/* Categories of the rays of leak_test(). */
enum { LK_RANDOM, LK_VERTEX, LK_VERTEX_ULP, LK_EDGE, LK_EDGE_ULP, LK_CATEGORIES };
static const char *const lk_names[LK_CATEGORIES] = {"random directions", "at vertices",
                                                    "at vertices +-1 ulp", "at edge points",
                                                    "at edge points +-1 ulp"};

/* The mesh's distinct undirected edges (a << 32 | b with a < b), sorted. */
static uint64_t *unique_edges(const sr_scene *s, size_t *count)
{
    size_t nt = sr_scene_triangle_count(s);
    uint64_t *e = sorted_edges(s);
    size_t m = 0;
    for (size_t i = 0; i < 3 * nt; ++i)
        if (m == 0 || e[i] != e[m - 1])
            e[m++] = e[i];
    *count = m;
    return e;
}

/* Each coordinate of p moved by one ulp up or down (at random). */
static void jitter_ulp(uint32_t *st, const float p[3], float q[3])
{
    for (int k = 0; k < 3; ++k)
        q[k] = nextafterf(p[k], check_rand(st) & 1 ? INFINITY : -INFINITY);
}

/* Appends a ray from o towards the point p (and `jitters` more towards p
 * moved by one ulp) to rays/cat. */
static void aim(rt_ray *rays, unsigned char *cat, size_t *n, uint32_t *st, const float o[3],
                const float p[3], int exact_cat, int jitters)
{
    float d[3], q[3];
    for (int k = 0; k < 3; ++k)
        d[k] = p[k] - o[k];
    make_ray(&rays[*n], o, d);
    cat[(*n)++] = (unsigned char)exact_cat;
    for (int j = 0; j < jitters; ++j) {
        jitter_ulp(st, p, q);
        for (int k = 0; k < 3; ++k)
            d[k] = q[k] - o[k];
        make_ray(&rays[*n], o, d);
        cat[(*n)++] = (unsigned char)(exact_cat + 1);
    }
}

/* Rays from inside a closed mesh (origins within `radius` of c, which must
 * lie inside it) must all hit with the watertight intersector: n_random
 * rays in random directions, then rays aimed exactly at the mesh's shared
 * vertices and at points v0 + s (v1 - v0) of its shared edges, and at
 * those points moved by one ulp, from c and from a few other interior
 * points (every `edge_stride`-th edge only, for large meshes). */
static void leak_test(const char *name, const sr_scene *s, const float c[3], float radius,
                      size_t n_random, size_t edge_stride)
{
    static const float edge_s[] = {0.5f, 0.25f, 1.0f / 3.0f, 0.9f};
    enum { NS = sizeof edge_s / sizeof edge_s[0], JIT = 2 };
    /* c and points at half the radius around it. */
    static const float offs[][3] = {
        {0, 0, 0}, {0.5f, 0, 0}, {0, -0.5f, 0}, {0, 0, 0.5f}, {-0.3f, 0.3f, -0.3f}};
    enum { NO = sizeof offs / sizeof offs[0] };
    const float *pos = sr_scene_positions(s);
    const uint32_t *ix = sr_scene_indices(s);
    size_t nt = sr_scene_triangle_count(s), nv = sr_scene_vertex_count(s);
    size_t ne;
    uint64_t *edges = unique_edges(s, &ne);
    unsigned char *used = calloc(nv, 1);
    size_t nused = 0;
    for (size_t i = 0; i < 3 * nt; ++i)
        if (!used[ix[i]]) {
            used[ix[i]] = 1;
            ++nused;
        }
    size_t ne_aim = (ne + edge_stride - 1) / edge_stride;
    size_t cap = n_random + NO * (nused * (1 + JIT) + ne_aim * NS * (1 + JIT));
    rt_ray *rays = malloc(cap * sizeof *rays);
    unsigned char *cat = malloc(cap);
    rt_hit *hits = malloc(cap * sizeof *hits);
    uint32_t st = 4242;
    size_t n = 0;
    for (size_t i = 0; i < n_random; ++i) {
        float o[3], d[3];
        random_dir(&st, o);
        for (int k = 0; k < 3; ++k)
            o[k] = c[k] + radius * o[k];
        random_dir(&st, d);
        make_ray(&rays[n], o, d);
        cat[n++] = LK_RANDOM;
    }
    for (int oi = 0; oi < NO; ++oi) {
        float o[3];
        for (int k = 0; k < 3; ++k)
            o[k] = c[k] + radius * offs[oi][k];
        for (size_t v = 0; v < nv; ++v)
            if (used[v])
                aim(rays, cat, &n, &st, o, pos + 3 * v, LK_VERTEX, JIT);
        for (size_t e = 0; e < ne; e += edge_stride) {
            const float *v0 = pos + 3 * (edges[e] >> 32), *v1 = pos + 3 * (edges[e] & 0xffffffffu);
            for (int si = 0; si < NS; ++si) {
                float p[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = v0[k] + edge_s[si] * (v1[k] - v0[k]);
                aim(rays, cat, &n, &st, o, p, LK_EDGE, JIT);
            }
        }
    }
    CHECK(n == cap, "%s: %zu rays built, %zu expected", name, n, cap);
    CHECK(n >= 1000000 || n_random < 1000000, "%s: only %zu rays", name, n);
    size_t per_cat[LK_CATEGORIES] = {0};
    for (size_t i = 0; i < n; ++i)
        ++per_cat[cat[i]];
    printf("%s: %zu rays from inside (%d origins for the aimed rays, %zu vertices, %zu of %zu "
           "edges):",
           name, n, (int)NO, nused, ne_aim, ne);
    for (int k = 0; k < LK_CATEGORIES; ++k)
        printf(" %zu %s%s", per_cat[k], lk_names[k], k + 1 < LK_CATEGORIES ? "," : "\n");
    for (int w = 0; w < 2; ++w) {
        rt_tracer *t = make_tracer(s, RT_EXEC_FUSED, w ? RT_ISECT_WATERTIGHT : RT_ISECT_MT);
        if (!t)
            continue;
        CHECK_OK(ctx, rt_tracer_trace(t, rays, n, hits));
        size_t leaks = 0, leaks_cat[LK_CATEGORIES] = {0};
        for (size_t i = 0; i < n; ++i)
            if (hits[i].tri == RT_NO_HIT) {
                ++leaks;
                ++leaks_cat[cat[i]];
            }
        printf("  %-16s %zu leaks of %zu rays (", w ? "watertight:" : "Moller-Trumbore:", leaks, n);
        for (int k = 0; k < LK_CATEGORIES; ++k)
            printf("%zu %s%s", leaks_cat[k], lk_names[k], k + 1 < LK_CATEGORIES ? ", " : ")\n");
        if (w)
            CHECK(leaks == 0, "%s: watertight intersector leaked %zu of %zu rays", name, leaks, n);
        rt_tracer_destroy(t);
    }
    free(edges);
    free(used);
    free(cat);
    free(rays);
    free(hits);
}

static void test_watertight(void)
{
    sr_scene_builder *b = NULL;
    sr_scene_builder_create("sphere", &b);
    char err[256];
    sr_material m = sr_material_make(SR_MATERIAL_DIFFUSE, "d");
    uint32_t mi;
    sr_scene_builder_add_material(b, &m, &mi, err, sizeof err);
    float c[3] = {0.3f, -0.2f, 0.1f};
    CHECK(sr_scene_builder_add_sphere(b, c, 1.0f, 24, mi, NULL, err, sizeof err) == SLUICE_OK, "%s",
          err);
    sr_scene *s = NULL;
    sr_scene_builder_finish(b, SR_SCENE_DEFAULT_LIGHT, &s, err, sizeof err);
    sr_scene_builder_destroy(b);
    if (s) {
        CHECK(is_closed(s), "the tessellated sphere is not closed");
        leak_test("sphere (11520 triangles)", s, c, 0.8f, 1000000, 1);
        sr_scene_destroy(s);
    }
    s = load("bunny");
    if (s) {
        if (is_closed(s))
            leak_test("bunny", s, (float[3]){0, 0, 0}, 0.05f, 200000, 16);
        else
            printf("bunny: not a closed mesh (edges with other than two triangles): no leak "
                   "test\n");
        sr_scene_destroy(s);
    }
}

/* ------------------------------------------------------------------ */
/* Images                                                              */
/* ------------------------------------------------------------------ */

static const char *const mode_names[] = {"cast", "shadow", "whitted", "path"};

/* Renders `spp` samples; returns the image (NULL on failure) and the
 * non-finite counts. */
static sr_image *render_samples(const sr_scene *s, rt_exec exec, unsigned mode, unsigned w,
                                unsigned h, unsigned spp, uint32_t seed, unsigned light_samples)
{
    rt_tracer *t = make_tracer(s, exec, RT_ISECT_MT);
    if (!t)
        return NULL;
    const sr_render_settings *rs = sr_scene_render_settings(s);
    rt_render_options o = {0};
    o.mode = mode;
    o.width = w;
    o.height = h;
    o.max_depth = rs->max_depth;
    o.light_samples = light_samples;
    o.seed = seed;
    rt_renderer *r = NULL;
    char err[512];
    sr_image *img = NULL;
    CHECK(rt_renderer_create(t, &o, &r, err, sizeof err) == SLUICE_OK, "%s", err);
    sr_image_create(w, h, 3, &img, err, sizeof err);
    for (unsigned i = 0; r && i < spp; ++i)
        CHECK_OK(ctx, rt_renderer_sample(r));
    size_t bad = 1;
    if (r)
        CHECK_OK(ctx, rt_renderer_image(r, img, &bad));
    CHECK(bad == 0, "%zu non-finite pixels", bad);
    CHECK(r && rt_renderer_stats(r)->nonfinite == 0, "non-finite contributions");
    rt_renderer_destroy(r);
    rt_tracer_destroy(t);
    return img;
}

/* render_samples with the scene's light samples, at most 4. */
static sr_image *render(const sr_scene *s, rt_exec exec, unsigned mode, unsigned w, unsigned h,
                        unsigned spp, uint32_t seed)
{
    unsigned ls = sr_scene_render_settings(s)->light_samples;
    return render_samples(s, exec, mode, w, h, spp, seed, ls > 4 ? 4 : ls);
}

/* Stored references: cornell 64x64, 1 spp (4 for path), fused and stream
 * compared against the same file. Thresholds: the tracer is deterministic, so
 * a correct build reproduces the reference up to float rounding across
 * compilers: rmse <= 1e-3 for cast, shadow and whitted; path tracing,
 * noisier where a few paths change, rmse <= 1e-2. */
static void test_reference_images(const char *write_dir)
{
    sr_scene *s = load("cornell");
    if (!s)
        return;
    for (unsigned mode = 0; mode < 4; ++mode) {
        unsigned spp = mode == RT_MODE_PATH ? 4 : 1;
        char path[512];
        snprintf(path, sizeof path, "%s/cornell_%s_64.exr", write_dir ? write_dir : RT_TEST_DATA,
                 mode_names[mode]);
        if (write_dir) {
            sr_image *img = render(s, RT_EXEC_FUSED, mode, 64, 64, spp, 1);
            char err[512];
            CHECK(img && sr_image_write(img, path, err, sizeof err) == SLUICE_OK, "%s", err);
            printf("wrote %s\n", path);
            sr_image_destroy(img);
            continue;
        }
        sr_image *ref = NULL;
        char err[512];
        if (sr_image_read(path, &ref, err, sizeof err) != SLUICE_OK) {
            CHECK(0, "reference %s: %s", path, err);
            continue;
        }
        for (int e = 0; e < 2; ++e) {
            sr_image *img = render(s, e ? RT_EXEC_FUSED : RT_EXEC_STREAM, mode, 64, 64, spp, 1);
            if (!img)
                continue;
            sr_image_metrics m;
            CHECK(sr_image_compare(img, ref, &m, err, sizeof err) == SLUICE_OK, "%s", err);
            double limit = mode == RT_MODE_PATH ? 1e-2 : 1e-3;
            printf("cornell %-8s %-6s vs reference: rmse %.3g, max %.3g\n", mode_names[mode],
                   e ? "fused" : "stream", m.rmse, m.max_error);
            CHECK(m.rmse <= limit && m.nan_count == 0 && m.inf_count == 0, "%s %s: rmse %g > %g",
                  mode_names[mode], e ? "fused" : "stream", m.rmse, limit);
            sr_image_destroy(img);
        }
        sr_image_destroy(ref);
    }
    sr_scene_destroy(s);
}

/* test_reference_images against the stored references. */
static void test_reference_images_stored(void)
{
    test_reference_images(NULL);
}

static int images_identical(const sr_image *a, const sr_image *b)
{
    size_t n = (size_t)sr_image_width(a) * sr_image_height(a) * 3;
    return memcmp(sr_image_pixels_const(a), sr_image_pixels_const(b), n * sizeof(float)) == 0;
}

/* The automatic grid: the sparse density for a large mesh whose voxels stay
 * mostly empty (teapotahedron), the dense one for small scenes (ring,
 * glassball; cornell, where the edge floor decides either way). */
static void test_auto_grid(void)
{
    static const struct {
        const char *scene;
        int sparse; /* expects the sparse density's grid */
    } cases[] = {{"teapotahedron", 1}, {"ring", 0}, {"glassball", 0}, {"cornell", 0}};
    for (size_t c = 0; c < sizeof cases / sizeof *cases; ++c) {
        sr_scene *s = load(cases[c].scene);
        CHECK(s != NULL, "load %s", cases[c].scene);
        if (!s)
            continue;
        rt_tracer *t = make_tracer(s, RT_EXEC_FUSED, RT_ISECT_MT);
        if (t) {
            const sr_scene_stats *ss = sr_scene_statistics(s);
            size_t nt = sr_scene_triangle_count(s);
            double edge = rt_grid_edge_quartile(sr_scene_positions(s), sr_scene_indices(s), nt);
            unsigned want =
                cases[c].sparse
                    ? rt_grid_auto_min_dim_density(ss->bounds_min, ss->bounds_max, nt, edge,
                                                   RT_GRID_AUTO_DENSITY_SPARSE)
                    : rt_grid_auto_min_dim_edge(ss->bounds_min, ss->bounds_max, nt, edge);
            unsigned got = rt_tracer_grid_min_dim(t);
            CHECK(got == want, "%s: grid min dim %u, expected %u", cases[c].scene, got, want);
            const rt_grid_desc *d = &rt_tracer_grid(t)->desc;
            unsigned mn = d->dims[0] < d->dims[1] ? d->dims[0] : d->dims[1];
            mn = mn < d->dims[2] ? mn : d->dims[2];
            CHECK(mn <= got, "%s: grid %ux%ux%u for min dim %u", cases[c].scene, d->dims[0],
                  d->dims[1], d->dims[2], got);
            rt_tracer_destroy(t);
        }
        sr_scene_destroy(s);
    }
}

static void test_determinism(void)
{
    sr_scene *s = load("cornell");
    if (!s)
        return;
    sr_image *a = render(s, RT_EXEC_FUSED, RT_MODE_PATH, 48, 48, 3, 77);
    sr_image *b = render(s, RT_EXEC_FUSED, RT_MODE_PATH, 48, 48, 3, 77);
    sr_image *c = render(s, RT_EXEC_STREAM, RT_MODE_PATH, 48, 48, 3, 77);
    sr_image *d = render(s, RT_EXEC_FUSED, RT_MODE_PATH, 48, 48, 3, 78);
    if (a && b && c && d) {
        CHECK(images_identical(a, b), "same seed, different images");
        CHECK(images_identical(a, c), "stream and fused path images differ");
        CHECK(!images_identical(a, d), "different seeds, same image");
    }
    sr_image_destroy(a);
    sr_image_destroy(b);
    sr_image_destroy(c);
    sr_image_destroy(d);
    sr_scene_destroy(s);

    /* the fused mode traces shadow rays where it makes them (rt_direct.cl),
     * the stream mode as a stream: the same rays and hits, summed in fixed
     * point, so the same image bit for bit (area lights; ring's point
     * light) */
    const char *lit[] = {"cornell", "glassball", "ring"};
    for (size_t i = 0; i < 3; ++i) {
        s = load(lit[i]);
        if (!s)
            continue;
        /* whitted on each; shadow mode, which lights mirrors and glass too,
         * on glassball */
        for (unsigned mode = i == 1 ? RT_MODE_SHADOW : RT_MODE_WHITTED; mode <= RT_MODE_WHITTED;
             ++mode) {
            /* 12 samples: a block of 8 side by side and 4 one at a time */
            sr_image *st = render_samples(s, RT_EXEC_STREAM, mode, 32, 24, 1, 5, 12);
            sr_image *fu = render_samples(s, RT_EXEC_FUSED, mode, 32, 24, 1, 5, 12);
            CHECK(st && fu && images_identical(st, fu), "%s %s: stream and fused images differ",
                  lit[i], mode_names[mode]);
            sr_image_destroy(st);
            sr_image_destroy(fu);
        }
        sr_scene_destroy(s);
    }

    /* whitted and path on scenes with mirrors and glass: no NaN/Inf */
    const char *scenes[] = {"glassball", "teapotahedron", "ring"};
    for (size_t i = 0; i < 3; ++i) {
        s = load(scenes[i]);
        if (!s)
            continue;
        sr_image_destroy(render(s, RT_EXEC_FUSED, RT_MODE_WHITTED, 40, 40, 1, 1));
        sr_image_destroy(render(s, RT_EXEC_STREAM, RT_MODE_PATH, 32, 32, 2, 1));
        sr_scene_destroy(s);
    }
}

/* A camera inside the grid (in the middle of the cornell box). */
static void test_camera_inside(void)
{
    sr_scene *s = load("cornell");
    if (!s)
        return;
    sr_camera cam = *sr_scene_camera(s);
    float eye[3] = {278, 400, 300}, at[3] = {100, 0, 500};
    memcpy(cam.eye, eye, sizeof eye);
    memcpy(cam.look_at, at, sizeof at);
    char err[256] = "";
    sr_scene *in = scene_copy(s, 1.0f, 0.0f, &cam, err, sizeof err);
    CHECK(in != NULL, "cornell with the camera inside: %s", err);
    if (in) {
        sr_image *img = render(in, RT_EXEC_STREAM, RT_MODE_CAST, 32, 32, 1, 1);
        size_t lit = 0;
        if (img)
            for (size_t i = 0; i < 32 * 32 * 3; ++i)
                lit += sr_image_pixels(img)[i] > 0;
        CHECK(lit == 32 * 32 * 3, "camera inside the box: %zu of %d values lit", lit, 32 * 32 * 3);
        sr_image_destroy(img);
        sr_scene_destroy(in);
    }
    sr_scene_destroy(s);
}

/* ------------------------------------------------------------------ */
/* Command line                                                        */
/* ------------------------------------------------------------------ */

/* Runs `cmd` through the shell; returns the exit status (128 + signal for a
 * signal) and the first part of its stderr in `out`. */
static void test_cli(const char *exe)
{
    char out[8192], cmd[2048];
    struct {
        const char *args, *expect;
    } bad[] = {
        {"--mode bogus", "--mode"},
        {"--exec warp", "--exec"},
        {"--size 0x10", "--size"},
        {"--size 100000x100000", "--size"},
        {"--size abc", "--size"},
        {"--spp 0", "--spp"},
        {"--spp -3", "--spp"},
        {"--intersector foo", "--intersector"},
        {"--grid-min-dim 0", "--grid-min-dim"},
        {"--intersect-threshold 2", "--intersect-threshold"},
        {"--out image.bmp", "--out"},
        {"--frobnicate 1", "--frobnicate"},
        {"--out x.png --scene", "--scene"},
        {"--scene no-such-scene-file.obj", "no-such-scene-file.obj"},
        {"--min-spp 3", "--min-spp"},
        {"--min-spp 0", "--min-spp"},
        {"--target-error -1", "--target-error"},
        {"--sample-map map.bmp", "--sample-map"},
        /* where results go is checked before rendering */
        {"--out no-such-folder/x.png", "the folder no-such-folder does not exist"},
        {"--stats no-such-folder/s.json --out x.png", "--stats no-such-folder/s.json"},
        {"--sample-map no-such-folder/m.png --target-error 0.1", "--sample-map"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; ++i) {
        snprintf(cmd, sizeof cmd, "%s %s --out cli_bad.png", exe, bad[i].args);
        if (strstr(bad[i].args, "--out"))
            snprintf(cmd, sizeof cmd, "%s %s", exe, bad[i].args);
        int rc = check_run(cmd, out, sizeof out);
        CHECK(rc != 0 && rc < 128, "%s: exit %d", bad[i].args, rc);
        CHECK(strstr(out, bad[i].expect) != NULL, "%s: message does not name %s: %s", bad[i].args,
              bad[i].expect, out);
        CHECK(!strstr(out, "rays:"), "%s: rendered before refusing: %s", bad[i].args, out);
    }
    snprintf(cmd, sizeof cmd, "%s --help", exe);
    CHECK(check_run(cmd, out, sizeof out) == 0 && strstr(out, "examples"), "--help");
    /* Without its image module (OpenImageIO) the renderer stops before
     * rendering, naming where it looked, and writes nothing. */
    remove("cli_nomod.png");
    snprintf(cmd, sizeof cmd,
             "SLUICE_IMAGE_MODULE=no-such-dir/m.so %s --scene cornell --size 32x24 "
             "--out cli_nomod.png",
             exe);
    int nomod = check_run(cmd, out, sizeof out);
    CHECK(nomod == 1 && strstr(out, "no-such-dir/m.so") && strstr(out, "--out cli_nomod.png") &&
              !strstr(out, "rays:"),
          "no image module: exit %d: %s", nomod, out);
    CHECK(access("cli_nomod.png", F_OK) != 0, "no image module: an image was written");
    /* --no-image renders and reports without it, and writes no image */
    remove("out.png");
    snprintf(cmd, sizeof cmd,
             "SLUICE_IMAGE_MODULE=no-such-dir/m.so %s --scene cornell --size 32x24 --no-image "
             "--exec fused --mode shadow",
             exe);
    nomod = check_run(cmd, out, sizeof out);
    CHECK(nomod == 0 && strstr(out, "rays:") && access("out.png", F_OK) != 0,
          "--no-image: exit %d: %s", nomod, out);
    const char *writers[] = {"--out cli_x.png", "--checkpoint 1", "--sample-map cli_m.png"};
    for (size_t i = 0; i < 3; ++i) {
        snprintf(cmd, sizeof cmd, "%s --no-image %s", exe, writers[i]);
        nomod = check_run(cmd, out, sizeof out);
        char opt[32];
        snprintf(opt, sizeof opt, "%.*s", (int)strcspn(writers[i], " "), writers[i]);
        CHECK(nomod == 2 && strstr(out, "--no-image") && strstr(out, opt),
              "--no-image %s: exit %d: %s", writers[i], nomod, out);
    }

    snprintf(cmd, sizeof cmd,
             "%s --scene cornell --mode shadow --size 32x24 --exec fused --out cli_ok.exr "
             "--stats cli_ok.json --quiet",
             exe);
    CHECK(check_run(cmd, out, sizeof out) == 0, "render: %s", out);
    FILE *f = fopen("cli_ok.json", "r");
    CHECK(f != NULL, "no stats file");
    if (f) {
        size_t n = fread(out, 1, sizeof out - 1, f);
        out[n] = '\0';
        fclose(f);
        CHECK(strstr(out, "\"v\"") && strstr(out, "\"kernels\""), "stats JSON: %s", out);
    }
    sr_image *img = NULL;
    char err[256];
    CHECK(sr_image_read("cli_ok.exr", &img, err, sizeof err) == SLUICE_OK, "%s", err);
    CHECK(img && sr_image_width(img) == 32 && sr_image_height(img) == 24, "image size");
    sr_image_destroy(img);

    /* a target error: the statistics say what adaptive sampling skipped */
    snprintf(cmd, sizeof cmd,
             "%s --scene cornell --mode path --size 32x32 --light-samples 1 --target-error 0.02 "
             "--exec fused --out cli_ok.exr --stats cli_ok.json --no-profile --sample-map "
             "cli_map.exr",
             exe);
    CHECK(check_run(cmd, out, sizeof out) == 0 && strstr(out, "sampling: target relMSE 0.02") &&
              strstr(out, "target 0.02 reached"),
          "--target-error: %s", out);
    f = fopen("cli_ok.json", "r");
    if (f) {
        size_t n = fread(out, 1, sizeof out - 1, f);
        out[n] = '\0';
        fclose(f);
    }
    CHECK(f && strstr(out, "\"sampling\": {\"target\": 0.02, \"adaptive\": true"),
          "--target-error stats JSON: %s", out);
    /* the sample map: samples over the most any tile took, 1 somewhere */
    CHECK(sr_image_read("cli_map.exr", &img, err, sizeof err) == SLUICE_OK, "%s", err);
    if (img) {
        const float *px = sr_image_pixels_const(img);
        float most = 0, least = 1;
        for (size_t i = 0; i < 32 * 32 * 3; ++i) {
            most = px[i] > most ? px[i] : most;
            least = px[i] < least ? px[i] : least;
        }
        CHECK(sr_image_width(img) == 32 && most == 1.0f && least > 0.0f,
              "sample map: %ux%u, from %g to %g", sr_image_width(img), sr_image_height(img),
              (double)least, (double)most);
        sr_image_destroy(img);
        img = NULL;
    }

    /* Ctrl-C: finish the sample, write the image, exit 130 */
    remove("cli_int.exr");
    snprintf(cmd, sizeof cmd,
             "%s --scene cornell --mode path --size 64x64 --spp 100000 --out cli_int.exr --quiet "
             "--progress & pid=$!; sleep 4; kill -INT $pid; wait $pid",
             exe);
    int rc = check_run(cmd, out, sizeof out);
    CHECK(rc == 130, "SIGINT: exit %d: %s", rc, out);
    CHECK(sr_image_read("cli_int.exr", &img, err, sizeof err) == SLUICE_OK,
          "no image after SIGINT: %s", err);
    sr_image_destroy(img);
}

/* A 1 x 1 one-sided area light (radiance 10) at height 1 over a 20 x 20
 * diffuse floor (albedo 0.5): under the light's centre the floor's radiance
 * is 0.5 / pi * E with E = 10 * 4 pi F, F = 0.0598641 the form factor to a
 * 0.5 x 0.5 rectangle with a corner overhead (bench/scenes/quadlight.json).
 * Shadow rays start offset from the surface (scene_eps, 1e-4 of the
 * diagonal); aimed from the unshifted point with its distance, they reached
 * the light's own surface and every pixel was black (issue 13, item 1). */
static void test_near_area_light(void)
{
    FILE *f = fopen("rt_near_light.json", "w");
    if (!f) {
        CHECK(0, "cannot write rt_near_light.json");
        return;
    }
    fputs("{\"materials\": {\"floor\": {\"kind\": \"diffuse\", \"albedo\": 0.5},"
          " \"lamp\": {\"kind\": \"emissive\", \"emission\": 10}},"
          " \"meshes\": [{\"shape\": \"quad\", \"corner\": [-10, 0, -10], \"u\": [0, 0, 20],"
          " \"v\": [20, 0, 0], \"material\": \"floor\"}, {\"shape\": \"quad\","
          " \"corner\": [-0.5, 1, -0.5], \"u\": [1, 0, 0], \"v\": [0, 0, 1],"
          " \"material\": \"lamp\"}],"
          " \"camera\": {\"eye\": [0, 0.5, 0], \"look_at\": [0, 0, 0], \"up\": [0, 0, 1],"
          " \"vfov\": 20, \"width\": 32, \"height\": 32}}",
          f);
    fclose(f);
    sr_scene *s = load("rt_near_light.json");
    if (!s)
        return;
    const double expect = 0.5 * 10.0 * 4.0 * 0.0598641; /* pi cancels */
    const unsigned modes[2] = {RT_MODE_SHADOW, RT_MODE_PATH};
    for (int k = 0; k < 2; ++k) {
        unsigned mode = modes[k];
        sr_image *img = render(s, RT_EXEC_STREAM, mode, 32, 32, 16, 1);
        if (!img)
            continue;
        const float *px = sr_image_pixels_const(img);
        double sum = 0;
        for (unsigned y = 12; y < 20; ++y)
            for (unsigned x = 12; x < 20; ++x)
                sum += px[(y * 32 + x) * 3];
        double mean = sum / 64;
        printf("area light near a large floor, %s: centre %.4f, analytic %.4f\n", mode_names[mode],
               mean, expect);
        CHECK(fabs(mean / expect - 1.0) < 0.05, "%s: centre %g, analytic %g", mode_names[mode],
              mean, expect);
        sr_image_destroy(img);
    }
    sr_scene_destroy(s);
}

/* The test groups, in the order they run; `--only NAME[,NAME...]` runs just
 * those (e.g. on a GPU, where NVIDIA compiles every program afresh and the
 * reference images cannot always be read). */
static const struct {
    const char *name;
    void (*run)(void);
} groups[] = {
    {"random_rays", test_random_rays},     {"one_triangle", test_one_triangle_and_edges},
    {"watertight", test_watertight},       {"reference_images", test_reference_images_stored},
    {"determinism", test_determinism},     {"auto_grid", test_auto_grid},
    {"camera_inside", test_camera_inside}, {"near_area_light", test_near_area_light},
};

/* Whether the comma-separated list `only` (NULL: every group) names `name`. */
static int group_selected(const char *only, const char *name)
{
    if (!only)
        return 1;
    size_t n = strlen(name);
    for (const char *p = only; *p;) {
        const char *e = strchr(p, ',');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        if (len == n && !strncmp(p, name, n))
            return 1;
        p += len + (e != NULL);
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *write_dir = NULL, *cli = NULL, *only = NULL;
    for (int i = 1; i + 1 < argc; ++i) {
        if (!strcmp(argv[i], "--write-refs"))
            write_dir = argv[++i];
        else if (!strcmp(argv[i], "--cli"))
            cli = argv[++i];
        else if (!strcmp(argv[i], "--only"))
            only = argv[++i];
    }
    if (cli) {
        test_cli(cli);
        return check_summary();
    }
    ctx = check_context(0);
    if (write_dir) {
        test_reference_images(write_dir);
        sluice_context_destroy(ctx);
        return check_summary();
    }
    int ran = 0;
    for (size_t i = 0; i < sizeof groups / sizeof groups[0]; ++i)
        if (group_selected(only, groups[i].name)) {
            groups[i].run();
            ++ran;
        }
    if (total_rays_checked || !only) {
        printf("rays checked against the brute force: %zu\n", total_rays_checked);
        if (group_selected(only, "random_rays") && group_selected(only, "one_triangle"))
            CHECK(total_rays_checked >= 1000000, "only %zu rays checked", total_rays_checked);
    }
    CHECK(ran > 0, "--only %s names no test group", only ? only : "");
    sluice_context_destroy(ctx);
    return check_summary();
}
