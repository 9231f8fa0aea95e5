/* Tests of the stream runtime: streams, kernels with mapped and conditional
 * outputs (ordered and unordered), counters, loops, profiling and errors,
 * against plain C references. */
#include "check.h"
#include "sluice/streams.h"

#include <math.h>
#include <string.h>

static const char *kernels_src =
    "#include \"sluice.cl\"\n"
    "__kernel void scale(SLUICE_PARAMS, global const float *in, global float *out, float k)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i)\n"
    "        out[i] = in[i] * k;\n"
    "}\n"
    "__kernel void split3(SLUICE_PARAMS, global const uint *in, global uint *a,\n"
    "                     global uint *b, global uint *c)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i) {\n"
    "        uint x = in[i];\n"
    "        SLUICE_EMIT_IF(0, a, x, x % 3u == 0u);\n"
    "        SLUICE_EMIT_IF(1, b, x, x % 3u == 1u);\n"
    "        SLUICE_EMIT_IF(2, c, x, x % 3u == 2u);\n"
    "        SLUICE_COUNT(0, 1u);\n"
    "        SLUICE_COUNT(1, x & 1u);\n"
    "    }\n"
    "}\n"
    /* split3 whose even chunks of 16 records take `spin` steps a record
     * (test_chain_strides) */
    "__kernel void split3_slow(SLUICE_PARAMS, global const uint *in, global uint *a,\n"
    "                          global uint *b, global uint *c, uint spin)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i) {\n"
    "        uint x = in[i], h = x;\n"
    "        for (uint s = (i / 16u) % 2u ? spin : 0u; s < spin; ++s)\n"
    "            h = h * 1664525u + 1013904223u;\n"
    "        if (h == 0xffffffffu && x == 0xfffffffeu)\n"
    "            x = 0u;\n"
    "        SLUICE_EMIT_IF(0, a, x, x % 3u == 0u);\n"
    "        SLUICE_EMIT_IF(1, b, x, x % 3u == 1u);\n"
    "        SLUICE_EMIT_IF(2, c, x, x % 3u == 2u);\n"
    "    }\n"
    "}\n"
    "__kernel void group_of(SLUICE_PARAMS, global const uint *in, global uint *out)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i)\n"
    "        out[i] = (uint)get_group_id(0);\n"
    "}\n"
    "__kernel void dup(SLUICE_PARAMS, global const uint *in, global uint *out)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i) {\n"
    "        uint x = in[i];\n"
    "        for (uint j = 0; j < x % 3u; ++j)\n"
    "            SLUICE_EMIT(0, out, x * 4u + j);\n"
    "    }\n"
    "}\n"
    "__kernel void iota(SLUICE_PARAMS, global uint *out)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i)\n"
    "        out[i] = i;\n"
    "}\n"
    /* Block emission as in the README's "Writing a kernel", but always in
     * blocks (no SLUICE_EMIT16_FAST test), so that runtime_portable
     * (SLUICE_NO_SIMD=1) runs SLUICE_EMIT16's lane-by-lane path. */
    "__kernel void small_values(SLUICE_PARAMS, global const uint *in, global uint *out)\n"
    "{\n"
    "    SLUICE_FOR_EACH_RANGE(b, e) {\n"
    "        uint i = b;\n"
    "        for (; i + 16u <= e; i += 16u) {\n"
    "            uint16 x = SLUICE_LOAD16(in + i);\n"
    "            SLUICE_EMIT16(0, out, x, sluice_mask16(as_int16(x < (uint16)100u)));\n"
    "        }\n"
    "        for (; i < e; ++i)\n"
    "            SLUICE_EMIT_IF(0, out, in[i], in[i] < 100u);\n"
    "    }\n"
    "}\n"
    /* The README's 4-record blocks (SLUICE_FOR_EACH_BLOCK, SLUICE_EMIT4):
     * blocks of 4 in the interleaved layout (runtime_gpu, runtime_interleaved),
     * one chunk elsewhere. */
    "__kernel void small_values4(SLUICE_PARAMS, global const uint *in, global uint *out)\n"
    "{\n"
    "    SLUICE_FOR_EACH_BLOCK(b, e) {\n"
    "        uint i = b;\n"
    "        if (e - b == 4u && (b & 3u) == 0u) {\n"
    "            uint4 x = *(global const uint4 *)(in + b);\n"
    "            SLUICE_EMIT4(0, out, x, sluice_mask4(x < (uint4)100u));\n"
    "            i = e;\n"
    "        }\n"
    "        for (; i < e; ++i)\n"
    "            SLUICE_EMIT_IF(0, out, in[i], in[i] < 100u);\n"
    "    }\n"
    "}\n"
    /* SLUICE_FOR_EACH_BLOCK_OF: blocks of 8 in the interleaved layout, two
     * vectors each (the library's compaction takes 16 this way). */
    "__kernel void small_values_of8(SLUICE_PARAMS, global const uint *in, global uint *out)\n"
    "{\n"
    "    SLUICE_FOR_EACH_BLOCK_OF(b, e, 8u) {\n"
    "        uint i = b;\n"
    "        for (; i + 4u <= e && (i & 3u) == 0u; i += 4u) {\n"
    "            uint4 x = *(global const uint4 *)(in + i);\n"
    "            SLUICE_EMIT4(0, out, x, sluice_mask4(x < (uint4)100u));\n"
    "        }\n"
    "        for (; i < e; ++i)\n"
    "            SLUICE_EMIT_IF(0, out, in[i], in[i] < 100u);\n"
    "    }\n"
    "}\n"
    /* Nine mapped outputs: one more than a launch sets the lengths of. */
    "__kernel void fan9(SLUICE_PARAMS, global const uint *in, global uint *o0,\n"
    "                   global uint *o1, global uint *o2, global uint *o3, global uint *o4,\n"
    "                   global uint *o5, global uint *o6, global uint *o7, global uint *o8)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i) {\n"
    "        uint x = in[i];\n"
    "        o0[i] = x; o1[i] = x + 1u; o2[i] = x + 2u; o3[i] = x + 3u; o4[i] = x + 4u;\n"
    "        o5[i] = x + 5u; o6[i] = x + 6u; o7[i] = x + 7u; o8[i] = x + 8u;\n"
    "    }\n"
    "}\n"
    /* Halves every value and keeps those still above 1: a shrinking loop. */
    "__kernel void halve(SLUICE_PARAMS, global const uint *in, global uint *out)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i) {\n"
    "        uint x = in[i] / 2u;\n"
    "        SLUICE_EMIT_IF(0, out, x, x > 1u);\n"
    "        SLUICE_COUNT(0, x > 1u);\n"
    "    }\n"
    "}\n"
    "__kernel void add_up(SLUICE_PARAMS, global const uint *in)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i)\n"
    "        SLUICE_COUNT(0, in[i]);\n"
    "}\n";

static sluice_program *program(sluice_context *ctx)
{
    sluice_program *p = NULL;
    CHECK_OK(ctx, sluice_program_create_source(ctx, "test_kernels.cl", kernels_src, NULL, &p));
    return p;
}

static void test_streams(sluice_context *ctx)
{
    sluice_stream *s = NULL, *t = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 10, &s));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 0, &t));
    uint32_t v[10] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, w[20] = {0};
    size_t n = 99;
    CHECK_OK(ctx, sluice_stream_length(s, &n));
    CHECK(n == 0, "new stream length %zu", n);
    CHECK_OK(ctx, sluice_stream_upload(s, v, 10));
    CHECK(sluice_stream_upload(s, v, 11) == SLUICE_ERROR_OVERFLOW, "upload over capacity");
    CHECK_OK(ctx, sluice_stream_download(s, w, 20, &n));
    CHECK(n == 10 && memcmp(v, w, sizeof v) == 0, "round trip");
    CHECK_OK(ctx, sluice_stream_grow(s, 1000));
    CHECK(sluice_stream_capacity(s) == 1000, "grow capacity");
    memset(w, 0, sizeof w);
    CHECK_OK(ctx, sluice_stream_download(s, w, 20, &n));
    CHECK(n == 10 && memcmp(v, w, sizeof v) == 0, "grow keeps records");
    CHECK_OK(ctx, sluice_stream_swap(s, t));
    CHECK(sluice_stream_capacity(t) == 1000 && sluice_stream_capacity(s) == 0, "swap");
    CHECK_OK(ctx, sluice_stream_length(t, &n));
    CHECK(n == 10, "swap moves the length (%zu)", n);
    CHECK_OK(ctx, sluice_stream_set_length(t, 3));
    CHECK_OK(ctx, sluice_stream_length(t, &n));
    CHECK(n == 3, "set_length");
    CHECK(sluice_stream_set_length(t, 1001) == SLUICE_ERROR_OVERFLOW, "set_length over capacity");
    sluice_stream *d = NULL;
    CHECK(sluice_stream_create(ctx, 8, 0, NULL) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL out");
    CHECK(sluice_stream_create(ctx, 0, 5, &d) == SLUICE_ERROR_INVALID_ARGUMENT && !d,
          "record size 0");
    sluice_stream *u = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 8, 3, &u));
    CHECK(sluice_stream_swap(s, u) == SLUICE_ERROR_INVALID_ARGUMENT, "swap of mixed sizes");
    /* A request larger than device memory fails cleanly. */
    sluice_device_info info;
    sluice_context_device(ctx, &info);
    sluice_stream *huge = NULL;
    sluice_status st =
        sluice_stream_create(ctx, 1024, (size_t)(info.global_mem_bytes / 512), &huge);
    CHECK(st == SLUICE_ERROR_OUT_OF_MEMORY && !huge, "huge stream: %s", sluice_status_string(st));
    CHECK(strstr(sluice_context_error(ctx), "bytes") != NULL, "message: %s",
          sluice_context_error(ctx));
    sluice_stream_destroy(s);
    sluice_stream_destroy(t);
    sluice_stream_destroy(u);
    sluice_stream_destroy(NULL);
}

