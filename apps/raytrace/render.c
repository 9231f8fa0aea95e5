/* See render.h. */
#include "render.h"
#include "app_error.h"

#include "kernels.h"
#include "skipped.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Most shadow rays held at once: a wave whose hits would emit more is shaded
 * in slices (each slice's shadow rays traced and resolved before the next). */
#define RT_SHADOW_CAP ((size_t)1 << 20)

/* Shade counters (rt_shade.cl). */
enum { SC_SHADES = 0, SC_SHADOW, SC_REFLECT, SC_REFRACT, SC_PATH, SC_NONFINITE, SC_COUNT };

/* Fused direct light counters (rt_direct.cl). */
enum { DC_SHADOW = 0, DC_NONFINITE, DC_VOXELS, DC_TESTS, DC_SLICES, DC_SLICES_SKIPPED, DC_COUNT };

struct rt_renderer {
    rt_tracer *t;
    rt_render_options opt;
    rt_frame frame;
    const sr_device_scene *ds;
    sluice_program *program; /* camera.cl and rt_shade.cl, built for the mode and scene */
    sluice_kernel *k_raygen, *k_shade, *k_resolve;
    sluice_counters *counters;
    /* the fused mode's direct light (rt_direct.cl): each
     * hit's shadow rays traced where they are made, not as a stream */
    int direct;
    sluice_kernel *k_direct;
    sluice_counters *direct_counters; /* DC_* */
    sr_film *film;
    sr_adaptive *sampling;
    sluice_stream *rays, *next, *hits, *shadow, *shadow_hits;
    sluice_stream *gather; /* rt_gather (one record when not gathering): a sample's */
    char skipped[384];
    size_t per_shadow, per_secondary;
    rt_render_stats stats;
};

void rt_renderer_destroy(rt_renderer *r)
{
    if (!r)
        return;
    sluice_kernel_destroy(r->k_raygen);
    sluice_kernel_destroy(r->k_shade);
    sluice_kernel_destroy(r->k_resolve);
    sluice_kernel_destroy(r->k_direct);
    sluice_program_destroy(r->program);
    sluice_counters_destroy(r->counters);
    sluice_counters_destroy(r->direct_counters);
    sr_film_destroy(r->film);
    sr_adaptive_destroy(r->sampling);
    sluice_stream *s[] = {r->rays, r->next, r->hits, r->shadow, r->shadow_hits, r->gather};
    for (size_t i = 0; i < sizeof s / sizeof *s; ++i)
        sluice_stream_destroy(s[i]);
    free(r);
}

static size_t bytes_of(sluice_stream *s)
{
    return s ? sluice_stream_record_size(s) * (sluice_stream_capacity(s) + 1) : 0;
}

static void update_bytes(rt_renderer *r)
{
    r->stats.stream_bytes = bytes_of(r->rays) + bytes_of(r->next) + bytes_of(r->hits) +
                            bytes_of(r->shadow) + bytes_of(r->shadow_hits) + bytes_of(r->gather) +
                            sr_film_bytes(r->film);
}

/* The shading program: eye rays and shading built for the render mode and
 * the scene, so that code neither needs is not compiled (Purcell builds only
 * what a scene needs); r->skipped says what was left out. */
static sluice_status build_program(rt_renderer *r, const sr_scene_stats *ss)
{
    unsigned mode = r->opt.mode;
    int traces_specular = mode == RT_MODE_WHITTED || mode == RT_MODE_PATH;
    int mirror = traces_specular && (ss->kinds_present & SR_KIND_BIT(SR_MATERIAL_MIRROR));
    int glass = traces_specular && (ss->kinds_present & SR_KIND_BIT(SR_MATERIAL_GLASS));
    char opts[640];
    snprintf(opts, sizeof opts, "%s%s%s%s%s%s%s", r->opt.gather ? " -DRT_GATHER" : "",
             r->ds->layout == SR_TRI_VERTICES ? " -DRT_WATERTIGHT" : "",
             mirror ? " -DRT_HAS_MIRROR" : "", glass ? " -DRT_HAS_GLASS" : "",
             ss->has_normals ? " -DRT_HAS_NORMALS" : "",
             r->direct ? " -DRT_DIRECT_FUSED -DRT_PACKETS_ONLY -DRT_SURFACE_INLINE " : "",
             r->direct ? rt_tracer_build_options(r->t) : "");
    char *k = r->skipped;
    size_t n = sizeof r->skipped;
    k[0] = '\0';
    sr_skipped_add(k, n, traces_specular && !mirror && !glass,
                   "reflection kernels and passes (no mirror or glass)");
    sr_skipped_add(k, n, traces_specular && (mirror || glass) && !glass,
                   "refraction code (no glass)");
    sr_skipped_add(k, n, !traces_specular, "reflection/refraction (mode does not trace them)");
    sr_skipped_add(k, n, mode != RT_MODE_CAST && sr_scene_light_count(r->ds->scene) == 0,
                   "shadow pass (no lights)");
    sr_skipped_add(k, n, mode != RT_MODE_CAST && ss->point_lights == 0,
                   "point-light shadow rays (none)");
    sr_skipped_add(k, n, mode != RT_MODE_CAST && ss->emissive_triangles == 0,
                   "area-light sampling (none)");
    sr_skipped_add(k, n, mode == RT_MODE_CAST, "shadow pass (cast mode)");
    sr_skipped_add(k, n, !ss->has_normals, "normal interpolation (no vertex normals)");
    sr_skipped_add(k, n, r->direct, "shadow-ray streams (fused: traced where they are made)");
    /* the fused direct light also takes the tracer's packet code */
    static const char *const names[] = {
        "rt_types.h", "triangle.cl", "rng.cl",      "film.cl",     "surface.cl",  "lights.cl",
        "camera.cl",  "rt_shade.cl", "rt_trace.cl", "rt_lanes.cl", "rt_fused.cl", "rt_direct.cl"};
    size_t count = r->direct ? sizeof names / sizeof *names : 8;
    sluice_status st = sr_program_create(r->ds->ctx, names, count, opts, &r->program);
    if (st == SLUICE_OK)
        st = sluice_program_build(r->program);
    return st;
}

sluice_status rt_renderer_create(rt_tracer *t, const rt_render_options *opt, rt_renderer **out,
                                 char *err, size_t err_size)
{
    if (out)
        *out = NULL;
    if (!t || !opt || !out || opt->mode > RT_MODE_PATH || opt->width == 0 || opt->height == 0 ||
        opt->width > SR_SCENE_MAX_IMAGE_SIDE || opt->height > SR_SCENE_MAX_IMAGE_SIDE ||
        (uint64_t)opt->width * opt->height > (1u << 26) || opt->light_samples == 0 ||
        opt->light_samples > 1024 || opt->max_depth > 64) {
        sr_set_error(err, err_size, "renderer: bad options");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    rt_renderer *r = calloc(1, sizeof *r);
    if (!r) {
        sr_set_error(err, err_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    r->t = t;
    r->opt = *opt;
    r->ds = rt_tracer_scene(t);
    const sr_scene *sc = r->ds->scene;
    const sr_scene_stats *ss = sr_scene_statistics(sc);
    rt_frame *f = &r->frame;
    memset(f, 0, sizeof *f);
    sr_camera_frame(sr_scene_camera(sc), opt->width, opt->height, f);
    f->seed = opt->seed;
    f->mode = opt->mode;
    f->max_depth = opt->max_depth;
    f->light_samples = opt->light_samples;
    f->point_lights = (rt_u32)ss->point_lights;
    sr_area_lights al;
    sr_scene_area_lights(sc, &al);
    f->area_lights = (rt_u32)al.count;
    f->area_total = (float)al.total_area;
    f->scene_eps = r->ds->scene_eps;

    unsigned mode = opt->mode;
    int specular_kinds = (ss->kinds_present &
                          (SR_KIND_BIT(SR_MATERIAL_MIRROR) | SR_KIND_BIT(SR_MATERIAL_GLASS))) != 0;
    int glass = (ss->kinds_present & SR_KIND_BIT(SR_MATERIAL_GLASS)) != 0;
    r->direct = mode != RT_MODE_CAST && (ss->point_lights || (al.count && opt->light_samples)) &&
                rt_tracer_packets(t);
    r->per_shadow = mode == RT_MODE_CAST || r->direct
                        ? 0
                        : ss->point_lights + (al.count ? opt->light_samples : 0);
    r->per_secondary =
        mode == RT_MODE_PATH ? 1 : (mode == RT_MODE_WHITTED && specular_kinds ? 1 : 0);
    if (glass && mode == RT_MODE_WHITTED)
        r->per_secondary = 2;

    size_t pixels = (size_t)opt->width * opt->height;
    sluice_context *ctx = r->ds->ctx;
    sluice_status st = build_program(r, ss);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(r->program, "rt_raygen", &r->k_raygen);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(r->program, "rt_shade", &r->k_shade);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(r->program, "rt_shadow_resolve", &r->k_resolve);
    static const char *const names[] = {"shades",  "shadow", "reflect",
                                        "refract", "path",   "nonfinite"};
    if (st == SLUICE_OK)
        st = sluice_counters_create(ctx, SC_COUNT, names, &r->counters);
    static const char *const direct_names[] = {"shadow", "nonfinite", "voxels",
                                               "tests",  "slices",    "slices_skipped"};
    if (st == SLUICE_OK && r->direct)
        st = sluice_kernel_create(r->program, "rt_direct", &r->k_direct);
    if (st == SLUICE_OK && r->direct) /* hits that see the light cost many times the others */
        st = sluice_kernel_set_uneven(r->k_direct, 1);
    if (st == SLUICE_OK && r->direct)
        st = sluice_counters_create(ctx, DC_COUNT, direct_names, &r->direct_counters);
    if (st == SLUICE_OK && r->direct)
        st = sluice_kernel_set_counters(r->k_direct, r->direct_counters);
    size_t shadow_cap = r->per_shadow ? pixels * r->per_shadow : 1;
    if (shadow_cap > RT_SHADOW_CAP)
        shadow_cap = RT_SHADOW_CAP > r->per_shadow ? RT_SHADOW_CAP : r->per_shadow;
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(rt_ray), pixels, &r->rays);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(rt_ray),
                                  r->per_secondary ? pixels * r->per_secondary : 1, &r->next);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(rt_hit), pixels * (r->per_secondary > 1 ? 2 : 1),
                                  &r->hits);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(rt_ray), shadow_cap, &r->shadow);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(rt_hit), shadow_cap, &r->shadow_hits);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(rt_gather), opt->gather ? pixels : 1, &r->gather);
    if (st == SLUICE_OK)
        st = sr_film_create(ctx, opt->width, opt->height, &r->film, NULL, 0);
    if (st == SLUICE_OK && (st = sr_adaptive_create(ctx, opt->width, opt->height, &opt->sampling,
                                                    &r->sampling, err, err_size)) != SLUICE_OK) {
        rt_renderer_destroy(r);
        return st;
    }
    if (st == SLUICE_OK)
        st = sluice_kernel_set_counters(r->k_shade, r->counters);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_counters(r->k_resolve, r->counters);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "renderer: %s", sluice_context_error(ctx));
        rt_renderer_destroy(r);
        return st;
    }
    update_bytes(r);
    *out = r;
    return SLUICE_OK;
}

