/* See cli.h. */
#include "cli.h"

#include "data_path.h"
#include "image.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* The source tree's scenes/, recorded at build time (apps/render/meson.build). */
#ifndef SR_SCENES_SOURCE_DIR
#define SR_SCENES_SOURCE_DIR ""
#endif

void sr_cli_common_init(sr_cli_common *c)
{
    memset(c, 0, sizeof *c);
    c->scene = "cornell";
    c->out = "out.png";
    c->seed = 1;
    c->profile = 1;
    c->adaptive = 1;
}

int sr_cli_bad(const char *prog, const char *opt, const char *value, const char *why)
{
    fprintf(stderr, "%s: %s%s%s: %s (see --help)\n", prog, opt, value ? " " : "",
            value ? value : "", why);
    return 2;
}

int sr_cli_uint(const char *s, unsigned lo, unsigned hi, unsigned *out)
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

int sr_cli_double(const char *s, double lo, double hi, double *out)
{
    if (!s || !*s)
        return 0;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || *end || !isfinite(v) || !(v >= lo && v <= hi))
        return 0;
    *out = v;
    return 1;
}

int sr_cli_size(const char *s, unsigned *w, unsigned *h, const char **why)
{
    unsigned a, b;
    char x;
    int n = 0;
    if (!s || s[0] == '-' || sscanf(s, "%u%c%u%n", &a, &x, &b, &n) != 3 || (size_t)n != strlen(s) ||
        (x != 'x' && x != 'X')) {
        *why = "expected WxH, e.g. 512x512";
        return 0;
    }
    if (a == 0 || b == 0 || a > 16384 || b > 16384 || (unsigned long long)a * b > (1u << 26)) {
        *why = "size out of range (1 .. 16384 per side, at most 2^26 pixels)";
        return 0;
    }
    *w = a;
    *h = b;
    return 1;
}

int sr_cli_choice(const char *s, const char *const *names)
{
    for (int k = 0; s && names[k]; ++k)
        if (!strcmp(s, names[k]))
            return k;
    return -1;
}

int sr_cli_common_parse(const char *prog, int argc, char **argv, int *i, sr_cli_common *c)
{
    const char *a = argv[*i];
    static const struct {
        const char *name;
        size_t field;
    } flags[] = {{"--progress", offsetof(sr_cli_common, progress)},
                 {"--quiet", offsetof(sr_cli_common, quiet)},
                 {"--no-image", offsetof(sr_cli_common, no_image)}};
    for (size_t k = 0; k < sizeof flags / sizeof *flags; ++k)
        if (!strcmp(a, flags[k].name)) {
            *(int *)((char *)c + flags[k].field) = 1;
            return 1;
        }
    if (!strcmp(a, "--no-profile")) {
        c->profile = 0;
        return 1;
    }
    if (!strcmp(a, "--no-adaptive")) {
        c->adaptive = 0;
        return 1;
    }
    static const char *const valued[] = {"--scene",        "--out",     "--stats",      "--device",
                                         "--size",         "--seed",    "--checkpoint", "--time",
                                         "--target-error", "--min-spp", "--sample-map", NULL};
    int which = sr_cli_choice(a, valued);
    if (which < 0)
        return 0;
    if (*i + 1 >= argc)
        return sr_cli_bad(prog, a, NULL, "needs a value");
    const char *v = argv[++*i];
    const char *why = NULL;
    switch (which) {
    case 0:
        c->scene = v;
        break;
    case 1:
        c->out = v;
        c->out_given = 1;
        break;
    case 2:
        c->stats = v;
        break;
    case 3:
        c->device = v;
        break;
    case 4:
        if (!sr_cli_size(v, &c->width, &c->height, &why))
            return sr_cli_bad(prog, a, v, why);
        break;
    case 5:
        if (!sr_cli_uint(v, 0, UINT_MAX, &c->seed))
            return sr_cli_bad(prog, a, v, "expected a whole number from 0 to 4294967295");
        break;
    case 6:
        if (!sr_cli_uint(v, 1, 1u << 20, &c->checkpoint))
            return sr_cli_bad(prog, a, v, "expected a whole number from 1 to 1048576");
        break;
    case 7:
        if (!sr_cli_double(v, 1e-3, 1e7, &c->time_limit))
            return sr_cli_bad(prog, a, v, "expected seconds, from 0.001 to 10000000");
        break;
    case 8:
        if (!sr_cli_double(v, 1e-12, 1.0, &c->target_error))
            return sr_cli_bad(prog, a, v, "expected a relMSE above 0 and at most 1");
        break;
    case 9:
        if (!sr_cli_uint(v, 2, 1u << 20, &c->min_samples) || c->min_samples % 2)
            return sr_cli_bad(prog, a, v, "expected an even number from 2 to 1048576");
        break;
    default:
        c->sample_map = v;
        break;
    }
    return 1;
}