/* Launches kernel scale (out[i] = in[i] * kf, a mapped output) over `in`. */
static void launch_scale(sluice_context *ctx, sluice_kernel *k, sluice_stream *in,
                         sluice_stream *out, float kf)
{
    CHECK_OK(ctx, sluice_kernel_set_input(k, 0, in));
    CHECK_OK(ctx, sluice_kernel_set_stream(k, 1, out, 1));
    CHECK_OK(ctx, sluice_kernel_set_arg(k, 2, sizeof kf, &kf));
    CHECK_OK(ctx, sluice_kernel_launch(k));
}

static void test_map(sluice_context *ctx, sluice_program *p)
{
    sluice_kernel *k = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "scale", &k));
    if (!k)
        return;
    const size_t sizes[] = {0, 1, 7, 255, 256, 257, 100000};
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; ++si) {
        size_t n = sizes[si];
        float *in = malloc((n + 1) * sizeof *in), *out = malloc((n + 1) * sizeof *out);
        for (size_t i = 0; i < n; ++i)
            in[i] = (float)i * 0.5f;
        sluice_stream *a, *b;
        CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &a));
        CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &b));
        CHECK_OK(ctx, sluice_stream_upload(a, in, n));
        launch_scale(ctx, k, a, b, 3.0f);
        size_t got = 99;
        CHECK_OK(ctx, sluice_stream_download(b, out, n, &got));
        CHECK(got == n, "mapped length %zu of %zu", got, n);
        int bad = 0;
        for (size_t i = 0; i < got; ++i)
            bad += out[i] != in[i] * 3.0f;
        CHECK(bad == 0, "scale n=%zu: %d wrong", n, bad);
        sluice_stream_destroy(a);
        sluice_stream_destroy(b);
        free(in);
        free(out);
    }
    /* Argument errors. */
    CHECK(sluice_kernel_set_arg(k, 9, 4, &sizes) == SLUICE_ERROR_INVALID_ARGUMENT, "arg index");
    CHECK(strstr(sluice_context_error(ctx), "argument 9") != NULL, "%s", sluice_context_error(ctx));
    CHECK(sluice_kernel_set_arg(k, 2, 2, &sizes) == SLUICE_ERROR_INVALID_ARGUMENT, "arg size");
    sluice_kernel_destroy(k);

    sluice_kernel *g = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "iota", &g));
    sluice_stream *o;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 5000, &o));
    CHECK(sluice_kernel_launch_count(g, 10) == SLUICE_ERROR_INVALID_ARGUMENT, "unset argument");
    CHECK(strstr(sluice_context_error(ctx), "argument 0 is not set") != NULL, "%s",
          sluice_context_error(ctx));
    CHECK_OK(ctx, sluice_kernel_set_stream(g, 0, o, 0));
    CHECK_OK(ctx, sluice_kernel_launch_count(g, 5000));
    uint32_t *r = malloc(5000 * 4);
    CHECK_OK(ctx, sluice_stream_set_length(o, 5000));
    CHECK_OK(ctx, sluice_stream_download(o, r, 5000, NULL));
    int bad = 0;
    for (uint32_t i = 0; i < 5000; ++i)
        bad += r[i] != i;
    CHECK(bad == 0, "generator: %d wrong", bad);
    CHECK(sluice_kernel_launch(g) == SLUICE_ERROR_INVALID_ARGUMENT, "launch without input");
    free(r);
    sluice_stream_destroy(o);
    sluice_kernel_destroy(g);
}

/* The split into three conditional outputs against a C reference. */
/* Makes the three outputs of kernel split3 (capacity `cap`) and launches it
 * over `in`, counting into `cn`. */
static void launch_split3(sluice_context *ctx, sluice_kernel *k, sluice_stream *in, size_t cap,
                          sluice_stream *out[3], sluice_counters *cn, sluice_output_mode mode)
{
    CHECK_OK(ctx, sluice_kernel_set_input(k, 0, in));
    for (unsigned j = 0; j < 3; ++j) {
        CHECK_OK(ctx, sluice_stream_create(ctx, 4, cap, &out[j]));
        CHECK_OK(ctx, sluice_kernel_set_output(k, 1 + j, j, out[j], mode));
    }
    CHECK_OK(ctx, sluice_kernel_set_counters(k, cn));
    CHECK_OK(ctx, sluice_kernel_launch(k));
}

static void test_split(sluice_context *ctx, sluice_program *p, size_t n, int pattern,
                       sluice_output_mode mode, int uneven)
{
    sluice_kernel *k = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "split3", &k));
    CHECK_OK(ctx, sluice_kernel_set_uneven(k, uneven));
    sluice_counters *cn = NULL;
    const char *names[] = {"records", "odd"};
    CHECK_OK(ctx, sluice_counters_create(ctx, 2, names, &cn));
    uint32_t *in = malloc((n + 1) * 4), *ref[3], *got = malloc((n + 1) * 4);
    size_t rn[3] = {0, 0, 0};
    uint32_t seed = 12345u + (uint32_t)n, odd = 0;
    for (int j = 0; j < 3; ++j)
        ref[j] = malloc((n + 1) * 4);
    for (size_t i = 0; i < n; ++i) {
        uint32_t x = pattern == 0   ? check_rand(&seed)
                     : pattern == 1 ? 7u                 /* all equal: one output */
                     : pattern == 2 ? (uint32_t)(3 * i)  /* everything to output 0 */
                                    : (uint32_t)(n - i); /* reverse */
        in[i] = x;
        ref[x % 3][rn[x % 3]++] = x;
        odd += x & 1u;
    }
    sluice_stream *s_in, *s_out[3] = {NULL, NULL, NULL};
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &s_in));
    CHECK_OK(ctx, sluice_stream_upload(s_in, in, n));
    launch_split3(ctx, k, s_in, n, s_out, cn, mode);
    for (int j = 0; j < 3; ++j) {
        size_t len = 0;
        CHECK_OK(ctx, sluice_stream_download(s_out[j], got, n, &len));
        CHECK(len == rn[j], "n=%zu pattern %d uneven %d output %d: length %zu, want %zu", n,
              pattern, uneven, j, len, rn[j]);
        if (mode == SLUICE_UNORDERED) {
            CHECK(check_sort_u32(got, len), "out of memory");
            CHECK(check_sort_u32(ref[j], rn[j]), "out of memory");
        }
        CHECK(len == rn[j] && memcmp(got, ref[j], len * 4) == 0,
              "n=%zu pattern %d uneven %d output %d (%s): records differ", n, pattern, uneven, j,
              mode == SLUICE_ORDERED ? "ordered" : "unordered");
    }
    uint32_t cv[2];
    CHECK_OK(ctx, sluice_counters_read(cn, cv));
    CHECK(cv[0] == n && cv[1] == odd, "counters %u %u, want %zu %u", cv[0], cv[1], n, odd);
    CHECK(sluice_counters_index(cn, "odd") == 1 && sluice_counters_index(cn, "x") == -1,
          "counter names");
    for (int j = 0; j < 3; ++j) {
        sluice_stream_destroy(s_out[j]);
        free(ref[j]);
    }
    sluice_stream_destroy(s_in);
    sluice_counters_destroy(cn);
    sluice_kernel_destroy(k);
    free(in);
    free(got);
}

/* Which work-group took each record, with and without the uneven hint
 * (sluice_kernel_set_uneven): without it the groups take the stream in
 * order; with it, in the contiguous layout, each group still takes one run
 * of consecutive records (its chunks), every record once, but the runs are
 * spread over the groups (the CPU's guided scheduling hands out consecutive
 * groups). */
static void test_uneven(sluice_context *ctx, sluice_program *p, int contiguous)
{
    sluice_kernel *k = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "group_of", &k));
    const size_t sizes[] = {1, 100, 3000, 65537, 300001};
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; ++si) {
        size_t n = sizes[si];
        uint32_t *g = calloc(n, sizeof *g);
        sluice_stream *in = NULL, *out = NULL;
        CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &in));
        CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &out));
        CHECK_OK(ctx, sluice_stream_upload(in, g, n));
        for (int uneven = 0; uneven < 2; ++uneven) {
            CHECK_OK(ctx, sluice_kernel_set_uneven(k, uneven));
            CHECK_OK(ctx, sluice_kernel_set_input(k, 0, in));
            CHECK_OK(ctx, sluice_kernel_set_stream(k, 1, out, 1));
            CHECK_OK(ctx, sluice_kernel_launch(k));
            size_t got = 0;
            CHECK_OK(ctx, sluice_stream_download(out, g, n, &got));
            CHECK(got == n, "group_of n=%zu: %zu records", n, got);
            size_t runs = 1, falls = 0, most = got ? g[0] : 0;
            for (size_t i = 1; i < got; ++i) {
                runs += g[i] != g[i - 1];
                falls += g[i] < g[i - 1];
                most = g[i] > most ? g[i] : most;
            }
            /* one run per group: no group comes back after another */
            char *seen = calloc(most + 1, 1);
            int again = 0;
            for (size_t i = 0; i < got; ++i) {
                if (i && g[i] == g[i - 1])
                    continue;
                again |= seen[g[i]];
                seen[g[i]] = 1;
            }
            free(seen);
            CHECK(!again, "group_of n=%zu uneven %d: a group took two runs of records", n, uneven);
            if (!uneven || !contiguous || runs < 3)
                CHECK(falls == 0, "group_of n=%zu uneven %d: groups out of order (%zu falls)", n,
                      uneven, falls);
            else
                CHECK(falls > 0, "group_of n=%zu: %zu groups in order despite the uneven hint", n,
                      runs);
        }
        sluice_stream_destroy(in);
        sluice_stream_destroy(out);
        free(g);
    }
    CHECK(sluice_kernel_set_uneven(NULL, 1) == SLUICE_ERROR_INVALID_ARGUMENT,
          "uneven: NULL kernel");
    sluice_kernel_destroy(k);
}

