/*
 * The numerical stress suite (issue 13, item 5): each case prints a measured
 * figure and checks it against a stated bound.
 *
 *   furnace_knn         closed sphere, albedo 0.5, point light at its centre:
 *                       the kNN radiance estimate of the indirect light
 *                       against the analytic value: mean within 3%, each
 *                       estimate within 25%
 *   furnace_path        the same sphere, albedo 0.5, point light at its centre:
 *                       the path tracer's mean radiance against the analytic
 *                       value, within 1%
 *   furnace_photonmap   the same sphere through the whole photon mapper
 *                       (direct light by shadow rays, indirect by the kNN
 *                       estimate): within 1%
 *   furnace_progressive progressive photon mapping on the same sphere: its
 *                       RMS error falls with samples (bound: 16 samples
 *                       below 0.6 of 1; theory 0.40), mean within 1%
 *   accumulation        10^6 samples per pixel through the film's 64-bit fixed
 *                       point against a double sum: within one quantum
 *                       (2^-24) of the mean; a float sum's drift is printed
 *   scaled, translated  cornell scaled by 1e-4 and 1e6 and moved by 1e5, 1e6
 *                       and 1e7, direct light with shadow rays, against the
 *                       untouched scene (the bounds and what breaks are below)
 *   grazing             a tilted plane lit at 2 degrees from its horizon:
 *                       no pixel darkened by shadow rays hitting the plane
 *                       they leave (acne), with either intersector
 *   leaks               the inside of a closed box, point lights just outside
 *                       its edges and a corner: no lit pixel with the
 *                       watertight intersector, at most 0.5% with
 *                       Moller-Trumbore
 *
 * kNN ties and photons on cell faces are test_knn's (against FLANN); no NaN
 * or Inf reaches an image (the film drops them and counts them: every case
 * here checks the count is zero).
 */
#include "check.h"
#include "film.h"
#include "test_program.h"
#include "furnace.h"
#include "image.h"
#include "image_metrics.h"
#include "knn.h"
#include "photons.h"
#include "point_grid.h"
#include "kernels.h"
#include "photonmap.h"
#include "render.h"
#include "scene.h"
#include "scene_copy.h"
#include "tracer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static sluice_context *ctx;

/* Renders `spp` samples of `mode` and returns the image (NULL on failure,
 * after a failed check); counts non-finite pixels and contributions. */
static sr_image *render_with(const sr_scene *s, rt_intersector isect, unsigned mode, unsigned w,
                             unsigned h, unsigned spp, unsigned max_depth, unsigned light_samples)
{
    char err[512] = "";
    rt_tracer_options to = rt_tracer_options_default();
    to.exec = RT_EXEC_FUSED;
    to.intersector = isect;
    rt_tracer *t = NULL;
    rt_renderer *r = NULL;
    sr_image *img = NULL;
    sluice_status st = rt_tracer_create(ctx, s, &to, &t, err, sizeof err);
    rt_render_options o;
    memset(&o, 0, sizeof o);
    o.mode = mode;
    o.width = w;
    o.height = h;
    o.max_depth = max_depth;
    o.light_samples = light_samples;
    o.seed = 7;
    if (st == SLUICE_OK)
        st = rt_renderer_create(t, &o, &r, err, sizeof err);
    for (unsigned i = 0; st == SLUICE_OK && i < spp; ++i) {
        st = rt_renderer_sample(r);
        if (st != SLUICE_OK)
            snprintf(err, sizeof err, "%s", sluice_context_error(ctx));
    }
    if (st == SLUICE_OK)
        st = sr_image_create(w, h, 3, &img, err, sizeof err);
    size_t bad = 0;
    if (st == SLUICE_OK)
        st = rt_renderer_image(r, img, &bad);
    CHECK(st == SLUICE_OK, "render %s: %s", sr_scene_source(s), err);
    if (st == SLUICE_OK) {
        CHECK(bad == 0 && rt_renderer_stats(r)->nonfinite == 0,
              "%s: %zu non-finite pixels, %llu contributions dropped", sr_scene_source(s), bad,
              (unsigned long long)rt_renderer_stats(r)->nonfinite);
    } else {
        sr_image_destroy(img);
        img = NULL;
    }
    rt_renderer_destroy(r);
    rt_tracer_destroy(t);
    /* STRESS_IMAGES=DIR keeps every image, to look at a failure */
    const char *dir = getenv("STRESS_IMAGES");
    if (img && dir) {
        static unsigned serial;
        char path[512];
        snprintf(path, sizeof path, "%s/stress-%02u.exr", dir, serial++);
        if (sr_image_write(img, path, err, sizeof err) == SLUICE_OK)
            printf("wrote %s\n", path);
    }
    return img;
}