/* Grows `s` to hold at least `n` records (never shrinks). */
static sluice_status ensure(sluice_stream *s, size_t n)
{
    return sluice_stream_capacity(s) >= n ? SLUICE_OK : sluice_stream_grow(s, n);
}

/* Binds what rt_shade and rt_direct read of the scene, from argument
 * `first` on: the film's accumulator, the triangles, their indices,
 * normals and materials, the lights, and the frame. */
static sluice_status bind_scene(rt_renderer *r, sluice_kernel *k, unsigned first)
{
    const sr_device_scene *ds = rt_tracer_scene(r->t);
    sluice_stream *bufs[] = {
        sr_film_accum(r->film), ds->tri_records,  ds->indices,   ds->normals, ds->tri_mat,
        ds->materials,          ds->point_lights, ds->area_tris, ds->area_cdf};
    sluice_status st = SLUICE_OK;
    for (unsigned i = 0; i < 9 && st == SLUICE_OK; ++i)
        st = sluice_kernel_set_stream(k, first + i, bufs[i], 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, first + 9, sizeof r->frame, &r->frame);
    return st;
}

/* The fused mode's direct light for rays [base, base + count) of the wave
 * (rt_direct.cl): the same arguments as rt_shade's but the outputs, then
 * the tracer's. */