/* Several records per input, appended after existing contents, and overflow. */
static void test_multi_emit(sluice_context *ctx, sluice_program *p, sluice_output_mode mode)
{
    const size_t n = 10001;
    sluice_kernel *k = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "dup", &k));
    uint32_t *in = malloc(n * 4), *ref = malloc(3 * n * 4 + 8), *got = malloc(3 * n * 4 + 8);
    size_t rn = 2;
    ref[0] = 111;
    ref[1] = 222;
    for (size_t i = 0; i < n; ++i) {
        in[i] = (uint32_t)(i * 7919u % 10007u);
        for (uint32_t j = 0; j < in[i] % 3; ++j)
            ref[rn++] = in[i] * 4 + j;
    }
    sluice_stream *a, *o;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, rn, &o));
    CHECK_OK(ctx, sluice_stream_upload(a, in, n));
    CHECK_OK(ctx, sluice_stream_upload(o, ref, 2)); /* appended after these */
    CHECK_OK(ctx, sluice_kernel_set_input(k, 0, a));
    CHECK_OK(ctx, sluice_kernel_set_output(k, 1, 0, o, mode));
    CHECK_OK(ctx, sluice_kernel_launch(k));
    size_t len = 0;
    CHECK_OK(ctx, sluice_stream_download(o, got, rn, &len));
    if (mode == SLUICE_UNORDERED) {
        CHECK(check_sort_u32(got + 2, len - 2), "out of memory");
        CHECK(check_sort_u32(ref + 2, rn - 2), "out of memory");
    }
    CHECK(len == rn && memcmp(got, ref, rn * 4) == 0, "multi-emit: length %zu want %zu", len, rn);
    /* Second launch into a full stream: overflow is reported, nothing crashes. */
    CHECK_OK(ctx, sluice_kernel_launch(k));
    sluice_status st = sluice_stream_download(o, got, rn, &len);
    CHECK(st == SLUICE_ERROR_OVERFLOW && len == rn, "overflow: %s, %zu", sluice_status_string(st),
          len);
    CHECK(memcmp(got, ref, 2 * 4) == 0, "records before the overflow are intact");
    char named[160];
    snprintf(named, sizeof named,
             "stream overflowed: %zu records were emitted into output slot 0 of kernel dup, a "
             "stream of capacity %zu",
             2 + 2 * (rn - 2), rn);
    CHECK(strstr(sluice_context_error(ctx), named), "overflow message: %s",
          sluice_context_error(ctx));
    /* An overflowed stream used as input is an error, never read as
     * truncated. Its length only on the device: the launch is queued, reads
     * no records and makes its output void; reading that output reports the
     * overflow where it began. */
    sluice_kernel *h = NULL;
    sluice_stream *ho = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "halve", &h));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 2 * rn, &ho));
    sluice_stream_destroy(a); /* forget o's host-side length: reread it on the device */
    CHECK_OK(ctx, sluice_kernel_set_output(k, 1, 0, o, mode));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &a));
    CHECK_OK(ctx, sluice_stream_upload(a, in, n));
    CHECK_OK(ctx, sluice_kernel_set_input(k, 0, a));
    CHECK_OK(ctx, sluice_kernel_launch(k)); /* o stays over capacity, length on the device */
    CHECK_OK(ctx, sluice_kernel_set_input(h, 0, o));
    CHECK_OK(ctx, sluice_kernel_set_output(h, 1, 0, ho, SLUICE_UNORDERED));
    CHECK_OK(ctx, sluice_kernel_launch(h));
    size_t got_h = 1, emitted = 2 + 3 * (rn - 2); /* three launches appended to o */
    st = sluice_stream_length(ho, &got_h);
    char want[256];
    snprintf(want, sizeof want,
             "stream overflowed: %zu records were emitted into output slot 0 of kernel dup, a "
             "stream of capacity %zu; output slot 0 of kernel halve, written from it, is void",
             emitted, rn);
    CHECK(st == SLUICE_ERROR_OVERFLOW && got_h == 0 && strstr(sluice_context_error(ctx), want),
          "overflowed input on the device: %s, %zu: %s", sluice_status_string(st), got_h,
          sluice_context_error(ctx));
    CHECK(sluice_stream_download(ho, got, rn, &got_h) == SLUICE_ERROR_OVERFLOW && got_h == 0,
          "a void stream downloads nothing: %zu", got_h);
    /* A mapped output takes the input's length: void too. */
    sluice_kernel *sc = NULL;
    sluice_stream *mo = NULL;
    float two = 2.0f;
    CHECK_OK(ctx, sluice_kernel_create(p, "scale", &sc));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, rn, &mo));
    CHECK_OK(ctx, sluice_kernel_set_input(sc, 0, o));
    CHECK_OK(ctx, sluice_kernel_set_stream(sc, 1, mo, 1));
    CHECK_OK(ctx, sluice_kernel_set_arg(sc, 2, sizeof two, &two));
    CHECK_OK(ctx, sluice_kernel_launch(sc));
    CHECK(sluice_stream_length(mo, &got_h) == SLUICE_ERROR_OVERFLOW &&
              strstr(sluice_context_error(ctx), "the mapped output (argument 1) of kernel scale, "
                                                "written from it, is void"),
          "mapped output of an overflowed input: %s", sluice_context_error(ctx));
    sluice_stream_destroy(mo);
    sluice_kernel_destroy(sc);
    /* Its length known on the host: the launch itself fails. */
    size_t len_o = 0;
    CHECK(sluice_stream_length(o, &len_o) == SLUICE_ERROR_OVERFLOW && len_o == emitted,
          "overflowed length %zu, want %zu", len_o, emitted);
    CHECK(sluice_kernel_launch(h) == SLUICE_ERROR_OVERFLOW, "launch over an overflowed input");
    CHECK(strstr(sluice_context_error(ctx), "kernel halve: its input (argument 0) stream "
                                            "overflowed: ") &&
              strstr(sluice_context_error(ctx), "output slot 0 of kernel dup"),
          "launch message: %s", sluice_context_error(ctx));
    /* Recovery: growing an overflowed stream empties it, and it fills again. */
    CHECK_OK(ctx, sluice_stream_grow(o, emitted));
    CHECK(sluice_stream_length(o, &len_o) == SLUICE_OK && len_o == 0, "grown empty: %zu", len_o);
    CHECK_OK(ctx, sluice_kernel_launch(k));
    CHECK_OK(ctx, sluice_stream_length(o, &len_o));
    CHECK(len_o == rn - 2, "refilled after growing: %zu, want %zu", len_o, rn - 2);
    sluice_stream_destroy(ho);
    sluice_kernel_destroy(h);
    sluice_stream_destroy(a);
    sluice_stream_destroy(o);
    sluice_kernel_destroy(k);
    free(in);
    free(ref);
    free(got);
}

/* SLUICE_FOR_EACH_RANGE + SLUICE_EMIT16 and SLUICE_FOR_EACH_BLOCK(_OF) +
 * SLUICE_EMIT4 against C, on lengths around the 16-, 8- and 4-record
 * blocks, both modes. */
static void test_block_emit(sluice_context *ctx, sluice_program *p, const char *kernel)
{
    /* the last one long enough that the interleaved layout gives a
     * work-item several blocks (chunks of 32 records and more) */
    const size_t sizes[] = {0, 1, 3, 4, 5, 7, 8, 9, 15, 16, 17, 1000, 1027, 100003, 2097159};
    sluice_kernel *k = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, kernel, &k));
    for (int m = 0; m < 2; ++m) {
        for (size_t si = 0; si < sizeof sizes / sizeof *sizes; ++si) {
            size_t n = sizes[si], rn = 0, len = 0;
            uint32_t seed = 99u + (uint32_t)n;
            uint32_t *in = malloc(n * 4 + 4), *ref = malloc(n * 4 + 4), *got = malloc(n * 4 + 4);
            for (size_t i = 0; i < n; ++i) {
                in[i] = check_rand(&seed) % 200u;
                if (in[i] < 100u)
                    ref[rn++] = in[i];
            }
            sluice_stream *a = NULL, *o = NULL;
            CHECK_OK(ctx, sluice_stream_create(ctx, 4, n ? n : 1, &a));
            CHECK_OK(ctx, sluice_stream_create(ctx, 4, n ? n : 1, &o));
            CHECK_OK(ctx, sluice_stream_upload(a, in, n));
            CHECK_OK(ctx, sluice_kernel_set_input(k, 0, a));
            CHECK_OK(ctx, sluice_kernel_set_output(k, 1, 0, o, (sluice_output_mode)m));
            CHECK_OK(ctx, sluice_kernel_launch(k));
            CHECK_OK(ctx, sluice_stream_download(o, got, n, &len));
            if (m == SLUICE_UNORDERED && rn > 1 && len == rn) {
                CHECK(check_sort_u32(got, len), "out of memory");
                CHECK(check_sort_u32(ref, rn), "out of memory");
            }
            CHECK(len == rn && (rn == 0 || memcmp(got, ref, rn * 4) == 0),
                  "%s n=%zu mode %d: %zu records, want %zu", kernel, n, m, len, rn);
            sluice_stream_destroy(a);
            sluice_stream_destroy(o);
            free(in);
            free(ref);
            free(got);
        }
    }
    sluice_kernel_destroy(k);
}

typedef struct loop_user {
    sluice_kernel *k;
    sluice_stream *a, *b;
    sluice_counters *cn;
} loop_user;

