/*
 * sluice-raytrace: Purcell's streaming ray tracer (thesis ch. 3 and 5) on
 * Sluice. Parses the command line, loads the scene, renders samples with
 * progress and checkpoints, writes the image and the statistics.
 */
#include "progress.h"
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
    fprintf(
        out,
        "usage: " PROG " [options]\n"
        "Renders a scene with Purcell's streaming ray tracer (uniform grid, 3D-DDA,\n"
        "conditional output streams) on OpenCL.\n\n"
        "  --scene NAME|FILE        built-in scene or scene/mesh file (default cornell)\n"
        "  --mode M                 cast | shadow | whitted | path (default: the scene's\n"
        "                           suggestion, else shadow)\n"
        "  --exec E                 stream (multipass, Purcell 4.1.2) | fused (default stream)\n"
        "  --intersector I          mt (Moller-Trumbore) | watertight (default mt)\n"
        "  --size WxH               image size (default: the scene camera's)\n"
        "  --spp N                  samples per pixel (default: the scene's)\n"
        "  --light-samples N        shadow rays per area light and hit (default: the scene's)\n"
        "  --max-depth N            bounces in whitted and path modes (default: the scene's)\n"
        "  --seed N                 random seed (default 1); same seed, same image\n"
        "  --out FILE               .png or .exr (default out.png)\n"
        "  --stats FILE             write the statistics as JSON\n"
        "  --grid-min-dim N|auto    voxels along the shortest axis, 1 .. 1024 (default auto:\n"
        "                           about %g voxels per triangle, voxels no smaller than\n"
        "                           the lower quartile of the triangles' edges)\n"
        "  --grid-build B           device | host (default device)\n"
        "  --intersect-threshold F  stream mode: intersect when >= F of live rays need it\n"
        "                           (default 0.2)\n"
        "  --unroll-steps K         stream mode: voxels per traverse pass (default 32)\n"
        "  --unroll-tests M         stream mode: triangle tests per intersect pass (default 64)\n"
        "  --ordered                stream mode: ordered conditional outputs\n"
        "  --progress               progress bar with ETA on stderr\n"
        "  --checkpoint N           write the image every N samples\n"
        "  --device NAME            OpenCL device (substring of \"platform / device\")\n"
        "  --no-profile             do not time kernels\n"
        "  --quiet                  no statistics table\n"
        "  --help                   this text\n\n"
        "Ctrl-C finishes the current sample, writes the image so far and exits with 130.\n\n"
        "examples:\n"
        "  " PROG " --scene cornell --mode shadow --size 512x512 --out cornell.png\n"
        "  " PROG " --scene bunny --mode cast --exec fused --stats bunny.json\n"
        "  " PROG " --scene glassball --mode whitted --max-depth 8 --out glass.exr\n"
        "  " PROG " --scene cornell --mode path --spp 64 --progress --checkpoint 16\n",
        RT_GRID_AUTO_DENSITY);
}

static int bad(const char *opt, const char *value, const char *why)
{
    fprintf(stderr, PROG ": %s %s: %s (see --help)\n", opt, value ? value : "", why);
    return 2;
}

