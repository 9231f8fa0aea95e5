/*
 * Tests of the renderers' quasi-random sampling (kernels/render/rng.cl:
 * rt_owen, rt_sobol2; kernels/render/lights.cl: rt_area_light_sample), run
 * as kernels and checked on the host:
 *   - the net property: points 0 .. 2^m - 1 of every scrambled sequence, with
 *     and without a shuffled index, put exactly one point in every elementary
 *     interval of area 2^-m (m = 0 .. 10, every split of m between x and y);
 *   - every point alone is uniform: over 4096 scrambles, point 5's
 *     coordinates fill 16 bins each within a chi-square bound, and their
 *     means are within 4 standard errors of 1/2;
 *   - Owen scrambling keeps intervals: the top m bits of rt_owen(x) depend
 *     only on the top m bits of x;
 *   - the light sampler keeps strata: 2^m stratified points land on two
 *     triangles of areas 1:3 in the ratio of their areas, to one point, and
 *     every point lies on the triangle it names;
 *   - what stratification buys, measured: the variance of 4-, 16- and
 *     64-point estimates of a disc's area (a penumbra) and of a smooth
 *     irradiance integral (an unshadowed point) against independent points,
 *     with a bound on the ratio for each (printed).
 */
#include "check.h"
#include "test_program.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static sluice_context *ctx;

static const char sampling_cl[] =
    "__kernel void sobol(SLUICE_PARAMS, global float2 *out, uint n, uint shuffle)\n"
    "{\n"
    "    SLUICE_FOR_EACH (i) {\n"
    "        uint s = i / n, k = i % n, seed = rt_hash(s * 7919u + 1u);\n"
    "        out[i] = rt_sobol2(shuffle ? rt_owen(k, rt_hash(seed + 17u)) : k, seed);\n"
    "    }\n"
    "}\n"
    "__kernel void owen(SLUICE_PARAMS, global uint *out, global const uint *x, uint seed)\n"
    "{\n"
    "    SLUICE_FOR_EACH (i) out[i] = rt_owen(x[i], seed);\n"
    "}\n"
    "__kernel void iid(SLUICE_PARAMS, global float2 *out, uint n)\n"
    "{\n"
    "    SLUICE_FOR_EACH (i) {\n"
    "        uint key = rt_key(0x1234u, i);\n"
    "        out[i] = (float2)(rt_rand(key, 0u), rt_rand(key, 1u));\n"
    "    }\n"
    "}\n"
    "__kernel void light(SLUICE_PARAMS, global float4 *out, global const float2 *u,\n"
    "                    global const float *tv, global const uint *tris,\n"
    "                    global const float *cdf, uint count)\n"
    "{\n"
    "    SLUICE_FOR_EACH (i) {\n"
    "        float3 q, ln;\n"
    "        uint t = rt_area_light_sample(u[i].x, u[i].y, count, tris, cdf, tv, &q, &ln);\n"
    "        out[i] = (float4)(q.x, q.y, q.z, (float)t);\n"
    "    }\n"
    "}\n";

static sluice_program *prog;

/* Runs kernel `name` over `count` records with the streams and uint
 * arguments given (streams first; the first is the output, `count` records
 * long afterwards). Returns 1 when it ran. */
static int run(const char *name, size_t count, sluice_stream **streams, unsigned ns,
               const uint32_t *args, unsigned na)
{
    sluice_kernel *k = NULL;
    sluice_status st = sluice_kernel_create(prog, name, &k);
    for (unsigned i = 0; i < ns && st == SLUICE_OK; ++i)
        st = sluice_kernel_set_stream(k, i, streams[i], 0);
    for (unsigned i = 0; i < na && st == SLUICE_OK; ++i)
        st = sluice_kernel_set_arg(k, ns + i, sizeof args[i], &args[i]);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, count);
    if (st == SLUICE_OK) /* the kernels write by index: the output is all of it */
        st = sluice_stream_set_length(streams[0], count);
    if (st == SLUICE_OK)
        st = sluice_context_finish(ctx);
    CHECK(st == SLUICE_OK, "%s: %s", name, sluice_context_error(ctx));
    sluice_kernel_destroy(k);
    return st == SLUICE_OK;
}

/* `seeds` sequences of n points (shuffled indices or not), on the host:
 * 2 floats per point, sequence by sequence; NULL on failure. */
