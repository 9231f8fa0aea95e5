/* See photons.h. */
#include "photons.h"
#include "app_error.h"
#include "clock.h"
#include "kernels.h"
#include "skipped.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PM_PI 3.14159265358979323846

/* Bounce counters (pm_photon.cl). */
enum {
    PC_STORED = 0,
    PC_BOUNCED,
    PC_LEFT,
    PC_ABSORBED,
    PC_DEPTH,
    PC_NONFINITE,
    PC_CAUSTIC,
    PC_COUNT
};

/* Photons per emission batch at most (the ray, hit and bounce streams hold
 * this many records: 64 + 24 + 64 bytes each). */
#define PM_BATCH_MAX ((size_t)1 << 20)

struct pm_photons {
    rt_tracer *tracer;
    const sr_device_scene *ds;
    sluice_program *program;
    sluice_kernel *k_emit, *k_bounce, *k_route, *k_scale;
    sluice_counters *counters;
    sluice_stream *rays, *next, *hits, *stored;
    sluice_stream *photon_at, *ray_at, *route; /* pm_bounce's results, by photon */
    float area_prob;                           /* share of the photons that leave area lights */
    int specular;                              /* the scene has mirrors or glass */
    float spec[4];                             /* their bounding sphere: centre, radius */
    double yield; /* stored per emitted in the last trace (0: none yet) */
};

/* Share of each batch's photons sent toward the mirrors and glass when the
 * scene has any (Jensen's projection map, kept unbiased as a fixed-share
 * mixture with the lights' own emission: see pm_emit). Half keeps the uniform part's
 * indirect light well sampled while caustic photons, which a point light
 * far from a small mirror rarely sends, cost a few emissions each. */
#define PM_SPECULAR_SHARE 0.5f

void pm_photons_destroy(pm_photons *p)
{
    if (!p)
        return;
    sluice_kernel_destroy(p->k_emit);
    sluice_kernel_destroy(p->k_bounce);
    sluice_kernel_destroy(p->k_route);
    sluice_kernel_destroy(p->k_scale);
    sluice_program_destroy(p->program);
    sluice_counters_destroy(p->counters);
    sluice_stream *s[] = {p->rays, p->next, p->hits, p->stored, p->photon_at, p->ray_at, p->route};
    for (size_t i = 0; i < sizeof s / sizeof *s; ++i)
        sluice_stream_destroy(s[i]);
    free(p);
}

/* The bounding sphere of the mirror and glass triangles (centre of their
 * box, the farthest vertex from it, padded); radius 0 when there are none. */