static sluice_status halve_pass(void *user, unsigned pass, unsigned choice)
{
    (void)pass;
    (void)choice;
    loop_user *u = user;
    sluice_status st = sluice_stream_clear(u->b);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(u->k, 0, u->a);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(u->k, 1, 0, u->b, SLUICE_UNORDERED);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(u->k);
    if (st == SLUICE_OK)
        st = sluice_stream_swap(u->a, u->b);
    return st;
}

static unsigned stop_at_three(void *user, unsigned pass, const uint32_t *values, size_t count)
{
    (void)user;
    (void)values;
    (void)count;
    return pass >= 3 ? SLUICE_LOOP_STOP : pass;
}

/* sluice_counters_read_restart: a read gives the counts since the last
 * reset or restart, modulo 2^32 (a counter that wraps on the device still
 * reads right). */
static void launch_add_up(sluice_context *ctx, sluice_kernel *k, sluice_stream *s,
                          const uint32_t *in, size_t n)
{
    CHECK_OK(ctx, sluice_stream_upload(s, in, n));
    CHECK_OK(ctx, sluice_kernel_set_input(k, 0, s));
    CHECK_OK(ctx, sluice_kernel_launch(k));
}

static void test_counters_restart(sluice_context *ctx, sluice_program *p)
{
    sluice_kernel *k = NULL;
    sluice_stream *s = NULL;
    sluice_counters *cn = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "add_up", &k));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 4, &s));
    CHECK_OK(ctx, sluice_counters_create(ctx, 1, NULL, &cn));
    CHECK_OK(ctx, sluice_kernel_set_counters(k, cn));
    const uint32_t a[2] = {5u, 7u}, big = 0xfffffff0u, small = 0x20u;
    uint32_t v = 1;
    launch_add_up(ctx, k, s, a, 2);
    CHECK_OK(ctx, sluice_counters_read(cn, &v));
    CHECK(v == 12u, "read %u, want 12", v);
    CHECK_OK(ctx, sluice_counters_read(cn, &v));
    CHECK(v == 12u, "a second read %u, want 12 (a read does not restart)", v);
    CHECK_OK(ctx, sluice_counters_read_restart(cn, &v));
    CHECK(v == 12u, "read_restart %u, want 12", v);
    CHECK_OK(ctx, sluice_counters_read(cn, &v));
    CHECK(v == 0u, "after a restart %u, want 0", v);
    launch_add_up(ctx, k, s, a, 2);
    launch_add_up(ctx, k, s, a, 1);
    CHECK_OK(ctx, sluice_counters_read_restart(cn, &v));
    CHECK(v == 17u, "two launches after a restart %u, want 17", v);
    launch_add_up(ctx, k, s, &big, 1); /* the device's counter wraps */
    CHECK_OK(ctx, sluice_counters_read_restart(cn, &v));
    CHECK(v == big, "%#x, want %#x", v, big);
    launch_add_up(ctx, k, s, &small, 1);
    CHECK_OK(ctx, sluice_counters_read(cn, &v));
    CHECK(v == small, "after the wrap %#x, want %#x", v, small);
    CHECK_OK(ctx, sluice_counters_reset(cn));
    CHECK_OK(ctx, sluice_counters_read(cn, &v));
    CHECK(v == 0u, "after a reset %u, want 0", v);
    launch_add_up(ctx, k, s, a, 2);
    CHECK_OK(ctx, sluice_counters_read(cn, &v));
    CHECK(v == 12u, "after a reset and a launch %u, want 12", v);
    CHECK(sluice_counters_read_restart(NULL, &v) == SLUICE_ERROR_INVALID_ARGUMENT &&
              sluice_counters_read_restart(cn, NULL) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL arguments");
    sluice_counters_destroy(cn);
    sluice_stream_destroy(s);
    sluice_kernel_destroy(k);
}

static void test_loop(sluice_context *ctx, sluice_program *p)
{
    const size_t n = 50000;
    loop_user u = {0};
    CHECK_OK(ctx, sluice_kernel_create(p, "halve", &u.k));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &u.a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &u.b));
    CHECK_OK(ctx, sluice_counters_create(ctx, 1, NULL, &u.cn));
    CHECK_OK(ctx, sluice_kernel_set_counters(u.k, u.cn));
    uint32_t *in = malloc(n * 4), seed = 99, maxv = 0;
    for (size_t i = 0; i < n; ++i) {
        in[i] = check_rand(&seed) >> (i % 32);
        maxv = in[i] > maxv ? in[i] : maxv;
    }
    CHECK_OK(ctx, sluice_stream_upload(u.a, in, n));
    /* Reference: passes until the largest value halves down to <= 1. */
    unsigned want = 0;
    for (uint32_t x = maxv; x > 1; x /= 2)
        ++want;
    sluice_stream *watch[] = {u.a};
    sluice_loop_desc d = {0};
    d.pass = halve_pass;
    d.user = &u;
    d.streams = watch;
    d.stream_count = 1;
    d.counters = u.cn;
    d.reset_counters = 1;
    sluice_loop *loop = NULL;
    CHECK_OK(ctx, sluice_loop_create(ctx, &d, &loop));
    CHECK_OK(ctx, sluice_loop_run(loop));
    CHECK(sluice_loop_pass_count(loop) == want, "passes %u want %u", sluice_loop_pass_count(loop),
          want);
    const sluice_pass_stats *ps = sluice_loop_pass(loop, 0);
    size_t alive = 0;
    for (size_t i = 0; i < n; ++i)
        alive += in[i] / 2 > 1;
    CHECK(ps && ps->values[0] == alive && ps->values[1] == alive, "pass 0 values %u %u, want %zu",
          ps ? ps->values[0] : 0, ps ? ps->values[1] : 0, alive);
    CHECK(sluice_loop_pass(loop, want) == NULL, "no stats past the end");
    /* every pass counts from zero (the counter restarts, no reset), and
     * afterwards the counter reads the last pass's count */
    for (unsigned i = 0; i < want; ++i) {
        ps = sluice_loop_pass(loop, i);
        CHECK(ps->values[1] == ps->values[0], "pass %u: counted %u, emitted %u", i, ps->values[1],
              ps->values[0]);
    }
    uint32_t last = 0;
    CHECK_OK(ctx, sluice_counters_read(u.cn, &last));
    CHECK(want > 0 && last == sluice_loop_pass(loop, want - 1)->values[1],
          "after the loop the counter reads %u, want the last pass's %u", last,
          want > 0 ? sluice_loop_pass(loop, want - 1)->values[1] : 0);
    sluice_loop_destroy(loop);

    /* Pass limit and oracle. */
    CHECK_OK(ctx, sluice_stream_upload(u.a, in, n));
    d.max_passes = 2;
    CHECK_OK(ctx, sluice_loop_create(ctx, &d, &loop));
    CHECK(sluice_loop_run(loop) == SLUICE_ERROR_LIMIT, "pass limit");
    sluice_loop_destroy(loop);
    CHECK_OK(ctx, sluice_stream_upload(u.a, in, n));
    d.max_passes = 0;
    d.oracle = stop_at_three;
    CHECK_OK(ctx, sluice_loop_create(ctx, &d, &loop));
    CHECK_OK(ctx, sluice_loop_run(loop));
    CHECK(sluice_loop_pass_count(loop) == 3 && sluice_loop_pass(loop, 2)->choice == 2,
          "oracle stops after 3 passes");
    sluice_loop_destroy(loop);
    sluice_loop_desc bad = {0};
    bad.pass = halve_pass;
    CHECK(sluice_loop_create(ctx, &bad, &loop) == SLUICE_ERROR_INVALID_ARGUMENT,
          "loop that cannot stop");
    free(in);
    sluice_counters_destroy(u.cn);
    sluice_stream_destroy(u.a);
    sluice_stream_destroy(u.b);
    sluice_kernel_destroy(u.k);
}

/* Mapped outputs of an input whose length is on the device take its length,
 * the ninth as well (set by a kernel of its own), and are void when it
 * overflowed, even an input of capacity 0 (a launch over it is still
 * queued). */
static void test_mapped_lengths(sluice_context *ctx, sluice_program *p)
{
    const size_t n = 5000, cap = 3000;
    sluice_kernel *fan = NULL, *h = NULL;
    sluice_stream *o[9] = {NULL}, *src = NULL, *half = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "fan9", &fan));
    CHECK_OK(ctx, sluice_kernel_create(p, "halve", &h));
    for (unsigned j = 0; j < 9; ++j) {
        CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &o[j]));
        CHECK_OK(ctx, sluice_kernel_set_stream(fan, 1 + j, o[j], 1));
    }
    for (int overflowed = 0; overflowed < 2; ++overflowed) {
        /* check_fill emits n records: into a capacity of n, or of cap. */
        CHECK_OK(ctx, check_overflowed(ctx, n, overflowed ? cap : n, 0, &src));
        CHECK_OK(ctx, sluice_kernel_set_input(fan, 0, src));
        CHECK_OK(ctx, sluice_kernel_launch(fan));
        for (unsigned j = 0; j < 9; ++j) {
            size_t len = 1;
            sluice_status st = sluice_stream_length(o[j], &len);
            if (overflowed)
                CHECK(st == SLUICE_ERROR_OVERFLOW && len == 0 && check_overflow_named(ctx, n, cap),
                      "mapped output %u of an overflowed input: %s", j, sluice_context_error(ctx));
            else
                CHECK(st == SLUICE_OK && len == n, "mapped output %u: %s, %zu", j,
                      sluice_status_string(st), len);
        }
        sluice_stream_destroy(src);
    }
    CHECK_OK(ctx, check_overflowed(ctx, 5, 0, 0, &src));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 10, &half));
    CHECK_OK(ctx, sluice_kernel_set_input(h, 0, src));
    CHECK_OK(ctx, sluice_kernel_set_output(h, 1, 0, half, SLUICE_ORDERED));
    CHECK_OK(ctx, sluice_kernel_launch(h));
    size_t len = 1;
    CHECK(sluice_stream_length(half, &len) == SLUICE_ERROR_OVERFLOW && len == 0 &&
              check_overflow_named(ctx, 5, 0),
          "output of an overflowed input of capacity 0: %s", sluice_context_error(ctx));
    sluice_stream_destroy(src);
    sluice_stream_destroy(half);
    for (unsigned j = 0; j < 9; ++j)
        sluice_stream_destroy(o[j]);
    sluice_kernel_destroy(fan);
    sluice_kernel_destroy(h);
}

