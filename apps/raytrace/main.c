/*
 * sluice-raytrace: Purcell's streaming ray tracer (thesis ch. 3 and 5) on
 * Sluice. Parses the command line, loads the scene, renders samples with
 * progress and checkpoints, writes the image and the statistics.
 */
#include "cli.h"
#include "progressive.h"
#include "skipped.h"
#include "render.h"
#include "stats.h"
#include "tracer.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

#define PROG "sluice-raytrace"

static void usage(FILE *out)
{
    fprintf(out, "usage: " PROG " [options]\n"
                 "Renders a scene with Purcell's streaming ray tracer (uniform grid, 3D-DDA,\n"
                 "conditional output streams) on OpenCL. Scenes that ask for photon mapping are\n"
                 "rendered by sluice-photonmap.\n\n");
    sr_cli_common_usage(out);
    fprintf(
        out,
        "\nray tracer options:\n"
        "  --mode M                 cast | shadow | whitted | path (default: the scene's\n"
        "                           suggestion, else shadow)\n"
        "  --exec E                 stream (multipass, Purcell 4.1.2) | fused (default stream)\n"
        "  --intersector I          mt (Moller-Trumbore) | watertight (default mt)\n"
        "  --spp N                  samples per pixel (default: the scene's; with --time and\n"
        "                           no --spp, as many as the time allows)\n"
        "  --light-samples N        shadow rays per area light and hit (default: the scene's)\n"
        "  --max-depth N            bounces in whitted and path modes (default: the scene's)\n"
        "  --grid-min-dim N|auto    voxels along the shortest axis, 1 .. 1024 (default auto:\n"
        "                           about %g voxels per triangle for meshes of %u\n"
        "                           triangles or more where most voxels stay empty,\n"
        "                           else %g; voxels no smaller than the lower quartile\n"
        "                           of the triangles' edges)\n"
        "  --grid-build B           device | host (default device)\n"
        "  --intersect-threshold F  stream mode: intersect when >= F of live rays need it\n"
        "                           (default 0.2)\n"
        "  --unroll-steps K         stream mode: voxels per traverse pass (default 32)\n"
        "  --unroll-tests M         stream mode: triangle tests per intersect pass (default 256)\n"
        "  --ordered                stream mode: ordered conditional outputs\n\n"
        "Ctrl-C finishes the current sample, writes the image so far and exits with 130.\n\n"
        "examples:\n"
        "  " PROG " --scene cornell --mode shadow --size 512x512 --out cornell.png\n"
        "  " PROG " --scene bunny --mode cast --exec fused --stats bunny.json\n"
        "  " PROG " --scene glassball --mode whitted --max-depth 8 --out glass.exr\n"
        "  " PROG " --scene cornell --mode path --spp 64 --progress --checkpoint 16\n"
        "  " PROG " --scene cornell --mode path --time 30 --out cornell-30s.png\n",
        RT_GRID_AUTO_DENSITY_SPARSE, RT_GRID_SPARSE_MIN_TRIANGLES, RT_GRID_AUTO_DENSITY);
}

typedef struct cli {
    sr_cli_common common;
    int mode; /* -1: scene's */
    rt_tracer_options topt;
    unsigned spp, light_samples, max_depth;
    int have_spp, have_ls, have_depth;
} cli;

static const char *const mode_names[] = {"cast", "shadow", "whitted", "path", NULL};

