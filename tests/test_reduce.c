/* Tests of sluice_reduce against a plain C reference: SUM, MIN and MAX of
 * uint32 (exact, wrapping sums) and float (double-precision reference with a
 * relative bound for sums) streams, adversarial lengths and patterns, the
 * identities of empty streams, NaN and infinities, a device-side length, and
 * argument errors. */
#include "check.h"
#include "sluice/streams.h"

#include <float.h>
#include <math.h>
#include <string.h>

enum pattern { RANDOM, EQUAL, SORTED, REVERSE, PATTERNS };
static const char *const pattern_names[] = {"random", "equal", "sorted", "reverse"};
static const char *const op_names[] = {"sum", "min", "max"};

static uint32_t u32_at(size_t i, size_t n, int pattern, uint32_t *seed)
{
    switch (pattern) {
    case RANDOM:
        return check_rand(seed);
    case EQUAL:
        return 0xfedcba98u;
    case SORTED:
        return (uint32_t)i * 3u + 1u;
    default:
        return (uint32_t)(n - i) * 3u + 1u;
    }
}

static float f32_at(size_t i, size_t n, int pattern, uint32_t *seed)
{
    switch (pattern) {
    case RANDOM:
        return (float)((double)check_rand(seed) / 2147483648.0 - 1.0) * 1000.0f;
    case EQUAL:
        return -0.3f;
    case SORTED:
        return (float)i - (float)n * 0.5f;
    default:
        return (float)n * 0.5f - (float)i;
    }
}

/* Longest chain of float additions behind the blocked sum, for any chunking
 * with 1024 .. 2*sqrt(n) records per chunk; the error bound is this times
 * FLT_EPSILON times the sum of the magnitudes. */
static double float_depth(size_t n)
{
    double d = 2048.0 + 4.0 * sqrt((double)n) + 8.0;
    return d < (double)n + 1.0 ? d : (double)n + 1.0;
}

static void check_u32(sluice_context *ctx, sluice_stream *s, const uint32_t *v, size_t n,
                      const char *what)
{
    CHECK_OK(ctx, sluice_stream_upload(s, v, n));
    uint32_t want[3] = {0u, UINT32_MAX, 0u};
    for (size_t i = 0; i < n; ++i) {
        want[0] += v[i];
        want[1] = v[i] < want[1] ? v[i] : want[1];
        want[2] = v[i] > want[2] ? v[i] : want[2];
    }
    for (int op = 0; op < 3; ++op) {
        uint32_t got = 0x12345678u;
        CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_U32, (sluice_reduce_op)op, &got));
        CHECK(got == want[op], "u32 %s %s n=%zu: %u, want %u", op_names[op], what, n, got,
              want[op]);
    }
}

static void check_f32(sluice_context *ctx, sluice_stream *s, const float *v, size_t n,
                      const char *what)
{
    CHECK_OK(ctx, sluice_stream_upload(s, v, n));
    double sum = 0.0, mag = 0.0;
    float lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; ++i) {
        sum += v[i];
        mag += fabs(v[i]);
        lo = fminf(lo, v[i]);
        hi = fmaxf(hi, v[i]);
    }
    float got[3];
    for (int op = 0; op < 3; ++op)
        CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_F32, (sluice_reduce_op)op, &got[op]));
    double tol = float_depth(n) * FLT_EPSILON * mag + FLT_MIN;
    CHECK(fabs((double)got[0] - sum) <= tol, "f32 sum %s n=%zu: %.9g, want %.9g (tol %g)", what, n,
          got[0], sum, tol);
    CHECK(memcmp(&got[1], &lo, 4) == 0, "f32 min %s n=%zu: %g, want %g", what, n, got[1], lo);
    CHECK(memcmp(&got[2], &hi, 4) == 0, "f32 max %s n=%zu: %g, want %g", what, n, got[2], hi);
}

