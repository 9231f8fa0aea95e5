/*
 * Adaptive sampling and the target error (apps/render/adaptive.h), each case
 * a measured figure against a stated bound:
 *
 *   estimator     a synthetic film (a quarter constant, a quarter and a half
 *                 with uniform noise of two known variances) sampled through
 *                 sr_adaptive: the image's relMSE estimate against the
 *                 known variance of the mean, within 25% (3 standard
 *                 deviations of the estimate, plus the few percent that the
 *                 smaller half's mean in the denominator adds);
 *                 the resolved image against a plain C mean of the same
 *                 samples, within one fixed-point quantum
 *   stopping      the same film with a target: constant tiles stop at the
 *                 first check, the less noisy ones where their variance of
 *                 the mean reaches the target (between the checks around
 *                 it), the noisiest go on until the image's estimate
 *                 reaches the target; every count even, the image still the
 *                 exact mean
 *   furnace       the path-traced white furnace rendered to a target of
 *                 1e-3, with and without adaptive sampling: the true relMSE
 *                 against the analytic image within a factor of 2 of it
 *   cornell       cornell, path traced, to a target of 1e-2 with adaptive
 *                 sampling: true relMSE against a 1,024-sample render within
 *                 a factor of 2, and some tiles stopped early
 */
#include "adaptive.h"
#include "check.h"
#include "film.h"
#include "test_program.h"
#include "furnace.h"
#include "image.h"
#include "image_metrics.h"
#include "progressive.h"
#include "render.h"
#include "scene.h"
#include "tracer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static sluice_context *ctx;

/* ------------------------------------------------------------------ */
/* A synthetic film                                                    */
/* ------------------------------------------------------------------ */

/* Sample s of pixel p, with u uniform in [0, 1) (a hash: the same float on
 * host and device): 1 on the left quarter, 0.75 + u / 2 on the next, 0.5 + u
 * on the right half (mean 1, variance 0, 1/48, 1/12), added to the film
 * half of the sample, for the listed tiles only. */
static const char synth_cl[] =
    "inline float synth_value(uint p, uint s, uint x, uint width)\n"
    "{\n"
    "    uint h = p * 0x9E3779B9u ^ s * 0x85EBCA6Bu;\n"
    "    h ^= h >> 16; h *= 0x7FEB352Du; h ^= h >> 15; h *= 0x846CA68Bu; h ^= h >> 16;\n"
    "    float u = (float)(h >> 8) * 0x1p-24f;\n"
    "    return x < width / 4u ? 1.0f : x < width / 2u ? 0.75f + 0.5f * u : 0.5f + u;\n"
    "}\n"
    "__kernel void synth(SLUICE_PARAMS, global long *accum, global const uint *tiles,\n"
    "                    uint width, uint height, uint sample)\n"
    "{\n"
    "    SLUICE_FOR_EACH (i) {\n"
    "        uint across = (width + 7u) / 8u, tile = tiles[i / 64u], within = i % 64u;\n"
    "        uint x = (tile % across) * 8u + within % 8u, y = (tile / across) * 8u + within / 8u;\n"
    "        if (x < width && y < height) {\n"
    "            uint p = y * width + x;\n"
    "            float v = synth_value(p, sample, x, width);\n"
    "            rt_add(accum, p + (sample & 1u) * width * height, (float3)(v, v, v));\n"
    "        }\n"
    "    }\n"
    "}\n";

static float synth_value(uint32_t p, uint32_t s, uint32_t x, uint32_t width)
{
    uint32_t h = p * 0x9E3779B9u ^ s * 0x85EBCA6Bu;
    h ^= h >> 16;
    h *= 0x7FEB352Du;
    h ^= h >> 15;
    h *= 0x846CA68Bu;
    h ^= h >> 16;
    float u = (float)(h >> 8) * 0x1p-24f;
    return x < width / 4u ? 1.0f : x < width / 2u ? 0.75f + 0.5f * u : 0.5f + u;
}

typedef struct synth {
    sluice_program *prog;
    sluice_kernel *k;
} synth;

static int synth_create(synth *s)
{
    memset(s, 0, sizeof *s);
    sluice_status st = film_program_create(ctx, "synth.cl", synth_cl, &s->prog);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(s->prog, "synth", &s->k);
    CHECK(st == SLUICE_OK, "synth kernel: %s", sluice_context_error(ctx));
    return st == SLUICE_OK;
}

static void synth_destroy(synth *s)
{
    sluice_kernel_destroy(s->k);
    sluice_program_destroy(s->prog);
}

/* Runs up to `samples` samples of the synthetic film through `a`, checking
 * after each. Returns the status. */
