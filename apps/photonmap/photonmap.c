/* See photonmap.h. */
#include "photonmap.h"
#include "app_error.h"
#include "clock.h"
#include "kernels.h"
#include "skipped.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PM_PI 3.14159265358979323846

/* Gather counters (pm_render.cl). */
enum { GC_ADDED = 0, GC_EMPTY, GC_NONFINITE, GC_COUNT };

struct pm_renderer {
    sluice_context *ctx;
    const sr_scene *scene;
    pm_options opt;
    rt_tracer *tracer;
    rt_renderer *whitted;
    pm_photons *photons;
    sr_point_grid *grid;
    pm_knn *knn;
    sluice_program *program;
    sluice_kernel *k_queries, *k_add;
    sluice_counters *counters;
    sluice_stream *queries, *results;
    sluice_stream *map; /* the photons (owned by `photons`) */
    size_t map_count;
    int prepared;
    float max_radius;
    float radius2;             /* progressive: this sample's squared search radius */
    int map_built;             /* the map of this sample is built (progressive) */
    double estimate_in_sample; /* seconds of estimates during the current sample */
    sluice_status gather_status;
    /* intermediate images (pm_options.pass_image): the current gather's
     * estimates drawn over the film */
    sr_film *preview;
    sr_image *preview_img;
    sluice_stream *preview_points;
    int preview_failed;
    char *err; /* the current call's message buffer (gather writes there) */
    size_t err_size;
    pm_stats stats;
    char skipped[768];
};

pm_options pm_options_default(void)
{
    pm_options o;
    memset(&o, 0, sizeof o);
    o.width = 512;
    o.height = 384;
    o.seed = 1;
    o.light_samples = 1;
    o.max_depth = 5;
    o.photons = 16000;
    o.k = 64;
    o.map = SR_POINT_GRID_COUNT;
    o.slots = 256;
    o.knn = PM_KNN_ATLEAST;
    o.shells_per_pass = 1;
    o.tracer = rt_tracer_options_default();
    o.alpha = 2.0f / 3.0f;
    o.photon_grid = SR_POINT_GRID_LAYOUT_AUTO;
    return o;
}

void pm_renderer_destroy(pm_renderer *r)
{
    if (!r)
        return;
    rt_renderer_destroy(r->whitted);
    pm_photons_destroy(r->photons);
    sr_point_grid_destroy(r->grid);
    pm_knn_destroy(r->knn);
    sluice_kernel_destroy(r->k_queries);
    sluice_kernel_destroy(r->k_add);
    sluice_program_destroy(r->program);
    sluice_counters_destroy(r->counters);
    sluice_stream_destroy(r->queries);
    sluice_stream_destroy(r->results);
    sr_film_destroy(r->preview);
    sr_image_destroy(r->preview_img);
    rt_tracer_destroy(r->tracer);
    free(r);
}

/* The area of the surfaces photons are stored on (diffuse and glossy). */
static double storing_area(const sr_scene *sc)
{
    const float *p = sr_scene_positions(sc);
    const uint32_t *ix = sr_scene_indices(sc);
    const uint32_t *tm = sr_scene_triangle_materials(sc);
    const sr_material *m = sr_scene_materials(sc);
    double area = 0;
    for (size_t t = 0; t < sr_scene_triangle_count(sc); ++t) {
        sr_material_kind kind = m[tm[t]].kind;
        if (kind != SR_MATERIAL_DIFFUSE && kind != SR_MATERIAL_GLOSSY)
            continue;
        const float *a = p + 3 * ix[3 * t], *b = p + 3 * ix[3 * t + 1], *c = p + 3 * ix[3 * t + 2];
        double u[3], v[3];
        for (int k = 0; k < 3; ++k) {
            u[k] = b[k] - a[k];
            v[k] = c[k] - a[k];
        }
        double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2],
               z = u[0] * v[1] - u[1] * v[0];
        area += 0.5 * sqrt(x * x + y * y + z * z);
    }
    return area;
}

static sluice_status gather(void *user, sluice_stream *points, size_t n);

