/*
 * The photon mapper (apps/photonmap): photon tracing, the three photon-map
 * builds giving the same image, determinism, the hashed photon map against
 * the dense one on a scene with a huge photon box, and (with --cli PATH) the
 * command line. The furnaces are test_stress's.
 * Prints "N passed, N failed".
 */
#include "check.h"
#include "photonmap.h"
#include "photons.h"
#include "scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/wait.h>

static sluice_context *ctx;

/* Renders one sample of `scene` at w x h; the image's pixels (malloc'ed, or
 * NULL on failure) and the statistics. */
static float *render(const sr_scene *scene, pm_options o, unsigned w, unsigned h, pm_stats *stats)
{
    char err[1024] = "";
    o.width = w;
    o.height = h;
    pm_renderer *r = NULL;
    sr_image *img = NULL;
    float *px = NULL;
    sluice_status st = pm_renderer_create(ctx, scene, &o, &r, err, sizeof err);
    CHECK(st == SLUICE_OK, "pm_renderer_create: %s", err);
    if (st == SLUICE_OK)
        st = pm_renderer_sample(r, err, sizeof err);
    CHECK(st == SLUICE_OK, "pm_renderer_sample: %s", err);
    if (st == SLUICE_OK)
        st = sr_image_create(w, h, 3, &img, err, sizeof err);
    size_t bad = 1;
    if (st == SLUICE_OK)
        st = sr_film_resolve(pm_renderer_film(r), 1.0, img, &bad);
    CHECK(st == SLUICE_OK && bad == 0, "image: %zu non-finite pixels", bad);
    if (st == SLUICE_OK) {
        px = malloc((size_t)w * h * 3 * sizeof *px);
        if (px)
            memcpy(px, sr_image_pixels(img), (size_t)w * h * 3 * sizeof *px);
        *stats = *pm_renderer_stats(r);
    }
    sr_image_destroy(img);
    pm_renderer_destroy(r);
    return px;
}

static sr_scene *builtin(const char *name)
{
    char err[512];
    sr_scene_load_options lo;
    memset(&lo, 0, sizeof lo);
    sr_scene *s = NULL;
    sluice_status st = sr_scene_load_builtin(name, &lo, &s, err, sizeof err);
    CHECK(st == SLUICE_OK, "%s: %s", name, err);
    return s;
}

/* Every map build stores the same photons per cell in the same order (the
 * stencil with enough slots), so the images agree bit for bit; the same
 * seed gives the same image; another seed another one. */
static void test_builds_agree(void)
{
    sr_scene *s = builtin("glassball");
    if (!s)
        return;
    const unsigned w = 96, h = 72;
    pm_options o = pm_options_default();
    o.photons = 5000;
    o.k = 32;
    o.light_samples = 2;
    o.slots = 4096;
    pm_stats st[3];
    float *img[3];
    static const sr_point_grid_build_kind kinds[3] = {SR_POINT_GRID_COUNT, SR_POINT_GRID_BITONIC,
                                                      SR_POINT_GRID_STENCIL};
    for (int i = 0; i < 3; ++i) {
        o.map = kinds[i];
        img[i] = render(s, o, w, h, &st[i]);
    }
    CHECK(st[0].photons.stored >= 5000, "stored %llu of 5000",
          (unsigned long long)st[0].photons.stored);
    CHECK(st[0].photons.caustic > 0 && st[0].photons.caustic <= st[0].photons.stored,
          "caustic photons %llu", (unsigned long long)st[0].photons.caustic);
    CHECK(st[0].photons.emitted > st[0].photons.stored, "emitted %llu",
          (unsigned long long)st[0].photons.emitted);
    CHECK(st[0].queries > 0 && st[0].found > 0, "estimates %llu found %llu",
          (unsigned long long)st[0].queries, (unsigned long long)st[0].found);
    CHECK(st[2].map.overflow_points == 0, "stencil with 4096 slots dropped %zu",
          st[2].map.overflow_points);
    for (int i = 1; i < 3; ++i)
        CHECK(img[0] && img[i] && !memcmp(img[0], img[i], (size_t)w * h * 3 * sizeof(float)),
              "build %d's image differs from the count build's", i);
    /* same seed, same image */
    o.map = SR_POINT_GRID_COUNT;
    pm_stats again;
    float *b = render(s, o, w, h, &again);
    CHECK(img[0] && b && !memcmp(img[0], b, (size_t)w * h * 3 * sizeof(float)),
          "same seed, different image");
    free(b);
    o.seed = 7;
    b = render(s, o, w, h, &again);
    CHECK(img[0] && b && memcmp(img[0], b, (size_t)w * h * 3 * sizeof(float)) != 0,
          "another seed, the same image");
    free(b);
    /* a stencil map with few slots drops photons and says so */
    o.seed = 1;
    o.map = SR_POINT_GRID_STENCIL;
    o.slots = 4;
    b = render(s, o, w, h, &again);
    CHECK(again.map.overflow_points > 0 && again.map.overfull_cells > 0,
          "stencil with 4 slots: overflow %zu in %zu cells", again.map.overflow_points,
          again.map.overfull_cells);
    free(b);
    for (int i = 0; i < 3; ++i)
        free(img[i]);
    sr_scene_destroy(s);
}