static sr_image *render(const sr_scene *s, unsigned mode, unsigned w, unsigned h, unsigned spp,
                        unsigned max_depth, unsigned light_samples)
{
    return render_with(s, RT_ISECT_MT, mode, w, h, spp, max_depth, light_samples);
}

static double image_mean(const sr_image *img, int channel)
{
    size_t n = (size_t)sr_image_width(img) * sr_image_height(img);
    const float *p = sr_image_pixels_const(img);
    double sum = 0;
    for (size_t i = 0; i < n; ++i)
        sum += p[3 * i + (size_t)channel];
    return sum / (double)n;
}

/* ------------------------------------------------------------------ */
/* Furnaces                                                            */
/* ------------------------------------------------------------------ */

static void test_furnace_path(void)
{
    sr_scene *s = furnace_scene();
    if (!s)
        return;
    /* 32x32 pixels, 256 paths each, up to 64 bounces (Russian roulette past
     * two keeps it unbiased; 0.5^64 of the light is cut) */
    sr_image *img = render(s, RT_MODE_PATH, 32, 32, 256, 64, 1);
    if (img) {
        double expect = furnace_radiance(), worst = 0;
        for (int c = 0; c < 3; ++c)
            worst = fmax(worst, fabs(image_mean(img, c) / expect - 1));
        printf("furnace, path tracer: mean %.5f, analytic %.5f, worst channel %+.3f%% "
               "(bound 1%%)\n",
               image_mean(img, 1), expect, 100 * (image_mean(img, 1) / expect - 1));
        CHECK(worst < 0.01, "path-traced furnace off by %.2f%%", 100 * worst);
    }
    sr_image_destroy(img);
    sr_scene_destroy(s);
}

