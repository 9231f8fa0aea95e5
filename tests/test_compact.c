/* Tests of sluice_compact, sluice_split and sluice_partition against plain C
 * references: ordered outputs must match exactly, unordered ones as
 * multisets. Record sizes of 4 .. 20 bytes, adversarial lengths and flag
 * patterns (nothing kept, everything kept), NaN, overflow and argument
 * errors. */
#include "check.h"
#include "sluice/streams.h"

#include <math.h>
#include <string.h>

/* Compares `got` with `want` (count records of `rs` bytes): exactly when
 * ordered, as sorted multisets otherwise (both arrays may be sorted). */
static int same_records(void *got, void *want, size_t count, size_t rs, sluice_output_mode mode)
{
    if (mode == SLUICE_UNORDERED && count > 1 &&
        (!check_sort_records(got, count, rs) || !check_sort_records(want, count, rs)))
        return 0; /* out of memory */
    return count == 0 || memcmp(got, want, count * rs) == 0;
}

enum flags_pattern { F_RANDOM, F_NONE, F_ALL, F_ALTERNATE, F_PATTERNS };
static const char *const flag_names[] = {"random", "none", "all", "alternate"};

static void check_compact(sluice_context *ctx, size_t n, size_t rs, int pattern,
                          sluice_output_mode mode)
{
    size_t words = rs / 4;
    uint32_t seed = 4242u + (uint32_t)(n * 7 + rs);
    uint32_t *in = malloc((n * words + 1) * 4), *flags = malloc((n + 1) * 4);
    uint32_t *want = malloc((n * words + 1) * 4), *got = malloc((n * words + 1) * 4);
    size_t kept = 0;
    for (size_t i = 0; i < n; ++i) {
        for (size_t w = 0; w < words; ++w)
            in[i * words + w] = (uint32_t)i * 16u + (uint32_t)w; /* unique records */
        uint32_t r = check_rand(&seed);
        flags[i] = pattern == F_RANDOM ? (r % 3 == 0 ? r : 0u)
                   : pattern == F_NONE ? 0u
                   : pattern == F_ALL  ? 1u
                                       : (uint32_t)(i & 1);
        if (flags[i]) {
            memcpy(want + kept * words, in + i * words, rs);
            kept++;
        }
    }
    sluice_stream *a = NULL, *f = NULL, *o = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, rs, n, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &f));
    CHECK_OK(ctx, sluice_stream_create(ctx, rs, n + 5, &o));
    CHECK_OK(ctx, sluice_stream_upload(a, in, n));
    CHECK_OK(ctx, sluice_stream_upload(f, flags, n));
    CHECK_OK(ctx, sluice_stream_set_length(o, 3)); /* overwritten, not appended */
    CHECK_OK(ctx, sluice_compact(ctx, a, f, o, mode));
    size_t count = 0;
    CHECK_OK(ctx, sluice_stream_download(o, got, n, &count));
    CHECK(count == kept, "compact %zu x %zu B %s: %zu kept, want %zu", n, rs, flag_names[pattern],
          count, kept);
    CHECK(count == kept && same_records(got, want, kept, rs, mode),
          "compact %zu x %zu B %s %s: records differ", n, rs, flag_names[pattern],
          mode == SLUICE_ORDERED ? "ordered" : "unordered");
    sluice_stream_destroy(a);
    sluice_stream_destroy(f);
    sluice_stream_destroy(o);
    free(in);
    free(flags);
    free(want);
    free(got);
}

