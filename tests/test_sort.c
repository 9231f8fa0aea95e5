/* Tests of sluice_sort_bitonic and sluice_sort_radix against a plain C
 * sort (check_sort_by_u32, tests/check.h: stable, so pairs of key and original
 * index come out in the order qsort by key then index gives): many
 * lengths (powers of two and their neighbours), key patterns, with and
 * without values, radix stability, and the error paths. */
#include "check.h"
#include "sluice/streams.h"

#include <string.h>

typedef sluice_status (*sort_fn)(sluice_context *, sluice_stream *, sluice_stream *);

typedef struct pair {
    uint32_t key, index;
} pair;

enum { RANDOM, EQUAL, SORTED, REVERSE, HIGH, FEW, PATTERNS };
static const char *pattern_name[] = {"random", "equal", "sorted", "reverse", "high bits", "few"};

static void fill_keys(uint32_t *k, size_t n, int pattern, uint32_t seed)
{
    uint32_t s = seed | 1u;
    for (size_t i = 0; i < n; ++i) {
        switch (pattern) {
        case RANDOM:
            k[i] = check_rand(&s);
            break;
        case EQUAL:
            k[i] = 0xdeadbeefu;
            break;
        case SORTED:
            k[i] = (uint32_t)i * 3u;
            break;
        case REVERSE:
            k[i] = (uint32_t)(n - i) * 5u;
            break;
        case HIGH:
            k[i] = 0xff000000u | (check_rand(&s) & 0x00ff00ffu);
            break;
        default:
            k[i] = check_rand(&s) % 5u;
            break;
        }
    }
}

/* Sorts n keys of a pattern with `sort`, with or without values (values =
 * original index), and checks against the reference. */
static void run_case(sluice_context *ctx, const char *name, sort_fn sort, int stable, size_t n,
                     int pattern, int with_values)
{
    uint32_t *k = malloc((n + 1) * sizeof *k), *got = malloc((n + 1) * sizeof *got);
    uint32_t *gv = malloc((n + 1) * sizeof *gv), *idx = malloc((n + 1) * sizeof *idx);
    pair *ref = malloc((n + 1) * sizeof *ref);
    unsigned char *seen = calloc(n + 1, 1);
    sluice_stream *sk = NULL, *sv = NULL;
    if (!k || !got || !gv || !idx || !ref || !seen) {
        CHECK(0, "out of host memory");
        goto out;
    }
    fill_keys(k, n, pattern, (uint32_t)(n * 2654435761u + (size_t)pattern));
    for (size_t i = 0; i < n; ++i) {
        ref[i].key = k[i];
        ref[i].index = (uint32_t)i;
        idx[i] = (uint32_t)i;
    }
    /* listed by index, sorted stably by key: key, then index */
    CHECK(check_sort_by_u32(ref, n, sizeof *ref), "out of memory");
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &sk));
    CHECK_OK(ctx, sluice_stream_upload(sk, k, n));
    if (with_values) {
        CHECK_OK(ctx, sluice_stream_create(ctx, 4, n + 3, &sv));
        CHECK_OK(ctx, sluice_stream_upload(sv, idx, n));
    }
    sluice_status st = sort(ctx, sk, sv);
    CHECK(st == SLUICE_OK, "%s n=%zu %s values=%d: %s", name, n, pattern_name[pattern], with_values,
          sluice_context_error(ctx));
    size_t cnt = 0;
    CHECK_OK(ctx, sluice_stream_download(sk, got, n, &cnt));
    CHECK(cnt == n, "%s: length %zu after sort of %zu", name, cnt, n);
    size_t bad = n;
    for (size_t i = 0; i < n && bad == n; ++i)
        if (got[i] != ref[i].key)
            bad = i;
    CHECK(bad == n, "%s n=%zu %s values=%d: key %zu is %u, expected %u", name, n,
          pattern_name[pattern], with_values, bad, got[bad], ref[bad].key);
    if (with_values) {
        CHECK_OK(ctx, sluice_stream_download(sv, gv, n, &cnt));
        bad = n;
        for (size_t i = 0; i < n && bad == n; ++i) {
            if (stable ? gv[i] != ref[i].index : (gv[i] >= n || seen[gv[i]] || k[gv[i]] != got[i]))
                bad = i;
            else if (!stable)
                seen[gv[i]] = 1;
        }
        CHECK(bad == n, "%s n=%zu %s: value %zu (%u) does not follow its key%s", name, n,
              pattern_name[pattern], bad, gv[bad], stable ? " stably" : "");
    }