static void test_sizes(sluice_context *ctx)
{
    const size_t sizes[] = {
        0,   1,    2,    3,    4,    5,    7,     8,     9,       255,     256,
        257, 1023, 1024, 1025, 4095, 4097, 65535, 65537, 1048575, 1048577, (size_t)1 << 24};
    const size_t max = (size_t)1 << 24;
    sluice_stream *s = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, max, &s));
    uint32_t *u = malloc(max * 4);
    float *f = malloc(max * 4);
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; ++si) {
        size_t n = sizes[si];
        for (int pat = 0; pat < PATTERNS; ++pat) {
            if (n == max && pat != RANDOM && pat != EQUAL)
                continue;
            uint32_t seed = 99u + (uint32_t)n;
            for (size_t i = 0; i < n; ++i)
                u[i] = u32_at(i, n, pat, &seed);
            for (size_t i = 0; i < n; ++i)
                f[i] = f32_at(i, n, pat, &seed);
            check_u32(ctx, s, u, n, pattern_names[pat]);
            check_f32(ctx, s, f, n, pattern_names[pat]);
        }
    }
    sluice_stream_destroy(s);
    free(u);
    free(f);
}

/* Identities, extreme values, NaN (ignored by MIN and MAX) and infinities. */
static void test_special(sluice_context *ctx)
{
    sluice_stream *s = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 5000, &s));
    uint32_t u;
    float f;
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_U32, SLUICE_SUM, &u));
    CHECK(u == 0, "empty u32 sum %u", u);
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_U32, SLUICE_MIN, &u));
    CHECK(u == UINT32_MAX, "empty u32 min %u", u);
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_U32, SLUICE_MAX, &u));
    CHECK(u == 0, "empty u32 max %u", u);
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_F32, SLUICE_SUM, &f));
    CHECK(f == 0.0f, "empty f32 sum %g", f);
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_F32, SLUICE_MIN, &f));
    CHECK(f == INFINITY, "empty f32 min %g", f);
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_F32, SLUICE_MAX, &f));
    CHECK(f == -INFINITY, "empty f32 max %g", f);

    /* Extremes of uint32 and a wrapping sum. */
    uint32_t e[5000];
    for (int i = 0; i < 5000; ++i)
        e[i] = i % 2 ? UINT32_MAX : 0u;
    check_u32(ctx, s, e, 5000, "extremes");

    float g[5000];
    for (int i = 0; i < 5000; ++i)
        g[i] = (float)(i % 97) - 40.0f;
    g[1234] = NAN;
    g[17] = NAN;
    CHECK_OK(ctx, sluice_stream_upload(s, g, 5000));
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_F32, SLUICE_MIN, &f));
    CHECK(f == -40.0f, "min ignores NaN: %g", f);
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_F32, SLUICE_MAX, &f));
    CHECK(f == 56.0f, "max ignores NaN: %g", f);
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_F32, SLUICE_SUM, &f));
    CHECK(isnan(f), "sum with NaN is NaN: %g", f);
    g[1234] = -INFINITY;
    g[17] = INFINITY;
    CHECK_OK(ctx, sluice_stream_upload(s, g, 5000));
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_F32, SLUICE_MIN, &f));
    CHECK(f == -INFINITY, "min -inf: %g", f);
    CHECK_OK(ctx, sluice_reduce(ctx, s, SLUICE_F32, SLUICE_MAX, &f));
    CHECK(f == INFINITY, "max inf: %g", f);
    sluice_stream_destroy(s);
}

/* The length known only on the device: the output of a conditional kernel
 * (multiples of 3 of 0 .. n-1). */