static void check_split(sluice_context *ctx, size_t n, size_t rs, unsigned count,
                        sluice_output_mode mode)
{
    size_t words = rs / 4;
    uint32_t seed = 31337u + (uint32_t)(n + count * 11 + rs);
    uint32_t *in = malloc((n * words + 1) * 4), *buckets = malloc((n + 1) * 4);
    uint32_t *want[SLUICE_MAX_OUTPUTS], *got = malloc((n * words + 1) * 4);
    size_t nwant[SLUICE_MAX_OUTPUTS] = {0};
    for (unsigned b = 0; b < count; ++b)
        want[b] = malloc((n * words + 1) * 4);
    for (size_t i = 0; i < n; ++i) {
        for (size_t w = 0; w < words; ++w)
            in[i * words + w] = (uint32_t)i * 16u + (uint32_t)w;
        uint32_t r = check_rand(&seed);
        /* Mostly valid buckets, some dropped (>= count), some huge. */
        buckets[i] = r % 10 == 0 ? r : r % (count + 1);
        if (buckets[i] < count) {
            memcpy(want[buckets[i]] + nwant[buckets[i]] * words, in + i * words, rs);
            nwant[buckets[i]]++;
        }
    }
    sluice_stream *a = NULL, *bk = NULL, *outs[SLUICE_MAX_OUTPUTS] = {NULL};
    CHECK_OK(ctx, sluice_stream_create(ctx, rs, n, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &bk));
    for (unsigned b = 0; b < count; ++b)
        CHECK_OK(ctx, sluice_stream_create(ctx, rs, n, &outs[b]));
    CHECK_OK(ctx, sluice_stream_upload(a, in, n));
    CHECK_OK(ctx, sluice_stream_upload(bk, buckets, n));
    CHECK_OK(ctx, sluice_split(ctx, a, bk, outs, count, mode));
    for (unsigned b = 0; b < count; ++b) {
        size_t c = 0;
        CHECK_OK(ctx, sluice_stream_download(outs[b], got, n, &c));
        CHECK(c == nwant[b] && same_records(got, want[b], c, rs, mode),
              "split %zu x %zu B into %u, output %u: %zu records (want %zu) or records differ", n,
              rs, count, b, c, nwant[b]);
        sluice_stream_destroy(outs[b]);
        free(want[b]);
    }
    sluice_stream_destroy(a);
    sluice_stream_destroy(bk);
    free(in);
    free(buckets);
    free(got);
}

static void check_partition(sluice_context *ctx, size_t n, sluice_scalar_type type, int pattern,
                            sluice_output_mode mode)
{
    uint32_t seed = 555u + (uint32_t)n;
    uint32_t *in = malloc((n + 1) * 4), *lo = malloc((n + 1) * 4), *hi = malloc((n + 1) * 4);
    uint32_t *got = malloc((n + 1) * 4);
    size_t nlo = 0, nhi = 0;
    uint32_t tu = 1u << 31;
    float tf = 0.25f;
    for (size_t i = 0; i < n; ++i) {
        uint32_t r = check_rand(&seed);
        if (type == SLUICE_U32) {
            /* random; all below; all above; sorted */
            in[i] = pattern == 0   ? r
                    : pattern == 1 ? r >> 1
                    : pattern == 2 ? r | tu
                                   : (uint32_t)i << 8;
        } else {
            float x = pattern == 0   ? (float)r / 4294967296.0f - 0.5f
                      : pattern == 1 ? -1.0f
                      : pattern == 2 ? 1.0f
                                     : (float)i / (float)n;
            if (pattern == 0 && r % 17 == 0)
                x = NAN;
            memcpy(&in[i], &x, 4);
        }
        float x;
        memcpy(&x, &in[i], 4);
        int below = type == SLUICE_U32 ? in[i] < tu : x < tf;
        if (below)
            lo[nlo++] = in[i];
        else
            hi[nhi++] = in[i];
    }
    sluice_stream *a = NULL, *b = NULL, *c = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &b));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &c));
    CHECK_OK(ctx, sluice_stream_upload(a, in, n));
    const void *t = type == SLUICE_U32 ? (const void *)&tu : (const void *)&tf;
    CHECK_OK(ctx, sluice_partition(ctx, a, type, t, b, c, mode));
    size_t cnt = 0;
    CHECK_OK(ctx, sluice_stream_download(b, got, n, &cnt));
    CHECK(cnt == nlo && same_records(got, lo, nlo, 4, mode),
          "partition %zu %s pattern %d below: %zu (want %zu) or records differ", n,
          type == SLUICE_U32 ? "u32" : "f32", pattern, cnt, nlo);
    CHECK_OK(ctx, sluice_stream_download(c, got, n, &cnt));
    CHECK(cnt == nhi && same_records(got, hi, nhi, 4, mode),
          "partition %zu %s pattern %d above: %zu (want %zu) or records differ", n,
          type == SLUICE_U32 ? "u32" : "f32", pattern, cnt, nhi);
    sluice_stream_destroy(a);
    sluice_stream_destroy(b);
    sluice_stream_destroy(c);
    free(in);
    free(lo);
    free(hi);
    free(got);
}