/* Renders `spp` progressive samples of `scene` at w x h; the image's pixels
 * (malloc'ed, or NULL on failure) and the statistics. */
static float *render_ppm(const sr_scene *scene, pm_options o, unsigned w, unsigned h, unsigned spp,
                         pm_stats *stats)
{
    char err[1024] = "";
    o.width = w;
    o.height = h;
    o.progressive = 1;
    pm_renderer *r = NULL;
    sr_image *img = NULL;
    float *px = NULL;
    sluice_status st = pm_renderer_create(ctx, scene, &o, &r, err, sizeof err);
    CHECK(st == SLUICE_OK, "pm_renderer_create: %s", err);
    for (unsigned i = 0; st == SLUICE_OK && i < spp; ++i)
        st = pm_renderer_sample(r, err, sizeof err);
    CHECK(st == SLUICE_OK, "pm_renderer_sample: %s", err);
    if (st == SLUICE_OK)
        st = sr_image_create(w, h, 3, &img, err, sizeof err);
    size_t bad = 1;
    if (st == SLUICE_OK)
        st = sr_film_resolve(pm_renderer_film(r), 1.0 / spp, img, &bad);
    CHECK(st == SLUICE_OK && bad == 0, "image: %zu non-finite pixels", bad);
    if (st == SLUICE_OK) {
        px = malloc((size_t)w * h * 3 * sizeof *px);
        if (px)
            memcpy(px, sr_image_pixels(img), (size_t)w * h * 3 * sizeof *px);
        *stats = *pm_renderer_stats(r);
    }
    sr_image_destroy(img);
    pm_renderer_destroy(r);
    return px;
}

/* The hashed photon map (Purcell 6.4.4) end to end, on
 * scenes/distant-wall.json: a small room whose photons' box a wall 500
 * units away stretches to thousands of search radii. The progressive
 * radius search finds the same photons over the hash as over the dense grid
 * (test_knn checks that photon by photon), so the images agree up to the
 * order in which each estimate's power is summed: float rounding, far below
 * the noise of one sample. Also: auto takes the hash there and for every
 * progressive radius search, the dense grid for Purcell's k-nearest search;
 * the same seed gives
 * the same image; the hash is refused where it cannot serve. */