out:
    sluice_stream_destroy(sk);
    sluice_stream_destroy(sv);
    free(k);
    free(got);
    free(gv);
    free(idx);
    free(ref);
    free(seen);
}

static void test_sort(sluice_context *ctx, const char *name, sort_fn sort, int stable,
                      size_t largest)
{
    const size_t small[] = {0,   1,    2,    3,    7,     100,   511,   512,
                            513, 1023, 1024, 1025, 65535, 65536, 65537, 100003};
    for (size_t si = 0; si < sizeof small / sizeof *small; ++si)
        for (int p = 0; p < PATTERNS; ++p)
            for (int v = 0; v < 2; ++v)
                run_case(ctx, name, sort, stable, small[si], p, v);
    /* 2^20 +- 1 with every pattern, then the largest size (random). */
    const size_t big[] = {((size_t)1 << 20) - 1, (size_t)1 << 20, ((size_t)1 << 20) + 1};
    for (size_t bi = 0; bi < 3; ++bi)
        for (int p = 0; p < PATTERNS; ++p)
            run_case(ctx, name, sort, stable, big[bi], p, p == RANDOM || p == FEW);
    if (largest > big[2]) {
        run_case(ctx, name, sort, stable, largest, RANDOM, 1);
        run_case(ctx, name, sort, stable, largest, FEW, 0);
    }
}

static void test_errors(sluice_context *ctx, const char *name, sort_fn sort)
{
    sluice_stream *k = NULL, *v = NULL, *k8 = NULL, *shortv = NULL;
    uint32_t data[16] = {5, 3, 1, 4, 2, 9, 8, 7, 6, 0, 11, 15, 13, 12, 14, 10};
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 16, &k));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 16, &v));
    CHECK_OK(ctx, sluice_stream_create(ctx, 8, 16, &k8));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 16, &shortv));
    CHECK_OK(ctx, sluice_stream_upload(k, data, 16));
    CHECK_OK(ctx, sluice_stream_upload(v, data, 16));
    CHECK_OK(ctx, sluice_stream_upload(k8, data, 8));
    CHECK_OK(ctx, sluice_stream_upload(shortv, data, 15));
    CHECK(sort(NULL, k, v) == SLUICE_ERROR_INVALID_ARGUMENT, "%s: NULL context", name);
    CHECK(sort(ctx, NULL, v) == SLUICE_ERROR_INVALID_ARGUMENT, "%s: NULL keys", name);
    CHECK(sort(ctx, k8, NULL) == SLUICE_ERROR_INVALID_ARGUMENT, "%s: 8-byte keys", name);
    CHECK(strstr(sluice_context_error(ctx), "4 bytes") != NULL, "%s: message %s", name,
          sluice_context_error(ctx));
    CHECK(sort(ctx, k, k8) == SLUICE_ERROR_INVALID_ARGUMENT, "%s: 8-byte values", name);
    CHECK(sort(ctx, k, shortv) == SLUICE_ERROR_INVALID_ARGUMENT, "%s: short values", name);
    CHECK(sort(ctx, k, k) == SLUICE_ERROR_INVALID_ARGUMENT, "%s: values are the keys", name);
    /* The failed calls left the keys alone; a good call still works. */
    uint32_t got[16];
    size_t cnt = 0;
    CHECK_OK(ctx, sluice_stream_download(k, got, 16, &cnt));
    CHECK(cnt == 16 && memcmp(got, data, sizeof data) == 0, "%s: failed calls touched keys", name);
    CHECK_OK(ctx, sort(ctx, k, v));
    CHECK_OK(ctx, sluice_stream_download(k, got, 16, &cnt));
    int ok = cnt == 16;
    for (uint32_t i = 0; i < 16 && ok; ++i)
        ok = got[i] == i;
    CHECK(ok, "%s: 16 keys after the errors", name);
    sluice_stream_destroy(k);
    sluice_stream_destroy(v);
    sluice_stream_destroy(k8);
    sluice_stream_destroy(shortv);
}