static float *sobol_points(uint32_t n, uint32_t seeds, uint32_t shuffle)
{
    size_t total = (size_t)n * seeds;
    sluice_stream *out = NULL;
    float *host = malloc(total * 2 * sizeof(float));
    int ok = host && sluice_stream_create(ctx, 2 * sizeof(float), total, &out) == SLUICE_OK;
    uint32_t args[] = {n, shuffle};
    ok = ok && run("sobol", total, &out, 1, args, 2);
    ok = ok && sluice_stream_download(out, host, total, NULL) == SLUICE_OK;
    sluice_stream_destroy(out);
    if (!ok) {
        free(host);
        return NULL;
    }
    return host;
}

/* 1 when the n = 2^m points put exactly one point in every elementary
 * interval [i 2^-a, (i+1) 2^-a) x [j 2^-b, (j+1) 2^-b), a + b = m. */
static int is_net(const float *p, unsigned m)
{
    uint32_t n = 1u << m;
    unsigned char *seen = calloc(n, 1);
    if (!seen)
        return 0;
    int ok = 1;
    for (unsigned a = 0; a <= m && ok; ++a) {
        memset(seen, 0, n);
        for (uint32_t k = 0; k < n && ok; ++k) {
            float x = p[2 * k], y = p[2 * k + 1];
            ok = x >= 0.0f && x < 1.0f && y >= 0.0f && y < 1.0f;
            uint32_t i = (uint32_t)(x * (float)(1u << a)),
                     j = (uint32_t)(y * (float)(1u << (m - a)));
            uint32_t cell = (i << (m - a)) | j;
            ok = ok && !seen[cell];
            if (ok)
                seen[cell] = 1;
        }
    }
    free(seen);
    return ok;
}

static void test_nets(void)
{
    for (uint32_t shuffle = 0; shuffle < 2; ++shuffle) {
        const uint32_t seeds = 64;
        float *p = sobol_points(1024, seeds, shuffle);
        if (!p)
            return;
        unsigned failures = 0;
        for (uint32_t s = 0; s < seeds; ++s)
            for (unsigned m = 0; m <= 10; ++m)
                failures += !is_net(p + (size_t)s * 1024 * 2, m);
        CHECK(failures == 0, "%s index: %u of %u prefixes are not (0,m,2)-nets",
              shuffle ? "shuffled" : "plain", failures, seeds * 11);
        /* the first 2^m points of a shuffled sequence are a net, but not the
         * plain one's: the shuffle must change which points come first */
        if (shuffle) {
            float *plain = sobol_points(1024, seeds, 0);
            CHECK(plain && memcmp(plain, p, 16 * 2 * sizeof(float)) != 0,
                  "the shuffled sequence starts as the plain one");
            free(plain);
        }
        free(p);
    }
}

static void test_uniform(void)
{
    const uint32_t seeds = 4096, n = 8;
    float *p = sobol_points(n, seeds, 1);
    if (!p)
        return;
    for (int dim = 0; dim < 2; ++dim) {
        unsigned bins[16] = {0};
        double sum = 0.0;
        for (uint32_t s = 0; s < seeds; ++s) {
            float v = p[((size_t)s * n + 5) * 2 + dim];
            bins[(int)(v * 16.0f)]++;
            sum += v;
        }
        double chi2 = 0.0, expect = seeds / 16.0;
        for (int b = 0; b < 16; ++b)
            chi2 += (bins[b] - expect) * (bins[b] - expect) / expect;
        /* 15 degrees of freedom: P(chi2 > 37.7) = 0.001 */
        CHECK(chi2 < 37.7, "dimension %d: chi-square %.1f over 16 bins", dim, chi2);
        double mean = sum / seeds, se = sqrt(1.0 / 12.0 / seeds);
        CHECK(fabs(mean - 0.5) < 4.0 * se, "dimension %d: mean %.4f", dim, mean);
    }
    free(p);
}