static sluice_status direct_slice(rt_renderer *r, size_t base, size_t count)
{
    sluice_kernel *k = r->k_direct;
    uint32_t b = (uint32_t)base;
    sluice_status st = sluice_kernel_set_stream(k, 0, r->rays, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, r->hits, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 2, sizeof b, &b);
    if (st == SLUICE_OK)
        st = bind_scene(r, k, 3);
    if (st == SLUICE_OK)
        st = rt_tracer_bind_packets(r->t, k, 13);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, count);
    uint32_t c[DC_COUNT];
    if (st == SLUICE_OK)
        st = sluice_counters_read_restart(r->direct_counters, c);
    if (st != SLUICE_OK)
        return st;
    r->stats.rays[RT_KIND_SHADOW] += c[DC_SHADOW];
    r->stats.nonfinite += c[DC_NONFINITE];
    rt_tracer_add_traced(r->t, c[DC_SHADOW], c[DC_VOXELS], c[DC_TESTS], c[DC_SLICES],
                         c[DC_SLICES_SKIPPED]);
    return SLUICE_OK;
}

static sluice_status shade_slice(rt_renderer *r, size_t base, size_t count)
{
    rt_tracer *t = r->t;
    sluice_kernel *k = r->k_shade;
    uint32_t b = (uint32_t)base;
    /* the counters count from the last slice's read (read and restarted
     * below: no reset command) */
    sluice_status st = sluice_stream_clear(r->shadow);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 0, r->rays, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, r->hits, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 2, sizeof b, &b);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 3, 0, r->shadow, SLUICE_UNORDERED);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 4, 1, r->next, SLUICE_UNORDERED);
    if (st == SLUICE_OK)
        st = bind_scene(r, k, 5);
    /* gather points accumulate over the sample's slices (rt_renderer_sample
     * hands them over at its end): room for one more a ray (the length is
     * the slices' before, whose work the last wave's read has waited for) */
    size_t have = 0;
    if (st == SLUICE_OK && r->opt.gather)
        st = sluice_stream_length(r->gather, &have);
    if (st == SLUICE_OK && r->opt.gather)
        st = ensure(r->gather, have + count);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 15, 2, r->gather, SLUICE_UNORDERED);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, count);
    if (st == SLUICE_OK && r->direct)
        st = direct_slice(r, base, count);
    size_t ns = 0;
    if (st == SLUICE_OK && r->per_shadow)
        st = sluice_stream_length(r->shadow, &ns);
    if (st == SLUICE_OK && ns) {
        st = rt_tracer_trace_stream(t, r->shadow, ns, r->shadow_hits);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_input(r->k_resolve, 0, r->shadow);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(r->k_resolve, 1, r->shadow_hits, 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(r->k_resolve, 2, sr_film_accum(r->film), 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch(r->k_resolve);
    }
    uint32_t c[SC_COUNT];
    if (st == SLUICE_OK)
        st = sluice_counters_read_restart(r->counters, c);
    if (st != SLUICE_OK)
        return st;
    r->stats.shades += c[SC_SHADES];
    r->stats.rays[RT_KIND_SHADOW] += c[SC_SHADOW];
    r->stats.rays[RT_KIND_REFLECT] += c[SC_REFLECT];
    r->stats.rays[RT_KIND_REFRACT] += c[SC_REFRACT];
    r->stats.rays[RT_KIND_PATH] += c[SC_PATH];
    r->stats.nonfinite += c[SC_NONFINITE];
    return SLUICE_OK;
}

sluice_status rt_renderer_sample(rt_renderer *r)
{
    if (!r)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (rt_renderer_done(r) || sr_adaptive_active_tiles(r->sampling) == 0)
        return SLUICE_OK;
    rt_tracer *t = r->t;
    size_t w = r->opt.width, h = r->opt.height;
    size_t tiles = sr_adaptive_active_tiles(r->sampling);
    size_t n = sr_adaptive_active_pixels(r->sampling);
    unsigned s = sr_adaptive_begin_sample(r->sampling);
    r->frame.sample = s;
    /* the first sample goes through pixel centres, later ones are jittered */
    r->frame.jitter = s > 0;
    r->frame.film_half = (s & 1u) ? (rt_u32)(w * h) : 0u;
    sluice_status st = sluice_stream_clear(r->rays);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(r->gather);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(r->k_raygen, 0, 0, r->rays, SLUICE_ORDERED);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(r->k_raygen, 1, sizeof r->frame, &r->frame);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(r->k_raygen, 2, sr_adaptive_tile_list(r->sampling), 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(r->k_raygen, tiles * 64);
    r->stats.rays[RT_KIND_EYE] += n;
    while (st == SLUICE_OK && n) {
        r->stats.waves++;
        st = ensure(r->hits, sluice_stream_capacity(r->rays));
        if (st == SLUICE_OK)
            st = rt_tracer_trace_stream(t, r->rays, n, r->hits);
        if (st == SLUICE_OK && r->per_secondary)
            st = ensure(r->next, n * r->per_secondary);
        if (st == SLUICE_OK)
            st = sluice_stream_clear(r->next);
        size_t slice = n;
        if (r->per_shadow && slice * r->per_shadow > sluice_stream_capacity(r->shadow))
            slice = sluice_stream_capacity(r->shadow) / r->per_shadow;
        for (size_t base = 0; st == SLUICE_OK && base < n; base += slice)
            st = shade_slice(r, base, n - base < slice ? n - base : slice);
        size_t nn = 0;
        if (st == SLUICE_OK && r->per_secondary)
            st = sluice_stream_length(r->next, &nn);
        if (st == SLUICE_OK && nn) {
            st = sluice_stream_swap(r->rays, r->next);
            if (st == SLUICE_OK)
                st = ensure(r->hits, sluice_stream_capacity(r->rays));
        }
        n = nn;
    }
    /* the gather points of every wave at once: one radiance estimate a
     * sample, not one a wave (a launch chain each), before the sampling
     * check reads the film */
    size_t ng = 0;
    if (st == SLUICE_OK && r->opt.gather)
        st = sluice_stream_length(r->gather, &ng);
    if (st == SLUICE_OK && ng)
        st = r->opt.gather(r->opt.gather_user, r->gather, ng);
    if (st == SLUICE_OK)
        st = rt_tracer_collect_maxima(t);
    if (st == SLUICE_OK)
        r->stats.samples++;
    if (st == SLUICE_OK)
        st = sr_adaptive_check(r->sampling, r->film, NULL);
    update_bytes(r);
    return st;
}

int rt_renderer_done(const rt_renderer *r)
{
    return r && sr_adaptive_done(r->sampling);
}

sluice_status rt_renderer_image(rt_renderer *r, sr_image *img, size_t *bad_pixels)
{
    if (bad_pixels)
        *bad_pixels = 0;
    if (!r)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    return sr_film_resolve_tiles(r->film, NULL, sr_adaptive_tile_samples(r->sampling), img, NULL,
                                 bad_pixels);
}

sluice_status rt_renderer_write(rt_renderer *r, const char *path, size_t *bad_pixels, char *err,
                                size_t err_size)
{
    if (!r) {
        sr_set_error(err, err_size, "rt_renderer_write: NULL renderer");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    return sr_film_write(r->film, sr_adaptive_tile_samples(r->sampling), path, bad_pixels, err,
                         err_size);
}

sluice_status rt_renderer_write_sample_map(rt_renderer *r, const char *path, char *err,
                                           size_t err_size)
{
    if (!r || !path) {
        sr_set_error(err, err_size, "rt_renderer_write_sample_map: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sr_image *img = NULL;
    sluice_status st = sr_image_create(r->opt.width, r->opt.height, 3, &img, err, err_size);
    if (st == SLUICE_OK)
        st = sr_adaptive_sample_map(r->sampling, img);
    if (st == SLUICE_OK)
        st = sr_image_write(img, path, err, err_size);
    sr_image_destroy(img);
    return st;
}

const uint32_t *rt_renderer_tile_samples(const rt_renderer *r)
{
    return r ? sr_adaptive_tile_samples(r->sampling) : NULL;
}

const sr_adaptive_stats *rt_renderer_sampling(const rt_renderer *r)
{
    return r ? sr_adaptive_statistics(r->sampling) : NULL;
}

sr_film *rt_renderer_film(rt_renderer *r)
{
    return r ? r->film : NULL;
}

const char *rt_renderer_skipped(const rt_renderer *r)
{
    return r ? r->skipped : "";
}

const rt_render_stats *rt_renderer_stats(const rt_renderer *r)
{
    return r ? &r->stats : NULL;
}