int sr_cli_output_path(const char *prog, const char *opt, const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!path[0] || (slash && !slash[1]))
        return sr_cli_bad(prog, opt, path, "expected a file name");
    char dir[PATH_MAX];
    if (sr_path_dir(path, dir, sizeof dir) != 0)
        return sr_cli_bad(prog, opt, path, "the path is too long");
    char why[PATH_MAX + 64];
    struct stat st;
    int found = stat(dir, &st) == 0, e = errno;
    if (!found || !S_ISDIR(st.st_mode)) {
        if (found)
            snprintf(why, sizeof why, "%s is not a folder", dir);
        else if (e == ENOENT || e == ENOTDIR)
            snprintf(why, sizeof why, "the folder %s does not exist", dir);
        else
            snprintf(why, sizeof why, "the folder %s: %s", dir, strerror(e));
        return sr_cli_bad(prog, opt, path, why);
    }
    if (access(dir, W_OK | X_OK) != 0) {
        snprintf(why, sizeof why, "the folder %s is not writable", dir);
        return sr_cli_bad(prog, opt, path, why);
    }
    if (stat(path, &st) == 0 && (S_ISDIR(st.st_mode) || access(path, W_OK) != 0))
        return sr_cli_bad(prog, opt, path,
                          S_ISDIR(st.st_mode) ? "names a folder, not a file"
                                              : "the file exists and is not writable");
    return 0;
}

int sr_cli_image_path(const char *prog, const char *opt, const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot || (strcasecmp(dot, ".png") != 0 && strcasecmp(dot, ".exr") != 0 &&
                 strcasecmp(dot, ".hdr") != 0))
        return sr_cli_bad(prog, opt, path, "the file name must end in .png, .exr or .hdr");
    return sr_cli_output_path(prog, opt, path);
}

int sr_cli_common_finish(const char *prog, const sr_cli_common *c)
{
    /* where the results go is checked before any rendering, so that a long
     * render does not end by failing to write them */
    if (c->stats && sr_cli_output_path(prog, "--stats", c->stats))
        return 2;
    if (c->no_image) {
        const char *writes = c->out_given    ? "--out"
                             : c->checkpoint ? "--checkpoint"
                             : c->sample_map ? "--sample-map"
                                             : NULL;
        char why[64];
        snprintf(why, sizeof why, "writes no image: leave out %s", writes ? writes : "");
        return writes ? sr_cli_bad(prog, "--no-image", NULL, why) : 0;
    }
    int rc = sr_cli_image_path(prog, "--out", c->out);
    if (!rc && c->sample_map)
        rc = sr_cli_image_path(prog, "--sample-map", c->sample_map);
    return rc;
}