/* Adds the estimates of the first `answered` gather points to `accum`. */
static sluice_status add_estimates(pm_renderer *r, sluice_stream *points, sluice_stream *accum,
                                   size_t answered)
{
    uint32_t a = (uint32_t)answered;
    sluice_status st = sluice_kernel_set_input(r->k_add, 0, points);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(r->k_add, 1, r->results, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(r->k_add, 2, accum, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(r->k_add, 3, sizeof a, &a);
    float fixed = r->opt.progressive ? r->radius2 : 0.0f;
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(r->k_add, 4, sizeof fixed, &fixed);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(r->k_add);
    return st;
}

/* The kNN pass hook: the film plus the estimates as they stand, handed to
 * pm_options.pass_image. Its time is kept out of the phases. */
static sluice_status preview_pass(void *user, unsigned pass, size_t answered)
{
    (void)pass;
    pm_renderer *r = user;
    double t0 = sr_clock_seconds();
    sluice_context *ctx = r->ctx;
    sr_film *film = rt_renderer_film(r->whitted);
    sluice_status st = SLUICE_OK;
    if (!r->preview)
        st = sr_film_create(ctx, r->opt.width, r->opt.height, &r->preview, r->err, r->err_size);
    if (st == SLUICE_OK && !r->preview_img)
        st = sr_image_create(r->opt.width, r->opt.height, 3, &r->preview_img, r->err, r->err_size);
    if (st != SLUICE_OK) {
        r->preview_failed = 1;
        return st;
    }
    st = sr_film_clear(r->preview);
    if (st == SLUICE_OK)
        st = add_estimates(r, r->preview_points, sr_film_accum(r->preview), answered);
    if (st == SLUICE_OK)
        st = sr_film_resolve_tiles(film, r->preview, rt_renderer_tile_samples(r->whitted),
                                   r->preview_img, NULL, NULL);
    if (st != SLUICE_OK) {
        sr_set_error(r->err, r->err_size, "intermediate image: %s",
                     st == SLUICE_ERROR_OUT_OF_MEMORY ? "out of memory"
                                                      : sluice_context_error(ctx));
        r->preview_failed = 1;
        return st;
    }
    st = r->opt.pass_image(r->opt.pass_image_user, r->preview_img, r->stats.pass_images, r->err,
                           r->err_size);
    r->preview_failed = st != SLUICE_OK;
    r->stats.pass_images++;
    r->stats.pass_images_s += sr_clock_seconds() - t0;
    return st;
}

sluice_status pm_renderer_create(sluice_context *ctx, const sr_scene *scene, const pm_options *opt,
                                 pm_renderer **out, char *err, size_t err_size)
{
    if (out)
        *out = NULL;
    if (!ctx || !scene || !opt || !out || opt->k == 0 || opt->k > PM_KNN_MAX_K ||
        !(opt->max_radius >= 0) || (unsigned)opt->map > (unsigned)SR_POINT_GRID_STENCIL ||
        opt->slots == 0 || opt->slots > SR_POINT_GRID_MAX_SLOTS ||
        (unsigned)opt->photon_grid > (unsigned)SR_POINT_GRID_LAYOUT_AUTO) {
        sr_set_error(err, err_size, "photon mapper: bad options");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (opt->photon_grid == SR_POINT_GRID_HASHED) {
        /* only the radius search reads buckets that mix cells, and only the
         * compact builds list a bucket's photons whole (Purcell 6.4.4) */
        const char *why = !opt->progressive   ? "the k-nearest searches need the dense grid (use "
                                                "--progressive, whose radius search reads a hash)"
                          : opt->grid_dims[0] ? "--grid sets a dense grid's dimensions"
                          : opt->map == SR_POINT_GRID_STENCIL
                              ? "the stencil build's power redistribution is per cell, and a "
                                "bucket mixes cells"
                              : NULL;
        if (why) {
            sr_set_error(err, err_size, "photon mapper: no hashed photon map here: %s", why);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
    }
    pm_renderer *r = calloc(1, sizeof *r);
    if (!r) {
        sr_set_error(err, err_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    r->ctx = ctx;
    r->scene = scene;
    r->opt = *opt;
    r->err = err;
    r->err_size = err_size;
    sluice_status st = rt_tracer_create(ctx, scene, &opt->tracer, &r->tracer, err, err_size);
    rt_render_options ro;
    memset(&ro, 0, sizeof ro);
    ro.mode = RT_MODE_WHITTED;
    ro.width = opt->width;
    ro.height = opt->height;
    ro.max_depth = opt->max_depth;
    ro.light_samples = opt->light_samples;
    ro.seed = opt->seed;
    ro.gather = gather;
    ro.gather_user = r;
    ro.sampling = opt->sampling;
    if (st == SLUICE_OK)
        st = rt_renderer_create(r->tracer, &ro, &r->whitted, err, err_size);
    if (st == SLUICE_OK)
        st = pm_photons_create(r->tracer, &r->photons, err, err_size);
    if (st != SLUICE_OK) {
        pm_renderer_destroy(r);
        return st;
    }
    const sr_device_scene *ds = rt_tracer_scene(r->tracer);
    static const char *const names[] = {"rt_types.h", "pm_types.h", "triangle.cl",
                                        "film.cl",    "surface.cl", "pm_render.cl"};
    st = sr_shared_program_create(ctx, names, sizeof names / sizeof *names,
                                  ds->layout == SR_TRI_VERTICES ? "-DRT_WATERTIGHT" : NULL,
                                  &r->program);
    if (st == SLUICE_OK)
        st = sluice_program_build(r->program);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(r->program, "pm_gather_queries", &r->k_queries);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(r->program, "pm_gather_add", &r->k_add);
    static const char *const ctr[] = {"estimates", "empty", "nonfinite"};
    if (st == SLUICE_OK)
        st = sluice_counters_create(ctx, GC_COUNT, ctr, &r->counters);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_counters(r->k_add, r->counters);
    size_t pixels = (size_t)opt->width * opt->height;
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(pm_query), pixels, &r->queries);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(pm_knn_result), pixels, &r->results);
    if (st == SLUICE_OK)
        st = sr_point_grid_create(ctx, &r->grid);
    /* the map build's stream algorithms, built now: setup, not the phase */
    if (st == SLUICE_OK && (st = sr_point_grid_prepare(r->grid, r->opt.map)) != SLUICE_OK) {
        sr_set_error(err, err_size, "photon mapper: %s", sr_point_grid_error(r->grid));
        pm_renderer_destroy(r);
        return st;
    }
    if (st == SLUICE_OK)
        st = pm_knn_create(ctx, &r->knn);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "photon mapper: %s", sluice_context_error(ctx));
        pm_renderer_destroy(r);
        return st;
    }
    *out = r;
    return SLUICE_OK;
}

/* The bounds of the stored photons (the scene's when there are none). */
static sluice_status photon_bounds(pm_renderer *r, const sr_scene_stats *ss, float lo[3],
                                   float hi[3])
{
    memcpy(lo, ss->bounds_min, 3 * sizeof(float));
    memcpy(hi, ss->bounds_max, 3 * sizeof(float));
    if (r->map_count == 0)
        return SLUICE_OK;
    pm_photon *ph = malloc(r->map_count * sizeof *ph);
    if (!ph)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    sluice_status st = sluice_stream_download(r->map, ph, r->map_count, NULL);
    float a[3] = {INFINITY, INFINITY, INFINITY}, b[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; st == SLUICE_OK && i < r->map_count; ++i) {
        const float p[3] = {ph[i].px, ph[i].py, ph[i].pz};
        for (int k = 0; k < 3; ++k)
            if (isfinite(p[k])) {
                a[k] = fminf(a[k], p[k]);
                b[k] = fmaxf(b[k], p[k]);
            }
    }
    free(ph);
    for (int k = 0; st == SLUICE_OK && k < 3; ++k)
        if (a[k] <= b[k]) {
            lo[k] = fmaxf(a[k], lo[k]);
            hi[k] = fminf(b[k], hi[k]);
            if (lo[k] > hi[k])
                lo[k] = hi[k] = 0.5f * (a[k] + b[k]);
        }
    return st;
}

/* Builds the photon map over the photons: a dense grid of cells about
 * `cell` wide (sr_point_grid_desc_auto), or of the --grid dimensions; or,
 * for a radius search of `search_radius` (> 0: the progressive estimate),
 * the layout sr_point_grid_plan_auto chooses for pm_options.photon_grid
 * (Purcell 6.4.4's hash unless the dense grid is asked for). */
static sluice_status build_grid(pm_renderer *r, float cell, float search_radius, char *err,
                                size_t err_size)
{
    const sr_scene_stats *ss = sr_scene_statistics(r->scene);
    size_t n = r->map_count ? r->map_count : 1;
    char msg[256] = "";
    sluice_status st;
    sr_point_grid_plan plan;
    memset(&plan, 0, sizeof plan);
    plan.layout = SR_POINT_GRID_DENSE;
    if (r->opt.grid_dims[0]) {
        st = sr_point_grid_desc_dims(ss->bounds_min, ss->bounds_max, r->opt.grid_dims, &plan.dense,
                                     msg, sizeof msg);
        snprintf(plan.why, sizeof plan.why, "dense: --grid sets its dimensions");
    } else {
        /* the photons' own box: photons lie on the surfaces that store them
         * (glassball's and ring's floors: a flat box, one cell high) */
        float lo[3], hi[3];
        st = photon_bounds(r, ss, lo, hi);
        if (st != SLUICE_OK) {
            snprintf(msg, sizeof msg, "reading the photons: %s", sluice_context_error(r->ctx));
        } else if (search_radius > 0 && r->opt.map != SR_POINT_GRID_STENCIL) {
            st = sr_point_grid_plan_auto(lo, hi, n, cell, search_radius, r->opt.photon_grid, &plan,
                                         msg, sizeof msg);
        } else {
            st = sr_point_grid_desc_auto(lo, hi, n, cell, &plan.dense, msg, sizeof msg);
            snprintf(plan.why, sizeof plan.why, "dense: %s",
                     search_radius > 0 ? "the stencil build needs it (its power redistribution "
                                         "is per cell; a bucket mixes cells)"
                                       : "the k-nearest search needs it");
        }
    }
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "photon map grid: %s", msg);
        return st;
    }
    r->stats.map_layout = plan.layout;
    snprintf(r->stats.map_why, sizeof r->stats.map_why, "%s", plan.why);
    double t0 = sr_clock_seconds();
    if (plan.layout == SR_POINT_GRID_HASHED) {
        memset(&r->stats.map_grid, 0, sizeof r->stats.map_grid);
        r->stats.map_hash = plan.hash;
        st = sr_point_grid_build_hashed(r->grid, &plan.hash, r->map, sizeof(pm_photon),
                                        r->map_count, r->opt.map);
    } else {
        r->stats.map_grid = plan.dense;
        memset(&r->stats.map_hash, 0, sizeof r->stats.map_hash);
        st = sr_point_grid_build(r->grid, &plan.dense, r->map, sizeof(pm_photon), r->map_count,
                                 r->opt.map, r->opt.slots);
    }
    r->stats.build_map_s += sr_clock_seconds() - t0;
    if (st == SLUICE_OK)
        st = sr_point_grid_statistics(r->grid, &r->stats.map);
    if (st != SLUICE_OK)
        sr_set_error(err, err_size, "building the photon map: %s", sr_point_grid_error(r->grid));
    return st;
}

