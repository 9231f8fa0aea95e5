/*
 * sluice-photonmap: Purcell's photon mapper (thesis ch. 6) on Sluice. Parses
 * the command line, loads the scene, traces photons, builds the photon map,
 * renders samples with progress and checkpoints, writes the image and the
 * statistics (Purcell's Table 6.1 phases and more).
 */
#include "cli.h"
#include "clock.h"
#include "json.h"
#include "photonmap.h"
#include "progressive.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PROG "sluice-photonmap"

static void usage(FILE *out)
{
    fputs("usage: " PROG " [options]\n"
          "Renders a scene with Purcell's GPU photon mapper on OpenCL: photons traced as\n"
          "streams, a photon map built as a uniform grid (bitonic sort, stencil routing or\n"
          "counting sort), the kNN-grid radiance estimate at diffuse hits, direct light\n"
          "by shadow rays, mirrors and glass followed (thesis ch. 6).\n\n",
          out);
    sr_cli_common_usage(out);
    fputs("\nphoton mapper options:\n"
          "  --photons N              photons to store (default: the scene's, else 16000)\n"
          "  --k N                    photons sought per radiance estimate (default: the\n"
          "                           scene's, else 64)\n"
          "  --max-radius R           largest search radius, scene units (default: 3 times\n"
          "                           the radius k photons would take spread evenly)\n"
          "  --map M                  count | bitonic | stencil: how the photon map grid is\n"
          "                           built (default count)\n"
          "  --slots M                stencil: places per cell, m*m (default 256, m = 16)\n"
          "  --grid WxHxD|auto        photon-map grid cells (default auto: cells about the\n"
          "                           expected search radius); Purcell's: 250x1x250 (glassball,\n"
          "                           ring), 25x25x50 (cornell)\n"
          "  --knn atleast|exact      Purcell's at-least-k search or Jensen's k nearest\n"
          "                           (default atleast)\n"
          "  --shells-per-pass N|all  kNN shells holding photons each pass explores per\n"
          "                           estimate (default 1, Purcell's; all: one pass)\n"
          "  --spp N                  samples per pixel (default 1; with --time and no\n"
          "                           --spp, as many as the time allows)\n"
          "  --light-samples N        shadow rays per area light and hit (default: the scene's)\n"
          "  --max-depth N            mirror/glass bounces of eye rays and photon bounces\n"
          "                           (default: the scene's)\n"
          "  --exec stream|fused      the tracer's execution mode (default stream)\n"
          "  --progressive            progressive photon mapping: every sample traces new\n"
          "                           photons and gathers all within a radius that shrinks\n"
          "                           as r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1) (Knaus and\n"
          "                           Zwicker 2011): converges as samples grow; r_0 is\n"
          "                           --max-radius, or between the radius of k photons\n"
          "                           around the photons and spread evenly\n"
          "  --alpha A                progressive radius reduction, 0 < A < 1 (default 2/3)\n"
          "  --photon-grid dense|hash|auto\n"
          "                           the photon map's layout (default auto): a dense grid\n"
          "                           (a record per cell of the photons' box), or cells of\n"
          "                           the search radius hashed into a table of 2 to 4\n"
          "                           buckets per photon (Purcell 6.4.4); hash needs\n"
          "                           --progressive (only its radius search reads it), the\n"
          "                           count or bitonic build and no --grid; auto takes it\n"
          "                           there (its search is the faster one, most where the\n"
          "                           photons' box is far larger than the radius: a small\n"
          "                           lit object and a distant wall); the statistics say\n"
          "                           which and why\n"
          "  --pass-images FILE       also write the image after every kNN pass, the\n"
          "                           estimates as they stand (Purcell 6.3.4): FILE with\n"
          "                           -0000, -0001, ... before its extension (.png, .exr,\n"
          "                           .hdr); their cost is left out of the phases\n\n"
          "Ctrl-C finishes the current sample, writes the image so far and exits with 130.\n\n"
          "examples:\n"
          "  " PROG " --scene glassball --out glassball.png\n"
          "  " PROG " --scene ring --map stencil --grid 250x1x250 --stats ring.json\n"
          "  " PROG " --scene cornell --photons 65000 --k 500 --grid 25x25x50 --light-samples 32\n"
          "  " PROG " --scene glassball --pass-images frames/glassball.png\n"
          "  " PROG " --scene glassball --progressive --spp 64 --out glassball-ppm.png\n"
          "  " PROG " --scene scenes/distant-wall.json --progressive --max-radius 0.15 --spp 16\n",
          out);
}