static void test_furnace_photonmap(void)
{
    sr_scene *s = furnace_scene();
    if (!s)
        return;
    char err[512] = "";
    pm_options o = pm_options_default();
    o.width = 32;
    o.height = 32;
    o.max_depth = 64;
    o.photons = 200000;
    o.k = 400;
    o.seed = 5;
    pm_renderer *r = NULL;
    sr_image *img = NULL;
    sluice_status st = pm_renderer_create(ctx, s, &o, &r, err, sizeof err);
    for (int i = 0; st == SLUICE_OK && i < 4; ++i)
        st = pm_renderer_sample(r, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_image_create(32, 32, 3, &img, err, sizeof err);
    size_t bad = 0;
    if (st == SLUICE_OK)
        st = sr_film_resolve(pm_renderer_film(r), 1.0 / pm_renderer_stats(r)->samples, img, &bad);
    CHECK(st == SLUICE_OK, "photon-mapped furnace: %s", err);
    if (st == SLUICE_OK) {
        double expect = furnace_radiance(), worst = 0;
        for (int c = 0; c < 3; ++c)
            worst = fmax(worst, fabs(image_mean(img, c) / expect - 1));
        printf("furnace, photon mapper (%u photons stored, k %u): mean %.5f, analytic %.5f, "
               "worst channel %+.3f%% (bound 1%%)\n",
               (unsigned)pm_renderer_stats(r)->photons.stored, o.k, image_mean(img, 1), expect,
               100 * (image_mean(img, 1) / expect - 1));
        CHECK(bad == 0 && pm_renderer_stats(r)->nonfinite == 0, "furnace: non-finite pixels");
        CHECK(worst < 0.01, "photon-mapped furnace off by %.2f%%", 100 * worst);
    }
    sr_image_destroy(img);
    pm_renderer_destroy(r);
    sr_scene_destroy(s);
}

/* The furnace at the kNN estimate: the indirect irradiance the photon map
 * holds (photons stored after at least one bounce) is I / R^2 * a / (1 - a);
 * the estimate sum(Phi) / (pi r^2) at points on the wall must match it. */
static void test_furnace_knn(void)
{
    const float R = furnace_R, a = furnace_a, I = furnace_I;
    char err[512];
    sr_scene *scene = furnace_scene();
    if (!scene)
        return;
    sluice_status st = SLUICE_OK;
    pm_options o = pm_options_default();
    o.max_depth = 64;
    pm_renderer *r = NULL;
    st = pm_renderer_create(ctx, scene, &o, &r, err, sizeof err);
    CHECK(st == SLUICE_OK, "furnace renderer: %s", err);
    pm_photons *ph = NULL;
    if (st == SLUICE_OK)
        st = pm_photons_create(pm_renderer_tracer(r), &ph, err, sizeof err);
    sluice_stream *photons = NULL;
    size_t n = 0;
    pm_photon_stats ps;
    memset(&ps, 0, sizeof ps);
    pm_photon_options po = {60000, 64, 3, 0};
    if (st == SLUICE_OK)
        st = pm_photons_trace(ph, &po, &photons, &n, &ps);
    CHECK(st == SLUICE_OK && n >= 60000, "furnace photons: %zu stored (%s)", n,
          sluice_context_error(ctx));
    CHECK(ps.left_scene == 0, "%llu photons left a closed sphere",
          (unsigned long long)ps.left_scene);
    sr_point_grid *g = NULL;
    pm_knn *knn = NULL;
    rt_grid_desc desc;
    const float lo[3] = {-R * 1.01f, -R * 1.01f, -R * 1.01f},
                hi[3] = {R * 1.01f, R * 1.01f, R * 1.01f};
    if (st == SLUICE_OK)
        st = sr_point_grid_desc_auto(lo, hi, n, 0.1f, &desc, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_point_grid_create(ctx, &g);
    if (st == SLUICE_OK)
        st = sr_point_grid_build(g, &desc, photons, sizeof(pm_photon), n, SR_POINT_GRID_COUNT, 1);
    if (st == SLUICE_OK)
        st = pm_knn_create(ctx, &knn);
    enum { Q = 2000 };
    pm_query *q = malloc(Q * sizeof *q);
    pm_knn_result *res = malloc(Q * sizeof *res);
    sluice_stream *qs = NULL, *rs = NULL;
    if (st == SLUICE_OK && q && res) {
        /* points on the sphere (slightly inside: the facets lie within it),
         * normals facing the centre */
        for (unsigned i = 0; i < Q; ++i) {
            float z = 1.0f - 2.0f * (i + 0.5f) / Q, t = 2.39996323f * (float)i;
            float s = sqrtf(1.0f - z * z);
            float d[3] = {s * cosf(t), s * sinf(t), z};
            q[i] = (pm_query){
                0.995f * R * d[0], 0.995f * R * d[1], 0.995f * R * d[2], -d[0], -d[1], -d[2], i};
        }
        st = sluice_stream_create(ctx, sizeof(pm_query), Q, &qs);
        if (st == SLUICE_OK)
            st = sluice_stream_upload(qs, q, Q);
        if (st == SLUICE_OK)
            st = sluice_stream_create(ctx, sizeof(pm_knn_result), Q, &rs);
        pm_knn_options ko = {200, R, PM_KNN_ATLEAST, 1, NULL, NULL, 0};
        if (st == SLUICE_OK)
            st = pm_knn_query(knn, g, photons, qs, Q, rs, &ko, NULL);
        if (st == SLUICE_OK)
            st = sluice_stream_download(rs, res, Q, NULL);
        CHECK(st == SLUICE_OK, "furnace query: %s", knn ? pm_knn_error(knn) : "");
        if (st == SLUICE_OK) {
            double expect = I / (R * R) * a / (1 - a), sum = 0, worst = 0;
            for (unsigned i = 0; i < Q; ++i) {
                double e = res[i].r2 > 0 ? res[i].sg / (3.14159265358979 * res[i].r2) : 0;
                sum += e;
                worst = fmax(worst, fabs(e / expect - 1));
            }
            double mean = sum / Q;
            /* the mean over 2,000 estimates: within 3% (photon noise and
             * the flat facets; measured -0.00% on 20 x 48^2 facets); each
             * estimate of at least 200 photons (noise about 7%): within 25%
             * (measured 18.5% worst). A
             * bias in photon directions (emission and first bounce sharing
             * random numbers) once put 975% here. */
            CHECK(fabs(mean / expect - 1) < 0.03, "furnace mean %.5f, analytic %.5f", mean, expect);
            CHECK(worst < 0.25, "furnace worst estimate off by %.1f%%", 100 * worst);
            printf("furnace: mean estimate %.5f, analytic %.5f (%+.2f%%), worst %.1f%%\n", mean,
                   expect, 100 * (mean / expect - 1), 100 * worst);
        }
    }
    free(q);
    free(res);
    sluice_stream_destroy(qs);
    sluice_stream_destroy(rs);
    pm_knn_destroy(knn);
    sr_point_grid_destroy(g);
    pm_photons_destroy(ph);
    pm_renderer_destroy(r);
    sr_scene_destroy(scene);
}

/* Progressive photon mapping converges: on the furnace, the pixels' RMS
 * error against the analytic radiance after 1, 4 and 16 samples. Each
 * sample traces new photons with a smaller radius, so both the noise and the
 * bias fall: MSE ~ N^(-2/3) (Knaus and Zwicker 2011), RMS ~ N^(-1/3), 0.40
 * from 1 to 16 samples; the bound is 0.6. The same renderer without it keeps
 * its one photon map: its error stays (printed beside, not bounded). */
static void test_furnace_progressive(void)
{
    sr_scene *s = furnace_scene();
    if (!s)
        return;
    const double expect = furnace_radiance();
    double rms[2][3] = {{0, 0, 0}, {0, 0, 0}}, mean16 = 0;
    for (int prog = 0; prog < 2; ++prog) {
        char err[512] = "";
        pm_options o = pm_options_default();
        o.width = 32;
        o.height = 32;
        o.max_depth = 64;
        o.photons = 20000;
        o.k = 100;
        o.seed = 11;
        o.progressive = prog;
        pm_renderer *r = NULL;
        sr_image *img = NULL;
        sluice_status st = pm_renderer_create(ctx, s, &o, &r, err, sizeof err);
        if (st == SLUICE_OK)
            st = sr_image_create(32, 32, 3, &img, err, sizeof err);
        for (unsigned n = 1, at = 0; st == SLUICE_OK && n <= 16; ++n) {
            st = pm_renderer_sample(r, err, sizeof err);
            if (st != SLUICE_OK || (n != 1 && n != 4 && n != 16))
                continue;
            size_t bad = 0;
            st = sr_film_resolve(pm_renderer_film(r), 1.0 / n, img, &bad);
            if (st != SLUICE_OK)
                break;
            const float *px = sr_image_pixels_const(img);
            double se = 0;
            for (size_t j = 0; j < 32 * 32; ++j)
                se += (px[3 * j + 1] - expect) * (px[3 * j + 1] - expect);
            rms[prog][at++] = sqrt(se / (32 * 32)) / expect;
            if (prog && n == 16)
                mean16 = image_mean(img, 1);
            CHECK(bad == 0, "progressive furnace: %zu non-finite pixels", bad);
        }
        CHECK(st == SLUICE_OK, "progressive furnace: %s", err);
        sr_image_destroy(img);
        pm_renderer_destroy(r);
    }
    double slope = log(rms[1][2] / rms[1][0]) / log(16.0);
    printf("furnace, relative RMS error after 1, 4, 16 samples: progressive %.4f %.4f %.4f "
           "(slope %.2f, theory -0.33; bound: 16 samples below 0.6 of 1), fixed map %.4f %.4f "
           "%.4f; progressive mean after 16 %+.2f%% (bound 1%%)\n",
           rms[1][0], rms[1][1], rms[1][2], slope, rms[0][0], rms[0][1], rms[0][2],
           100 * (mean16 / expect - 1));
    CHECK(rms[1][2] < 0.6 * rms[1][0] && rms[1][1] < rms[1][0],
          "progressive photon mapping does not converge: RMS %.4f, %.4f, %.4f", rms[1][0],
          rms[1][1], rms[1][2]);
    CHECK(fabs(mean16 / expect - 1) < 0.01, "progressive furnace mean off by %.2f%%",
          100 * fabs(mean16 / expect - 1));
    sr_scene_destroy(s);
}

/* ------------------------------------------------------------------ */
/* Accumulation                                                        */
/* ------------------------------------------------------------------ */

/* Sample i of pixel p: a hash in [0, 2), the same float on host and device
 * (integer hash, exact scaling). */
static const char accumulate_cl[] =
    "__kernel void accumulate(SLUICE_PARAMS, global long *accum, uint samples)\n"
    "{\n"
    "    SLUICE_FOR_EACH (p) {\n"
    "        for (uint i = 0; i < samples; ++i) {\n"
    "            uint h = p * 0x9E3779B9u ^ i * 0x85EBCA6Bu;\n"
    "            h ^= h >> 16; h *= 0x7FEB352Du; h ^= h >> 15; h *= 0x846CA68Bu; h ^= h >> 16;\n"
    "            float v = (float)(h >> 8) * 0x1p-23f;\n"
    "            rt_add(accum, p, (float3)(v, v * 0.5f, v * 0.001f));\n"
    "        }\n"
    "    }\n"
    "}\n";

static float sample_value(uint32_t p, uint32_t i)
{
    uint32_t h = p * 0x9E3779B9u ^ i * 0x85EBCA6Bu;
    h ^= h >> 16;
    h *= 0x7FEB352Du;
    h ^= h >> 15;
    h *= 0x846CA68Bu;
    h ^= h >> 16;
    return (float)(h >> 8) * 0x1p-23f;
}

static void test_accumulation(void)
{
    enum { W = 8, H = 4 };
    const uint32_t samples = 1000000;
    sluice_program *prog = NULL;
    sluice_kernel *k = NULL;
    sr_film *film = NULL;
    sr_image *img = NULL;
    char err[256] = "";
    sluice_status st = film_program_create(ctx, "accumulate.cl", accumulate_cl, &prog);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(prog, "accumulate", &k);
    if (st == SLUICE_OK)
        st = sr_film_create(ctx, W, H, &film, err, sizeof err);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 0, sr_film_accum(film), 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 1, sizeof samples, &samples);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, W * H);
    if (st == SLUICE_OK)
        st = sr_image_create(W, H, 3, &img, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_film_resolve(film, 1.0 / samples, img, NULL);
    CHECK(st == SLUICE_OK, "accumulation: %s %s", err, sluice_context_error(ctx));
    if (st == SLUICE_OK) {
        /* the bound: each sample is cut to a multiple of 2^-24 (at most one
         * quantum off, always down), so the mean is within one quantum, and
         * the image's float rounds it by half an ulp: within 2^-24 (1 + m) */
        double worst_fixed = 0, worst_float = 0;
        const float *px = sr_image_pixels_const(img);
        for (uint32_t p = 0; p < W * H; ++p) {
            double exact[3] = {0, 0, 0};
            float naive[3] = {0, 0, 0};
            for (uint32_t i = 0; i < samples; ++i) {
                float v = sample_value(p, i), c[3] = {v, v * 0.5f, v * 0.001f};
                for (int j = 0; j < 3; ++j) {
                    exact[j] += c[j];
                    naive[j] += c[j];
                }
            }
            for (int j = 0; j < 3; ++j) {
                double mean = exact[j] / samples;
                worst_fixed =
                    fmax(worst_fixed, fabs(px[3 * p + (uint32_t)j] - mean) * 0x1p24 / (1 + mean));
                worst_float = fmax(worst_float, fabs((double)naive[j] / samples - mean) / mean);
            }
        }
        printf("accumulation, 10^6 samples per pixel: fixed point within %.3f of the double "
               "mean, in units of 2^-24 (1 + mean) (bound 1); a plain float sum drifts by %.2g "
               "(relative)\n",
               worst_fixed, worst_float);
        CHECK(worst_fixed <= 1.0, "film accumulation off by %.3f quanta", worst_fixed);
    }
    sr_image_destroy(img);
    sr_film_destroy(film);
    sluice_kernel_destroy(k);
    sluice_program_destroy(prog);
}

/* ------------------------------------------------------------------ */
/* Scaled and translated scenes                                        */
/* ------------------------------------------------------------------ */

static void test_scaled_translated(void)
{
    char err[256] = "";
    sr_scene *s = NULL;
    sr_scene_load_options lo = {0};
    if (sr_scene_load_builtin("cornell", &lo, &s, err, sizeof err) != SLUICE_OK) {
        CHECK(0, "cornell: %s", err);
        return;
    }
    enum { W = 64, H = 64, SPP = 4, LS = 4 };
    sr_image *ref = render(s, RT_MODE_SHADOW, W, H, SPP, 1, LS);
    /* Bounds (rmse of the shadow-ray image, values about 0 .. 1): scaling
     * keeps every relative spacing, so the image barely moves (the same random
     * numbers hit the same places; measured 0.0000). Moving the box (555
     * units) by 1e5 leaves coordinates a float spacing of 2^-7 (measured
     * 0.0002), by 1e6 2^-4 (0.0015). By 1e7 the spacing is 1 and the
     * ray-origin offset (sr_scene_epsilon: 4e-6 of the largest coordinate)
     * 40 units: shadow rays start past thin geometry and some pixels are
     * lit that should not be (measured rmse 0.084, max 4.25). That is the
     * limit: up to 1e6 times the scene's size, translations are safe. */
    static const struct {
        float scale, offset;
        double bound;
    } cases[] = {
        {1e-4f, 0.0f, 0.002}, {1e6f, 0.0f, 0.002}, {1.0f, 1e5f, 0.002},
        {1.0f, 1e6f, 0.01},   {1.0f, 1e7f, 0.25},
    };
    for (size_t i = 0; ref && i < sizeof cases / sizeof *cases; ++i) {
        sr_scene *t = scene_copy(s, cases[i].scale, cases[i].offset, NULL, err, sizeof err);
        CHECK(t != NULL, "cornell moved: %s", err);
        sr_image *img = t ? render(t, RT_MODE_SHADOW, W, H, SPP, 1, LS) : NULL;
        sr_image_metrics m;
        if (img && sr_image_compare(img, ref, &m, err, sizeof err) == SLUICE_OK) {
            printf("cornell scaled by %g, moved by %g: shadow-ray image rmse %.4f, max %.3f "
                   "(bound %.3f)\n",
                   (double)cases[i].scale, (double)cases[i].offset, m.rmse, m.max_error,
                   cases[i].bound);
            CHECK(m.rmse <= cases[i].bound && m.nan_count == 0 && m.inf_count == 0,
                  "cornell scaled by %g, moved by %g: rmse %.4f > %.3f", (double)cases[i].scale,
                  (double)cases[i].offset, m.rmse, cases[i].bound);
        }
        sr_image_destroy(img);
        sr_scene_destroy(t);
    }
    sr_image_destroy(ref);
    sr_scene_destroy(s);
}

/* ------------------------------------------------------------------ */
/* Shadow acne and light leaks                                         */
/* ------------------------------------------------------------------ */

/* A plane tilted off the axes (so no coordinate is exact), 2 triangles of
 * 200 x 200, lit by a point light 2 degrees above its horizon, 5,000 units
 * away. Nothing blocks the light anywhere, and across the view the
 * irradiance (cos / d^2) varies by less than 10%: a pixel darker than 0.8
 * of the mean is a shadow ray that hit the plane it leaves (acne). */
static void test_grazing(void)
{
    char err[256] = "";
    sr_scene_builder *b = NULL;
    sr_scene *s = NULL;
    sluice_status st = sr_scene_builder_create("grazing", &b);
    sr_material floor = sr_material_make(SR_MATERIAL_DIFFUSE, "floor");
    uint32_t mf = 0;
    /* rotation about (1, 0.3, 0.2) by 0.4 rad, then a move */
    const float ax[3] = {0.9418f, 0.2825f, 0.1884f}, ang = 0.4f;
    float c = cosf(ang), sn = sinf(ang), t = 1 - c, x = ax[0], y = ax[1], z = ax[2];
    float rot[16] = {t * x * x + c,
                     t * x * y - sn * z,
                     t * x * z + sn * y,
                     13.7f,
                     t * x * y + sn * z,
                     t * y * y + c,
                     t * y * z - sn * x,
                     -4.1f,
                     t * x * z - sn * y,
                     t * y * z + sn * x,
                     t * z * z + c,
                     7.3f,
                     0,
                     0,
                     0,
                     1};
    const float corner[3] = {-100, 0, -100}, u[3] = {0, 0, 200}, v[3] = {200, 0, 0};
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_material(b, &floor, &mf, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_quad(b, corner, u, v, mf, rot, err, sizeof err);
    /* the light 5,000 away along +x, 2 degrees up (tan 2deg = 0.0349); the
     * camera over the plane, looking down at its middle */
    const float pts[4][3] = {{5000, 174.6f, 0}, {0, 150, 10}, {0, 0, 0}, {0, 0, 1}};
    float w[4][3];
    for (int k = 0; k < 4; ++k)
        for (int i = 0; i < 3; ++i)
            w[k][i] = rot[4 * i] * pts[k][0] + rot[4 * i + 1] * pts[k][1] +
                      rot[4 * i + 2] * pts[k][2] + (k < 3 ? rot[4 * i + 3] : 0.0f);
    sr_point_light l = {{w[0][0], w[0][1], w[0][2]}, {1e8f, 1e8f, 1e8f}};
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_point_light(b, &l, err, sizeof err);
    sr_camera cam = {{w[1][0], w[1][1], w[1][2]},
                     {w[2][0], w[2][1], w[2][2]},
                     {w[3][0], w[3][1], w[3][2]},
                     60.0f,
                     96,
                     96};
    if (st == SLUICE_OK)
        st = sr_scene_builder_set_camera(b, &cam, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_scene_builder_finish(b, 0, &s, err, sizeof err);
    sr_scene_builder_destroy(b);
    CHECK(st == SLUICE_OK, "grazing scene: %s", err);
    if (!s)
        return;
    for (int i = 0; i < 2; ++i) {
        rt_intersector isect = i ? RT_ISECT_WATERTIGHT : RT_ISECT_MT;
        sr_image *img = render_with(s, isect, RT_MODE_SHADOW, 96, 96, 1, 1, 1);
        if (img) {
            size_t n = 96 * 96, dark = 0;
            const float *p = sr_image_pixels_const(img);
            double mean = image_mean(img, 1);
            for (size_t j = 0; j < n; ++j)
                dark += p[3 * j + 1] < 0.8 * mean;
            printf("grazing light (2 degrees), %s: mean %.4f, %zu of %zu pixels darker than 0.8 "
                   "of it (bound 0)\n",
                   i ? "watertight" : "mt", mean, dark, n);
            CHECK(mean > 0 && dark == 0, "shadow acne (%s): %zu dark pixels",
                  i ? "watertight" : "mt", dark);
        }
        sr_image_destroy(img);
    }
    sr_scene_destroy(s);
}

static sr_scene *leak_scene(const sr_camera *cam)
{
    char err[256] = "";
    sr_scene_builder *b = NULL;
    sr_scene *s = NULL;
    sluice_status st = sr_scene_builder_create("leaks", &b);
    sr_material wall = sr_material_make(SR_MATERIAL_DIFFUSE, "wall");
    uint32_t mw = 0;
    const float lo[3] = {-1.3f, -0.7f, -2.1f}, hi[3] = {1.7f, 2.9f, 1.1f};
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_material(b, &wall, &mw, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_box(b, lo, hi, mw, NULL, err, sizeof err);
    /* just outside: past an edge (x and y), past a corner, and beyond a face
     * near the middle of an edge */
    const sr_point_light lights[] = {
        {{hi[0] + 1e-3f, hi[1] + 1e-3f, 0.3f}, {5, 5, 5}},
        {{lo[0] - 1e-4f, hi[1] + 1e-4f, lo[2] - 1e-4f}, {5, 5, 5}},
        {{0.2f, lo[1] - 0.5f, hi[2] + 1e-3f}, {5, 5, 5}},
    };
    for (size_t i = 0; st == SLUICE_OK && i < sizeof lights / sizeof *lights; ++i)
        st = sr_scene_builder_add_point_light(b, &lights[i], err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_scene_builder_set_camera(b, cam, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_scene_builder_finish(b, 0, &s, err, sizeof err);
    sr_scene_builder_destroy(b);
    CHECK(st == SLUICE_OK, "leak scene: %s", err);
    return s;
}

static void test_leaks(void)
{
    /* two views from inside: toward the edge and corner lights, then toward
     * the bottom edge near the third */
    const sr_camera views[2] = {
        {{0.2f, 1.1f, -0.5f}, {1.7f, 2.9f, 0.3f}, {0, 1, 0}, 110.0f, 96, 96},
        {{0.2f, 1.1f, -0.5f}, {0.2f, -0.7f, 1.1f}, {0, 0, 1}, 110.0f, 96, 96},
    };
    /* Bounds: none through the watertight test; Moller-Trumbore (the
     * default, Purcell's) lets a ray through where it crosses an edge
     * between two walls within its rounding: measured 6 pixels of 18,432 on
     * these views, aimed at edges; the bound is 0.5% */
    const size_t n = 96 * 96;
    for (int i = 0; i < 2; ++i) {
        rt_intersector isect = i ? RT_ISECT_WATERTIGHT : RT_ISECT_MT;
        size_t lit = 0;
        for (int view = 0; view < 2; ++view) {
            sr_scene *s = leak_scene(&views[view]);
            sr_image *img = s ? render_with(s, isect, RT_MODE_SHADOW, 96, 96, 1, 1, 1) : NULL;
            if (img) {
                const float *p = sr_image_pixels_const(img);
                for (size_t j = 0; j < n; ++j)
                    lit += p[3 * j] != 0.0f || p[3 * j + 1] != 0.0f || p[3 * j + 2] != 0.0f;
            }
            sr_image_destroy(img);
            sr_scene_destroy(s);
        }
        size_t bound = i ? 0 : 2 * n / 200;
        printf("closed box, lights just outside its edges and corner, %s: %zu lit pixels of %zu "
               "(bound %zu)\n",
               i ? "watertight" : "mt", lit, 2 * n, bound);
        CHECK(lit <= bound, "light leaks (%s): %zu lit pixels", i ? "watertight" : "mt", lit);
    }
}

int main(void)
{
    ctx = check_context(0);
    test_accumulation();
    test_furnace_knn();
    test_furnace_path();
    test_furnace_photonmap();
    test_furnace_progressive();
    test_scaled_translated();
    test_grazing();
    test_leaks();
    sluice_context_destroy(ctx);
    return check_summary();
}