/* Overflow inside loops (issue 12): an output too small for a pass is an
 * error that stops the loop, whichever value the loop watches. */
typedef struct overflow_user {
    sluice_kernel *dup, *halve;
    sluice_stream *a, *b, *tmp;
    sluice_output_mode mode;
    int two_kernels; /* dup into tmp, then halve from tmp into b */
    int read_length; /* the pass function reads b's length itself */
} overflow_user;

static sluice_status overflow_pass(void *user, unsigned pass, unsigned choice)
{
    (void)pass;
    (void)choice;
    overflow_user *u = user;
    sluice_stream *first = u->two_kernels ? u->tmp : u->b;
    sluice_status st = sluice_stream_clear(u->b);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(u->tmp);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(u->dup, 0, u->a);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(u->dup, 1, 0, first, u->mode);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(u->dup);
    if (st == SLUICE_OK && u->two_kernels) {
        st = sluice_kernel_set_input(u->halve, 0, u->tmp);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_output(u->halve, 1, 0, u->b, SLUICE_UNORDERED);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch(u->halve);
    }
    size_t len;
    if (st == SLUICE_OK && u->read_length)
        st = sluice_stream_length(u->b, &len);
    if (st == SLUICE_OK)
        st = sluice_stream_swap(u->a, u->b);
    return st;
}

/* Goes on while the first watched value is non-zero, and always runs pass 0
 * (a loop that watches only a counter). */
static unsigned first_or_nonzero(void *user, unsigned pass, const uint32_t *values, size_t count)
{
    (void)user;
    return pass == 0 || (count && values[0]) ? 0 : SLUICE_LOOP_STOP;
}

/* Runs one loop of overflow_pass over `n` records from `in` (survivors of
 * capacity `b_cap`, the intermediate stream of `tmp_cap`) and checks that it
 * stops after pass 0 with SLUICE_ERROR_OVERFLOW and a message holding
 * `want`. With d.stream_count 1 the loop watches the survivors. */
static void check_loop_overflow(sluice_context *ctx, overflow_user *u, sluice_loop_desc d,
                                const uint32_t *in, size_t n, size_t b_cap, size_t tmp_cap,
                                const char *want, const char *what)
{
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &u->a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, b_cap, &u->b));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, tmp_cap, &u->tmp));
    CHECK_OK(ctx, sluice_stream_upload(u->a, in, n));
    sluice_stream *watch[] = {u->a};
    d.streams = d.stream_count ? watch : NULL;
    d.pass = overflow_pass;
    d.user = u;
    sluice_loop *loop = NULL;
    CHECK_OK(ctx, sluice_loop_create(ctx, &d, &loop));
    sluice_status st = sluice_loop_run(loop);
    CHECK(st == SLUICE_ERROR_OVERFLOW && sluice_loop_pass_count(loop) == 1,
          "%s: %s after %u passes", what, sluice_status_string(st), sluice_loop_pass_count(loop));
    CHECK(strstr(sluice_context_error(ctx), "loop pass 0: ") &&
              strstr(sluice_context_error(ctx), want),
          "%s: message %s, want %s", what, sluice_context_error(ctx), want);
    if (d.stream_count) { /* the watched stream is still overflowed: no pass runs */
        st = sluice_loop_run(loop);
        CHECK(st == SLUICE_ERROR_OVERFLOW && sluice_loop_pass_count(loop) == 0,
              "%s: run again: %s after %u passes", what, sluice_status_string(st),
              sluice_loop_pass_count(loop));
    }
    sluice_loop_destroy(loop);
    sluice_stream_destroy(u->a);
    sluice_stream_destroy(u->b);
    sluice_stream_destroy(u->tmp);
}

static void test_loop_overflow(sluice_context *ctx, sluice_program *p, sluice_output_mode mode)
{
    /* The issue: survivors of capacity 50000 receive about 100000 records in
     * pass 0. dup emits in[i] % 3 records per input record. */
    const size_t n = 100000, cap = 50000;
    uint32_t *in = malloc(n * 4);
    size_t emitted = 0;
    for (size_t i = 0; i < n; ++i) {
        in[i] = (uint32_t)(i * 7919u % 10007u);
        emitted += in[i] % 3;
    }
    overflow_user u = {0};
    u.mode = mode;
    sluice_counters *cn = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "dup", &u.dup));
    CHECK_OK(ctx, sluice_kernel_create(p, "halve", &u.halve));
    CHECK_OK(ctx, sluice_counters_create(ctx, 1, NULL, &cn));
    CHECK_OK(ctx, sluice_kernel_set_counters(u.halve, cn));
    char want[256];
    snprintf(want, sizeof want,
             "stream overflowed: %zu records were emitted into output slot 0 of kernel dup, a "
             "stream of capacity %zu",
             emitted, cap);
    CHECK(emitted > cap && emitted < n, "the test emits %zu records", emitted);

    /* One kernel, the survivors watched. */
    sluice_loop_desc d = {0};
    d.stream_count = 1;
    check_loop_overflow(ctx, &u, d, in, n, cap, cap, want, "watched survivors");

    /* Two kernels: dup overflows a stream the loop does not watch, halve
     * reads it; the survivors it writes are void and say where it began. */
    u.two_kernels = 1;
    char want_void[384];
    snprintf(want_void, sizeof want_void,
             "%s; output slot 0 of kernel halve, written from it, is void", want);
    check_loop_overflow(ctx, &u, d, in, n, n, cap, want_void, "unwatched stream");

    /* halve counted into its counter in that loop, over nothing: reading
     * the counter reports it until the counter is reset. */
    uint32_t count = 0;
    CHECK(sluice_counters_read(cn, &count) == SLUICE_ERROR_OVERFLOW &&
              strstr(sluice_context_error(ctx), "so the counts are void"),
          "void counters: %s", sluice_context_error(ctx));
    /* a restart reports the void counts once and clears the note */
    CHECK(sluice_counters_read_restart(cn, &count) == SLUICE_ERROR_OVERFLOW &&
              strstr(sluice_context_error(ctx), "so the counts are void"),
          "void counters, restarted: %s", sluice_context_error(ctx));
    CHECK_OK(ctx, sluice_counters_read(cn, &count));
    CHECK(count == 0, "after the restart %u, want 0", count);
    CHECK_OK(ctx, sluice_counters_reset(cn));
    CHECK_OK(ctx, sluice_counters_read(cn, &count));

    /* The same, watching only halve's counter: its overflow note stops the
     * loop (which would otherwise stop with OK: halve counted nothing). */
    d.stream_count = 0;
    d.counters = cn;
    d.reset_counters = 1;
    d.oracle = first_or_nonzero;
    snprintf(want_void, sizeof want_void,
             "%s; a kernel counting into these counters read it, so the counts are void", want);
    check_loop_overflow(ctx, &u, d, in, n, n, cap, want_void, "watched counter");

    /* A pass function that reads a length gets the error and ends the loop
     * with it, here where nothing is watched (the oracle runs pass 0). */
    u.two_kernels = 0;
    u.read_length = 1;
    d.counters = NULL;
    check_loop_overflow(ctx, &u, d, in, n, cap, cap, want, "pass function");

    sluice_counters_destroy(cn);
    sluice_kernel_destroy(u.dup);
    sluice_kernel_destroy(u.halve);
    free(in);
}

