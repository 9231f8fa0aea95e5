/* Tests of bounded routing (Purcell 6.2.2 stencil routing): exact fill and
 * overflow counts against a C reference; each bucket's stored payloads are
 * distinct payloads of records sent to that bucket, as many as its fill; the
 * unused places are 0xffffffff, or (the sparse form) keep what they held;
 * and the error paths. */
#include "check.h"
#include "sluice/streams.h"

#include <string.h>

/* What the sparse form's unused places hold before (and so after) it:
 * never a payload of these tests (below 1000 + 2^24). */
#define UNTOUCHED 0x5e5e5e5eu

static void run_case_as(sluice_context *ctx, size_t n, uint32_t buckets, uint32_t slots,
                        uint32_t key_range, int sparse)
{
    size_t total = (size_t)buckets * slots;
    uint32_t *k = malloc((n + 1) * sizeof *k), *v = malloc((n + 1) * sizeof *v);
    uint32_t *cnt = calloc((size_t)buckets + 1, sizeof *cnt);
    uint32_t *out = malloc((total + 1) * sizeof *out);
    uint32_t *fill = malloc(((size_t)buckets + 1) * sizeof *fill);
    uint32_t *ovf = malloc(((size_t)buckets + 1) * sizeof *ovf);
    unsigned char *used = calloc(n + 1, 1);
    uint32_t s = (uint32_t)(n * 7u + buckets * 13u + slots) | 1u;
    /* Payload i + 1000 of record i: distinct, and never 0xffffffff. */
    for (size_t i = 0; i < n; ++i) {
        k[i] = key_range ? check_rand(&s) % key_range : check_rand(&s);
        v[i] = (uint32_t)i + 1000u;
        if (k[i] < buckets)
            cnt[k[i]]++;
    }
    sluice_stream *sk = NULL, *sv = NULL, *so = NULL, *sf = NULL, *sov = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &sk));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &sv));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, total + 2, &so));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, buckets, &sf));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, buckets, &sov));
    CHECK_OK(ctx, sluice_stream_upload(sk, k, n));
    CHECK_OK(ctx, sluice_stream_upload(sv, v, n));
    if (sparse) {
        const uint32_t u = UNTOUCHED;
        CHECK_OK(ctx, sluice_stream_fill(so, &u, total + 2));
        CHECK_OK(ctx, sluice_route_bounded_sparse(ctx, sk, sv, buckets, slots, so, sf, sov));
    } else {
        CHECK_OK(ctx, sluice_route_bounded(ctx, sk, sv, buckets, slots, so, sf, sov));
    }
    size_t c1 = 0, c2 = 0, c3 = 0;
    CHECK_OK(ctx, sluice_stream_download(so, out, total, &c1));
    CHECK_OK(ctx, sluice_stream_download(sf, fill, buckets, &c2));
    CHECK_OK(ctx, sluice_stream_download(sov, ovf, buckets, &c3));
    CHECK(c1 == total && c2 == buckets && c3 == buckets, "lengths %zu %zu %zu", c1, c2, c3);
    size_t bad_counts = 0, bad_slots = 0;
    for (uint32_t b = 0; b < buckets; ++b) {
        uint32_t f = cnt[b] < slots ? cnt[b] : slots;
        if (fill[b] != f || ovf[b] != cnt[b] - f)
            bad_counts++;
        for (uint32_t q = 0; q < slots; ++q) {
            uint32_t x = out[(size_t)b * slots + q];
            if (q >= f) {
                bad_slots += x != (sparse ? UNTOUCHED : 0xffffffffu);
                continue;
            }
            /* A payload of a record sent to b, stored once. */
            size_t i = (size_t)x - 1000u;
            if (x < 1000u || i >= n || k[i] != b || used[i])
                bad_slots++;
            else
                used[i] = 1;
        }
    }
    CHECK(bad_counts == 0, "n=%zu buckets=%u slots=%u: %zu buckets with wrong counts", n, buckets,
          slots, bad_counts);
    CHECK(bad_slots == 0, "n=%zu buckets=%u slots=%u%s: %zu wrong places", n, buckets, slots,
          sparse ? " (sparse)" : "", bad_slots);
    sluice_stream_destroy(sk);
    sluice_stream_destroy(sv);
    sluice_stream_destroy(so);
    sluice_stream_destroy(sf);
    sluice_stream_destroy(sov);
    free(k);
    free(v);
    free(cnt);
    free(out);
    free(fill);
    free(ovf);
    free(used);
}

/* The case in both forms. */
static void run_case(sluice_context *ctx, size_t n, uint32_t buckets, uint32_t slots,
                     uint32_t key_range)
{
    run_case_as(ctx, n, buckets, slots, key_range, 0);
    run_case_as(ctx, n, buckets, slots, key_range, 1);
}