static int parse(int argc, char **argv, cli *c)
{
    memset(c, 0, sizeof *c);
    sr_cli_common_init(&c->common);
    c->mode = -1;
    c->topt = rt_tracer_options_default();
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
        if (!strcmp(a, "--ordered")) {
            c->topt.ordered = 1;
            continue;
        }
        if (strncmp(a, "--", 2) != 0)
            return sr_cli_bad(PROG, a, NULL, "unexpected argument");
        if (i + 1 >= argc)
            return sr_cli_bad(PROG, a, NULL, "needs a value");
        const char *v = argv[++i];
        unsigned u;
        int k;
        if (!strcmp(a, "--mode")) {
            if ((c->mode = sr_cli_choice(v, mode_names)) < 0)
                return sr_cli_bad(PROG, a, v, "expected cast, shadow, whitted or path");
        } else if (!strcmp(a, "--exec")) {
            if ((k = sr_cli_choice(v, (const char *const[]){"stream", "fused", NULL})) < 0)
                return sr_cli_bad(PROG, a, v, "expected stream or fused");
            c->topt.exec = k ? RT_EXEC_FUSED : RT_EXEC_STREAM;
        } else if (!strcmp(a, "--intersector")) {
            if ((k = sr_cli_choice(v, (const char *const[]){"mt", "watertight", NULL})) < 0)
                return sr_cli_bad(PROG, a, v, "expected mt or watertight");
            c->topt.intersector = k ? RT_ISECT_WATERTIGHT : RT_ISECT_MT;
        } else if (!strcmp(a, "--grid-build")) {
            if ((k = sr_cli_choice(v, (const char *const[]){"device", "host", NULL})) < 0)
                return sr_cli_bad(PROG, a, v, "expected device or host");
            c->topt.grid_build = k ? RT_GRID_BUILD_HOST : RT_GRID_BUILD_DEVICE;
        } else if (!strcmp(a, "--spp")) {
            if (!sr_cli_uint(v, 1, 1u << 20, &c->spp))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 1 to 1048576");
            c->have_spp = 1;
        } else if (!strcmp(a, "--light-samples")) {
            if (!sr_cli_uint(v, 1, 1024, &c->light_samples))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 1 to 1024");
            c->have_ls = 1;
        } else if (!strcmp(a, "--max-depth")) {
            if (!sr_cli_uint(v, 0, 64, &c->max_depth))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 0 to 64");
            c->have_depth = 1;
        } else if (!strcmp(a, "--grid-min-dim")) {
            if (!strcmp(v, "auto"))
                u = RT_GRID_AUTO_MIN_DIM;
            else if (!sr_cli_uint(v, 1, 1024, &u))
                return sr_cli_bad(PROG, a, v, "expected auto or a whole number from 1 to 1024");
            c->topt.grid_min_dim = u;
        } else if (!strcmp(a, "--unroll-steps")) {
            if (!sr_cli_uint(v, 1, 4096, &u))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 1 to 4096");
            c->topt.unroll_steps = u;
        } else if (!strcmp(a, "--unroll-tests")) {
            if (!sr_cli_uint(v, 1, 4096, &u))
                return sr_cli_bad(PROG, a, v, "expected a whole number from 1 to 4096");
            c->topt.unroll_tests = u;
        } else if (!strcmp(a, "--intersect-threshold")) {
            double f;
            if (!sr_cli_double(v, 0.0, 1.0, &f))
                return sr_cli_bad(PROG, a, v, "expected a number from 0 to 1");
            c->topt.intersect_threshold = (float)f;
        } else {
            return sr_cli_bad(PROG, a, NULL, "unknown option");
        }
    }
    return sr_cli_common_finish(PROG, &c->common);
}

/* What the progressive loop calls: one sample, a checkpoint image. */
typedef struct run {
    rt_renderer *rend;
    const char *out;
    sluice_context *ctx;
} run;

static sluice_status sample(void *user)
{
    run *r = user;
    sluice_status st = rt_renderer_sample(r->rend);
    if (st != SLUICE_OK)
        fprintf(stderr, PROG ": rendering: %s\n", sluice_context_error(r->ctx));
    return st;
}

static sluice_status write_image(run *r, size_t *bad_pixels)
{
    char err[512] = "";
    sluice_status st = rt_renderer_write(r->rend, r->out, bad_pixels, err, sizeof err);
    if (st != SLUICE_OK)
        fprintf(stderr, PROG ": writing %s: %s\n", r->out ? r->out : "the image",
                err[0] ? err : sluice_status_string(st));
    return st;
}

static sluice_status checkpoint(void *user)
{
    return write_image(user, NULL);
}