static void test_errors(sluice_context *ctx)
{
    const char *bad_src = "#include \"sluice.cl\"\n"
                          "__kernel void broken(SLUICE_PARAMS, global uint *x)\n"
                          "{\n"
                          "    SLUICE_FOR_EACH(i) x[i] = undefined_thing;\n"
                          "}\n";
    sluice_program *p = NULL;
    CHECK_OK(ctx, sluice_program_create_source(ctx, "broken.cl", bad_src, NULL, &p));
    sluice_kernel *k = NULL;
    sluice_status st = sluice_kernel_create(p, "broken", &k);
    CHECK(st == SLUICE_ERROR_BUILD && !k, "syntax error gives a build error: %s",
          sluice_status_string(st));
    CHECK(strstr(sluice_program_build_log(p), "broken.cl:4:") != NULL, "log names line 4: %s",
          sluice_program_build_log(p));
    CHECK(strstr(sluice_context_error(ctx), "broken.cl:4:") != NULL, "error names line 4");
    /* Whatever the vendor's log looks like, the message leads with the error
     * as `file:line:col: error: message` (runtime/src/build_log.h). */
    const char *lead = "broken.cl:4:31: error: use of undeclared identifier 'undefined_thing'\n";
    CHECK(strncmp(sluice_context_error(ctx), lead, strlen(lead)) == 0,
          "the message leads with the error: [%s]", sluice_context_error(ctx));
    sluice_program_destroy(p);

    /* Two errors after a warning: the errors lead, first error first, and
     * the warning is left out of them (the context is not verbose). */
    const char *two_src = "#include \"sluice.cl\"\n"
                          "#warning sluice test warning\n"
                          "__kernel void broken(SLUICE_PARAMS, global uint *x)\n"
                          "{\n"
                          "    SLUICE_FOR_EACH(i) x[i] = first_missing;\n"
                          "    x[0] = second_missing;\n"
                          "}\n";
    CHECK_OK(ctx, sluice_program_create_source(ctx, "two.cl", two_src, NULL, &p));
    CHECK(sluice_program_build(p) == SLUICE_ERROR_BUILD, "two errors give a build error");
    const char *two = sluice_context_error(ctx);
    const char *second = strchr(two, '\n');
    CHECK(second && strncmp(two, "two.cl:5:", 9) == 0 && strstr(two, ": error: ") < second &&
              strstr(two, "first_missing") < second,
          "first line is the first error: [%s]", two);
    CHECK(second && strncmp(second + 1, "two.cl:6:", 9) == 0 && strstr(second, "second_missing"),
          "second line is the second error: [%s]", two);
    const char *third = second ? strchr(second + 1, '\n') : NULL;
    CHECK(third && strncmp(third + 1, "building two.cl failed", 22) == 0,
          "then the note on the build, no warning: [%s]", two);
    CHECK(strstr(sluice_program_build_log(p), "sluice test warning") != NULL,
          "the build log keeps the warning: [%s]", sluice_program_build_log(p));
    sluice_program_destroy(p);

    CHECK(sluice_program_create_file(ctx, "/nonexistent/k.cl", NULL, &p) == SLUICE_ERROR_IO,
          "missing file");
    CHECK(strstr(sluice_context_error(ctx), "/nonexistent/k.cl") != NULL, "names the file");
    CHECK_OK(ctx, sluice_program_create_source(ctx, "ok.cl",
                                               "#include <sluice.cl>\n"
                                               "__kernel void f(SLUICE_PARAMS, global uint *x)\n"
                                               "{ SLUICE_FOR_EACH(i) x[i] = 1u; }\n",
                                               NULL, &p));
    CHECK(sluice_kernel_create(p, "nope", &k) == SLUICE_ERROR_NOT_FOUND, "unknown kernel");
    CHECK(sluice_kernel_create(NULL, "f", &k) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL program");
    sluice_program_destroy(p);
    sluice_counters *c = NULL;
    CHECK(sluice_counters_create(ctx, 0, NULL, &c) == SLUICE_ERROR_INVALID_ARGUMENT, "0 counters");
    CHECK(sluice_counters_create(ctx, 9, NULL, &c) == SLUICE_ERROR_INVALID_ARGUMENT, "9 counters");

    sluice_context *other = NULL;
    char msg[256];
    sluice_context_options o = {0};
    o.device = "no-such-device-anywhere";
    CHECK(sluice_context_create(&o, &other, msg, sizeof msg) == SLUICE_ERROR_NO_DEVICE && !other,
          "unknown device");
    CHECK(strstr(msg, "no-such-device-anywhere") != NULL, "message names the filter: %s", msg);
    CHECK(strcmp(sluice_status_string(SLUICE_ERROR_OVERFLOW), "stream overflow") == 0,
          "status string");
}

/* The value program `p` (kernel `put`, writing VAL to every record) writes,
 * or UINT32_MAX when it cannot be run. */
static uint32_t put_value(sluice_context *ctx, sluice_program *p)
{
    sluice_kernel *k = NULL;
    sluice_stream *o = NULL;
    uint32_t got[3] = {UINT32_MAX, UINT32_MAX, UINT32_MAX};
    CHECK_OK(ctx, sluice_kernel_create(p, "put", &k));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 3, &o));
    if (k && o && sluice_kernel_set_stream(k, 0, o, 0) == SLUICE_OK &&
        sluice_kernel_launch_count(k, 3) == SLUICE_OK &&
        sluice_stream_set_length(o, 3) == SLUICE_OK)
        CHECK_OK(ctx, sluice_stream_download(o, got, 3, NULL));
    sluice_kernel_destroy(k);
    sluice_stream_destroy(o);
    CHECK(got[0] == got[1] && got[1] == got[2], "put wrote %u %u %u", got[0], got[1], got[2]);
    return got[0];
}

/* Programs built before in the context are taken again for the same text
 * and options (program_cache.h), never for another text or other options,
 * with the same build log, while another program of the same text lives
 * or after it is gone, and after more programs than are kept have pushed
 * the first one out. */
static void test_kept_programs(sluice_context *ctx)
{
    const char *src = "#include \"sluice.cl\"\n"
                      "#warning kept program warning\n"
                      "__kernel void put(SLUICE_PARAMS, global uint *x)\n"
                      "{ SLUICE_FOR_EACH(i) x[i] = VAL; }\n";
    const char *other = "#include \"sluice.cl\"\n"
                        "__kernel void put(SLUICE_PARAMS, global uint *x)\n"
                        "{ SLUICE_FOR_EACH(i) x[i] = VAL + 100u; }\n";
    sluice_program *a = NULL, *b = NULL, *c = NULL;
    CHECK_OK(ctx, sluice_program_create_source(ctx, "kept.cl", src, "-DVAL=1u", &a));
    CHECK(put_value(ctx, a) == 1u, "first build");
    CHECK(strstr(sluice_program_build_log(a), "kept program warning") != NULL, "log: [%s]",
          sluice_program_build_log(a));
    /* the same text and options while the first lives, then after it is gone */
    CHECK_OK(ctx, sluice_program_create_source(ctx, "kept.cl", src, "-DVAL=1u", &b));
    CHECK(put_value(ctx, b) == 1u, "the same text again");
    CHECK(strcmp(sluice_program_build_log(a), sluice_program_build_log(b)) == 0,
          "the same log: [%s] [%s]", sluice_program_build_log(a), sluice_program_build_log(b));
    sluice_program_destroy(a);
    CHECK(put_value(ctx, b) == 1u, "the second after the first is gone");
    sluice_program_destroy(b);
    CHECK_OK(ctx, sluice_program_create_source(ctx, "kept.cl", src, "-DVAL=1u", &a));
    CHECK(put_value(ctx, a) == 1u, "the same text after both are gone");
    sluice_program_destroy(a);
    /* other options, another text: their own programs */
    CHECK_OK(ctx, sluice_program_create_source(ctx, "kept.cl", src, "-DVAL=2u", &b));
    CHECK(put_value(ctx, b) == 2u, "other options");
    CHECK_OK(ctx, sluice_program_create_source(ctx, "kept.cl", other, "-DVAL=2u", &c));
    CHECK(put_value(ctx, c) == 102u, "another text");
    CHECK(strstr(sluice_program_build_log(c), "kept program warning") == NULL,
          "another text's log: [%s]", sluice_program_build_log(c));
    sluice_program_destroy(b);
    sluice_program_destroy(c);
    /* more than the context keeps, then the first again */
    for (unsigned v = 3; v < 3 + 33; ++v) {
        char opt[32];
        snprintf(opt, sizeof opt, "-DVAL=%uu", v);
        CHECK_OK(ctx, sluice_program_create_source(ctx, "kept.cl", other, opt, &a));
        CHECK_OK(ctx, sluice_program_build(a));
        sluice_program_destroy(a);
    }
    CHECK_OK(ctx, sluice_program_create_source(ctx, "kept.cl", src, "-DVAL=1u", &a));
    CHECK(put_value(ctx, a) == 1u, "the first text after 33 others");
    CHECK(strstr(sluice_program_build_log(a), "kept program warning") != NULL, "log: [%s]",
          sluice_program_build_log(a));
    sluice_program_destroy(a);
}

/* Finds the profile entry called `name`; 0 when there is none. */
static int profile_find(sluice_context *ctx, const char *name, sluice_profile_entry *e)
{
    size_t count = sluice_profile_count(ctx);
    for (size_t i = 0; i < count; ++i)
        if (sluice_profile_get(ctx, i, e) == SLUICE_OK && strcmp(e->name, name) == 0)
            return 1;
    return 0;
}

/* The profile lists the kernels that ran, and only those, in the order of
 * their first launch; counts the records of a stream algorithm's kernels,
 * also when the input's length is only on the device; and counts mapped
 * outputs in the bytes. */
