/* Tests of the cell-start index (Purcell 6.2.2) built by binary search over
 * sorted keys and by counting, against a C reference: keys beyond the last
 * cell, empty cells, one cell, no keys, and the error paths. */
#include "check.h"
#include "sluice/streams.h"

#include <string.h>

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* start[c] = number of keys < c, for c in 0 .. cells. */
static void reference(const uint32_t *keys, size_t n, uint32_t cells, uint32_t *start)
{
    memset(start, 0, ((size_t)cells + 1) * sizeof *start);
    for (size_t i = 0; i < n; ++i)
        if (keys[i] < cells)
            start[keys[i] + 1]++;
    for (uint32_t c = 0; c < cells; ++c)
        start[c + 1] += start[c];
}

static void run_case(sluice_context *ctx, size_t n, uint32_t cells, uint32_t key_range)
{
    uint32_t *k = malloc((n + 1) * sizeof *k);
    uint32_t *ref = malloc(((size_t)cells + 2) * sizeof *ref);
    uint32_t *got = malloc(((size_t)cells + 2) * sizeof *got);
    uint32_t s = (uint32_t)(n * 31u + cells) | 1u;
    for (size_t i = 0; i < n; ++i)
        k[i] = key_range ? check_rand(&s) % key_range : check_rand(&s);
    reference(k, n, cells, ref);
    sluice_stream *keys = NULL, *start = NULL;
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, n, &keys));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, (size_t)cells + 5, &start));
    /* Counting takes unsorted keys. */
    CHECK_OK(ctx, sluice_stream_upload(keys, k, n));
    CHECK_OK(ctx, sluice_cell_index_count(ctx, keys, cells, start));
    size_t cnt = 0;
    memset(got, 0xab, ((size_t)cells + 1) * sizeof *got);
    CHECK_OK(ctx, sluice_stream_download(start, got, (size_t)cells + 1, &cnt));
    CHECK(cnt == (size_t)cells + 1 && memcmp(got, ref, ((size_t)cells + 1) * sizeof *got) == 0,
          "count: n=%zu cells=%u range=%u (length %zu)", n, cells, key_range, cnt);
    /* The search takes sorted keys. */
    qsort(k, n, sizeof *k, cmp_u32);
    CHECK_OK(ctx, sluice_stream_upload(keys, k, n));
    CHECK_OK(ctx, sluice_stream_set_length(start, 0));
    CHECK_OK(ctx, sluice_cell_index_search(ctx, keys, cells, start));
    memset(got, 0xab, ((size_t)cells + 1) * sizeof *got);
    CHECK_OK(ctx, sluice_stream_download(start, got, (size_t)cells + 1, &cnt));
    CHECK(cnt == (size_t)cells + 1 && memcmp(got, ref, ((size_t)cells + 1) * sizeof *got) == 0,
          "search: n=%zu cells=%u range=%u (length %zu)", n, cells, key_range, cnt);
    sluice_stream_destroy(keys);
    sluice_stream_destroy(start);
    free(k);
    free(ref);
    free(got);
}

static void test_errors(sluice_context *ctx)
{
    typedef sluice_status (*fn)(sluice_context *, sluice_stream *, uint32_t, sluice_stream *);
    fn f[2] = {sluice_cell_index_search, sluice_cell_index_count};
    sluice_stream *k = NULL, *s = NULL, *k8 = NULL, *small = NULL;
    uint32_t data[4] = {0, 1, 1, 3};
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 4, &k));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 8, &s));
    CHECK_OK(ctx, sluice_stream_create(ctx, 8, 8, &k8));
    CHECK_OK(ctx, sluice_stream_create(ctx, 4, 3, &small));
    CHECK_OK(ctx, sluice_stream_upload(k, data, 4));
    for (int i = 0; i < 2; ++i) {
        CHECK(f[i](NULL, k, 4, s) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL context");
        CHECK(f[i](ctx, NULL, 4, s) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL keys");
        CHECK(f[i](ctx, k, 4, NULL) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL start");
        CHECK(f[i](ctx, k8, 4, s) == SLUICE_ERROR_INVALID_ARGUMENT, "8-byte keys");
        CHECK(f[i](ctx, k, 4, k8) == SLUICE_ERROR_INVALID_ARGUMENT, "8-byte start");
        CHECK(f[i](ctx, k, 4, k) == SLUICE_ERROR_INVALID_ARGUMENT, "start is keys");
        CHECK(f[i](ctx, k, 3, small) == SLUICE_ERROR_OVERFLOW, "start too small");
        CHECK(f[i](ctx, k, 0xffffffffu, s) == SLUICE_ERROR_OVERFLOW, "huge cell count");
        CHECK_OK(ctx, f[i](ctx, k, 2, small));
        uint32_t got[3];
        size_t cnt = 0;
        CHECK_OK(ctx, sluice_stream_download(small, got, 3, &cnt));
        CHECK(cnt == 3 && got[0] == 0 && got[1] == 1 && got[2] == 3, "small case %d", i);
    }
    sluice_stream_destroy(k);
    sluice_stream_destroy(s);
    sluice_stream_destroy(k8);
    sluice_stream_destroy(small);
}

/* Overflowed keys are an error, never indexed as truncated (issue 12). */
static void test_overflowed_keys(sluice_context *ctx)
{
    const size_t n = 1000, cap = 600;
    typedef sluice_status (*index_fn)(sluice_context *, sluice_stream *, uint32_t, sluice_stream *);
    const index_fn f[2] = {sluice_cell_index_search, sluice_cell_index_count};
    for (int known = 0; known < 2; ++known) {
        for (int i = 0; i < 2; ++i) {
            sluice_stream *keys = NULL, *start = NULL;
            CHECK_OK(ctx, check_overflowed(ctx, n, cap, known, &keys));
            CHECK_OK(ctx, sluice_stream_create(ctx, 4, 1001, &start));
            sluice_status st = f[i](ctx, keys, 1000, start);
            CHECK(st == SLUICE_ERROR_OVERFLOW &&
                      strstr(sluice_context_error(ctx), "keys stream overflowed: ") &&
                      check_overflow_named(ctx, n, cap),
                  "cell index %d of overflowed keys (known %d): %s", i, known,
                  sluice_context_error(ctx));
            sluice_stream_destroy(keys);
            sluice_stream_destroy(start);
        }
    }
}

int main(void)
{
    sluice_context *ctx = check_context(0);
    test_errors(ctx);
    test_overflowed_keys(ctx);
    run_case(ctx, 0, 0, 0);           /* nothing at all */
    run_case(ctx, 0, 10, 10);         /* no keys: every start is 0 */
    run_case(ctx, 100, 0, 5);         /* no cells: every key is beyond */
    run_case(ctx, 100, 1, 1);         /* one cell holding everything */
    run_case(ctx, 100, 1, 3);         /* one cell, keys beyond it */
    run_case(ctx, 1000, 5000, 5000);  /* mostly empty cells */
    run_case(ctx, 1000, 5000, 10000); /* half the keys beyond the cells */
    run_case(ctx, 100000, 64, 70);
    run_case(ctx, 100000, 100000, 0); /* full-range keys: nearly all beyond */
    run_case(ctx, (size_t)1 << 20, 1u << 16, 1u << 16);
    run_case(ctx, (size_t)1 << 20, 1u << 20, (1u << 20) + 1000);
    run_case(ctx, 1000, 1u << 22, 1u << 22); /* many more cells than keys */
    sluice_context_destroy(ctx);
    return check_summary();
}
