/* Tests of sluice_scan against a plain C reference: exclusive and inclusive
 * prefix sums of uint32 (exact, wrapping) and float (double-precision
 * reference, relative bound) streams, adversarial lengths and patterns, a
 * device-side input length, and argument errors. */
#include "check.h"
#include "sluice/streams.h"

#include <float.h>
#include <math.h>
#include <string.h>

enum pattern { RANDOM, EQUAL, SORTED, REVERSE, PATTERNS };
static const char *const pattern_names[] = {"random", "equal", "sorted", "reverse"};

static void fill_u32(uint32_t *v, size_t n, int pattern, uint32_t *seed)
{
    for (size_t i = 0; i < n; ++i) {
        switch (pattern) {
        case RANDOM:
            v[i] = check_rand(seed); /* full range: the sums wrap */
            break;
        case EQUAL:
            v[i] = 0x9e3779b9u;
            break;
        case SORTED:
            v[i] = (uint32_t)i;
            break;
        default:
            v[i] = (uint32_t)(n - i);
            break;
        }
    }
}

static void fill_f32(float *v, size_t n, int pattern, uint32_t *seed)
{
    for (size_t i = 0; i < n; ++i) {
        switch (pattern) {
        case RANDOM: /* mixed signs in [-1, 1) */
            v[i] = (float)((double)check_rand(seed) / 2147483648.0 - 1.0);
            break;
        case EQUAL:
            v[i] = 0.1f;
            break;
        case SORTED:
            v[i] = (float)i / (float)(n ? n : 1);
            break;
        default:
            v[i] = (float)(n - i) / (float)(n ? n : 1);
            break;
        }
    }
}

/* Longest chain of float additions behind one output of the blocked scan,
 * bounded for any chunking with chunks of 1024 .. 2*sqrt(n) records: the
 * worst-case relative error is depth * FLT_EPSILON (times the sum of the
 * magnitudes). */
static double float_depth(size_t n)
{
    double d = 2048.0 + 4.0 * sqrt((double)n) + 8.0;
    return d < (double)n + 1.0 ? d : (double)n + 1.0;
}

/* Runs one scan of n uint32 records and compares with the reference. */
static void check_u32(sluice_context *ctx, size_t n, int pattern, int inclusive)
{
    uint32_t seed = 12345u + (uint32_t)n;
    uint32_t *in = malloc((n + 1) * 4), *out = malloc((n + 1) * 4);
    fill_u32(in, n, pattern, &seed);
    sluice_stream *a = NULL, *b = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n + 3, &b));
    CHECK_OK(ctx, sluice_stream_upload(a, in, n));
    CHECK_OK(ctx, sluice_stream_set_length(b, 2)); /* overwritten, not appended */
    uint32_t total = 0xdeadbeefu;
    CHECK_OK(ctx, sluice_scan(ctx, a, b, SLUICE_U32, inclusive, &total));
    size_t got = 0;
    CHECK_OK(ctx, sluice_stream_download(b, out, n + 1, &got));
    CHECK(got == n, "u32 n=%zu: output length %zu", n, got);
    uint32_t s = 0;
    size_t bad = 0, first = 0;
    for (size_t i = 0; i < n && i < got; ++i) {
        uint32_t want = inclusive ? s + in[i] : s;
        s += in[i];
        if (out[i] != want && bad++ == 0)
            first = i;
    }
    for (size_t i = got; i < n; ++i)
        s += in[i];
    CHECK(bad == 0, "u32 %s %s n=%zu: %zu wrong, first at %zu", pattern_names[pattern],
          inclusive ? "inclusive" : "exclusive", n, bad, first);
    CHECK(total == s, "u32 total n=%zu: %u, want %u", n, total, s);
    sluice_stream_destroy(a);
    sluice_stream_destroy(b);
    free(in);
    free(out);
}