static void test_owen_intervals(void)
{
    enum { N = 4096 };
    uint32_t *x = malloc(N * sizeof *x), *y = malloc(N * sizeof *y);
    sluice_stream *sx = NULL, *sy = NULL;
    int ok = x && y && sluice_stream_create(ctx, 4, N, &sx) == SLUICE_OK &&
             sluice_stream_create(ctx, 4, N, &sy) == SLUICE_OK;
    /* pairs of values that share their top m bits (m = i % 32) and differ
     * below them */
    uint32_t r = 12345u;
    for (int i = 0; ok && i < N; i += 2) {
        r = r * 1664525u + 1013904223u;
        unsigned m = (unsigned)(i / 2) % 32u;
        uint32_t low = m ? (0xffffffffu >> m) : 0xffffffffu;
        x[i] = r;
        x[i + 1] = (r & ~low) | ((r * 2654435761u) & low);
    }
    ok = ok && sluice_stream_upload(sx, x, N) == SLUICE_OK;
    sluice_stream *st[] = {sy, sx};
    uint32_t seed = 0xdeadbeefu;
    ok = ok && run("owen", N, st, 2, &seed, 1);
    ok = ok && sluice_stream_download(sy, y, N, NULL) == SLUICE_OK;
    unsigned bad = 0, distinct = 0;
    for (int i = 0; ok && i < N; i += 2) {
        unsigned m = (unsigned)(i / 2) % 32u;
        uint32_t high = m ? ~(0xffffffffu >> m) : 0u;
        bad += (y[i] & high) != (y[i + 1] & high);
        distinct += y[i] != x[i];
    }
    CHECK(ok && bad == 0, "%u pairs sharing their top bits were split by the scramble", bad);
    CHECK(ok && distinct > N / 2 - 8, "the scramble left %u of %d values as they were",
          N / 2 - distinct, N / 2);
    sluice_stream_destroy(sx);
    sluice_stream_destroy(sy);
    free(x);
    free(y);
}

/* Two triangles of areas 1 and 3 in the z = 0 plane: (0,0) (1,0) (0,2) and
 * (2,0) (5,0) (2,2), as records of v0 and two edges. */
static void test_light_strata(void)
{
    const float tv[18] = {0, 0, 0, 1, 0, 0, 0, 2, 0, 2, 0, 0, 3, 0, 0, 0, 2, 0};
    const uint32_t tris[2] = {0, 1};
    const float cdf[2] = {0.25f, 1.0f};
    const uint32_t n = 256, seeds = 32;
    float *u = sobol_points(n, seeds, 1);
    float *q = malloc((size_t)n * seeds * 4 * sizeof(float));
    sluice_stream *su = NULL, *sq = NULL, *stv = NULL, *str = NULL, *scdf = NULL;
    int ok = u && q && sluice_stream_create(ctx, 8, (size_t)n * seeds, &su) == SLUICE_OK &&
             sluice_stream_create(ctx, 16, (size_t)n * seeds, &sq) == SLUICE_OK &&
             sluice_stream_create(ctx, 4, 18, &stv) == SLUICE_OK &&
             sluice_stream_create(ctx, 4, 2, &str) == SLUICE_OK &&
             sluice_stream_create(ctx, 4, 2, &scdf) == SLUICE_OK;
    ok = ok && sluice_stream_upload(su, u, (size_t)n * seeds) == SLUICE_OK &&
         sluice_stream_upload(stv, tv, 18) == SLUICE_OK &&
         sluice_stream_upload(str, tris, 2) == SLUICE_OK &&
         sluice_stream_upload(scdf, cdf, 2) == SLUICE_OK;
    sluice_stream *st[] = {sq, su, stv, str, scdf};
    uint32_t count = 2;
    ok = ok && run("light", (size_t)n * seeds, st, 5, &count, 1);
    ok = ok && sluice_stream_download(sq, q, (size_t)n * seeds, NULL) == SLUICE_OK;
    unsigned off_ratio = 0, off_triangle = 0;
    for (uint32_t s = 0; ok && s < seeds; ++s) {
        /* prefixes of 4 .. 256 points: a quarter on triangle 0, to one */
        for (uint32_t len = 4; len <= n; len *= 2) {
            uint32_t first = 0;
            for (uint32_t k = 0; k < len; ++k)
                first += q[((size_t)s * n + k) * 4 + 3] == 0.0f;
            off_ratio += abs((int)first * 4 - (int)len) > 4;
        }
        for (uint32_t k = 0; k < n; ++k) {
            const float *p = q + ((size_t)s * n + k) * 4;
            float x = p[0] - (p[3] == 0.0f ? 0.0f : 2.0f), y = p[1];
            float xs = p[3] == 0.0f ? 1.0f : 3.0f; /* the triangle's base */
            off_triangle +=
                !(x >= -1e-6f && y >= -1e-6f && x / xs + y / 2.0f <= 1.0f + 1e-6f && p[2] == 0.0f);
        }
    }
    CHECK(ok && off_ratio == 0, "%u prefixes off the triangles' area ratio by more than 1 point",
          off_ratio);
    CHECK(ok && off_triangle == 0, "%u points off the triangle they name", off_triangle);
    sluice_stream *all[] = {su, sq, stv, str, scdf};
    for (int i = 0; i < 5; ++i)
        sluice_stream_destroy(all[i]);
    free(u);
    free(q);
}