static void test_errors(sluice_context *ctx)
{
    sluice_stream *a = NULL, *f = NULL, *o = NULL, *small = NULL, *wide = NULL, *odd = NULL;
    sluice_stream *shortf = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 100, &a));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 100, &f));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 100, &o));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 10, &small));
    CHECK_OK(ctx, sluice_stream_create(ctx, 8, 100, &wide));
    CHECK_OK(ctx, sluice_stream_create(ctx, 6, 100, &odd));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 50, &shortf));
    uint32_t v[100], ones[100];
    for (int i = 0; i < 100; ++i) {
        v[i] = (uint32_t)i;
        ones[i] = 1;
    }
    CHECK_OK(ctx, sluice_stream_upload(a, v, 100));
    CHECK_OK(ctx, sluice_stream_upload(f, ones, 100));
    CHECK_OK(ctx, sluice_stream_upload(shortf, ones, 50));
    const sluice_status inval = SLUICE_ERROR_INVALID_ARGUMENT;
    CHECK(sluice_compact(NULL, a, f, o, SLUICE_ORDERED) == inval, "NULL context");
    CHECK(sluice_compact(ctx, NULL, f, o, SLUICE_ORDERED) == inval, "NULL input");
    CHECK(sluice_compact(ctx, a, NULL, o, SLUICE_ORDERED) == inval, "NULL flags");
    CHECK(sluice_compact(ctx, a, f, NULL, SLUICE_ORDERED) == inval, "NULL output");
    CHECK(sluice_compact(ctx, a, f, a, SLUICE_ORDERED) == inval, "output is the input");
    CHECK(sluice_compact(ctx, a, f, f, SLUICE_ORDERED) == inval, "output is the flags");
    CHECK(sluice_compact(ctx, a, f, wide, SLUICE_ORDERED) == inval, "record size mismatch");
    CHECK(strstr(sluice_context_error(ctx), "8 bytes") != NULL, "message: %s",
          sluice_context_error(ctx));
    CHECK(sluice_compact(ctx, odd, f, odd, SLUICE_ORDERED) == inval, "6-byte records");
    CHECK(sluice_compact(ctx, a, wide, o, SLUICE_ORDERED) == inval, "8-byte flags");
    CHECK(sluice_compact(ctx, a, shortf, o, SLUICE_ORDERED) == inval, "short flags");
    CHECK(strstr(sluice_context_error(ctx), "flags") != NULL, "message: %s",
          sluice_context_error(ctx));
    CHECK(sluice_compact(ctx, a, f, o, (sluice_output_mode)5) == inval, "bad mode");
    for (int m = 0; m < 2; ++m) {
        sluice_status st = sluice_compact(ctx, a, f, small, (sluice_output_mode)m);
        CHECK(st == SLUICE_ERROR_OVERFLOW, "compact overflow: %s", sluice_status_string(st));
        CHECK(strstr(sluice_context_error(ctx), "output capacity 10") != NULL, "message: %s",
              sluice_context_error(ctx));
    }
    /* A small output is fine when few records are kept; flags may be the
     * input itself (keeps the non-zero values). */
    CHECK_OK(ctx, sluice_stream_upload(f, v, 100));
    CHECK_OK(ctx, sluice_stream_set_length(a, 11));
    CHECK_OK(ctx, sluice_compact(ctx, a, a, small, SLUICE_ORDERED));
    uint32_t got[16];
    size_t cnt = 0;
    CHECK_OK(ctx, sluice_stream_download(small, got, 16, &cnt));
    CHECK(cnt == 10 && got[0] == 1 && got[9] == 10, "compact by itself: %zu", cnt);
    CHECK_OK(ctx, sluice_stream_set_length(a, 100));

    sluice_stream *outs[3] = {o, small, NULL};
    CHECK(sluice_split(NULL, a, f, outs, 2, SLUICE_ORDERED) == inval, "split NULL context");
    CHECK(sluice_split(ctx, NULL, f, outs, 2, SLUICE_ORDERED) == inval, "split NULL input");
    CHECK(sluice_split(ctx, a, NULL, outs, 2, SLUICE_ORDERED) == inval, "split NULL buckets");
    CHECK(sluice_split(ctx, a, f, NULL, 2, SLUICE_ORDERED) == inval, "split NULL outputs");
    CHECK(sluice_split(ctx, a, f, outs, 3, SLUICE_ORDERED) == inval, "split NULL output 2");
    CHECK(sluice_split(ctx, a, f, outs, 0, SLUICE_ORDERED) == inval, "split 0 outputs");
    CHECK(sluice_split(ctx, a, f, outs, 9, SLUICE_ORDERED) == inval, "split 9 outputs");
    sluice_stream *dup[2] = {o, o};
    CHECK(sluice_split(ctx, a, f, dup, 2, SLUICE_ORDERED) == inval, "split same output twice");
    sluice_stream *mixed[2] = {o, wide};
    CHECK(sluice_split(ctx, a, f, mixed, 2, SLUICE_ORDERED) == inval, "split record size");
    CHECK(sluice_split(ctx, a, shortf, outs, 2, SLUICE_ORDERED) == inval, "split short buckets");
    /* buckets 0, 1, ..., 99: all but 0 and 1 dropped with 2 outputs. */
    CHECK_OK(ctx, sluice_split(ctx, a, f, outs, 2, SLUICE_UNORDERED));
    /* All to bucket 1 (the small output) overflows it. */
    CHECK_OK(ctx, sluice_stream_upload(f, ones, 100));
    sluice_status st = sluice_split(ctx, a, f, outs, 2, SLUICE_ORDERED);
    CHECK(st == SLUICE_ERROR_OVERFLOW, "split overflow: %s", sluice_status_string(st));
    CHECK(strstr(sluice_context_error(ctx), "output 1 capacity 10") != NULL, "message: %s",
          sluice_context_error(ctx));

    uint32_t t = 50;
    CHECK(sluice_partition(NULL, a, SLUICE_U32, &t, o, f, SLUICE_ORDERED) == inval,
          "partition NULL context");
    CHECK(sluice_partition(ctx, NULL, SLUICE_U32, &t, o, f, SLUICE_ORDERED) == inval,
          "partition NULL input");
    CHECK(sluice_partition(ctx, a, SLUICE_U32, NULL, o, f, SLUICE_ORDERED) == inval,
          "partition NULL threshold");
    CHECK(sluice_partition(ctx, a, SLUICE_U32, &t, NULL, f, SLUICE_ORDERED) == inval,
          "partition NULL below");
    CHECK(sluice_partition(ctx, a, SLUICE_U32, &t, o, NULL, SLUICE_ORDERED) == inval,
          "partition NULL above");
    CHECK(sluice_partition(ctx, a, SLUICE_U32, &t, o, o, SLUICE_ORDERED) == inval,
          "partition below == above");
    CHECK(sluice_partition(ctx, a, SLUICE_U32, &t, a, f, SLUICE_ORDERED) == inval,
          "partition in place");
    CHECK(sluice_partition(ctx, wide, SLUICE_U32, &t, o, f, SLUICE_ORDERED) == inval,
          "partition 8-byte input");
    CHECK(sluice_partition(ctx, a, SLUICE_U32, &t, o, wide, SLUICE_ORDERED) == inval,
          "partition 8-byte output");
    CHECK(sluice_partition(ctx, a, (sluice_scalar_type)9, &t, o, f, SLUICE_ORDERED) == inval,
          "partition bad type");
    st = sluice_partition(ctx, a, SLUICE_U32, &t, o, small, SLUICE_UNORDERED);
    CHECK(st == SLUICE_ERROR_OVERFLOW, "partition overflow: %s", sluice_status_string(st));
    CHECK(strstr(sluice_context_error(ctx), "above capacity 10") != NULL, "message: %s",
          sluice_context_error(ctx));
    sluice_stream_destroy(a);
    sluice_stream_destroy(f);
    sluice_stream_destroy(o);
    sluice_stream_destroy(small);
    sluice_stream_destroy(wide);
    sluice_stream_destroy(odd);
    sluice_stream_destroy(shortf);
}