static void check_f32(sluice_context *ctx, size_t n, int pattern, int inclusive)
{
    uint32_t seed = 777u + (uint32_t)n;
    float *in = malloc((n + 1) * 4), *out = malloc((n + 1) * 4);
    fill_f32(in, n, pattern, &seed);
    sluice_stream *a = NULL, *b = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &b));
    CHECK_OK(ctx, sluice_stream_upload(a, in, n));
    float total = -1.0f;
    CHECK_OK(ctx, sluice_scan(ctx, a, b, SLUICE_F32, inclusive, &total));
    size_t got = 0;
    CHECK_OK(ctx, sluice_stream_download(b, out, n, &got));
    CHECK(got == n, "f32 n=%zu: output length %zu", n, got);
    double eps = float_depth(n) * FLT_EPSILON;
    double s = 0.0, mag = 0.0, worst = 0.0;
    size_t bad = 0, first = 0;
    for (size_t i = 0; i < n && i < got; ++i) {
        double want = inclusive ? s + in[i] : s;
        double m = inclusive ? mag + fabs(in[i]) : mag;
        s += in[i];
        mag += fabs(in[i]);
        double e = fabs((double)out[i] - want);
        double tol = eps * m + FLT_MIN;
        if (m > 0 && e / m > worst)
            worst = e / m;
        if (!(e <= tol) && bad++ == 0)
            first = i;
    }
    CHECK(bad == 0, "f32 %s %s n=%zu: %zu out of tolerance, first at %zu", pattern_names[pattern],
          inclusive ? "inclusive" : "exclusive", n, bad, first);
    CHECK(fabs((double)total - s) <= eps * mag + FLT_MIN, "f32 total n=%zu: %g, want %g", n, total,
          s);
    if (n >= (1u << 20))
        printf("f32 scan n=%zu %s: worst error / sum of magnitudes %.3g (bound %.3g)\n", n,
               pattern_names[pattern], worst, eps);
    sluice_stream_destroy(a);
    sluice_stream_destroy(b);
    free(in);
    free(out);
}

/* The input's length known only on the device: the output of a kernel with
 * a conditional output (odd values of 0 .. n-1). */
static void test_device_length(sluice_context *ctx)
{
    static const char *src = "#include \"sluice.cl\"\n"
                             "__kernel void odd(SLUICE_PARAMS, global const uint *in,\n"
                             "                  global uint *out)\n"
                             "{\n"
                             "    SLUICE_FOR_EACH(i) {\n"
                             "        SLUICE_EMIT_IF(0, out, in[i], in[i] & 1u);\n"
                             "    }\n"
                             "}\n";
    const size_t n = 100003;
    uint32_t *v = malloc(n * 4), *out = malloc(n * 4);
    for (size_t i = 0; i < n; ++i)
        v[i] = (uint32_t)i;
    sluice_program *p = NULL;
    sluice_kernel *k = NULL;
    sluice_stream *a = NULL, *odd = NULL, *b = NULL;
    CHECK_OK(ctx, sluice_program_create_source(ctx, "odd.cl", src, NULL, &p));
    CHECK_OK(ctx, sluice_kernel_create(p, "odd", &k));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &odd));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &b));
    CHECK_OK(ctx, sluice_stream_upload(a, v, n));
    CHECK_OK(ctx, sluice_kernel_set_input(k, 0, a));
    CHECK_OK(ctx, sluice_kernel_set_output(k, 1, 0, odd, SLUICE_ORDERED));
    CHECK_OK(ctx, sluice_kernel_launch(k));
    /* Queued without reading the length back. */
    CHECK_OK(ctx, sluice_scan(ctx, odd, b, SLUICE_U32, 1, NULL));
    size_t got = 0;
    CHECK_OK(ctx, sluice_stream_download(b, out, n, &got));
    CHECK(got == n / 2, "device length: %zu records, want %zu", got, n / 2);
    uint32_t s = 0;
    size_t bad = 0;
    for (size_t i = 0; i < got; ++i) {
        s += 2u * (uint32_t)i + 1u;
        bad += out[i] != s;
    }
    CHECK(bad == 0, "device length: %zu wrong", bad);
    sluice_kernel_destroy(k);
    sluice_program_destroy(p);
    sluice_stream_destroy(a);
    sluice_stream_destroy(odd);
    sluice_stream_destroy(b);
    free(v);
    free(out);
}