static void specular_sphere(const sr_scene *sc, float out[4])
{
    const sr_material *mats = sr_scene_materials(sc);
    const uint32_t *tm = sr_scene_triangle_materials(sc);
    const uint32_t *idx = sr_scene_indices(sc);
    const float *pos = sr_scene_positions(sc);
    size_t nt = sr_scene_triangle_count(sc);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t found = 0;
    for (int pass = 0; pass < 2; ++pass) {
        /* pass 0: the box's centre; pass 1: the farthest vertex from it
         * (tight for a sphere, where the box's half-diagonal is sqrt 3
         * times too large and the cone three times too wide) */
        double c[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
        double r2 = 0.0, mag2 = 0.0;
        for (size_t t = 0; t < nt; ++t) {
            sr_material_kind k = mats[tm[t]].kind;
            if (k != SR_MATERIAL_MIRROR && k != SR_MATERIAL_GLASS)
                continue;
            found += pass == 0;
            for (int v = 0; v < 3; ++v) {
                const float *p = pos + 3 * (size_t)idx[3 * t + (size_t)v];
                double d2 = 0.0;
                for (int a = 0; a < 3; ++a) {
                    lo[a] = fmin(lo[a], p[a]);
                    hi[a] = fmax(hi[a], p[a]);
                    d2 += (p[a] - c[a]) * (p[a] - c[a]);
                    mag2 = fmax(mag2, (double)p[a] * p[a]);
                }
                r2 = fmax(r2, d2);
            }
        }
        memset(out, 0, 4 * sizeof *out);
        if (!found)
            return;
        if (pass == 1) {
            for (int a = 0; a < 3; ++a)
                out[a] = (float)c[a];
            /* float rounding of the centre must not leave a vertex outside */
            out[3] = (float)(sqrt(r2) * (1.0 + 1e-5) + 1e-6 * sqrt(3.0 * mag2));
        }
    }
}

static double luminance(const float c[3])
{
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
}

/* Photons leave each kind of light in proportion to its power: area lights
 * pi Le A (a Lambertian emitter), point lights 4 pi I. */
static float area_share(const sr_scene *sc)
{
    sr_area_lights al;
    sr_scene_area_lights(sc, &al);
    const sr_material *mats = sr_scene_materials(sc);
    const uint32_t *tm = sr_scene_triangle_materials(sc);
    double pa = 0, pp = 0;
    for (size_t i = 0; i < al.count; ++i)
        pa += PM_PI * al.area[i] * luminance(mats[tm[al.triangles[i]]].emission);
    const sr_point_light *pl = sr_scene_point_lights(sc);
    for (size_t i = 0; i < sr_scene_point_light_count(sc); ++i)
        pp += 4.0 * PM_PI * luminance(pl[i].intensity);
    if (al.count == 0)
        return 0.0f;
    if (sr_scene_point_light_count(sc) == 0 || !(pa + pp > 0))
        return 1.0f;
    return (float)(pa / (pa + pp));
}

sluice_status pm_photons_create(rt_tracer *tracer, pm_photons **out, char *err, size_t err_size)
{
    if (out)
        *out = NULL;
    if (!tracer || !out) {
        sr_set_error(err, err_size, "pm_photons_create: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    pm_photons *p = calloc(1, sizeof *p);
    if (!p) {
        sr_set_error(err, err_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    p->tracer = tracer;
    p->ds = rt_tracer_scene(tracer);
    const sr_scene_stats *ss = sr_scene_statistics(p->ds->scene);
    int mirror = (ss->kinds_present & SR_KIND_BIT(SR_MATERIAL_MIRROR)) != 0;
    int glass = (ss->kinds_present & SR_KIND_BIT(SR_MATERIAL_GLASS)) != 0;
    p->specular = mirror || glass;
    p->area_prob = area_share(p->ds->scene);
    specular_sphere(p->ds->scene, p->spec);
    char opts[160];
    snprintf(opts, sizeof opts, "-DRT_SURFACE_INLINE%s%s%s%s",
             p->ds->layout == SR_TRI_VERTICES ? " -DRT_WATERTIGHT" : "",
             mirror ? " -DRT_HAS_MIRROR" : "", glass ? " -DRT_HAS_GLASS" : "",
             ss->has_normals ? " -DRT_HAS_NORMALS" : "");
    static const char *const names[] = {"rt_types.h", "pm_types.h", "triangle.cl", "rng.cl",
                                        "surface.cl", "lights.cl",  "pm_photon.cl"};
    sluice_context *ctx = p->ds->ctx;
    sluice_status st =
        sr_program_create(ctx, names, sizeof names / sizeof *names, opts, &p->program);
    if (st == SLUICE_OK)
        st = sluice_program_build(p->program);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(p->program, "pm_emit", &p->k_emit);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(p->program, "pm_bounce", &p->k_bounce);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(p->program, "pm_route", &p->k_route);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(p->program, "pm_scale_power", &p->k_scale);
    static const char *const ctr[] = {"stored",      "bounced",   "left scene", "absorbed",
                                      "depth limit", "nonfinite", "caustic"};
    if (st == SLUICE_OK)
        st = sluice_counters_create(ctx, PC_COUNT, ctr, &p->counters);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_counters(p->k_bounce, p->counters);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(pm_photon), 1, &p->stored);
    /* bound now (and again every pass), so that the runtime's kernel for
     * ordered outputs is built here and not in the first pass */
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(p->k_route, 3, 0, p->stored, SLUICE_ORDERED);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "photon tracing: %s", sluice_context_error(ctx));
        pm_photons_destroy(p);
        return st;
    }
    *out = p;
    return SLUICE_OK;
}

/* Grows `*s` (or creates it) to hold at least `n` records of `size` bytes. */
static sluice_status ensure(sluice_context *ctx, sluice_stream **s, size_t size, size_t n)
{
    if (!*s)
        return sluice_stream_create(ctx, size, n, s);
    return sluice_stream_capacity(*s) >= n ? SLUICE_OK : sluice_stream_grow(*s, n);
}

/* Emits `n` photons (batch starting at photon `base`) into p->rays. */
static sluice_status emit(pm_photons *p, const pm_photon_options *opt, uint32_t base, size_t n)
{
    const sr_device_scene *ds = p->ds;
    pm_emit_args a;
    memset(&a, 0, sizeof a);
    a.seed = opt->seed;
    a.base = base;
    a.area_lights = (rt_u32)ds->area_light_count;
    a.point_lights = (rt_u32)ds->point_light_count;
    a.area_prob = p->area_prob;
    a.area_total = (float)ds->area_total;
    a.scene_eps = ds->scene_eps;
    /* the batch's first photons go toward the mirrors and glass (pm_emit) */
    a.cone_count =
        p->specular && !opt->no_projection ? (rt_u32)((double)n * PM_SPECULAR_SHARE + 0.5) : 0u;
    a.spec_prob = (float)((double)a.cone_count / (double)n);
    a.spec_x = p->spec[0];
    a.spec_y = p->spec[1];
    a.spec_z = p->spec[2];
    a.spec_r = p->spec[3];
    sluice_kernel *k = p->k_emit;
    sluice_status st = sluice_kernel_set_stream(k, 0, p->rays, 0);
    sluice_stream *bufs[] = {ds->tri_records,  ds->tri_mat,   ds->materials,
                             ds->point_lights, ds->area_tris, ds->area_cdf};
    for (unsigned i = 0; i < 6 && st == SLUICE_OK; ++i)
        st = sluice_kernel_set_stream(k, 1 + i, bufs[i], 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 7, sizeof a, &a);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, n);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(p->rays, n);
    return st;
}

/* One bounce pass over the n photons in p->rays: pm_bounce works out each
 * photon's bounce at its own index, pm_route appends the stored ones to
 * p->stored and puts the bounced ones in p->next. */
static sluice_status bounce(pm_photons *p, const pm_photon_options *opt, size_t n,
                            pm_photon_stats *stats)
{
    const sr_device_scene *ds = p->ds;
    sluice_context *ctx = ds->ctx;
    size_t have = 0;
    sluice_status st = sluice_stream_length(p->stored, &have);
    if (st == SLUICE_OK)
        st = ensure(ctx, &p->stored, sizeof(pm_photon), have + n);
    if (st == SLUICE_OK)
        st = ensure(ctx, &p->photon_at, sizeof(pm_photon), n);
    if (st == SLUICE_OK)
        st = ensure(ctx, &p->ray_at, sizeof(rt_ray), n);
    if (st == SLUICE_OK)
        st = ensure(ctx, &p->route, sizeof(uint32_t), n);
    if (st == SLUICE_OK)
        st = rt_tracer_trace_stream(p->tracer, p->rays, n, p->hits);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(p->next);
    sluice_kernel *k = p->k_bounce;
    uint32_t depth = opt->max_depth;
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(k, 0, p->rays);
    sluice_stream *per_photon[] = {p->hits,     p->photon_at,    p->ray_at,
                                   p->route,    ds->tri_records, ds->indices,
                                   ds->normals, ds->tri_mat,     ds->materials};
    for (unsigned i = 0; i < 9 && st == SLUICE_OK; ++i)
        st = sluice_kernel_set_stream(k, 1 + i, per_photon[i], 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 10, sizeof depth, &depth);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 11, sizeof ds->scene_eps, &ds->scene_eps);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(k);
    /* the route, one per photon of the pass, drives the routing launch */
    k = p->k_route;
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(p->route, n);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(k, 0, p->route);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, p->photon_at, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 2, p->ray_at, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 3, 0, p->stored, SLUICE_ORDERED);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 4, 1, p->next, SLUICE_ORDERED);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(k);
    /* read and restarted, not reset each pass: only pm_bounce counts */
    uint32_t c[PC_COUNT];
    if (st == SLUICE_OK)
        st = sluice_counters_read_restart(p->counters, c);
    if (st != SLUICE_OK)
        return st;
    stats->bounced += c[PC_BOUNCED];
    stats->left_scene += c[PC_LEFT];
    stats->absorbed += c[PC_ABSORBED];
    stats->depth_limit += c[PC_DEPTH];
    stats->nonfinite += c[PC_NONFINITE];
    stats->caustic += c[PC_CAUSTIC];
    stats->passes++;
    return SLUICE_OK;
}