/* An input that overflowed is an error, never read as truncated (issue 12):
 * at once when its length is known on the host; when it is only on the
 * device the outputs are void, and reading them (which the call does itself
 * for an output that may be too small) reports where the overflow began. */
static void test_overflowed_input(sluice_context *ctx)
{
    const size_t n = 1000, cap = 600;
    sluice_stream *f = NULL, *o = NULL, *small = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, cap, &f));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, cap, &o));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 10, &small));
    uint32_t ones[600];
    for (size_t i = 0; i < cap; ++i)
        ones[i] = 1;
    CHECK_OK(ctx, sluice_stream_upload(f, ones, cap));
    for (int known = 0; known < 2; ++known) {
        for (int m = 0; m < 2; ++m) {
            sluice_output_mode mode = (sluice_output_mode)m;
            sluice_stream *in = NULL, *outs[2] = {o, small};
            uint32_t t = 50;
            sluice_status st[3];
            const char *fn[3] = {"sluice_compact", "sluice_split", "sluice_partition"};
            CHECK_OK(ctx, check_overflowed(ctx, n, cap, known, &in));
            st[0] = sluice_compact(ctx, in, f, o, mode);
            if (!known) { /* queued: the output is void */
                size_t len = 1;
                CHECK(st[0] == SLUICE_OK, "compact queued: %s", sluice_status_string(st[0]));
                st[0] = sluice_stream_length(o, &len);
                CHECK(len == 0 && strstr(sluice_context_error(ctx),
                                         "output slot 0 of kernel compact_w1, written from it, "
                                         "is void"),
                      "void compaction: %s", sluice_context_error(ctx));
            }
            CHECK(st[0] == SLUICE_ERROR_OVERFLOW && check_overflow_named(ctx, n, cap),
                  "compact, known %d: %s", known, sluice_context_error(ctx));
            st[1] = sluice_split(ctx, in, f, outs, 2, mode);
            CHECK(st[1] == SLUICE_ERROR_OVERFLOW && check_overflow_named(ctx, n, cap),
                  "split, known %d: %s", known, sluice_context_error(ctx));
            st[2] = sluice_partition(ctx, in, SLUICE_U32, &t, o, small, mode);
            CHECK(st[2] == SLUICE_ERROR_OVERFLOW && check_overflow_named(ctx, n, cap),
                  "partition, known %d: %s", known, sluice_context_error(ctx));
            if (known)
                for (int i = 0; i < 3; ++i)
                    CHECK(st[i] == SLUICE_ERROR_OVERFLOW, "%s", fn[i]);
            /* An overflowed flags stream is refused as well. */
            if (known) {
                sluice_status sf = sluice_compact(ctx, o, in, small, mode);
                CHECK(sf == SLUICE_ERROR_OVERFLOW &&
                          strstr(sluice_context_error(ctx),
                                 "sluice_compact: the flags stream overflowed: ") &&
                          check_overflow_named(ctx, n, cap),
                      "overflowed flags: %s", sluice_context_error(ctx));
            }
            sluice_stream_destroy(in);
        }
    }
    sluice_stream_destroy(f);
    sluice_stream_destroy(o);
    sluice_stream_destroy(small);
}