/* The median, over up to 1,024 photons spread through the map, of the
 * radius that their own k nearest photons take: the density seen from the
 * photons (a caustic's where they crowd into one). */
static sluice_status photon_knn_radius(pm_renderer *r, float max_radius, float *out)
{
    enum { SAMPLES = 1024 };
    size_t n = r->map_count, m = n < SAMPLES ? n : SAMPLES;
    *out = 0.0f;
    if (m == 0)
        return SLUICE_OK;
    pm_photon *ph = malloc(n * sizeof *ph);
    pm_query *q = malloc(m * sizeof *q);
    pm_knn_result *res = malloc(m * sizeof *res);
    float *radii = malloc(m * sizeof *radii);
    sluice_status st = ph && q && res && radii ? SLUICE_OK : SLUICE_ERROR_OUT_OF_MEMORY;
    if (st == SLUICE_OK)
        st = sluice_stream_download(r->map, ph, n, NULL);
    for (size_t i = 0; st == SLUICE_OK && i < m; ++i) {
        const pm_photon *p = &ph[i * n / m];
        q[i] = (pm_query){p->px, p->py, p->pz, -p->dx, -p->dy, -p->dz, (uint32_t)i};
    }
    if (st == SLUICE_OK && sluice_stream_capacity(r->queries) < m)
        st = sluice_stream_grow(r->queries, m);
    if (st == SLUICE_OK && sluice_stream_capacity(r->results) < m)
        st = sluice_stream_grow(r->results, m);
    if (st == SLUICE_OK)
        st = sluice_stream_upload(r->queries, q, m);
    pm_knn_options ko = {r->opt.k, max_radius, PM_KNN_EXACT, 0, NULL, NULL, PM_KNN_ALL_SHELLS};
    if (st == SLUICE_OK)
        st = pm_knn_query(r->knn, r->grid, r->map, r->queries, m, r->results, &ko, NULL);
    if (st == SLUICE_OK)
        st = sluice_stream_download(r->results, res, m, NULL);
    size_t k = 0;
    for (size_t i = 0; st == SLUICE_OK && i < m; ++i)
        if (res[i].r2 > 0.0f)
            radii[k++] = sqrtf(res[i].r2);
    if (st == SLUICE_OK && k > 0) {
        /* the median, by selection sort's first half: m is small */
        for (size_t i = 0; i <= k / 2; ++i)
            for (size_t j = i + 1; j < k; ++j)
                if (radii[j] < radii[i]) {
                    float t = radii[i];
                    radii[i] = radii[j];
                    radii[j] = t;
                }
        *out = radii[k / 2];
    }
    free(ph);
    free(q);
    free(res);
    free(radii);
    return st;
}