static void test_hashed_map(void)
{
    char err[1024] = "";
    sr_scene_load_options lo;
    memset(&lo, 0, sizeof lo);
    sr_scene *s = NULL;
    sluice_status st = sr_scene_load(PM_SCENES_DIR "/distant-wall.json", &lo, &s, err, sizeof err);
    CHECK(st == SLUICE_OK, "distant-wall.json: %s", err);
    if (!s)
        return;
    const unsigned w = 64, h = 48, spp = 3;
    pm_options o = pm_options_default();
    o.photons = 4000;
    o.k = 32;
    o.max_radius = 0.15f;
    o.max_depth = 5;
    pm_stats sd, sh, sa, sh2;
    o.photon_grid = SR_POINT_GRID_DENSE;
    float *dense = render_ppm(s, o, w, h, spp, &sd);
    o.photon_grid = SR_POINT_GRID_HASHED;
    float *hash = render_ppm(s, o, w, h, spp, &sh);
    float *again = render_ppm(s, o, w, h, spp, &sh2);
    o.photon_grid = SR_POINT_GRID_LAYOUT_AUTO;
    float *autom = render_ppm(s, o, w, h, spp, &sa);
    CHECK(sd.maps_dense == spp && sd.maps_hashed == 0 && sd.map_layout == SR_POINT_GRID_DENSE,
          "dense asked for: %u dense, %u hashed maps", sd.maps_dense, sd.maps_hashed);
    CHECK(sh.maps_hashed == spp && sh.maps_dense == 0 && sh.map_layout == SR_POINT_GRID_HASHED &&
              sh.map_hash.buckets >= 2 * 4000 && sh.map_hash.cell == sh.max_radius,
          "hash asked for: %u dense, %u hashed maps, %u buckets, cell %g (radius %g)",
          sh.maps_dense, sh.maps_hashed, sh.map_hash.buckets, (double)sh.map_hash.cell,
          (double)sh.max_radius);
    CHECK(sa.maps_hashed == spp && strstr(sa.map_why, "coarser"),
          "auto on a huge photon box: %u hashed maps: %s", sa.maps_hashed, sa.map_why);
    CHECK(sd.found == sh.found && sd.found > 1000 && sd.queries == sh.queries,
          "the layouts find %llu and %llu photons", (unsigned long long)sd.found,
          (unsigned long long)sh.found);
    size_t differ = 0, n = (size_t)w * h * 3;
    double worst = 0.0, mean = 0.0;
    for (size_t i = 0; dense && hash && i < n; ++i) {
        double d = fabs((double)dense[i] - (double)hash[i]);
        worst = fmax(worst, d);
        mean += dense[i] / (double)n;
        differ += d > 1e-5 * fabs((double)dense[i]) + 1e-7;
    }
    CHECK(dense && hash && differ == 0,
          "hash and dense images differ beyond rounding in %zu values (largest %g, mean value %g)",
          differ, worst, mean);
    CHECK(hash && again && !memcmp(hash, again, n * sizeof *hash), "hash: same seed, other image");
    CHECK(autom && hash && !memcmp(hash, autom, n * sizeof *hash), "auto: not the hash's image");
    free(dense);
    free(hash);
    free(again);
    free(autom);

    /* auto takes the hash for the progressive radius search also where the
     * dense cells fit (cornell), and keeps the dense grid for the k-nearest
     * search */
    sr_scene *c = builtin("cornell");
    if (c) {
        pm_options oc = pm_options_default();
        oc.photons = 2000;
        oc.k = 32;
        oc.light_samples = 1;
        pm_stats sc;
        float *img = render_ppm(c, oc, 32, 32, 1, &sc);
        CHECK(sc.maps_hashed == 1 && strstr(sc.map_why, "hash (auto") && strstr(sc.map_why, "fit"),
              "cornell, auto: %s", sc.map_why);
        free(img);
        img = render(c, oc, 32, 32, &sc);
        CHECK(sc.maps_dense == 1 && strstr(sc.map_why, "k-nearest"), "cornell, kNN: %s",
              sc.map_why);
        free(img);
        sr_scene_destroy(c);
    }

    /* the hash where it cannot serve */
    struct {
        int progressive;
        uint32_t dims;
        sr_point_grid_build_kind map;
        const char *why;
    } bad[] = {{0, 0, SR_POINT_GRID_COUNT, "k-nearest"},
               {1, 16, SR_POINT_GRID_COUNT, "--grid"},
               {1, 0, SR_POINT_GRID_STENCIL, "stencil"}};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; ++i) {
        pm_options ob = o;
        ob.photon_grid = SR_POINT_GRID_HASHED;
        ob.progressive = bad[i].progressive;
        ob.grid_dims[0] = ob.grid_dims[1] = ob.grid_dims[2] = bad[i].dims;
        ob.map = bad[i].map;
        pm_renderer *r = NULL;
        err[0] = '\0';
        st = pm_renderer_create(ctx, s, &ob, &r, err, sizeof err);
        CHECK(st == SLUICE_ERROR_INVALID_ARGUMENT && !r && strstr(err, bad[i].why),
              "hash refused (%s): %s", bad[i].why, err);
        pm_renderer_destroy(r);
    }
    sr_scene_destroy(s);
}