static void test_errors(sluice_context *ctx)
{
    sluice_stream *a = NULL, *small = NULL, *wide = NULL, *b = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 100, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 99, &small));
    CHECK_OK(ctx, sluice_stream_create(ctx, 8, 100, &wide));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 100, &b));
    uint32_t v[100];
    for (int i = 0; i < 100; ++i)
        v[i] = (uint32_t)i;
    CHECK_OK(ctx, sluice_stream_upload(a, v, 100));
    CHECK_OK(ctx, sluice_stream_upload(wide, v, 50));
    CHECK(sluice_scan(NULL, a, b, SLUICE_U32, 0, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL context");
    CHECK(sluice_scan(ctx, NULL, b, SLUICE_U32, 0, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL input");
    CHECK(sluice_scan(ctx, a, NULL, SLUICE_U32, 0, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL output");
    CHECK(sluice_scan(ctx, a, a, SLUICE_U32, 0, NULL) == SLUICE_ERROR_INVALID_ARGUMENT, "in place");
    CHECK(sluice_scan(ctx, a, b, (sluice_scalar_type)7, 0, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "bad type");
    CHECK(sluice_scan(ctx, wide, b, SLUICE_U32, 0, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "8-byte input records");
    CHECK(strstr(sluice_context_error(ctx), "4 bytes") != NULL, "message: %s",
          sluice_context_error(ctx));
    CHECK(sluice_scan(ctx, a, wide, SLUICE_F32, 1, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "8-byte output records");
    sluice_status st = sluice_scan(ctx, a, small, SLUICE_U32, 0, NULL);
    CHECK(st == SLUICE_ERROR_OVERFLOW, "too-small output: %s", sluice_status_string(st));
    CHECK(strstr(sluice_context_error(ctx), "output capacity 99") != NULL, "message: %s",
          sluice_context_error(ctx));
    /* A shorter input fits. */
    CHECK_OK(ctx, sluice_stream_set_length(a, 99));
    CHECK_OK(ctx, sluice_scan(ctx, a, small, SLUICE_U32, 0, NULL));
    sluice_stream_destroy(a);
    sluice_stream_destroy(small);
    sluice_stream_destroy(wide);
    sluice_stream_destroy(b);
}

/* An input that overflowed is an error, never scanned as truncated (issue
 * 12). Case 0: its length only on the device, the call queued, the output
 * void; 1: the same with the total, which the call reads anyway; 2: an
 * output too small for the capacity, so the call reads the input's length;
 * 3: the length known on the host. */
static void test_overflowed_input(sluice_context *ctx)
{
    const size_t n = 1000, cap = 600;
    for (int c = 0; c < 4; ++c) {
        sluice_stream *in = NULL, *out = NULL;
        CHECK_OK(ctx, check_overflowed(ctx, n, cap, c == 3, &in));
        CHECK_OK(ctx, sluice_stream_create(ctx, 4, c == 2 ? cap - 1 : cap, &out));
        uint32_t total = 7;
        sluice_status st = sluice_scan(ctx, in, out, SLUICE_U32, 0, c == 1 ? &total : NULL);
        if (c == 0) {
            size_t len = 1;
            CHECK(st == SLUICE_OK, "scan queued: %s", sluice_status_string(st));
            st = sluice_stream_length(out, &len);
            CHECK(len == 0 && strstr(sluice_context_error(ctx),
                                     "the output of sluice_scan, written from it, is void"),
                  "void scan: %s", sluice_context_error(ctx));
        } else {
            CHECK(strstr(sluice_context_error(ctx), "sluice_scan: the input stream overflowed: "),
                  "case %d: %s", c, sluice_context_error(ctx));
        }
        CHECK(st == SLUICE_ERROR_OVERFLOW && check_overflow_named(ctx, n, cap),
              "scan of an overflowed input, case %d: %s: %s", c, sluice_status_string(st),
              sluice_context_error(ctx));
        CHECK(total == 7, "no total from an overflowed input: %u", total);
        sluice_stream_destroy(in);
        sluice_stream_destroy(out);
    }
}

/* sluice_streams_prepare: builds what it is asked for (every algorithm,
 * then nothing, then the scan again, and a scan runs after), refuses
 * unknown bits by name and a NULL context. */
static void test_prepare(sluice_context *ctx)
{
    CHECK_OK(ctx, sluice_streams_prepare(ctx, SLUICE_ALG_ALL));
    CHECK_OK(ctx, sluice_streams_prepare(ctx, 0));
    CHECK_OK(ctx, sluice_streams_prepare(ctx, SLUICE_ALG_SCAN));
    CHECK(sluice_streams_prepare(ctx, 1u << 7) == SLUICE_ERROR_INVALID_ARGUMENT &&
              strstr(sluice_context_error(ctx), "unknown algorithm bits 0x80"),
          "unknown bits: %s", sluice_context_error(ctx));
    CHECK(sluice_streams_prepare(NULL, SLUICE_ALG_SCAN) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL context");
}

int main(void)
{
    sluice_context *ctx = check_context(0);
    test_prepare(ctx);
    const size_t sizes[] = {0,   1,    2,    3,    4,    5,    7,     8,     9,       255,    256,
                            257, 1023, 1024, 1025, 4095, 4097, 65535, 65537, 1048575, 1048577};
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; ++si)
        for (int pat = 0; pat < PATTERNS; ++pat)
            for (int incl = 0; incl < 2; ++incl) {
                check_u32(ctx, sizes[si], pat, incl);
                check_f32(ctx, sizes[si], pat, incl);
            }
    /* 2^24 records: one of each type. */
    check_u32(ctx, (size_t)1 << 24, RANDOM, 0);
    check_f32(ctx, (size_t)1 << 24, RANDOM, 1);
    check_f32(ctx, (size_t)1 << 24, EQUAL, 0);
    test_device_length(ctx);
    test_errors(ctx);
    test_overflowed_input(ctx);
    sluice_context_destroy(ctx);
    return check_summary();
}