/* Traces the photons of `seed`, chooses the radius and grid and builds the
 * map; the phases' times and the photon counts add up over calls. */
static sluice_status trace_and_build(pm_renderer *r, uint32_t seed, char *err, size_t err_size)
{
    pm_photon_options po = {r->opt.photons, r->opt.max_depth, seed, 0};
    pm_photon_stats before = r->stats.photons;
    sluice_status st = pm_photons_trace(r->photons, &po, &r->map, &r->map_count, &r->stats.photons);
    if (r->stats.samples > 0) {
        pm_photon_stats *ps = &r->stats.photons;
        ps->emitted += before.emitted;
        ps->stored += before.stored;
        ps->caustic += before.caustic;
        ps->bounced += before.bounced;
        ps->left_scene += before.left_scene;
        ps->absorbed += before.absorbed;
        ps->depth_limit += before.depth_limit;
        ps->nonfinite += before.nonfinite;
        ps->passes += before.passes;
        ps->batches += before.batches;
    }
    r->stats.trace_photons_s += r->stats.photons.seconds;
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "tracing photons: %s", sluice_context_error(r->ctx));
        return st;
    }
    /* Search radius and grid: the expected radius of k photons spread evenly
     * over the storing surfaces is sqrt(k A / (pi N)); the maximum radius is
     * three times that (denser places, caustics, end well inside it). The
     * cells are a quarter of the expected radius: photons crowd into
     * caustics, and cells as large as the radius there make every estimate
     * take whole cells (blocky caustics on glassball; a quarter is about
     * Purcell's 250x1x250 there). Progressive: the radius search's radius
     * r_i starts at max_radius when set, else at photon_knn_radius, and
     * dense cells are sized for half of it (hashed cells: r_i itself). */
    const sr_scene_stats *ss = sr_scene_statistics(r->scene);
    double area = storing_area(r->scene);
    size_t n = r->map_count ? r->map_count : 1;
    float expected = (float)sqrt((double)r->opt.k * (area > 0 ? area : 1.0) / (PM_PI * (double)n));
    float diag = 0;
    for (int k = 0; k < 3; ++k)
        diag += (ss->bounds_max[k] - ss->bounds_min[k]) * (ss->bounds_max[k] - ss->bounds_min[k]);
    diag = sqrtf(diag);
    if (!(expected > 0) || !isfinite(expected))
        expected = diag > 0 ? diag / 16 : 1.0f;
    float cell = expected / 4.0f;
    if (r->opt.progressive) {
        if (r->stats.samples == 0) {
            float r0 = r->opt.max_radius;
            if (!(r0 > 0)) {
                /* from the photons' own k nearest, on a grid for that
                 * search first */
                st = build_grid(r, cell, 0.0f, err, err_size);
                if (st != SLUICE_OK)
                    return st;
                float seen = 0.0f;
                st = photon_knn_radius(r, fminf(3.0f * expected, diag), &seen);
                if (st != SLUICE_OK) {
                    const char *why = pm_knn_error(r->knn);
                    sr_set_error(err, err_size, "the first radius: %s",
                                 why[0] ? why : sluice_context_error(r->ctx));
                    return st;
                }
                /* Between the density seen from the photons and the one
                 * spread over the surfaces (equal where photons are
                 * even): on glassball the first is 0.013, the second 0.36,
                 * and relMSE after 16 samples was 0.0025-0.0028 for r_0
                 * from 0.03 to 0.07, 0.0033 at 0.02, 0.0043 at 0.1 and
                 * 0.077 (after 8) at 0.36; their geometric mean is 0.069. */
                r0 = seen > 0 ? sqrtf(seen * expected) : expected;
            }
            r->radius2 = r0 * r0;
            r->stats.radius0 = r0;
        } else {
            double i = r->stats.samples;
            r->radius2 = (float)(r->radius2 * (i + r->opt.alpha) / (i + 1.0));
        }
        r->max_radius = sqrtf(r->radius2);
        cell = r->max_radius / 2.0f;
    } else {
        r->max_radius = r->opt.max_radius > 0 ? r->opt.max_radius : fminf(3.0f * expected, diag);
        if (!(r->max_radius > 0))
            r->max_radius = 1.0f;
    }
    r->stats.max_radius = r->max_radius;
    r->stats.radius = r->opt.progressive ? r->max_radius : 0.0f;
    st = build_grid(r, cell, r->opt.progressive ? r->max_radius : 0.0f, err, err_size);
    if (st != SLUICE_OK)
        return st;
    if (r->stats.map_layout == SR_POINT_GRID_HASHED)
        r->stats.maps_hashed++;
    else
        r->stats.maps_dense++;
    return SLUICE_OK;
}