static int parse_uint(const char *s, unsigned lo, unsigned hi, unsigned *out)
{
    if (!s || !*s || *s == '-' || *s == '+')
        return 0;
    char *end;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (errno || *end || v < lo || v > hi)
        return 0;
    *out = (unsigned)v;
    return 1;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct cli {
    const char *scene, *out, *stats, *device;
    int mode; /* -1: scene's */
    rt_tracer_options topt;
    unsigned width, height, spp, light_samples, max_depth, seed, checkpoint;
    int have_spp, have_ls, have_depth, progress, profile, quiet;
} cli;

static const char *const mode_names[] = {"cast", "shadow", "whitted", "path"};

static int parse(int argc, char **argv, cli *c)
{
    memset(c, 0, sizeof *c);
    c->scene = "cornell";
    c->out = "out.png";
    c->mode = -1;
    c->topt = rt_tracer_options_default();
    c->seed = 1;
    c->profile = 1;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return -1;
        }
        if (!strcmp(a, "--progress")) {
            c->progress = 1;
            continue;
        }
        if (!strcmp(a, "--ordered")) {
            c->topt.ordered = 1;
            continue;
        }
        if (!strcmp(a, "--no-profile")) {
            c->profile = 0;
            continue;
        }
        if (!strcmp(a, "--quiet")) {
            c->quiet = 1;
            continue;
        }
        if (strncmp(a, "--", 2) != 0)
            return bad(a, NULL, "unexpected argument");
        if (i + 1 >= argc)
            return bad(a, NULL, "needs a value");
        const char *v = argv[++i];
        unsigned u;
        if (!strcmp(a, "--scene")) {
            c->scene = v;
        } else if (!strcmp(a, "--out")) {
            c->out = v;
        } else if (!strcmp(a, "--stats")) {
            c->stats = v;
        } else if (!strcmp(a, "--device")) {
            c->device = v;
        } else if (!strcmp(a, "--mode")) {
            c->mode = -2;
            for (int m = 0; m < 4; ++m)
                if (!strcmp(v, mode_names[m]))
                    c->mode = m;
            if (c->mode == -2)
                return bad(a, v, "expected cast, shadow, whitted or path");
        } else if (!strcmp(a, "--exec")) {
            if (!strcmp(v, "stream"))
                c->topt.exec = RT_EXEC_STREAM;
            else if (!strcmp(v, "fused"))
                c->topt.exec = RT_EXEC_FUSED;
            else
                return bad(a, v, "expected stream or fused");
        } else if (!strcmp(a, "--intersector")) {
            if (!strcmp(v, "mt"))
                c->topt.intersector = RT_ISECT_MT;
            else if (!strcmp(v, "watertight"))
                c->topt.intersector = RT_ISECT_WATERTIGHT;
            else
                return bad(a, v, "expected mt or watertight");
        } else if (!strcmp(a, "--grid-build")) {
            if (!strcmp(v, "device"))
                c->topt.grid_build = RT_GRID_BUILD_DEVICE;
            else if (!strcmp(v, "host"))
                c->topt.grid_build = RT_GRID_BUILD_HOST;
            else
                return bad(a, v, "expected device or host");
        } else if (!strcmp(a, "--size")) {
            unsigned w, h;
            char x;
            int n = 0;
            if (sscanf(v, "%u%c%u%n", &w, &x, &h, &n) != 3 || (size_t)n != strlen(v) ||
                (x != 'x' && x != 'X') || v[0] == '-')
                return bad(a, v, "expected WxH, e.g. 512x512");
            if (w == 0 || h == 0 || w > 16384 || h > 16384 ||
                (unsigned long long)w * h > (1u << 26))
                return bad(a, v, "size out of range (1 .. 16384 per side, at most 2^26 pixels)");
            c->width = w;
            c->height = h;
        } else if (!strcmp(a, "--spp")) {
            if (!parse_uint(v, 1, 1u << 20, &c->spp))
                return bad(a, v, "expected a whole number from 1 to 1048576");
            c->have_spp = 1;
        } else if (!strcmp(a, "--light-samples")) {
            if (!parse_uint(v, 1, 1024, &c->light_samples))
                return bad(a, v, "expected a whole number from 1 to 1024");
            c->have_ls = 1;
        } else if (!strcmp(a, "--max-depth")) {
            if (!parse_uint(v, 0, 64, &c->max_depth))
                return bad(a, v, "expected a whole number from 0 to 64");
            c->have_depth = 1;
        } else if (!strcmp(a, "--seed")) {
            if (!parse_uint(v, 0, UINT_MAX, &c->seed))
                return bad(a, v, "expected a whole number from 0 to 4294967295");
        } else if (!strcmp(a, "--checkpoint")) {
            if (!parse_uint(v, 1, 1u << 20, &c->checkpoint))
                return bad(a, v, "expected a whole number from 1 to 1048576");
        } else if (!strcmp(a, "--grid-min-dim")) {
            if (!strcmp(v, "auto"))
                u = RT_GRID_AUTO_MIN_DIM;
            else if (!parse_uint(v, 1, 1024, &u))
                return bad(a, v, "expected auto or a whole number from 1 to 1024");
            c->topt.grid_min_dim = u;
        } else if (!strcmp(a, "--unroll-steps")) {
            if (!parse_uint(v, 1, 4096, &u))
                return bad(a, v, "expected a whole number from 1 to 4096");
            c->topt.unroll_steps = u;
        } else if (!strcmp(a, "--unroll-tests")) {
            if (!parse_uint(v, 1, 4096, &u))
                return bad(a, v, "expected a whole number from 1 to 4096");
            c->topt.unroll_tests = u;
        } else if (!strcmp(a, "--intersect-threshold")) {
            char *end;
            errno = 0;
            double f = strtod(v, &end);
            if (errno || *end || !*v || !(f >= 0.0 && f <= 1.0))
                return bad(a, v, "expected a number from 0 to 1");
            c->topt.intersect_threshold = (float)f;
        } else {
            return bad(a, NULL, "unknown option");
        }
    }
    const char *dot = strrchr(c->out, '.');
    if (!dot || (strcasecmp(dot, ".png") != 0 && strcasecmp(dot, ".exr") != 0 &&
                 strcasecmp(dot, ".hdr") != 0))
        return bad("--out", c->out, "the file name must end in .png, .exr or .hdr");
    return 0;
}