int main(void)
{
    sluice_context *ctx = check_context(0);
    const size_t sizes[] = {0, 1, 7, 8, 9, 255, 257, 4095, 4097, 65537};
    const size_t record_sizes[] = {4, 8, 12, 16, 20};
    for (int m = 0; m < 2; ++m) {
        sluice_output_mode mode = (sluice_output_mode)m;
        for (size_t si = 0; si < sizeof sizes / sizeof *sizes; ++si) {
            for (size_t ri = 0; ri < sizeof record_sizes / sizeof *record_sizes; ++ri)
                for (int p = 0; p < F_PATTERNS; ++p)
                    check_compact(ctx, sizes[si], record_sizes[ri], p, mode);
            for (unsigned count = 1; count <= SLUICE_MAX_OUTPUTS; ++count)
                check_split(ctx, sizes[si], count == 3 ? 12 : count == 5 ? 8 : 4, count, mode);
            for (int p = 0; p < 4; ++p) {
                check_partition(ctx, sizes[si], SLUICE_U32, p, mode);
                check_partition(ctx, sizes[si], SLUICE_F32, p, mode);
            }
        }
        /* 2^24 records. */
        check_partition(ctx, (size_t)1 << 24, SLUICE_U32, 0, mode);
        check_compact(ctx, (size_t)1 << 24, 4, F_RANDOM, mode);
    }
    check_split(ctx, (size_t)1 << 20, 16, 8, SLUICE_ORDERED);
    test_errors(ctx);
    test_overflowed_input(ctx);
    sluice_context_destroy(ctx);

    /* Chunks of 37 and 4096 records: 16-record blocks (SLUICE_EMIT16) with
     * tails, and chunks whose reserved room is shorter than one block. */
    const unsigned chunks[] = {37, 4096};
    for (size_t c = 0; c < sizeof chunks / sizeof *chunks; ++c) {
        char err[256];
        sluice_context_options o = {0};
        o.chunk = chunks[c];
        CHECK(sluice_context_create(&o, &ctx, err, sizeof err) == SLUICE_OK, "context: %s", err);
        if (!ctx)
            break;
        for (int m = 0; m < 2; ++m) {
            sluice_output_mode mode = (sluice_output_mode)m;
            for (size_t si = 0; si < sizeof sizes / sizeof *sizes; ++si) {
                for (int p = 0; p < F_PATTERNS; ++p) {
                    check_compact(ctx, sizes[si], 4, p, mode);
                    check_partition(ctx, sizes[si], SLUICE_F32, p, mode);
                }
                check_split(ctx, sizes[si], 4, 5, mode);
            }
        }
        sluice_context_destroy(ctx);
    }
    return check_summary();
}