static void test_profile_rows(sluice_context *ctx, sluice_program *p, int chained)
{
    sluice_profile_reset(ctx);
    CHECK(sluice_profile_count(ctx) == 0, "no entry after a reset");
    sluice_kernel *idle = NULL, *scale = NULL, *split = NULL;
    CHECK_OK(ctx, sluice_kernel_create(p, "dup", &idle)); /* made, never launched */
    CHECK_OK(ctx, sluice_kernel_create(p, "scale", &scale));
    CHECK_OK(ctx, sluice_kernel_create(p, "split3", &split));
    /* the multiples of 3 below N; N large enough that an ordered launch is
     * chained where the chain is on (kernel.c: four work-groups of 8
     * chunks of 256 records a compute unit, up to 96 of them) */
    enum { N = 3 << 18, THIRDS = 1 << 18 };
    uint32_t *v = malloc(N * sizeof *v);
    for (uint32_t i = 0; i < N; ++i)
        v[i] = i;
    sluice_stream *in = NULL, *mapped = NULL, *out[3] = {NULL, NULL, NULL}, *scanned = NULL;
    sluice_counters *cn = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, N, &in));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, N, &mapped));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, N, &scanned));
    CHECK_OK(ctx, sluice_counters_create(ctx, 2, NULL, &cn));
    CHECK_OK(ctx, sluice_stream_upload(in, v, N));
    launch_scale(ctx, scale, in, mapped, 2.0f);
    launch_split3(ctx, split, in, N, out, cn, SLUICE_ORDERED);
    /* out[0]'s length is only on the device: the scan's kernels read it there. */
    CHECK_OK(ctx, sluice_scan(ctx, out[0], scanned, SLUICE_U32, 0, NULL));
    CHECK_OK(ctx, sluice_scan(ctx, in, scanned, SLUICE_U32, 0, NULL));

    size_t count = sluice_profile_count(ctx);
    sluice_profile_entry e;
    if (chained) /* split3 placed its ordered records in one launch */
        CHECK(count == 5,
              "5 kernels ran (scale, split3 in one launch, 3 scan passes); the profile has %zu "
              "entries",
              count);
    else
        CHECK(count == 7,
              "6 kernels ran (scale, split3, sluice_scan_chunk_counts, 3 scan passes) and split3's "
              "count launch has a row of its own; the profile has %zu entries",
              count);
    for (size_t i = 0; i < count; ++i) {
        CHECK_OK(ctx, sluice_profile_get(ctx, i, &e));
        CHECK(e.launches > 0 && strcmp(e.name, "dup") != 0, "entry %zu: %s, %llu launches", i,
              e.name, (unsigned long long)e.launches);
    }
    CHECK(sluice_profile_get(ctx, 0, &e) == SLUICE_OK && strcmp(e.name, "scale") == 0,
          "entries in the order of the first launch: %s first", e.name);
    CHECK(profile_find(ctx, "scale", &e) && e.records_in == N && e.bytes == 8u * N,
          "scale: %llu records in, %llu bytes (input and mapped output: %d)",
          (unsigned long long)e.records_in, (unsigned long long)e.bytes, 8 * N);
    CHECK(profile_find(ctx, "split3", &e) && e.records_in == N && e.records_out == N &&
              e.bytes == 8u * N,
          "split3: %llu in, %llu out, %llu bytes", (unsigned long long)e.records_in,
          (unsigned long long)e.records_out, (unsigned long long)e.bytes);
    if (chained)
        CHECK(!profile_find(ctx, "split3 count", &e) &&
                  !profile_find(ctx, "sluice_scan_chunk_counts", &e),
              "a chained launch has no count launch and no scan of counts");
    else
        CHECK(profile_find(ctx, "split3 count", &e) && e.launches == 1 && e.records_in == 0,
              "split3 count: %llu launches, %llu records in (counted in split3's row)",
              (unsigned long long)e.launches, (unsigned long long)e.records_in);
    CHECK(profile_find(ctx, "scan_sums_u32", &e) && e.launches == 2 && e.records_in == THIRDS + N &&
              e.bytes == 4u * (THIRDS + N),
          "scan_sums_u32: %llu launches, %llu records in (want %d), %llu bytes",
          (unsigned long long)e.launches, (unsigned long long)e.records_in, THIRDS + N,
          (unsigned long long)e.bytes);
    CHECK(profile_find(ctx, "scan_apply_u32", &e) && e.records_in == THIRDS + N &&
              e.bytes == 8u * (THIRDS + N),
          "scan_apply_u32: %llu records in, %llu bytes", (unsigned long long)e.records_in,
          (unsigned long long)e.bytes);
    CHECK(profile_find(ctx, "scan_chunks_u32", &e) && e.records_in > 0,
          "scan_chunks_u32: %llu records in", (unsigned long long)e.records_in);
    if (!chained)
        CHECK(profile_find(ctx, "sluice_scan_chunk_counts", &e) && e.records_in > 0,
              "sluice_scan_chunk_counts: %llu records in", (unsigned long long)e.records_in);

    /* The printed table and the JSON have the same rows. */
    FILE *f = tmpfile();
    char table[8192] = {0};
    CHECK_OK(ctx, sluice_profile_print(ctx, f));
    rewind(f);
    table[fread(table, 1, sizeof table - 1, f)] = 0;
    fclose(f);
    CHECK(strstr(table, "scan_sums_u32") && !strstr(table, "dup"), "table:\n%s", table);
    CHECK_OK(ctx, sluice_profile_write_json(ctx, "test_runtime_profile_rows.json"));
    char json[8192] = {0};
    f = fopen("test_runtime_profile_rows.json", "r");
    if (f) {
        json[fread(json, 1, sizeof json - 1, f)] = 0;
        fclose(f);
    }
    CHECK(strstr(json, "\"scan_apply_u32\"") && !strstr(json, "\"dup\"") &&
              !strstr(json, "\"launches\": 0,"),
          "json: %s", json);

    /* After a reset only what runs next is listed. */
    sluice_profile_reset(ctx);
    CHECK_OK(ctx, sluice_kernel_launch(scale));
    CHECK(sluice_profile_count(ctx) == 1 && sluice_profile_get(ctx, 0, &e) == SLUICE_OK &&
              strcmp(e.name, "scale") == 0 && e.launches == 1 && e.records_in == N,
          "after a reset: %zu entries", sluice_profile_count(ctx));

    for (unsigned j = 0; j < 3; ++j)
        sluice_stream_destroy(out[j]);
    sluice_stream_destroy(in);
    sluice_stream_destroy(mapped);
    sluice_stream_destroy(scanned);
    sluice_counters_destroy(cn);
    sluice_kernel_destroy(idle);
    sluice_kernel_destroy(scale);
    sluice_kernel_destroy(split);
    free(v);
}

static void test_profile(void)
{
    sluice_context *ctx = check_context(1);
    sluice_program *p = program(ctx);
    test_split(ctx, p, 4097, 0, SLUICE_UNORDERED, 0);
    test_split(ctx, p, 4097, 0, SLUICE_ORDERED, 0);
    sluice_profile_entry e;
    CHECK(sluice_profile_count(ctx) >= 1, "profile entries");
    CHECK_OK(ctx, sluice_profile_get(ctx, 0, &e));
    CHECK(strcmp(e.name, "split3") == 0 && e.launches == 2 && e.records_in == 2 * 4097 &&
              e.records_out == 2 * 4097 && e.bytes == 4 * 4 * 4097 && e.device_seconds > 0,
          "profile %s %llu launches %llu in %llu out %llu bytes %g s", e.name,
          (unsigned long long)e.launches, (unsigned long long)e.records_in,
          (unsigned long long)e.records_out, (unsigned long long)e.bytes, e.device_seconds);
    FILE *f = tmpfile();
    CHECK_OK(ctx, sluice_profile_print(ctx, f));
    CHECK(ftell(f) > 100, "table printed");
    fclose(f);
    CHECK_OK(ctx, sluice_profile_write_json(ctx, "test_runtime_profile.json"));
    f = fopen("test_runtime_profile.json", "r");
    char buf[4096] = {0};
    if (f) {
        size_t got = fread(buf, 1, sizeof buf - 1, f);
        buf[got] = 0;
        fclose(f);
    }
    CHECK(strstr(buf, "\"name\": \"split3\"") && strstr(buf, "\"records_in\": 8194"), "json: %s",
          buf);
    CHECK(sluice_profile_write_json(ctx, "/nonexistent/dir/p.json") == SLUICE_ERROR_IO,
          "unwritable json path");
    /* ordered outputs in one launch: CPUs in the contiguous layout
     * (sluice_context_options.no_chain) */
    sluice_device_info info;
    CHECK_OK(ctx, sluice_context_device(ctx, &info));
    const char *layout = getenv("SLUICE_LAYOUT"), *no_chain = getenv("SLUICE_NO_CHAIN"),
               *groups = getenv("SLUICE_GROUP_CHAIN");
    int interleaved = layout ? strcmp(layout, "interleaved") == 0 : !info.is_cpu;
    int chained = (interleaved ? groups && *groups && strcmp(groups, "0") != 0
                               : info.is_cpu && strstr(info.platform, "Portable") != NULL &&
                                     info.compute_units <= 96) &&
                  !(no_chain && *no_chain && strcmp(no_chain, "0") != 0);
    test_profile_rows(ctx, p, chained);
    sluice_program_destroy(p);
    sluice_context_destroy(ctx);
    if (chained) { /* and the count launch's rows where the chain is off */
        char err[512];
        sluice_context_options o = {0};
        o.profile = 1;
        o.no_chain = 1;
        ctx = NULL;
        CHECK(sluice_context_create(&o, &ctx, err, sizeof err) == SLUICE_OK, "no_chain: %s", err);
        if (ctx) {
            p = program(ctx);
            test_profile_rows(ctx, p, 0);
            sluice_program_destroy(p);
            sluice_context_destroy(ctx);
        }
    }
}

/* sluice_stream_fill against C: record sizes that OpenCL's fill takes (4,
 * 128) and others (1, 12, 40, 200), counts around the doubling copies,
 * zero records, the length set; too many records and a NULL record are
 * errors that leave the stream as it was. */