static void test_errors(sluice_context *ctx)
{
    sluice_stream *k = NULL, *v = NULL, *o = NULL, *f = NULL, *ov = NULL, *b8 = NULL;
    sluice_stream *shortv = NULL, *small = NULL;
    uint32_t data[8] = {0, 1, 2, 3, 0, 1, 2, 3};
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 8, &k));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 8, &v));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 8, &o));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 4, &f));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 4, &ov));
    CHECK_OK(ctx, sluice_stream_create(ctx, 8, 8, &b8));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 8, &shortv));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 3, &small));
    CHECK_OK(ctx, sluice_stream_upload(k, data, 8));
    CHECK_OK(ctx, sluice_stream_upload(v, data, 8));
    CHECK_OK(ctx, sluice_stream_upload(shortv, data, 7));
    const sluice_status bad = SLUICE_ERROR_INVALID_ARGUMENT;
    CHECK(sluice_route_bounded(NULL, k, v, 4, 2, o, f, ov) == bad, "NULL context");
    CHECK(sluice_route_bounded(ctx, NULL, v, 4, 2, o, f, ov) == bad, "NULL keys");
    CHECK(sluice_route_bounded(ctx, k, NULL, 4, 2, o, f, ov) == bad, "NULL values");
    CHECK(sluice_route_bounded(ctx, k, v, 4, 2, NULL, f, ov) == bad, "NULL out");
    CHECK(sluice_route_bounded(ctx, k, v, 4, 2, o, NULL, ov) == bad, "NULL fill");
    CHECK(sluice_route_bounded(ctx, k, v, 4, 2, o, f, NULL) == bad, "NULL overflow");
    CHECK(sluice_route_bounded(ctx, b8, v, 4, 2, o, f, ov) == bad, "8-byte keys");
    CHECK(sluice_route_bounded(ctx, k, b8, 4, 2, o, f, ov) == bad, "8-byte values");
    CHECK(sluice_route_bounded(ctx, k, v, 4, 2, b8, f, ov) == bad, "8-byte out");
    CHECK(sluice_route_bounded(ctx, k, shortv, 4, 2, o, f, ov) == bad, "short values");
    CHECK(sluice_route_bounded(ctx, k, v, 4, 2, o, f, f) == bad, "fill is overflow");
    CHECK(sluice_route_bounded(ctx, k, v, 4, 3, o, f, ov) == SLUICE_ERROR_OVERFLOW,
          "out too small");
    CHECK(sluice_route_bounded(ctx, k, v, 4, 2, o, small, ov) == SLUICE_ERROR_OVERFLOW,
          "fill too small");
    CHECK(sluice_route_bounded(ctx, k, v, 0x10000u, 0x10000u, o, f, ov) == SLUICE_ERROR_OVERFLOW,
          "buckets x slots too large");
    CHECK_OK(ctx, sluice_route_bounded(ctx, k, v, 4, 2, o, f, ov));
    uint32_t got[8];
    size_t cnt = 0;
    CHECK_OK(ctx, sluice_stream_download(f, got, 4, &cnt));
    CHECK(cnt == 4 && got[0] == 2 && got[3] == 2, "fill after errors");
    sluice_stream_destroy(k);
    sluice_stream_destroy(v);
    sluice_stream_destroy(o);
    sluice_stream_destroy(f);
    sluice_stream_destroy(ov);
    sluice_stream_destroy(b8);
    sluice_stream_destroy(shortv);
    sluice_stream_destroy(small);
}

/* Overflowed keys or values are an error, never routed as truncated (issue
 * 12). */
static void test_overflowed(sluice_context *ctx)
{
    const size_t n = 1000, cap = 600;
    for (int known = 0; known < 2; ++known) {
        for (int which = 0; which < 2; ++which) { /* 0: the keys overflowed, 1: the values */
            sluice_stream *bad = NULL, *good = NULL, *o = NULL, *f = NULL, *ov = NULL;
            CHECK_OK(ctx, check_overflowed(ctx, n, cap, known, &bad));
            CHECK_OK(ctx, sluice_stream_create(ctx, 4, cap, &good));
            CHECK_OK(ctx, sluice_stream_set_length(good, cap));
            CHECK_OK(ctx, sluice_stream_create(ctx, 4, 16, &o));
            CHECK_OK(ctx, sluice_stream_create(ctx, 4, 4, &f));
            CHECK_OK(ctx, sluice_stream_create(ctx, 4, 4, &ov));
            sluice_status st = which ? sluice_route_bounded(ctx, good, bad, 4, 4, o, f, ov)
                                     : sluice_route_bounded(ctx, bad, good, 4, 4, o, f, ov);
            char want[64];
            snprintf(want, sizeof want, "%s stream overflowed: ", which ? "values" : "keys");
            CHECK(st == SLUICE_ERROR_OVERFLOW && strstr(sluice_context_error(ctx), want) &&
                      check_overflow_named(ctx, n, cap),
                  "routing overflowed %s (known %d): %s", which ? "values" : "keys", known,
                  sluice_context_error(ctx));
            sluice_stream_destroy(bad);
            sluice_stream_destroy(good);
            sluice_stream_destroy(o);
            sluice_stream_destroy(f);
            sluice_stream_destroy(ov);
        }
    }
}

int main(void)
{
    sluice_context *ctx = check_context(0);
    test_errors(ctx);
    test_overflowed(ctx);
    run_case(ctx, 0, 0, 0, 1);             /* nothing */
    run_case(ctx, 0, 10, 4, 10);           /* no records: all empty */
    run_case(ctx, 100, 10, 0, 10);         /* no places: all overflow */
    run_case(ctx, 100, 0, 4, 10);          /* no buckets: all dropped */
    run_case(ctx, 1000, 1, 8, 1);          /* one bucket, heavy contention */
    run_case(ctx, 1000, 100, 4, 150);      /* some keys beyond the buckets */
    run_case(ctx, 100000, 1000, 64, 1000); /* no bucket overflows (mostly) */
    run_case(ctx, 100000, 1000, 100, 1000);
    run_case(ctx, 1000000, 4096, 16, 5000); /* most buckets overflow */
    run_case(ctx, 1000000, 1u << 20, 2, 0); /* full-range keys */
    run_case(ctx, 1000000, 7, 100000, 7);   /* few buckets, many places */
    sluice_context_destroy(ctx);
    return check_summary();
}