typedef struct cli {
    sr_cli_common common;
    pm_options opt;
    unsigned spp;
    const char *pass_images; /* --pass-images pattern, or NULL */
    int have_spp, have_photons, have_k, have_ls, have_depth;
    int have_grid; /* --grid WxHxD (not auto) */
} cli;

static int parse(int argc, char **argv, cli *c)
{
    memset(c, 0, sizeof *c);
    sr_cli_common_init(&c->common);
    c->opt = pm_options_default();
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return -1;
        }
        int r = sr_cli_common_parse(PROG, argc, argv, &i, &c->common);
        if (r == 2)
            return 2;
        if (r == 1)
            continue;
        if (strncmp(a, "--", 2) != 0)
            return sr_cli_bad(PROG, a, NULL, "unexpected argument");
        if (!strcmp(a, "--progressive")) { /* the one option without a value */
            c->opt.progressive = 1;
            continue;
        }
        if (i + 1 >= argc)
            return sr_cli_bad(PROG, a, NULL, "needs a value");
        const char *v = argv[++i];
        int k;
        if (!strcmp(a, "--photons")) {
            if (!sr_cli_uint(v, 1, 1u << 26, &c->opt.photons))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 1 to 67108864");
            c->have_photons = 1;
        } else if (!strcmp(a, "--k")) {
            if (!sr_cli_uint(v, 1, 65536, &c->opt.k))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 1 to 65536");
            c->have_k = 1;
        } else if (!strcmp(a, "--max-radius")) {
            double r;
            if (!sr_cli_double(v, 1e-30, 1e30, &r))
                return sr_cli_bad(PROG, a, v, "expected a positive number");
            c->opt.max_radius = (float)r;
        } else if (!strcmp(a, "--map")) {
            if ((k = sr_cli_choice(v, (const char *const[]){"count", "bitonic", "stencil", NULL})) <
                0)
                return sr_cli_bad(PROG, a, v, "expected count, bitonic or stencil");
            c->opt.map = k == 0 ? SR_POINT_GRID_COUNT
                                : (k == 1 ? SR_POINT_GRID_BITONIC : SR_POINT_GRID_STENCIL);
        } else if (!strcmp(a, "--slots")) {
            if (!sr_cli_uint(v, 1, SR_POINT_GRID_MAX_SLOTS, &c->opt.slots))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 1 to 65536");
        } else if (!strcmp(a, "--grid")) {
            unsigned d[3];
            char x1, x2;
            int n = 0;
            if (!strcmp(v, "auto")) {
                memset(c->opt.grid_dims, 0, sizeof c->opt.grid_dims);
                c->have_grid = 0;
            } else if (sscanf(v, "%u%c%u%c%u%n", &d[0], &x1, &d[1], &x2, &d[2], &n) == 5 &&
                       (size_t)n == strlen(v) && x1 == 'x' && x2 == 'x' && v[0] != '-' && d[0] &&
                       d[1] && d[2] && d[0] <= 4096 && d[1] <= 4096 && d[2] <= 4096 &&
                       (unsigned long long)d[0] * d[1] * d[2] <= (1u << 26)) {
                memcpy(c->opt.grid_dims, d, sizeof d);
                c->have_grid = 1;
            } else {
                return sr_cli_bad(PROG, a, v,
                                  "expected auto or WxHxD (1 .. 4096 each, at most 2^26 cells)");
            }
        } else if (!strcmp(a, "--knn")) {
            if ((k = sr_cli_choice(v, (const char *const[]){"atleast", "exact", NULL})) < 0)
                return sr_cli_bad(PROG, a, v, "expected atleast or exact");
            c->opt.knn = k ? PM_KNN_EXACT : PM_KNN_ATLEAST;
        } else if (!strcmp(a, "--spp")) {
            if (!sr_cli_uint(v, 1, 1u << 20, &c->spp))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 1 to 1048576");
            c->have_spp = 1;
        } else if (!strcmp(a, "--light-samples")) {
            if (!sr_cli_uint(v, 1, 1024, &c->opt.light_samples))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 1 to 1024");
            c->have_ls = 1;
        } else if (!strcmp(a, "--max-depth")) {
            if (!sr_cli_uint(v, 0, 64, &c->opt.max_depth))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 0 to 64");
            c->have_depth = 1;
        } else if (!strcmp(a, "--exec")) {
            if ((k = sr_cli_choice(v, (const char *const[]){"stream", "fused", NULL})) < 0)
                return sr_cli_bad(PROG, a, v, "expected stream or fused");
            c->opt.tracer.exec = k ? RT_EXEC_FUSED : RT_EXEC_STREAM;
        } else if (!strcmp(a, "--shells-per-pass")) {
            if (!strcmp(v, "all"))
                c->opt.shells_per_pass = PM_KNN_ALL_SHELLS;
            else if (!sr_cli_uint(v, 1, 1u << 20, &c->opt.shells_per_pass))
                return sr_cli_bad(PROG, a, v, "expected all or a whole number from 1 to 1048576");
        } else if (!strcmp(a, "--alpha")) {
            double al;
            if (!sr_cli_double(v, 1e-6, 1.0 - 1e-6, &al))
                return sr_cli_bad(PROG, a, v, "expected a number between 0 and 1");
            c->opt.alpha = (float)al;
        } else if (!strcmp(a, "--photon-grid")) {
            if ((k = sr_cli_choice(v, (const char *const[]){"dense", "hash", "auto", NULL})) < 0)
                return sr_cli_bad(PROG, a, v, "expected dense, hash or auto");
            c->opt.photon_grid = k == 0   ? SR_POINT_GRID_DENSE
                                 : k == 1 ? SR_POINT_GRID_HASHED
                                          : SR_POINT_GRID_LAYOUT_AUTO;
        } else if (!strcmp(a, "--pass-images")) {
            if ((k = sr_cli_image_path(PROG, a, v)) != 0)
                return k;
            c->pass_images = v;
        } else {
            return sr_cli_bad(PROG, a, NULL, "unknown option");
        }
    }
    if (c->opt.photon_grid == SR_POINT_GRID_HASHED) {
        /* only the progressive radius search reads a hashed map, and only
         * the compact builds list a bucket whole (Purcell 6.4.4) */
        if (!c->opt.progressive)
            return sr_cli_bad(PROG, "--photon-grid", "hash",
                              "needs --progressive (the k-nearest searches need the dense grid)");
        if (c->have_grid)
            return sr_cli_bad(PROG, "--photon-grid", "hash",
                              "cannot take --grid WxHxD (the dimensions of a dense grid)");
        if (c->opt.map == SR_POINT_GRID_STENCIL)
            return sr_cli_bad(PROG, "--photon-grid", "hash",
                              "cannot take --map stencil (its power redistribution is per cell)");
    }
    if (c->common.no_image && c->pass_images)
        return sr_cli_bad(PROG, "--no-image", NULL, "writes no image: leave out --pass-images");
    return sr_cli_common_finish(PROG, &c->common);
}