static int write_image(rt_renderer *r, sr_image *img, const char *path, size_t *bad_pixels)
{
    char err[512] = "";
    sluice_status st = rt_renderer_image(r, img, bad_pixels);
    if (st == SLUICE_OK)
        st = sr_image_write(img, path, err, sizeof err);
    if (st != SLUICE_OK) {
        fprintf(stderr, PROG ": writing %s: %s\n", path, err[0] ? err : sluice_status_string(st));
        return 1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    cli c;
    int rc = parse(argc, argv, &c);
    if (rc)
        return rc < 0 ? 0 : rc;

    char err[1024] = "";
    sr_scene_load_options lo;
    memset(&lo, 0, sizeof lo);
    lo.flags = SR_SCENE_DEFAULT_LIGHT;
    sr_scene *scene = NULL;
    sluice_status st = sr_scene_load(c.scene, &lo, &scene, err, sizeof err);
    if (st != SLUICE_OK) {
        fprintf(stderr, PROG ": --scene %s: %s\n", c.scene, err);
        return 1;
    }
    const sr_render_settings *rs = sr_scene_render_settings(scene);
    const sr_camera *cam = sr_scene_camera(scene);
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
    ro.width = c.width ? c.width : cam->width;
    ro.height = c.height ? c.height : cam->height;
    ro.max_depth = c.have_depth ? c.max_depth : rs->max_depth;
    ro.light_samples = c.have_ls ? c.light_samples : (rs->light_samples ? rs->light_samples : 1);
    ro.seed = c.seed;
    unsigned spp = c.have_spp ? c.spp : (rs->samples_per_pixel ? rs->samples_per_pixel : 1);
    if ((unsigned long long)ro.width * ro.height > (1u << 26)) {
        fprintf(stderr, PROG ": --size %ux%u: too many pixels\n", ro.width, ro.height);
        sr_scene_destroy(scene);
        return 2;
    }

    sluice_context_options co;
    memset(&co, 0, sizeof co);
    co.device = c.device;
    co.profile = c.profile;
    sluice_context *ctx = NULL;
    rt_tracer *tracer = NULL;
    rt_renderer *rend = NULL;
    sr_image *img = NULL;
    int exit_code = 1;
    st = sluice_context_create(&co, &ctx, err, sizeof err);
    if (st != SLUICE_OK) {
        fprintf(stderr, PROG ": OpenCL: %s\n", err);
        goto done;
    }
    st = rt_tracer_create(ctx, scene, &c.topt, &tracer, err, sizeof err);
    if (st == SLUICE_OK)
        st = rt_renderer_create(tracer, &ro, &rend, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_image_create(ro.width, ro.height, 3, &img, err, sizeof err);
    if (st != SLUICE_OK) {
        fprintf(stderr, PROG ": %s\n", err);
        goto done;
    }
    if (c.profile)
        sluice_profile_reset(ctx);
    rt_progress_install_sigint();
    double t0 = now();
    unsigned done_samples = 0;
    int interrupted = 0;
    for (unsigned s = 0; s < spp; ++s) {
        st = rt_renderer_sample(rend);
        if (st != SLUICE_OK) {
            fprintf(stderr, PROG ": rendering: %s\n", sluice_context_error(ctx));
            goto done;
        }
        ++done_samples;
        if (c.progress)
            rt_progress_report(stderr, done_samples, spp, now() - t0);
        if (c.checkpoint && done_samples % c.checkpoint == 0 && done_samples < spp)
            if (write_image(rend, img, c.out, NULL))
                goto done;
        if (rt_progress_interrupted()) {
            interrupted = 1;
            break;
        }
    }
    double seconds = now() - t0;
    if (c.progress)
        rt_progress_finish(stderr);
    size_t bad_pixels = 0;
    if (write_image(rend, img, c.out, &bad_pixels))
        goto done;
    if (bad_pixels)
        fprintf(stderr, PROG ": warning: %zu non-finite pixels written as black\n", bad_pixels);

    rt_stats_report rep;
    memset(&rep, 0, sizeof rep);
    rep.scene = c.scene;
    rep.exec = c.topt.exec == RT_EXEC_FUSED ? "fused" : "stream";
    rep.mode = mode_names[ro.mode];
    rep.intersector = c.topt.intersector == RT_ISECT_WATERTIGHT ? "watertight" : "mt";
    rep.width = ro.width;
    rep.height = ro.height;
    rep.spp = done_samples;
    rep.seconds = seconds;
    rep.bad_pixels = bad_pixels;
    rep.trace = rt_tracer_stats(tracer);
    rep.render = rt_renderer_stats(rend);
    rep.grid = rt_tracer_grid(tracer);
    rep.scene_bytes = rt_tracer_scene_bytes(tracer);
    rep.tracer_stream_bytes = rt_tracer_stream_bytes(tracer);
    char skipped[768];
    snprintf(skipped, sizeof skipped, "%s", rt_renderer_skipped(rend));
    sr_skipped_add(skipped, sizeof skipped, 1, rt_tracer_skipped(tracer));
    rep.skipped = skipped;
    rep.fused_path = rt_tracer_fused_path(tracer);
    rep.interrupted = interrupted;
    if (!c.quiet)
        rt_stats_print(&rep, ctx, stderr);
    if (c.stats) {
        st = rt_stats_write_json(&rep, ctx, c.stats, err, sizeof err);
        if (st != SLUICE_OK) {
            fprintf(stderr, PROG ": --stats: %s\n", err);
            goto done;
        }
    }
    if (interrupted)
        fprintf(stderr, PROG ": interrupted after %u of %u samples; wrote %s\n", done_samples, spp,
                c.out);
    exit_code = interrupted ? 130 : 0;
done:
    sr_image_destroy(img);
    rt_renderer_destroy(rend);
    rt_tracer_destroy(tracer);
    sluice_context_destroy(ctx);
    sr_scene_destroy(scene);
    return exit_code;
}