/* Intermediate images (Purcell 6.3.4): one per kNN pass; the last one is
 * the final image; they do not change the image; a failing callback stops
 * the render with its status and message. */
typedef struct previews {
    unsigned count, fail_at;
    size_t pixels;
    float *last;
} previews;

static sluice_status keep_preview(void *user, const sr_image *img, unsigned index, char *err,
                                  size_t err_size)
{
    previews *p = user;
    CHECK(index == p->count, "image index %u, want %u", index, p->count);
    p->count++;
    memcpy(p->last, sr_image_pixels_const(img), p->pixels * 3 * sizeof(float));
    if (p->count == p->fail_at) {
        snprintf(err, err_size, "preview sink full");
        return SLUICE_ERROR_LIMIT;
    }
    return SLUICE_OK;
}

static void test_pass_images(void)
{
    sr_scene *s = builtin("glassball");
    if (!s)
        return;
    const unsigned w = 64, h = 48;
    pm_options o = pm_options_default();
    o.photons = 2000;
    o.k = 16;
    pm_stats plain_st, st;
    float *plain = render(s, o, w, h, &plain_st);
    previews p = {0, 0, (size_t)w * h, calloc((size_t)w * h * 3, sizeof(float))};
    o.pass_image = keep_preview;
    o.pass_image_user = &p;
    float *img = render(s, o, w, h, &st);
    CHECK(p.count == st.knn_passes && p.count == st.pass_images && p.count > 1,
          "%u images for %u kNN passes", p.count, st.knn_passes);
    CHECK(plain && img && !memcmp(plain, img, (size_t)w * h * 3 * sizeof(float)),
          "intermediate images change the image");
    size_t differ = 0;
    for (size_t i = 0; img && i < (size_t)w * h * 3; ++i)
        differ += fabsf(p.last[i] - img[i]) > 1e-6f * fmaxf(1.0f, img[i]);
    CHECK(differ == 0, "the last intermediate image differs from the final one in %zu values",
          differ);
    /* a failing callback stops the render with its status and message */
    char err[1024] = "";
    o.width = w;
    o.height = h;
    p.count = 0;
    p.fail_at = 2;
    pm_renderer *r = NULL;
    CHECK_OK(ctx, pm_renderer_create(ctx, s, &o, &r, err, sizeof err));
    sluice_status rs = r ? pm_renderer_sample(r, err, sizeof err) : SLUICE_ERROR_INVALID_ARGUMENT;
    CHECK(rs == SLUICE_ERROR_LIMIT && p.count == 2 && strstr(err, "preview sink full"),
          "failing callback: %s after %u images: %s", sluice_status_string(rs), p.count, err);
    pm_renderer_destroy(r);
    free(plain);
    free(img);
    free(p.last);
    sr_scene_destroy(s);
}