typedef struct run {
    pm_renderer *r;
    const char *out;
    char err[1024];
} run;

static sluice_status sample(void *user)
{
    run *u = user;
    sluice_status st = pm_renderer_sample(u->r, u->err, sizeof u->err);
    if (st != SLUICE_OK)
        fprintf(stderr, PROG ": %s\n", u->err);
    return st;
}

static sluice_status write_image(run *u, size_t *bad)
{
    char err[512] = "";
    sluice_status st = rt_renderer_write(pm_renderer_whitted(u->r), u->out, bad, err, sizeof err);
    if (st != SLUICE_OK)
        fprintf(stderr, PROG ": writing %s: %s\n", u->out ? u->out : "the image",
                err[0] ? err : sluice_status_string(st));
    return st;
}

static sluice_status checkpoint(void *user)
{
    return write_image(user, NULL);
}

static int estimate(void *user, double *error)
{
    run *u = user;
    rt_renderer *w = pm_renderer_whitted(u->r);
    *error = rt_renderer_sampling(w)->error;
    return rt_renderer_done(w);
}

/* --pass-images: the pattern with -NNNN before its extension. */
static sluice_status write_pass_image(void *user, const sr_image *img, unsigned index, char *err,
                                      size_t err_size)
{
    const char *pattern = user;
    const char *dot = strrchr(pattern, '.');
    char path[4096];
    int n = snprintf(path, sizeof path, "%.*s-%04u%s", (int)(dot - pattern), pattern, index, dot);
    if (n < 0 || (size_t)n >= sizeof path) {
        snprintf(err, err_size, "--pass-images %s: the file name is too long", pattern);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    char why[512] = "";
    sluice_status st = sr_image_write(img, path, why, sizeof why);
    if (st != SLUICE_OK)
        snprintf(err, err_size, "--pass-images: writing %s: %s", path,
                 why[0] ? why : sluice_status_string(st));
    return st;
}

static const char *const map_names[] = {"count", "bitonic", "stencil"};

/* The statistics as text (table) or JSON (same figures). */
static void report(FILE *f, int json, const cli *c, const pm_options *o, pm_renderer *r,
                   double setup, double total, unsigned spp, sluice_context *ctx)
{
    const pm_stats *s = pm_renderer_stats(r);
    const pm_photon_stats *p = &s->photons;
    const sr_point_grid_stats *m = &s->map;
    const rt_trace_stats *ts = rt_tracer_stats(pm_renderer_tracer(r));
    const rt_render_stats *rs = rt_renderer_stats(pm_renderer_whitted(r));
    double mean_found = s->queries ? (double)s->found / (double)s->queries : 0;
    double mean_radius = s->with_photons ? s->radius_sum / (double)s->with_photons : 0;
    const rt_grid_desc *g = &s->map_grid;
    unsigned passes = s->samples ? s->knn_passes / s->samples : 0;
    if (!json) {
        fprintf(f, "scene %s, %ux%u, %u spp, map %s, kNN %s, k %u, max radius %g\n",
                c->common.scene, o->width, o->height, spp, map_names[o->map],
                o->progressive ? "radius (progressive)"
                               : (o->knn == PM_KNN_EXACT ? "exact" : "atleast"),
                o->k, (double)s->max_radius);
        fprintf(f,
                "phases (s): trace photons %.3f, build map %.3f, trace rays %.3f, radiance "
                "estimate %.3f, total %.3f; before them, setup %.3f (the renderer made, its "
                "kernels built)\n",
                s->trace_photons_s, s->build_map_s, s->trace_rays_s, s->estimate_s, total, setup);
        fprintf(f,
                "photons: emitted %llu, stored %llu (caustic %llu), left the scene %llu, "
                "absorbed %llu, depth limit %llu, %u bounce passes in %u batches\n",
                (unsigned long long)p->emitted, (unsigned long long)p->stored,
                (unsigned long long)p->caustic, (unsigned long long)p->left_scene,
                (unsigned long long)p->absorbed, (unsigned long long)p->depth_limit, p->passes,
                p->batches);
        if (s->map_layout == SR_POINT_GRID_HASHED)
            fprintf(f,
                    "photon map: hash grid, cells %.4g, %u buckets, occupied buckets %zu, per "
                    "bucket max %u mean %.1f\n",
                    (double)s->map_hash.cell, s->map_hash.buckets, m->occupied_cells,
                    m->max_per_cell, m->mean_per_occupied);
        else
            fprintf(f,
                    "photon map: grid %ux%ux%u, occupied cells %zu, per cell max %u mean %.1f, "
                    "stencil overflow %zu photons in %zu cells\n",
                    g->dims[0], g->dims[1], g->dims[2], m->occupied_cells, m->max_per_cell,
                    m->mean_per_occupied, m->overflow_points, m->overfull_cells);
        fprintf(f, "photon map layout: dense %u, hash %u of %u maps; the last one %s\n",
                s->maps_dense, s->maps_hashed, s->maps_dense + s->maps_hashed, s->map_why);
        fprintf(f,
                "estimates: %llu, photons per estimate %.1f, mean radius %.4g, at max radius "
                "%llu, kNN passes per sample %u, live after pass:",
                (unsigned long long)s->queries, mean_found, mean_radius,
                (unsigned long long)s->hit_max_radius, passes);
        for (unsigned i = 0; i < PM_KNN_STATS_PASSES && s->live[i]; ++i)
            fprintf(f, " %u", s->live[i]);
        fprintf(f,
                "\nrays: eye %llu, shadow %llu, reflection %llu, refraction %llu, photon "
                "flights %llu; traced %llu\n",
                (unsigned long long)rs->rays[RT_KIND_EYE],
                (unsigned long long)rs->rays[RT_KIND_SHADOW],
                (unsigned long long)rs->rays[RT_KIND_REFLECT],
                (unsigned long long)rs->rays[RT_KIND_REFRACT],
                (unsigned long long)(p->emitted + p->bounced), (unsigned long long)ts->rays);
        if (s->pass_images)
            fprintf(f,
                    "intermediate images: %u written in %.3f s (left out of the phases, counted "
                    "in the total)\n",
                    s->pass_images, s->pass_images_s);
        if (o->progressive)
            fprintf(f,
                    "progressive: alpha %g, radius of the last sample %.4g (r_0 %.4g, "
                    "r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1))\n",
                    (double)o->alpha, (double)s->radius, (double)s->radius0);
        fprintf(f, "skipped: %s\n", pm_renderer_skipped(r));
        sr_adaptive_print(rt_renderer_sampling(pm_renderer_whitted(r)), f);
        if (sluice_profile_enabled(ctx))
            sluice_profile_print(ctx, f);
        return;
    }
    sluice_device_info dev = {0};
    sluice_context_device(ctx, &dev);
    fprintf(f, "{\n  \"program\": \"" PROG "\",\n  \"device\": ");
    sr_json_string(f, dev.name);
    fprintf(f, ",\n  \"scene\": ");
    sr_json_string(f, c->common.scene);
    fprintf(f,
            ",\n  \"width\": %u, \"height\": %u, \"spp\": %u, \"map\": \"%s\", \"knn\": "
            "\"%s\", \"k\": %u, \"max_radius\": %g,\n",
            o->width, o->height, spp, map_names[o->map],
            o->progressive ? "radius" : (o->knn == PM_KNN_EXACT ? "exact" : "atleast"), o->k,
            (double)s->max_radius);
    if (o->progressive)
        fprintf(f, "  \"progressive\": {\"alpha\": %g, \"radius0\": %g, \"radius\": %g},\n",
                (double)o->alpha, (double)s->radius0, (double)s->radius);
    fprintf(f,
            "  \"phases\": {\"trace_photons\": %.6f, \"build_map\": %.6f, \"trace_rays\": %.6f, "
            "\"radiance_estimate\": %.6f, \"total\": %.6f},\n",
            s->trace_photons_s, s->build_map_s, s->trace_rays_s, s->estimate_s, total);
    fprintf(f, "  \"setup_s\": %.6f,\n", setup);
    fprintf(f,
            "  \"photons\": {\"emitted\": %llu, \"stored\": %llu, \"caustic\": %llu, "
            "\"left_scene\": %llu, \"absorbed\": %llu, \"depth_limit\": %llu, \"nonfinite\": "
            "%llu, \"passes\": %u, \"batches\": %u},\n",
            (unsigned long long)p->emitted, (unsigned long long)p->stored,
            (unsigned long long)p->caustic, (unsigned long long)p->left_scene,
            (unsigned long long)p->absorbed, (unsigned long long)p->depth_limit,
            (unsigned long long)p->nonfinite, p->passes, p->batches);
    fprintf(f,
            "  \"map_grid\": {\"dims\": [%u, %u, %u], \"cells\": %zu, \"occupied\": %zu, "
            "\"max_per_cell\": %u, \"mean_per_occupied\": %.3f, \"overflow_points\": %zu, "
            "\"overfull_cells\": %zu},\n",
            g->dims[0], g->dims[1], g->dims[2], m->cells, m->occupied_cells, m->max_per_cell,
            m->mean_per_occupied, m->overflow_points, m->overfull_cells);
    /* the why strings hold no quotes or backslashes */
    fprintf(f,
            "  \"map_layout\": {\"last\": \"%s\", \"dense\": %u, \"hash\": %u, "
            "\"hash_cell\": %g, \"hash_buckets\": %u, \"why\": \"%s\"},\n",
            s->map_layout == SR_POINT_GRID_HASHED ? "hash" : "dense", s->maps_dense, s->maps_hashed,
            (double)s->map_hash.cell, s->map_hash.buckets, s->map_why);
    fprintf(f,
            "  \"estimates\": {\"count\": %llu, \"mean_photons\": %.3f, \"mean_radius\": %.6g, "
            "\"hit_max_radius\": %llu, \"passes\": %u, \"live_per_pass\": [",
            (unsigned long long)s->queries, mean_found, mean_radius,
            (unsigned long long)s->hit_max_radius, s->knn_passes);
    for (unsigned i = 0; i < PM_KNN_STATS_PASSES && s->live[i]; ++i)
        fprintf(f, "%s%u", i ? ", " : "", s->live[i]);
    fprintf(f,
            "]},\n  \"rays\": {\"eye\": %llu, \"shadow\": %llu, \"reflection\": %llu, "
            "\"refraction\": %llu, \"traced\": %llu},\n",
            (unsigned long long)rs->rays[RT_KIND_EYE], (unsigned long long)rs->rays[RT_KIND_SHADOW],
            (unsigned long long)rs->rays[RT_KIND_REFLECT],
            (unsigned long long)rs->rays[RT_KIND_REFRACT], (unsigned long long)ts->rays);
    fprintf(f, "  \"pass_images\": {\"count\": %u, \"seconds\": %.6f},\n", s->pass_images,
            s->pass_images_s);
    sr_adaptive_write_json(rt_renderer_sampling(pm_renderer_whitted(r)), f, 2);
    fprintf(f, ",\n");
    fprintf(f, "  \"skipped\": ");
    sr_json_string(f, pm_renderer_skipped(r));
    fprintf(f, ",\n");
    sr_json_kernels(f, ctx, 2);
    fprintf(f, "\n}\n");
}

int main(int argc, char **argv)
{
    cli c;
    int rc = parse(argc, argv, &c);
    if (rc)
        return rc < 0 ? 0 : rc;
    const sr_cli_common *cc = &c.common;
    char err[1024] = "";
    sr_scene *scene = NULL;
    if (sr_cli_load_scene(PROG, cc, &scene))
        return 1;
    sluice_status st = SLUICE_OK;
    const sr_render_settings *rs = sr_scene_render_settings(scene);
    const sr_camera *cam = sr_scene_camera(scene);
    pm_options *o = &c.opt;
    o->width = cc->width ? cc->width : cam->width;
    o->height = cc->height ? cc->height : cam->height;
    o->seed = cc->seed;
    o->sampling = sr_cli_sampling(cc);
    if (!c.have_photons && rs->photons)
        o->photons = rs->photons;
    if (!c.have_k && rs->photon_lookup)
        o->k = rs->photon_lookup;
    if (!c.have_ls)
        o->light_samples = rs->light_samples ? rs->light_samples : 1;
    if (!c.have_depth)
        o->max_depth = rs->max_depth;
    unsigned spp = c.have_spp ? c.spp : 1;
    if ((cc->time_limit > 0 || cc->target_error > 0) && !c.have_spp)
        spp = 1u << 20; /* as many as the time or the target allows */

    if (c.pass_images) {
        o->pass_image = write_pass_image;
        o->pass_image_user = (void *)c.pass_images;
    }

    sluice_context *ctx = NULL;
    pm_renderer *r = NULL;
    int exit_code = 1;
    if (sr_cli_context(PROG, cc, &ctx))
        goto done;
    double setup = sr_clock_seconds();
    st = pm_renderer_create(ctx, scene, o, &r, err, sizeof err);
    setup = sr_clock_seconds() - setup;
    if (st != SLUICE_OK) {
        fprintf(stderr, PROG ": %s\n", err);
        goto done;
    }
    if (sr_cli_images_ready(PROG, cc))
        goto done;
    if (cc->profile)
        sluice_profile_reset(ctx);
    double t0 = sr_clock_seconds();
    if (cc->progress)
        fprintf(stderr, PROG ": tracing %u photons and building the photon map\n", o->photons);
    st = pm_renderer_prepare(r, err, sizeof err);
    if (st != SLUICE_OK) {
        fprintf(stderr, PROG ": %s\n", err);
        goto done;
    }
    run u;
    memset(&u, 0, sizeof u);
    u.r = r;
    u.out = cc->no_image ? NULL : cc->out;
    sr_progressive prog = {"samples",    spp,    cc->time_limit,   cc->checkpoint,
                           cc->progress, stderr, cc->target_error, estimate};
    sr_progressive_result pr;
    st = sr_progressive_run(&prog, sample, checkpoint, &u, &pr);
    if (st != SLUICE_OK)
        goto done;
    sr_progressive_report_target(PROG, &prog, &pr, stderr);
    double total = sr_clock_seconds() - t0;
    size_t bad = 0;
    if (write_image(&u, &bad) != SLUICE_OK)
        goto done;
    if (cc->sample_map && rt_renderer_write_sample_map(pm_renderer_whitted(r), cc->sample_map, err,
                                                       sizeof err) != SLUICE_OK) {
        fprintf(stderr, PROG ": --sample-map %s: %s\n", cc->sample_map, err);
        goto done;
    }
    if (bad)
        fprintf(stderr, PROG ": warning: %zu non-finite pixels %s\n", bad,
                cc->no_image ? "(no image written)" : "written as black");
    if (!cc->quiet)
        report(stderr, 0, &c, o, r, setup, total, pr.done, ctx);
    if (cc->stats) {
        FILE *f = fopen(cc->stats, "w");
        if (!f) {
            fprintf(stderr, PROG ": --stats %s: cannot write the file\n", cc->stats);
            goto done;
        }
        report(f, 1, &c, o, r, setup, total, pr.done, ctx);
        if (fclose(f) != 0) {
            fprintf(stderr, PROG ": --stats %s: write failed\n", cc->stats);
            goto done;
        }
    }
    if (pr.interrupted)
        fprintf(stderr, PROG ": interrupted after %u of %u samples; wrote %s\n", pr.done, spp,
                cc->no_image ? "no image (--no-image)" : cc->out);
    exit_code = pr.interrupted ? 130 : 0;
done:
    pm_renderer_destroy(r);
    sluice_context_destroy(ctx);
    sr_scene_destroy(scene);
    return exit_code;
}