/* Integrands over the unit square: the disc of radius 0.4 about the centre
 * (a penumbra: light blocked over part of a light) and the irradiance
 * factor cos cos / d^2 from a unit square light 1 above a point under its
 * corner (smooth: an unshadowed point). */
static double disc(double x, double y)
{
    double dx = x - 0.5, dy = y - 0.5;
    return dx * dx + dy * dy < 0.16 ? 1.0 : 0.0;
}

static double irradiance(double x, double y)
{
    double d2 = x * x + y * y + 1.0;
    return 1.0 / (d2 * d2);
}

/* The variance over `seeds` sequences of the n-point mean of f, from the
 * points p (n per sequence). */
static double variance(const float *p, uint32_t n, uint32_t seeds, double (*f)(double, double))
{
    double mean = 0.0, m2 = 0.0;
    for (uint32_t s = 0; s < seeds; ++s) {
        double e = 0.0;
        for (uint32_t k = 0; k < n; ++k)
            e += f(p[((size_t)s * n + k) * 2], p[((size_t)s * n + k) * 2 + 1]);
        e /= n;
        double d = e - mean;
        mean += d / (s + 1);
        m2 += d * (e - mean);
    }
    return m2 / (seeds - 1);
}

static void test_variance(void)
{
    const uint32_t seeds = 2048;
    const uint32_t ns[] = {4, 16, 64};
    /* bounds on how many times lower the stratified variance is: measured
     * 2.1x, 1.5x, 6.2x (disc: at 16 points a 4x4 grid of strata, most of
     * them cut by the circle) and 12x, 100x, 1750x (smooth); the bounds
     * leave room for the sampling noise of the variances themselves (about
     * 3% each for 2,048 sequences) */
    const double min_disc[] = {1.6, 1.2, 4.0}, min_smooth[] = {8.0, 60.0, 1000.0};
    for (int t = 0; t < 3; ++t) {
        uint32_t n = ns[t];
        float *strat = sobol_points(n, seeds, 0);
        float *indep = malloc((size_t)n * seeds * 2 * sizeof(float));
        sluice_stream *out = NULL;
        int ok =
            strat && indep && sluice_stream_create(ctx, 8, (size_t)n * seeds, &out) == SLUICE_OK;
        ok = ok && run("iid", (size_t)n * seeds, &out, 1, &n, 1);
        ok = ok && sluice_stream_download(out, indep, (size_t)n * seeds, NULL) == SLUICE_OK;
        if (ok) {
            double d0 = variance(strat, n, seeds, disc), d1 = variance(indep, n, seeds, disc);
            double s0 = variance(strat, n, seeds, irradiance),
                   s1 = variance(indep, n, seeds, irradiance);
            printf("%2u points: variance stratified / independent: disc %.3g / %.3g (%.1fx), "
                   "smooth %.3g / %.3g (%.0fx)\n",
                   n, d0, d1, d1 / d0, s0, s1, s1 / s0);
            CHECK(d1 >= min_disc[t] * d0, "disc, %u points: only %.2fx", n, d1 / d0);
            CHECK(s1 >= min_smooth[t] * s0, "smooth, %u points: only %.1fx", n, s1 / s0);
        }
        CHECK(ok, "variance runs, %u points", n);
        sluice_stream_destroy(out);
        free(strat);
        free(indep);
    }
}

int main(void)
{
    ctx = check_context(0);
    static const char *const parts[] = {"rt_types.h", "rng.cl", "triangle.cl", "surface.cl",
                                        "lights.cl"};
    CHECK_OK(ctx, test_program_create(ctx, "sampling.cl", parts, 5, sampling_cl, &prog));
    if (prog) {
        test_nets();
        test_uniform();
        test_owen_intervals();
        test_light_strata();
        test_variance();
    }
    sluice_program_destroy(prog);
    sluice_context_destroy(ctx);
    return check_summary();
}