static void test_cli(const char *exe)
{
    char out[32768], cmd[2048];
    static const struct {
        const char *args, *expect;
    } bad[] = {
        {"--map bogus", "--map"},
        {"--grid 0x1x1", "--grid"},
        {"--grid 10x10", "--grid"},
        {"--k 0", "--k"},
        {"--knn foo", "--knn"},
        {"--photons -5", "--photons"},
        {"--max-radius -1", "--max-radius"},
        {"--slots 0", "--slots"},
        {"--out a.bmp", "--out"},
        {"--pass-images frames", "--pass-images"},
        {"--shells-per-pass 0", "--shells-per-pass"},
        {"--shells-per-pass some", "--shells-per-pass"},
        {"--time x", "--time"},
        {"--alpha 1.5", "--alpha"},
        {"--target-error 0", "--target-error"},
        {"--target-error 2", "--target-error"},
        {"--min-spp 5", "--min-spp"},
        {"--alpha 0", "--alpha"},
        {"--progressive --alpha", "--alpha"},
        {"--photon-grid sparse", "--photon-grid"},
        {"--photon-grid hash", "--progressive"},
        {"--progressive --photon-grid hash --grid 10x10x10", "--grid"},
        {"--progressive --photon-grid hash --map stencil", "stencil"},
        {"--frobnicate 1", "--frobnicate"},
        {"--scene no-such-scene.obj", "no-such-scene.obj"},
        /* where results go is checked before rendering */
        {"--out no-such-folder/a.png", "the folder no-such-folder does not exist"},
        {"--stats no-such-folder/s.json", "--stats no-such-folder/s.json"},
        {"--stats .", "names a folder"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; ++i) {
        snprintf(cmd, sizeof cmd, "%s %s", exe, bad[i].args);
        int rc = check_run(cmd, out, sizeof out);
        CHECK(rc != 0 && strstr(out, bad[i].expect), "'%s': exit %d, said: %s", bad[i].args, rc,
              out);
    }
    snprintf(cmd, sizeof cmd, "%s --help", exe);
    CHECK(check_run(cmd, out, sizeof out) == 0 && strstr(out, "--map") && strstr(out, "examples") &&
              strstr(out, "--photon-grid dense|hash|auto"),
          "--help");
    snprintf(cmd, sizeof cmd,
             "%s --scene glassball --size 64x48 --photons 2000 --map bitonic --out pm_cli.png "
             "--stats pm_cli.json --quiet",
             exe);
    CHECK(check_run(cmd, out, sizeof out) == 0, "glassball render: %s", out);
    FILE *f = fopen("pm_cli.json", "r");
    size_t n = f ? fread(out, 1, sizeof out - 1, f) : 0;
    out[n] = '\0';
    if (f)
        fclose(f);
    CHECK(strstr(out, "\"trace_photons\"") && strstr(out, "\"stored\"") &&
              strstr(out, "\"live_per_pass\"") && strstr(out, "\"kernels\": [") &&
              strstr(out, "{\"name\": \"pm_emit\", \"launches\": "),
          "statistics JSON: %s", out);
    /* progressive: the statistics name the radius, and it shrinks */
    snprintf(cmd, sizeof cmd,
             "%s --scene glassball --size 32x24 --photons 1000 --progressive --spp 4 --out "
             "pm_cli.png --stats pm_ppm.json --quiet",
             exe);
    CHECK(check_run(cmd, out, sizeof out) == 0, "--progressive: %s", out);
    f = fopen("pm_ppm.json", "r");
    n = f ? fread(out, 1, sizeof out - 1, f) : 0;
    out[n] = '\0';
    if (f)
        fclose(f);
    const char *ml = strstr(out, "\"map_layout\": {\"last\": \"");
    unsigned nd = 0, nh = 0;
    CHECK(ml && sscanf(ml + 24, "%*[a-z]\", \"dense\": %u, \"hash\": %u", &nd, &nh) == 2 &&
              nd + nh == 4 && strstr(ml, "\"why\": \""),
          "progressive: the layout of 4 maps (%u dense, %u hashed): %s", nd, nh, out);
    const char *pr = strstr(out, "\"progressive\"");
    double a = 0, r0 = 0, r3 = 0;
    CHECK(pr &&
              sscanf(pr, "\"progressive\": {\"alpha\": %lf, \"radius0\": %lf, \"radius\": %lf", &a,
                     &r0, &r3) == 3 &&
              fabs(r3 * r3 / (r0 * r0) - (1 + a) / 2 * (2 + a) / 3 * (3 + a) / 4) < 1e-4,
          "progressive radius: %s", out);
    /* progressive to a target error: tiles stop, the statistics say so */
    snprintf(cmd, sizeof cmd,
             "%s --scene glassball --size 32x24 --photons 1000 --progressive --target-error 0.01 "
             "--out pm_cli.png --stats pm_ppm.json --quiet",
             exe);
    CHECK(check_run(cmd, out, sizeof out) == 0 && strstr(out, "target 0.01 reached"),
          "--progressive --target-error: %s", out);
    f = fopen("pm_ppm.json", "r");
    n = f ? fread(out, 1, sizeof out - 1, f) : 0;
    out[n] = '\0';
    if (f)
        fclose(f);
    CHECK(strstr(out, "\"sampling\": {\"target\": 0.01, \"adaptive\": true"),
          "--target-error stats JSON: %s", out);
    /* intermediate images: pm_pass-0000.png on; a folder that does not
     * exist is an error naming the file */
    remove("pm_pass-0000.png");
    snprintf(cmd, sizeof cmd,
             "%s --scene glassball --size 32x24 --photons 500 --out pm_cli.png --pass-images "
             "pm_pass.png --quiet",
             exe);
    FILE *first = NULL;
    CHECK(check_run(cmd, out, sizeof out) == 0 && (first = fopen("pm_pass-0000.png", "rb")),
          "--pass-images: %s", out);
    if (first)
        fclose(first);
    snprintf(cmd, sizeof cmd,
             "%s --scene glassball --size 32x24 --photons 500 --out pm_cli.png --pass-images "
             "no-such-dir/p.png --quiet",
             exe);
    /* refused before rendering, naming the option and the folder */
    int rc = check_run(cmd, out, sizeof out);
    CHECK(rc == 2 && strstr(out, "--pass-images no-such-dir/p.png") &&
              strstr(out, "the folder no-such-dir does not exist"),
          "--pass-images into nowhere: %d %s", rc, out);
    /* --no-image: renders and reports without the image module, writes no
     * image; refused beside an option that writes one */
    remove("out.png");
    remove("pm_noimg.json");
    snprintf(cmd, sizeof cmd,
             "SLUICE_IMAGE_MODULE=no-such-dir/m.so %s --scene glassball --size 32x24 --photons 500 "
             "--no-image --stats pm_noimg.json --quiet",
             exe);
    rc = check_run(cmd, out, sizeof out);
    f = fopen("pm_noimg.json", "r");
    n = f ? fread(out + strlen(out), 1, sizeof out - 1 - strlen(out), f) : 0;
    if (f)
        fclose(f);
    CHECK(rc == 0 && n > 0 && strstr(out, "\"radiance_estimate\"") && access("out.png", F_OK) != 0,
          "--no-image: exit %d: %s", rc, out);
    snprintf(cmd, sizeof cmd, "%s --no-image --pass-images pm_pass.png", exe);
    rc = check_run(cmd, out, sizeof out);
    CHECK(rc == 2 && strstr(out, "--no-image") && strstr(out, "--pass-images"),
          "--no-image --pass-images: exit %d: %s", rc, out);
}

/* The total power of glassball's caustic photons (stored after glass only),
 * per seed, traced with Jensen's projection map (half the photons sent into
 * the cone toward the ball, pm_emit's fixed-share mixture) or without it:
 * the mean and standard error over `seeds` seeds. */
static int caustic_power(pm_photons *ph, int projection, unsigned seeds, double *mean, double *se)
{
    double sum = 0.0, sum2 = 0.0;
    pm_photon *host = NULL;
    for (unsigned k = 0; k < seeds; ++k) {
        pm_photon_options po = {20000, 8, 100 + k, !projection};
        sluice_stream *photons = NULL;
        size_t n = 0;
        pm_photon_stats ps;
        sluice_status st = pm_photons_trace(ph, &po, &photons, &n, &ps);
        pm_photon *grown = st == SLUICE_OK ? realloc(host, (n + 1) * sizeof *host) : NULL;
        if (grown)
            host = grown;
        if (st == SLUICE_OK && grown)
            st = sluice_stream_download(photons, host, n, NULL);
        CHECK(st == SLUICE_OK && grown, "tracing photons: %s", sluice_context_error(ctx));
        if (st != SLUICE_OK || !grown) {
            free(host);
            return 0;
        }
        double t = 0.0;
        for (size_t i = 0; i < n; ++i)
            if (host[i].flags & PM_PHOTON_CAUSTIC)
                t += (host[i].pr + host[i].pg + host[i].pb) / 3.0;
        sum += t;
        sum2 += t * t;
    }
    free(host);
    *mean = sum / seeds;
    *se = sqrt(fmax(sum2 / seeds - *mean * *mean, 0.0) / (seeds - 1));
    return 1;
}

/* The projection map moves photons, never power: both ways of emitting
 * carry the same caustic power on average (within 4 standard errors of the
 * difference, and 3%), and the projection's is the less noisy. */
static void test_projection_unbiased(void)
{
    sr_scene *s = builtin("glassball");
    if (!s)
        return;
    char err[512] = "";
    pm_options o = pm_options_default();
    o.width = 8;
    o.height = 8;
    pm_renderer *r = NULL;
    pm_photons *ph = NULL;
    sluice_status st = pm_renderer_create(ctx, s, &o, &r, err, sizeof err);
    if (st == SLUICE_OK)
        st = pm_photons_create(pm_renderer_tracer(r), &ph, err, sizeof err);
    CHECK(st == SLUICE_OK, "photon tracing on glassball: %s", err);
    double m[2], se[2];
    if (st == SLUICE_OK && caustic_power(ph, 1, 6, &m[1], &se[1]) &&
        caustic_power(ph, 0, 6, &m[0], &se[0])) {
        double diff = m[1] - m[0], se_diff = sqrt(se[0] * se[0] + se[1] * se[1]);
        printf("caustic power, 20,000 photons stored x 6 seeds: projection %.5f +- %.5f, "
               "without %.5f +- %.5f (difference %.2f standard errors, %+.2f%%)\n",
               m[1], se[1], m[0], se[0], diff / se_diff, 100.0 * diff / m[0]);
        CHECK(fabs(diff) <= 4.0 * se_diff && fabs(diff) <= 0.03 * m[0],
              "projection map: caustic power %.5f against %.5f without it", m[1], m[0]);
        CHECK(se[1] < se[0], "the projection's caustic power is the noisier: %.5f against %.5f",
              se[1], se[0]);
    }
    pm_photons_destroy(ph);
    pm_renderer_destroy(r);
    sr_scene_destroy(s);
}

/* The tracer's two modes give the same image bit for bit: the same hits
 * for the photons and the eye rays, and in the fused mode the direct
 * light's shadow rays traced where rt_direct makes them, their sums taken
 * in fixed point as the stream mode's resolve takes them. glassball: an
 * area light (several samples a hit) and glass; ring: a point light and a
 * mirror. With every shell in one pass the estimates add the same photons
 * in another order, so that setting is compared within one mode. */
static void test_exec_agree(void)
{
    static const char *const scenes[] = {"glassball", "ring"};
    for (int i = 0; i < 2; ++i) {
        sr_scene *s = builtin(scenes[i]);
        if (!s)
            continue;
        const unsigned w = 80, h = 60;
        pm_options o = pm_options_default();
        o.photons = 4000;
        o.k = 24;
        o.light_samples = 3;
        pm_stats st[2];
        float *img[2];
        for (int e = 0; e < 2; ++e) {
            o.tracer.exec = e ? RT_EXEC_FUSED : RT_EXEC_STREAM;
            img[e] = render(s, o, w, h, &st[e]);
        }
        CHECK(img[0] && img[1] && !memcmp(img[0], img[1], (size_t)w * h * 3 * sizeof(float)),
              "%s: the fused mode's image differs from the stream mode's", scenes[i]);
        CHECK(st[0].photons.stored == st[1].photons.stored &&
                  st[0].photons.emitted == st[1].photons.emitted && st[0].queries == st[1].queries,
              "%s: stream and fused: stored %llu / %llu photons, %llu / %llu estimates", scenes[i],
              (unsigned long long)st[0].photons.stored, (unsigned long long)st[1].photons.stored,
              (unsigned long long)st[0].queries, (unsigned long long)st[1].queries);
        double sum = 0.0;
        for (size_t p = 0; img[0] && p < (size_t)w * h * 3; ++p)
            sum += img[0][p];
        CHECK(sum > 0.0, "%s: a black image", scenes[i]);
        for (int e = 0; e < 2; ++e)
            free(img[e]);
        sr_scene_destroy(s);
    }
}

int main(int argc, char **argv)
{
    ctx = check_context(0);
    if (argc == 3 && !strcmp(argv[1], "--cli")) {
        test_cli(argv[2]);
    } else {
        test_builds_agree();
        test_exec_agree();
        test_pass_images();
        test_hashed_map();
        test_projection_unbiased();
    }
    sluice_context_destroy(ctx);
    return check_summary();
}