sluice_status pm_renderer_prepare(pm_renderer *r, char *err, size_t err_size)
{
    if (!r)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (r->prepared)
        return SLUICE_OK;
    sluice_status st = trace_and_build(r, r->opt.seed, err, err_size);
    if (st != SLUICE_OK)
        return st;
    r->map_built = 1;
    char *k = r->skipped;
    size_t ks = sizeof r->skipped;
    snprintf(k, ks, "%s", r->stats.photons.skipped);
    sr_skipped_add(k, ks, r->map_count == 0, "radiance estimates (no photons stored)");
    sr_skipped_add(k, ks, 1, "finished estimates (leave the kNN stream after their last pass)");
    sr_skipped_add(k, ks, 1, rt_renderer_skipped(r->whitted));
    sr_skipped_add(k, ks, 1, rt_tracer_skipped(r->tracer));
    r->prepared = 1;
    return SLUICE_OK;
}

/* The Whitted renderer's gather hook: the estimates of n gather points. */
static sluice_status gather(void *user, sluice_stream *points, size_t n)
{
    pm_renderer *r = user;
    if (r->map_count == 0 || n == 0) /* a sample with no diffuse hits */
        return SLUICE_OK;
    /* the tracing queued before the hook is the tracing phase's: wait for it
     * so that the estimate's clock does not count it */
    sluice_status st = sluice_context_finish(r->ctx);
    if (st != SLUICE_OK) {
        sr_set_error(r->err, r->err_size, "tracing: %s", sluice_context_error(r->ctx));
        r->gather_status = st;
        return st;
    }
    double t0 = sr_clock_seconds();
    if (sluice_stream_capacity(r->queries) < n)
        st = sluice_stream_grow(r->queries, n);
    if (st == SLUICE_OK && sluice_stream_capacity(r->results) < n)
        st = sluice_stream_grow(r->results, n);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(r->k_queries, 0, points);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(r->k_queries, 1, r->queries, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(r->k_queries);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(r->queries, n);
    /* progressive: every photon within r_i */
    pm_knn_options ko = {
        r->opt.k, r->max_radius,         r->opt.progressive ? PM_KNN_RADIUS : r->opt.knn, 1, NULL,
        NULL,     r->opt.shells_per_pass};
    if (r->opt.pass_image) {
        ko.on_pass = preview_pass;
        ko.on_pass_user = r;
        r->preview_points = points;
        r->preview_failed = 0;
    }
    pm_knn_stats ks;
    double previews_before = r->stats.pass_images_s;
    if (st == SLUICE_OK) {
        st = pm_knn_query(r->knn, r->grid, r->map, r->queries, n, r->results, &ko, &ks);
        if (st != SLUICE_OK) {
            if (!r->preview_failed) /* otherwise the hook has said why */
                sr_set_error(r->err, r->err_size, "radiance estimate: %s", pm_knn_error(r->knn));
            r->gather_status = st;
            return st;
        }
    }
    /* the counters count from the last read (restarted: no reset command) */
    if (st == SLUICE_OK)
        st = add_estimates(r, points, sr_film_accum(rt_renderer_film(r->whitted)), n);
    uint32_t c[GC_COUNT];
    if (st == SLUICE_OK)
        st = sluice_counters_read_restart(r->counters, c);
    if (st != SLUICE_OK) {
        sr_set_error(r->err, r->err_size, "radiance estimate: %s", sluice_context_error(r->ctx));
        r->gather_status = st;
        return st;
    }
    pm_stats *s = &r->stats;
    s->queries += ks.queries;
    s->found += (uint64_t)llround(ks.mean_count * (double)ks.queries);
    s->with_photons += ks.queries - ks.empty;
    s->radius_sum += ks.mean_radius * (double)(ks.queries - ks.empty);
    s->hit_max_radius += ks.hit_max_radius;
    s->nonfinite += c[GC_NONFINITE];
    s->knn_passes += ks.passes;
    for (unsigned i = 0; i < PM_KNN_STATS_PASSES; ++i)
        s->live[i] += ks.live[i];
    r->estimate_in_sample += sr_clock_seconds() - t0 - (r->stats.pass_images_s - previews_before);
    return SLUICE_OK;
}

sluice_status pm_renderer_sample(pm_renderer *r, char *err, size_t err_size)
{
    if (!r)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sluice_status st = pm_renderer_prepare(r, err, err_size);
    if (st == SLUICE_OK && r->opt.progressive && !r->map_built) {
        /* new photons, a smaller radius: sample i's own estimate */
        uint32_t seed = r->opt.seed ^ (0x9E3779B9u * (uint32_t)(r->stats.samples + 1));
        st = trace_and_build(r, seed, err, err_size);
    }
    if (st != SLUICE_OK)
        return st;
    r->map_built = 0;
    r->err = err;
    r->err_size = err_size;
    r->gather_status = SLUICE_OK;
    r->estimate_in_sample = 0;
    double previews_before = r->stats.pass_images_s;
    double t0 = sr_clock_seconds();
    st = rt_renderer_sample(r->whitted);
    double t = sr_clock_seconds() - t0 - (r->stats.pass_images_s - previews_before);
    r->stats.estimate_s += r->estimate_in_sample;
    r->stats.trace_rays_s += t - r->estimate_in_sample;
    if (st != SLUICE_OK) {
        if (r->gather_status == SLUICE_OK)
            sr_set_error(err, err_size, "rendering: %s", sluice_context_error(r->ctx));
        return st;
    }
    r->stats.samples++;
    return SLUICE_OK;
}

sr_film *pm_renderer_film(pm_renderer *r)
{
    return r ? rt_renderer_film(r->whitted) : NULL;
}

rt_tracer *pm_renderer_tracer(pm_renderer *r)
{
    return r ? r->tracer : NULL;
}

rt_renderer *pm_renderer_whitted(pm_renderer *r)
{
    return r ? r->whitted : NULL;
}

const pm_stats *pm_renderer_stats(const pm_renderer *r)
{
    return r ? &r->stats : NULL;
}

sluice_stream *pm_renderer_photons(pm_renderer *r, size_t *count)
{
    if (count)
        *count = r ? r->map_count : 0;
    return r ? r->map : NULL;
}

const sr_point_grid *pm_renderer_map(const pm_renderer *r)
{
    return r ? r->grid : NULL;
}

const char *pm_renderer_skipped(pm_renderer *r)
{
    return r ? r->skipped : "";
}