static sluice_status synth_run(synth *s, sr_adaptive *a, sr_film *film, unsigned w, unsigned h,
                               unsigned samples)
{
    sluice_status st = SLUICE_OK;
    for (unsigned i = 0; st == SLUICE_OK && i < samples && !sr_adaptive_done(a); ++i) {
        size_t tiles = sr_adaptive_active_tiles(a);
        uint32_t sample = sr_adaptive_begin_sample(a);
        st = sluice_kernel_set_stream(s->k, 0, sr_film_accum(film), 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(s->k, 1, sr_adaptive_tile_list(a), 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_arg(s->k, 2, sizeof w, &w);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_arg(s->k, 3, sizeof h, &h);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_arg(s->k, 4, sizeof sample, &sample);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch_count(s->k, tiles * 64);
        if (st == SLUICE_OK)
            st = sr_adaptive_check(a, film, NULL);
    }
    return st;
}

/* The largest difference of the resolved image from the plain C mean of
 * each pixel's samples, in units of the fixed point's quantum 2^-24 times
 * (1 + mean) (each sample is cut down by less than one quantum). */
static double synth_worst(const sr_image *img, const uint32_t *tile_samples, unsigned w, unsigned h)
{
    const float *px = sr_image_pixels_const(img);
    unsigned across = (w + 7) / 8;
    double worst = 0;
    for (unsigned y = 0; y < h; ++y)
        for (unsigned x = 0; x < w; ++x) {
            uint32_t p = y * w + x, n = tile_samples[(y / 8) * across + x / 8];
            double sum = 0;
            for (uint32_t i = 0; i < n; ++i)
                sum += synth_value(p, i, x, w);
            double mean = n ? sum / n : 0.0;
            worst = fmax(worst, fabs(px[3 * p] - mean) * 0x1p24 / (1 + mean));
        }
    return worst;
}

static void test_estimator(void)
{
    enum { W = 64, H = 32, N = 64 };
    synth s;
    if (!synth_create(&s))
        return;
    char err[256] = "";
    sr_film *film = NULL;
    sr_adaptive *a = NULL;
    sr_image *img = NULL;
    /* a target no render reaches, tiles never stop: estimates every check */
    sr_adaptive_options o = {1e-12, 0, 0};
    sluice_status st = sr_film_create(ctx, W, H, &film, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_adaptive_create(ctx, W, H, &o, &a, err, sizeof err);
    if (st == SLUICE_OK)
        st = synth_run(&s, a, film, W, H, N);
    if (st == SLUICE_OK)
        st = sr_image_create(W, H, 3, &img, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_film_resolve_tiles(film, NULL, sr_adaptive_tile_samples(a), img, NULL, NULL);
    CHECK(st == SLUICE_OK, "estimator: %s %s", err, sluice_context_error(ctx));
    if (st == SLUICE_OK) {
        const sr_adaptive_stats *as = sr_adaptive_statistics(a);
        /* mean 1 everywhere; relMSE of the mean: variance / n / (1 + 0.01),
         * the variance 1/48 on a quarter, 1/12 on half the image */
        unsigned n = as->error_samples;
        double truth = (0.25 / 48.0 + 0.5 / 12.0) / (n ? n : 1) / (1.0 + SR_IMAGE_REL_MSE_EPSILON);
        double worst = synth_worst(img, sr_adaptive_tile_samples(a), W, H);
        printf("estimator: relMSE estimate %.4g after %u samples against the known %.4g "
               "(bound: within 25%%); image within %.3f quanta of the plain C mean (bound 1)\n",
               as->error, as->error_samples, truth, worst);
        CHECK(n >= N * 3 / 4 && fabs(as->error / truth - 1) < 0.25,
              "estimate %g after %u samples, truth %g", as->error, n, truth);
        CHECK(as->tiles_active == as->tiles && as->pixel_samples == (uint64_t)N * W * H,
              "no tile may stop: %u of %u active", as->tiles_active, as->tiles);
        CHECK(worst <= 1.0, "resolved image off by %.3f quanta", worst);
    }
    sr_image_destroy(img);
    sr_adaptive_destroy(a);
    sr_film_destroy(film);
    synth_destroy(&s);
}

static void test_stopping(void)
{
    enum { W = 64, H = 32 };
    synth s;
    if (!synth_create(&s))
        return;
    char err[256] = "";
    sr_film *film = NULL;
    sr_adaptive *a = NULL;
    sr_image *img = NULL;
    const double target = 1e-3;
    sr_adaptive_options o = {target, 1, 0};
    sluice_status st = sr_film_create(ctx, W, H, &film, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_adaptive_create(ctx, W, H, &o, &a, err, sizeof err);
    if (st == SLUICE_OK)
        st = synth_run(&s, a, film, W, H, 4096);
    if (st == SLUICE_OK)
        st = sr_image_create(W, H, 3, &img, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_film_resolve_tiles(film, NULL, sr_adaptive_tile_samples(a), img, NULL, NULL);
    CHECK(st == SLUICE_OK, "stopping: %s %s", err, sluice_context_error(ctx));
    if (st == SLUICE_OK) {
        const sr_adaptive_stats *as = sr_adaptive_statistics(a);
        const uint32_t *n = sr_adaptive_tile_samples(a);
        unsigned across = W / 8, lo = ~0u, hi = 0, odd = 0, const_bad = 0, noisy_bad = 0;
        for (unsigned t = 0; t < as->tiles; ++t) {
            unsigned tx = t % across;
            odd += n[t] % 2;
            if (tx < across / 4) {
                const_bad += n[t] != 8;
            } else if (tx < across / 2) {
                lo = n[t] < lo ? n[t] : lo;
                hi = n[t] > hi ? n[t] : hi;
            } else {
                noisy_bad += n[t] != as->samples;
            }
        }
        /* the quarter of variance 1/48: (1/48) / n / 1.01 <= 1e-3 from
         * n = 21 on; checks at 16, 20, 24, 30, 36, 44, ...: its tiles stop
         * at 16 (an estimate 25% low) to 36 (30% high). The image's estimate
         * then reaches 1e-3 (about 0.25 * 8.6e-4 + 0.5 (1/12) / n / 1.01 from
         * n = 53 on) before the noisiest tiles' own would (n = 83). */
        double worst = synth_worst(img, n, W, H);
        printf("stopping at relMSE %g: constant tiles %s at 8 samples, the less noisy at %u to "
               "%u (bound: 16 to 36), the noisiest %s to the end (%u samples); %.1f%% of pixel "
               "samples skipped, estimate %.3g, image within %.3f quanta\n",
               target, const_bad ? "not all" : "all", lo, hi, noisy_bad ? "not all" : "all",
               as->samples, 100.0 * (1.0 - (double)as->pixel_samples / (double)as->pixel_uniform),
               as->error, worst);
        CHECK(const_bad == 0 && noisy_bad == 0 && odd == 0,
              "%u constant tiles past 8 samples, %u noisiest stopped early, %u odd counts",
              const_bad, noisy_bad, odd);
        CHECK(lo >= 16 && hi <= 36, "the less noisy tiles stopped at %u to %u samples", lo, hi);
        CHECK(as->samples >= 44 && as->samples <= 82, "the render stopped at %u samples",
              as->samples);
        CHECK(sr_adaptive_done(a) && as->error <= target && as->error_uniform <= as->error,
              "done %d, estimate %g, uniform %g", sr_adaptive_done(a), as->error,
              as->error_uniform);
        CHECK(worst <= 1.0, "resolved image off by %.3f quanta", worst);
    }
    sr_image_destroy(img);
    sr_adaptive_destroy(a);
    sr_film_destroy(film);
    synth_destroy(&s);
}

/* ------------------------------------------------------------------ */
/* Renders to a target                                                 */
/* ------------------------------------------------------------------ */

static sluice_status step(void *user)
{
    return rt_renderer_sample(user);
}

static int estimate(void *user, double *error)
{
    *error = rt_renderer_sampling(user)->error;
    return rt_renderer_done(user);
}

/* Renders `s` in path mode to `target` (0: `spp` samples, uniform) and
 * returns the image, or NULL after a failed check; `*stats` gets the
 * sampling statistics and `*res` the loop's result. */
static sr_image *render_to(const sr_scene *s, unsigned w, unsigned h, unsigned depth, double target,
                           int adaptive, unsigned spp, sr_adaptive_stats *stats,
                           sr_progressive_result *res)
{
    char err[512] = "";
    rt_tracer_options to = rt_tracer_options_default();
    to.exec = RT_EXEC_FUSED;
    rt_tracer *t = NULL;
    rt_renderer *r = NULL;
    sr_image *img = NULL;
    sluice_status st = rt_tracer_create(ctx, s, &to, &t, err, sizeof err);
    rt_render_options o;
    memset(&o, 0, sizeof o);
    o.mode = RT_MODE_PATH;
    o.width = w;
    o.height = h;
    o.max_depth = depth;
    o.light_samples = 1;
    o.seed = 3;
    o.sampling.target = target;
    o.sampling.adaptive = adaptive;
    if (st == SLUICE_OK)
        st = rt_renderer_create(t, &o, &r, err, sizeof err);
    sr_progressive p = {"samples", spp, 0, 0, 0, NULL, target, estimate};
    if (st == SLUICE_OK)
        st = sr_progressive_run(&p, step, NULL, r, res);
    if (st == SLUICE_OK)
        st = sr_image_create(w, h, 3, &img, err, sizeof err);
    size_t bad = 0;
    if (st == SLUICE_OK)
        st = rt_renderer_image(r, img, &bad);
    CHECK(st == SLUICE_OK && bad == 0, "render %s: %s %s (%zu non-finite pixels)",
          sr_scene_source(s), err, sluice_context_error(ctx), bad);
    if (st == SLUICE_OK) {
        *stats = *rt_renderer_sampling(r);
    } else {
        sr_image_destroy(img);
        img = NULL;
    }
    rt_renderer_destroy(r);
    rt_tracer_destroy(t);
    return img;
}

static void test_furnace(void)
{
    sr_scene *s = furnace_scene();
    if (!s)
        return;
    const double target = 1e-3;
    char err[256] = "";
    sr_image *truth = NULL;
    sluice_status st = sr_image_create(32, 32, 3, &truth, err, sizeof err);
    CHECK(st == SLUICE_OK, "%s", err);
    for (int adaptive = 0; st == SLUICE_OK && adaptive < 2; ++adaptive) {
        float *q = sr_image_pixels(truth);
        for (size_t i = 0; i < 32 * 32 * 3; ++i)
            q[i] = (float)furnace_radiance();
        sr_adaptive_stats as;
        sr_progressive_result res;
        sr_image *img = render_to(s, 32, 32, 64, target, adaptive, 4096, &as, &res);
        if (!img)
            continue;
        sr_image_metrics m;
        sr_image_compare(img, truth, &m, err, sizeof err);
        printf("furnace, target relMSE %g, %s: stopped after %u samples at an estimate of "
               "%.3g, %.1f%% of pixel samples skipped; true relMSE %.3g (bound: within a "
               "factor of 2 of the target)\n",
               target, adaptive ? "adaptive" : "uniform", res.done, res.error,
               100.0 * (1.0 - (double)as.pixel_samples / (double)as.pixel_uniform), m.rel_mse);
        CHECK(res.converged && m.rel_mse <= 2 * target && m.rel_mse >= target / 8,
              "furnace target: converged %d after %u, estimate %g, true %g", res.converged,
              res.done, res.error, m.rel_mse);
        sr_image_destroy(img);
    }
    sr_image_destroy(truth);
    sr_scene_destroy(s);
}

static void test_cornell(void)
{
    enum { W = 48, H = 48 };
    char err[512] = "";
    sr_scene *s = NULL;
    sr_scene_load_options lo = {0};
    if (sr_scene_load_builtin("cornell", &lo, &s, err, sizeof err) != SLUICE_OK) {
        CHECK(0, "cornell: %s", err);
        return;
    }
    const double target = 1e-2;
    sr_adaptive_stats as, ref_stats;
    sr_progressive_result res, ref_res;
    sr_image *ref = render_to(s, W, H, 4, 0, 0, 1024, &ref_stats, &ref_res);
    sr_image *img = ref ? render_to(s, W, H, 4, target, 1, 4096, &as, &res) : NULL;
    if (img) {
        sr_image_metrics m;
        sr_image_compare(img, ref, &m, err, sizeof err);
        printf("cornell, target relMSE %g, adaptive: %u samples, %u of %u tiles stopped early, "
               "%.1f%% of pixel samples skipped, estimate %.3g (%.3g had every tile taken "
               "every sample); true relMSE against 1,024 samples %.3g (bound: within a factor "
               "of 2 of the target)\n",
               target, res.done, as.tiles - as.tiles_active, as.tiles,
               100.0 * (1.0 - (double)as.pixel_samples / (double)as.pixel_uniform), as.error,
               as.error_uniform, m.rel_mse);
        CHECK(res.converged && m.rel_mse <= 2 * target, "cornell: converged %d, true %g",
              res.converged, m.rel_mse);
        CHECK(as.tiles_active < as.tiles && as.pixel_samples < as.pixel_uniform,
              "cornell: no tile stopped early");
    }
    sr_image_destroy(img);
    sr_image_destroy(ref);
    sr_scene_destroy(s);
}

int main(void)
{
    ctx = check_context(0);
    test_estimator();
    test_stopping();
    test_furnace();
    test_cornell();
    sluice_context_destroy(ctx);
    return check_summary();
}