static int estimate(void *user, double *error)
{
    run *r = user;
    *error = rt_renderer_sampling(r->rend)->error;
    return rt_renderer_done(r->rend);
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
    if (c.mode < 0 && rs->mode == SR_RENDER_PHOTON) {
        fprintf(stderr,
                PROG ": --scene %s: the scene asks for photon mapping; render it with "
                     "sluice-photonmap, or give --mode to ray trace it\n",
                cc->scene);
        sr_scene_destroy(scene);
        return 2;
    }
    if (c.mode < 0) {
        switch (rs->mode) {
        case SR_RENDER_CAST:
            c.mode = RT_MODE_CAST;
            break;
        case SR_RENDER_WHITTED:
            c.mode = RT_MODE_WHITTED;
            break;
        case SR_RENDER_PATH:
            c.mode = RT_MODE_PATH;
            break;
        default:
            c.mode = RT_MODE_SHADOW;
            break;
        }
    }
    rt_render_options ro;
    memset(&ro, 0, sizeof ro);
    ro.mode = (unsigned)c.mode;
    ro.width = cc->width ? cc->width : cam->width;
    ro.height = cc->height ? cc->height : cam->height;
    ro.max_depth = c.have_depth ? c.max_depth : rs->max_depth;
    ro.light_samples = c.have_ls ? c.light_samples : (rs->light_samples ? rs->light_samples : 1);
    ro.seed = cc->seed;
    ro.sampling = sr_cli_sampling(cc);
    unsigned spp = c.have_spp ? c.spp : (rs->samples_per_pixel ? rs->samples_per_pixel : 1);
    if ((cc->time_limit > 0 || cc->target_error > 0) && !c.have_spp)
        spp = 1u << 20; /* as many as the time or the target allows */
    if ((unsigned long long)ro.width * ro.height > (1u << 26)) {
        fprintf(stderr, PROG ": --size %ux%u: too many pixels\n", ro.width, ro.height);
        sr_scene_destroy(scene);
        return 2;
    }

    sluice_context *ctx = NULL;
    rt_tracer *tracer = NULL;
    rt_renderer *rend = NULL;
    int exit_code = 1;
    if (sr_cli_context(PROG, cc, &ctx))
        goto done;
    st = rt_tracer_create(ctx, scene, &c.topt, &tracer, err, sizeof err);
    if (st == SLUICE_OK)
        st = rt_renderer_create(tracer, &ro, &rend, err, sizeof err);
    if (st != SLUICE_OK) {
        fprintf(stderr, PROG ": %s\n", err);
        goto done;
    }
    if (sr_cli_images_ready(PROG, cc))
        goto done;
    if (cc->profile)
        sluice_profile_reset(ctx);
    run r = {rend, cc->no_image ? NULL : cc->out, ctx};
    sr_progressive prog = {"samples",    spp,    cc->time_limit,   cc->checkpoint,
                           cc->progress, stderr, cc->target_error, estimate};
    sr_progressive_result pr;
    st = sr_progressive_run(&prog, sample, checkpoint, &r, &pr);
    if (st != SLUICE_OK)
        goto done;
    sr_progressive_report_target(PROG, &prog, &pr, stderr);
    size_t bad_pixels = 0;
    if (write_image(&r, &bad_pixels) != SLUICE_OK)
        goto done;
    if (cc->sample_map &&
        rt_renderer_write_sample_map(rend, cc->sample_map, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, PROG ": --sample-map %s: %s\n", cc->sample_map, err);
        goto done;
    }
    if (bad_pixels)
        fprintf(stderr, PROG ": warning: %zu non-finite pixels %s\n", bad_pixels,
                cc->no_image ? "(no image written)" : "written as black");

    char skipped[768];
    snprintf(skipped, sizeof skipped, "%s", rt_renderer_skipped(rend));
    sr_skipped_add(skipped, sizeof skipped, 1, rt_tracer_skipped(tracer));
    rt_stats_report rep;
    memset(&rep, 0, sizeof rep);
    rep.scene = cc->scene;
    rep.exec = c.topt.exec == RT_EXEC_FUSED ? "fused" : "stream";
    rep.mode = mode_names[ro.mode];
    rep.intersector = c.topt.intersector == RT_ISECT_WATERTIGHT ? "watertight" : "mt";
    rep.width = ro.width;
    rep.height = ro.height;
    rep.spp = pr.done;
    rep.seconds = pr.seconds;
    rep.bad_pixels = bad_pixels;
    rep.trace = rt_tracer_stats(tracer);
    rep.render = rt_renderer_stats(rend);
    rep.sampling = rt_renderer_sampling(rend);
    rep.grid = rt_tracer_grid(tracer);
    rep.scene_bytes = rt_tracer_scene_bytes(tracer);
    rep.tracer_stream_bytes = rt_tracer_stream_bytes(tracer);
    rep.skipped = skipped;
    rep.fused_path = rt_tracer_fused_path(tracer);
    rep.interrupted = pr.interrupted;
    if (!cc->quiet)
        rt_stats_print(&rep, ctx, stderr);
    if (cc->stats) {
        st = rt_stats_write_json(&rep, ctx, cc->stats, err, sizeof err);
        if (st != SLUICE_OK) {
            fprintf(stderr, PROG ": --stats: %s\n", err);
            goto done;
        }
    }
    if (pr.interrupted)
        fprintf(stderr, PROG ": interrupted after %u of %u samples; wrote %s\n", pr.done, spp,
                cc->no_image ? "no image (--no-image)" : cc->out);
    else if (pr.out_of_time)
        fprintf(stderr, PROG ": time limit: %u samples in %.1f s; wrote %s\n", pr.done, pr.seconds,
                cc->no_image ? "no image (--no-image)" : cc->out);
    exit_code = pr.interrupted ? 130 : 0;
done:
    rt_renderer_destroy(rend);
    rt_tracer_destroy(tracer);
    sluice_context_destroy(ctx);
    sr_scene_destroy(scene);
    return exit_code;
}