void sr_cli_common_usage(FILE *out)
{
    fputs("  --scene NAME|FILE        built-in scene or scene/mesh file (default cornell); a\n"
          "                           bare file name not found here is looked up among the\n"
          "                           installed scenes (<datadir>/sluice/scenes)\n"
          "  --size WxH               image size (default: the scene camera's)\n"
          "  --seed N                 random seed (default 1); same seed, same image\n"
          "  --out FILE               image: .png (sRGB, 8-bit), .exr or .hdr (linear float)\n"
          "                           (default out.png)\n"
          "  --no-image               render and report (statistics, --stats), write no\n"
          "                           image: for timing, or where OpenImageIO is missing\n"
          "  --stats FILE             write the statistics as JSON\n"
          "  --progress               progress bar with ETA on stderr\n"
          "  --checkpoint N           write the image every N samples or passes\n"
          "  --time SECONDS           stop after this much rendering time (the image so far\n"
          "                           is written; at least one sample or pass runs)\n"
          "  --target-error E         stop once the image's relMSE, estimated from the\n"
          "                           render itself (all samples against the odd ones:\n"
          "                           noise, not bias), is at most E (with no --spp: up to\n"
          "                           2^20 samples). 8x8 tiles whose own estimate reaches E\n"
          "                           stop taking samples (adaptive sampling)\n"
          "  --no-adaptive            with --target-error, every pixel takes every sample\n"
          "  --min-spp N              samples before the first estimate (even, default 8)\n"
          "  --sample-map FILE        also write where the samples went: each pixel's\n"
          "                           samples over the most any tile took (grey, 0 to 1)\n"
          "  --device NAME            OpenCL device (substring of \"platform / device\")\n"
          "  --no-profile             do not time kernels\n"
          "  --quiet                  no statistics table\n"
          "  --help                   this text\n",
          out);
}

int sr_cli_load_scene(const char *prog, const sr_cli_common *c, sr_scene **out)
{
    char err[1024] = "", found[4096], tried[8192] = "";
    const char *path = c->scene;
    /* A bare file name that is neither a built-in scene nor a file here is
     * looked up among the installed scenes (<datadir>/sluice/scenes, found
     * relative to the program), then in the source tree's scenes/, so that
     * `--scene example.json` works from any folder. Paths inside the scene
     * (its meshes) resolve against the file found, as for any scene file. */
    if (!sr_scene_is_builtin(path) && !strchr(path, '/') && access(path, F_OK) != 0 &&
        sr_find_data_file("scenes", path, 0, SR_SCENES_SOURCE_DIR, found, sizeof found, tried,
                          sizeof tried) == 0)
        path = found;
    sr_scene_load_options lo;
    memset(&lo, 0, sizeof lo);
    lo.flags = SR_SCENE_DEFAULT_LIGHT;
    if (sr_scene_load(path, &lo, out, err, sizeof err) != SLUICE_OK) {
        if (path != found && tried[0])
            fprintf(stderr, "%s: --scene %s: %s (not found as %s either)\n", prog, c->scene, err,
                    tried);
        else
            fprintf(stderr, "%s: --scene %s: %s\n", prog, c->scene, err);
        return 1;
    }
    return 0;
}

sr_adaptive_options sr_cli_sampling(const sr_cli_common *c)
{
    sr_adaptive_options o = {c->target_error, c->adaptive, c->min_samples};
    return o;
}

int sr_cli_context(const char *prog, const sr_cli_common *c, sluice_context **out)
{
    char err[1024] = "";
    sluice_context_options co;
    memset(&co, 0, sizeof co);
    co.device = c->device;
    co.profile = c->profile;
    if (sluice_context_create(&co, out, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "%s: OpenCL: %s\n", prog, err);
        return 1;
    }
    return 0;
}

int sr_cli_images_ready(const char *prog, const sr_cli_common *c)
{
    char err[1024] = "";
    if (c->no_image)
        return 0; /* nothing to write (sr_cli_common_finish refused what would) */
    if (sr_image_io_load(err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "%s: --out %s: %s\n", prog, c->out, err);
        return 1;
    }
    return 0;
}