/* Overflowed keys or values are an error, never sorted as truncated (issue
 * 12), whether their length is known on the host or only on the device. */
static void test_overflowed(sluice_context *ctx, const char *name, sort_fn sort)
{
    const size_t n = 1000, cap = 600;
    for (int known = 0; known < 2; ++known) {
        for (int which = 0; which < 2; ++which) { /* 0: the keys overflowed, 1: the values */
            sluice_stream *bad = NULL, *good = NULL;
            CHECK_OK(ctx, check_overflowed(ctx, n, cap, known, &bad));
            CHECK_OK(ctx, sluice_stream_create(ctx, 4, cap, &good));
            CHECK_OK(ctx, sluice_stream_set_length(good, cap));
            sluice_status st = which ? sort(ctx, good, bad) : sort(ctx, bad, good);
            char want[64];
            snprintf(want, sizeof want, "%s stream overflowed: ", which ? "values" : "keys");
            CHECK(st == SLUICE_ERROR_OVERFLOW && strstr(sluice_context_error(ctx), want) &&
                      check_overflow_named(ctx, n, cap),
                  "%s with overflowed %s (known %d): %s", name, which ? "values" : "keys", known,
                  sluice_context_error(ctx));
            sluice_stream_destroy(bad);
            sluice_stream_destroy(good);
        }
    }
}

/* The radix sort's scratch is kept between sorts, grows to the largest and
 * is freed by sluice_context_release_scratch; sorts are right throughout. */
static void test_scratch(sluice_context *ctx)
{
    CHECK(sluice_context_sort_scratch_bytes(NULL) == 0, "sort scratch of no context");
    sluice_context_release_scratch(NULL);
    sluice_context_release_scratch(ctx);
    CHECK(sluice_context_sort_scratch_bytes(ctx) == 0 && sluice_context_scratch_bytes(ctx) == 0,
          "scratch after release: %zu, %zu", sluice_context_sort_scratch_bytes(ctx),
          sluice_context_scratch_bytes(ctx));
    const struct {
        size_t n;
        int values;
        size_t kept; /* bytes the context holds after the sort */
    } steps[] = {{1000, 0, 4000},  {1000, 1, 8000}, {500, 1, 8000}, {3001, 0, 12004},
                 {3001, 1, 24008}, {1, 1, 24008},   {0, 0, 0},      {777, 1, 6216}};
    for (size_t i = 0; i < sizeof steps / sizeof *steps; ++i) {
        if (steps[i].n == 0 && steps[i].kept == 0) {
            sluice_context_release_scratch(ctx);
            continue;
        }
        run_case(ctx, "radix (kept scratch)", sluice_sort_radix, 1, steps[i].n, RANDOM,
                 steps[i].values);
        CHECK(sluice_context_sort_scratch_bytes(ctx) == steps[i].kept,
              "after sorting %zu keys%s: %zu bytes of sort scratch, expected %zu", steps[i].n,
              steps[i].values ? " and values" : "", sluice_context_sort_scratch_bytes(ctx),
              steps[i].kept);
    }
}

int main(void)
{
    sluice_context *ctx = check_context(0);
    test_errors(ctx, "radix", sluice_sort_radix);
    test_errors(ctx, "bitonic", sluice_sort_bitonic);
    test_overflowed(ctx, "radix", sluice_sort_radix);
    test_overflowed(ctx, "bitonic", sluice_sort_bitonic);
    test_scratch(ctx);
    test_sort(ctx, "radix", sluice_sort_radix, 1, (size_t)1 << 24);
    test_sort(ctx, "bitonic", sluice_sort_bitonic, 0, 0);
    sluice_context_destroy(ctx);
    return check_summary();
}