sluice_status pm_photons_trace(pm_photons *p, const pm_photon_options *opt, sluice_stream **photons,
                               size_t *count, pm_photon_stats *stats)
{
    if (!p || !opt || !photons || !count || !stats)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    memset(stats, 0, sizeof *stats);
    *photons = p->stored;
    *count = 0;
    double t0 = sr_clock_seconds();
    const sr_device_scene *ds = p->ds;
    sluice_context *ctx = ds->ctx;
    sluice_status st = sluice_stream_clear(p->stored);
    int lights = ds->area_light_count + ds->point_light_count > 0;
    sr_skipped_add(stats->skipped, sizeof stats->skipped, !lights, "photon tracing (no lights)");
    sr_skipped_add(stats->skipped, sizeof stats->skipped, lights && opt->target == 0,
                   "photon tracing (no photons asked for)");
    sr_skipped_add(stats->skipped, sizeof stats->skipped, lights && !p->specular,
                   "caustic paths (no mirror or glass)");
    if (st != SLUICE_OK || !lights || opt->target == 0) {
        stats->seconds = sr_clock_seconds() - t0;
        return st;
    }
    /* Emit in batches until enough are stored, each sized by the share
     * stored so far; the first by the last trace's share (progressive
     * passes trace the same scene again and again: one batch each, not a
     * guess and a top-up), or the target itself on the first trace. */
    uint64_t limit = 256ull * opt->target + (1u << 20);
    size_t stored = 0;
    while (st == SLUICE_OK && stored < opt->target && stats->emitted < limit) {
        double share = stats->emitted   ? (double)stored / (double)stats->emitted
                       : p->yield > 0.0 ? p->yield
                                        : 1.0;
        double want = (double)(opt->target - stored) / (share > 0.01 ? share : 0.01) * 1.05;
        size_t n = want > (double)PM_BATCH_MAX ? PM_BATCH_MAX : (size_t)want + 1;
        if (n < 1024)
            n = 1024;
        if (stats->emitted + n > limit)
            n = (size_t)(limit - stats->emitted);
        st = ensure(ctx, &p->rays, sizeof(rt_ray), n);
        if (st == SLUICE_OK)
            st = ensure(ctx, &p->next, sizeof(rt_ray), n);
        if (st == SLUICE_OK)
            st = ensure(ctx, &p->hits, sizeof(rt_hit), sluice_stream_capacity(p->rays));
        if (st == SLUICE_OK)
            st = emit(p, opt, (uint32_t)stats->emitted, n);
        stats->emitted += n;
        stats->batches++;
        size_t live = n;
        while (st == SLUICE_OK && live) {
            st = bounce(p, opt, live, stats);
            if (st == SLUICE_OK)
                st = sluice_stream_length(p->next, &live);
            if (st == SLUICE_OK && live) {
                st = sluice_stream_swap(p->rays, p->next);
                if (st == SLUICE_OK)
                    st = ensure(ctx, &p->hits, sizeof(rt_hit), sluice_stream_capacity(p->rays));
            }
        }
        if (st == SLUICE_OK)
            st = sluice_stream_length(p->stored, &stored);
    }
    if (st == SLUICE_OK && stored)
        p->yield = (double)stored / (double)stats->emitted;
    if (st == SLUICE_OK)
        st = rt_tracer_collect_maxima(p->tracer);
    /* flux per photon: divide by all photons emitted (Jensen 2001, 5.1) */
    if (st == SLUICE_OK && stored) {
        float s = (float)(1.0 / (double)stats->emitted);
        st = sluice_kernel_set_input(p->k_scale, 0, p->stored);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_arg(p->k_scale, 1, sizeof s, &s);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch(p->k_scale);
    }
    if (st == SLUICE_OK)
        st = sluice_context_finish(ctx);
    stats->stored = stored;
    *photons = p->stored;
    *count = stored;
    stats->seconds = sr_clock_seconds() - t0;
    return st;
}