static void test_device_length(sluice_context *ctx)
{
    static const char *src = "#include \"sluice.cl\"\n"
                             "__kernel void by3(SLUICE_PARAMS, global const uint *in,\n"
                             "                  global uint *out)\n"
                             "{\n"
                             "    SLUICE_FOR_EACH(i) {\n"
                             "        SLUICE_EMIT_IF(0, out, in[i], in[i] % 3u == 0u);\n"
                             "    }\n"
                             "}\n";
    const size_t n = 300001;
    uint32_t *v = malloc(n * 4);
    uint32_t sum = 0, mx = 0;
    for (size_t i = 0; i < n; ++i) {
        v[i] = (uint32_t)i;
        if (i % 3 == 0) {
            sum += (uint32_t)i;
            mx = (uint32_t)i;
        }
    }
    sluice_program *p = NULL;
    sluice_kernel *k = NULL;
    sluice_stream *a = NULL, *b = NULL;
    CHECK_OK(ctx, sluice_program_create_source(ctx, "by3.cl", src, NULL, &p));
    CHECK_OK(ctx, sluice_kernel_create(p, "by3", &k));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &b));
    CHECK_OK(ctx, sluice_stream_upload(a, v, n));
    CHECK_OK(ctx, sluice_kernel_set_input(k, 0, a));
    CHECK_OK(ctx, sluice_kernel_set_output(k, 1, 0, b, SLUICE_UNORDERED));
    CHECK_OK(ctx, sluice_kernel_launch(k));
    uint32_t got = 0;
    CHECK_OK(ctx, sluice_reduce(ctx, b, SLUICE_U32, SLUICE_SUM, &got));
    CHECK(got == sum, "device length sum %u, want %u", got, sum);
    CHECK_OK(ctx, sluice_reduce(ctx, b, SLUICE_U32, SLUICE_MAX, &got));
    CHECK(got == mx, "device length max %u, want %u", got, mx);
    sluice_kernel_destroy(k);
    sluice_program_destroy(p);
    sluice_stream_destroy(a);
    sluice_stream_destroy(b);
    free(v);
}

static void test_errors(sluice_context *ctx)
{
    sluice_stream *s = NULL, *wide = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 10, &s));
    CHECK_OK(ctx, sluice_stream_create(ctx, 8, 10, &wide));
    uint32_t r;
    CHECK(sluice_reduce(NULL, s, SLUICE_U32, SLUICE_SUM, &r) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL context");
    CHECK(sluice_reduce(ctx, NULL, SLUICE_U32, SLUICE_SUM, &r) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL stream");
    CHECK(sluice_reduce(ctx, s, SLUICE_U32, SLUICE_SUM, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL result");
    CHECK(sluice_reduce(ctx, wide, SLUICE_U32, SLUICE_SUM, &r) == SLUICE_ERROR_INVALID_ARGUMENT,
          "8-byte records");
    CHECK(strstr(sluice_context_error(ctx), "4 bytes") != NULL, "message: %s",
          sluice_context_error(ctx));
    CHECK(sluice_reduce(ctx, s, (sluice_scalar_type)2, SLUICE_SUM, &r) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "bad type");
    CHECK(sluice_reduce(ctx, s, SLUICE_U32, (sluice_reduce_op)3, &r) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "bad operator");
    sluice_stream_destroy(s);
    sluice_stream_destroy(wide);
}

/* An input that overflowed is an error, never reduced as truncated (issue
 * 12): its length known on the host, or only on the device (the flag comes
 * back with the result), for a uint and a float reduction. */
static void test_overflowed_input(sluice_context *ctx)
{
    const size_t n = 1000, cap = 600;
    for (int known = 0; known < 2; ++known) {
        for (int t = 0; t < 2; ++t) {
            sluice_stream *in = NULL;
            CHECK_OK(ctx, check_overflowed(ctx, n, cap, known, &in));
            uint32_t r = 7;
            sluice_status st = sluice_reduce(ctx, in, t ? SLUICE_F32 : SLUICE_U32,
                                             t ? SLUICE_MAX : SLUICE_SUM, &r);
            CHECK(st == SLUICE_ERROR_OVERFLOW && r == 7 &&
                      strstr(sluice_context_error(ctx),
                             "sluice_reduce: the input stream overflowed: ") &&
                      check_overflow_named(ctx, n, cap),
                  "reduce of an overflowed input (known %d, type %d): %s", known, t,
                  sluice_context_error(ctx));
            sluice_stream_destroy(in);
        }
    }
}

int main(void)
{
    sluice_context *ctx = check_context(0);
    test_sizes(ctx);
    test_special(ctx);
    test_device_length(ctx);
    test_errors(ctx);
    test_overflowed_input(ctx);
    sluice_context_destroy(ctx);
    return check_summary();
}