static void test_fill(sluice_context *ctx)
{
    const size_t sizes[] = {1, 4, 12, 40, 128, 200};
    const size_t counts[] = {0, 1, 2, 3, 1000, 100003};
    for (size_t a = 0; a < sizeof sizes / sizeof *sizes; ++a) {
        size_t rs = sizes[a], cap = 100003;
        unsigned char rec[200], *got = malloc(cap * rs);
        for (size_t i = 0; i < rs; ++i)
            rec[i] = (unsigned char)(7 * i + rs + 1);
        sluice_stream *s = NULL;
        CHECK_OK(ctx, sluice_stream_create(ctx, rs, cap, &s));
        for (size_t c = 0; s && got && c < sizeof counts / sizeof *counts; ++c) {
            size_t n = counts[c], len = 99, bad = 0;
            CHECK_OK(ctx, sluice_stream_fill(s, rec, n));
            CHECK_OK(ctx, sluice_stream_length(s, &len));
            CHECK_OK(ctx, sluice_stream_download(s, got, cap, NULL));
            for (size_t i = 0; i < n; ++i)
                bad += memcmp(got + i * rs, rec, rs) != 0;
            CHECK(len == n && bad == 0, "fill %zu-byte records x %zu: length %zu, %zu wrong", rs, n,
                  len, bad);
        }
        if (s) {
            size_t len = 0;
            CHECK(sluice_stream_fill(s, rec, cap + 1) == SLUICE_ERROR_OVERFLOW &&
                      strstr(sluice_context_error(ctx), "capacity"),
                  "fill past capacity: %s", sluice_context_error(ctx));
            CHECK(sluice_stream_fill(s, NULL, 1) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL record");
            CHECK_OK(ctx, sluice_stream_length(s, &len));
            CHECK(len == cap, "a failed fill changed the length to %zu", len);
        }
        sluice_stream_destroy(s);
        free(got);
    }
    CHECK(sluice_stream_fill(NULL, "x", 1) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL stream");
}

/* SLUICE_CHUNK fixes the records per work-item: a number that is not one is
 * refused with a message naming the variable; an odd chunk (7 records)
 * splits as the default does, ordered and unordered. */
/* A context is refused while environment variable `var` holds `value`,
 * with a message that names the variable. */
static void check_env_refused(const char *var, const char *value)
{
    sluice_context *c = NULL;
    char msg[256] = "";
    setenv(var, value, 1);
    CHECK(sluice_context_create(NULL, &c, msg, sizeof msg) == SLUICE_ERROR_INVALID_ARGUMENT && !c,
          "%s=%s refused", var, value);
    CHECK(strstr(msg, var) != NULL, "the message names the variable: %s", msg);
}

static void test_chunk_env(void)
{
    check_env_refused("SLUICE_CHUNK", "12x");
    setenv("SLUICE_CHUNK", "7", 1);
    sluice_context *c = check_context(0);
    sluice_program *p = program(c);
    for (int m = 0; m < 2; ++m) {
        test_split(c, p, 1025, 0, m ? SLUICE_UNORDERED : SLUICE_ORDERED, m);
        test_split(c, p, 65537, 3, m ? SLUICE_UNORDERED : SLUICE_ORDERED, m);
    }
    sluice_program_destroy(p);
    sluice_context_destroy(c);
    unsetenv("SLUICE_CHUNK");
}

/* Whether split3 (ordered outputs) over in[0 .. n) gives the plain C
 * split's three outputs. */
static int split3_matches(sluice_context *ctx, sluice_program *p, const uint32_t *in, size_t n,
                          uint32_t spin)
{
    sluice_kernel *k = NULL;
    sluice_stream *s_in = NULL, *s_out[3] = {NULL, NULL, NULL};
    uint32_t *ref = malloc(3 * (n + 1) * 4), *got = malloc((n + 1) * 4);
    size_t rn[3] = {0, 0, 0};
    int ok = ref && got;
    for (size_t i = 0; ok && i < n; ++i)
        ref[(in[i] % 3u) * (n + 1) + rn[in[i] % 3u]++] = in[i];
    CHECK_OK(ctx, sluice_kernel_create(p, "split3_slow", &k));
    CHECK_OK(ctx, sluice_kernel_set_arg(k, 4, sizeof spin, &spin));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &s_in));
    CHECK_OK(ctx, sluice_stream_upload(s_in, in, n));
    CHECK_OK(ctx, sluice_kernel_set_input(k, 0, s_in));
    for (unsigned j = 0; j < 3; ++j) {
        CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &s_out[j]));
        CHECK_OK(ctx, sluice_kernel_set_output(k, 1 + j, j, s_out[j], SLUICE_ORDERED));
    }
    CHECK_OK(ctx, sluice_kernel_launch(k));
    for (int j = 0; ok && j < 3; ++j) {
        size_t len = 0;
        ok = sluice_stream_download(s_out[j], got, n, &len) == SLUICE_OK && len == rn[j] &&
             memcmp(got, ref + (size_t)j * (n + 1), len * 4) == 0;
    }
    for (int j = 0; j < 3; ++j)
        sluice_stream_destroy(s_out[j]);
    sluice_stream_destroy(s_in);
    sluice_kernel_destroy(k);
    free(ref);
    free(got);
    return ok;
}

/* Ordered outputs placed in one launch (the chain, kernels/sluice.cl) keep
 * their flags apart from the counts of earlier launches whatever a launch's
 * number of chunks. In a fresh context with chunks of 16 records: a launch
 * of 8 chunks whose counts are 8 each, the next launch's tag (its epoch, 2,
 * times 4), then a launch of 64 chunks whose even chunks are slow, so that
 * the odd ones look back before their neighbours publish. Where the flags
 * took a launch's own stride, the second launch's flags lay on the first
 * one's counts and read as published: every such launch placed its records
 * wrongly (40 of the 80 launches). */
static void test_chain_strides(void)
{
    sluice_context_options o;
    memset(&o, 0, sizeof o);
    o.chunk = 16;
    uint32_t a[128], b[1024], seed = 99u;
    for (size_t i = 0; i < 128; ++i) /* per chunk: 8 records to output 0, 8 to output 1 */
        a[i] = (uint32_t)(3 * i + (i % 16 >= 8));
    int bad = 0;
    for (int rep = 0; rep < 40; ++rep) {
        for (size_t i = 0; i < 1024; ++i)
            b[i] = check_rand(&seed);
        sluice_context *c = NULL;
        char msg[256] = "";
        CHECK(sluice_context_create(&o, &c, msg, sizeof msg) == SLUICE_OK && c, "context: %s", msg);
        if (!c)
            return;
        sluice_program *p = program(c);
        bad += !split3_matches(c, p, a, 128, 0u);
        bad += !split3_matches(c, p, b, 1024, 20000u);
        sluice_program_destroy(p);
        sluice_context_destroy(c);
    }
    CHECK(bad == 0, "ordered outputs after a launch of fewer chunks: %d of 80 launches wrong", bad);
}

/* SLUICE_LAYOUT and the layout option: a bad value is refused with a
 * message that names it; the GPU layout (interleaved records, a work-group
 * scanning the chunk counts) gives the same outputs on this device, for
 * sizes around its 256-record tiles and with one chunk per work-group or
 * many (up to 64001 records: with one record a chunk, a grid under the
 * 65535 work-items from which PoCL builds every kernel a second time). */
static void test_layout(void)
{
    check_env_refused("SLUICE_LAYOUT", "gpu");
    unsetenv("SLUICE_LAYOUT");
    sluice_context *c = NULL;
    char msg[256] = "";
    sluice_context_options o;
    memset(&o, 0, sizeof o);
    o.layout = (sluice_layout)7;
    msg[0] = '\0';
    CHECK(sluice_context_create(&o, &c, msg, sizeof msg) == SLUICE_ERROR_INVALID_ARGUMENT && !c,
          "layout 7 refused: %s", msg);
    o.layout = SLUICE_LAYOUT_INTERLEAVED;
    const unsigned chunks[] = {0, 1, 5};
    for (size_t ci = 0; ci < sizeof chunks / sizeof *chunks; ++ci) {
        o.chunk = chunks[ci];
        c = NULL;
        CHECK(sluice_context_create(&o, &c, msg, sizeof msg) == SLUICE_OK && c,
              "interleaved context: %s", msg);
        if (!c)
            return;
        sluice_program *p = program(c);
        const size_t sizes[] = {0, 1, 255, 256, 257, 4099, 64001};
        for (size_t i = 0; i < sizeof sizes / sizeof *sizes; ++i)
            for (int m = 0; m < 2; ++m)
                test_split(c, p, sizes[i], (int)(i % 4), m ? SLUICE_UNORDERED : SLUICE_ORDERED, m);
        test_multi_emit(c, p, SLUICE_ORDERED);
        test_multi_emit(c, p, SLUICE_UNORDERED);
        test_mapped_lengths(c, p);
        sluice_program_destroy(p);
        sluice_context_destroy(c);
    }
}

int main(void)
{
    sluice_context *ctx = check_context(0);
    sluice_program *p = program(ctx);
    test_streams(ctx);
    test_fill(ctx);
    test_map(ctx, p);
    const size_t sizes[] = {0, 1, 7, 1023, 1025, 65535, 65537, 1u << 20};
    for (size_t i = 0; i < sizeof sizes / sizeof *sizes; ++i)
        for (int pattern = 0; pattern < 4; ++pattern)
            for (int m = 0; m < 4; ++m)
                test_split(ctx, p, sizes[i], pattern, m & 1 ? SLUICE_UNORDERED : SLUICE_ORDERED,
                           m >> 1);
    sluice_device_info info;
    CHECK_OK(ctx, sluice_context_device(ctx, &info));
    const char *layout = getenv("SLUICE_LAYOUT");
    const char *no_spread = getenv("SLUICE_NO_SPREAD");
    int contiguous = (layout && *layout ? strcmp(layout, "contiguous") == 0 : info.is_cpu) &&
                     !(no_spread && *no_spread && strcmp(no_spread, "0") != 0);
    test_uneven(ctx, p, contiguous);
    test_multi_emit(ctx, p, SLUICE_ORDERED);
    test_multi_emit(ctx, p, SLUICE_UNORDERED);
    test_block_emit(ctx, p, "small_values");
    test_block_emit(ctx, p, "small_values4");
    test_block_emit(ctx, p, "small_values_of8");
    test_counters_restart(ctx, p);
    test_loop(ctx, p);
    test_mapped_lengths(ctx, p);
    test_loop_overflow(ctx, p, SLUICE_ORDERED);
    test_loop_overflow(ctx, p, SLUICE_UNORDERED);
    test_errors(ctx);
    /* the kept programs do not depend on the layout or the kernels' ISA:
     * checked in the plain run only (its 36 small builds cost every
     * variant's run as many compiles on a cold PoCL cache) */
    const char *simd = getenv("SLUICE_NO_SIMD"), *lib = getenv("POCL_KERNELLIB_NAME");
    if (!(layout && *layout) && !(simd && *simd) && !(lib && *lib))
        test_kept_programs(ctx);
    sluice_program_destroy(p);
    sluice_context_destroy(ctx);
    test_profile();
    test_chunk_env();
    test_chain_strides();
    test_layout();
    return check_summary();
}
