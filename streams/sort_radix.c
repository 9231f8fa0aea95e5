/* Stable LSD radix sort of uint32 keys with optional uint32 values
 * (kernels/sort_radix.cl). Purcell (6.2.2) sorts photons into grid cells
 * with a bitonic sort because the GPUs of 2004 could not scatter; a device
 * that can scatter does the same job with a radix sort in O(n) work.
 *
 * Design for PoCL on a CPU: a few large contiguous chunks, one work-item per
 * chunk (work-groups of one), so each pass is a serial histogram and a
 * serial, stable scatter per chunk with only a small table scan between. The
 * first launch counts all four digits at once; passes in which every key has
 * the same digit would only copy, so they are skipped.
 *
 * With the GPU layout (SLUICE_LAYOUT_INTERLEAVED) a work-group takes each
 * tile of keys instead, its work-items reading neighbouring keys, with 4-bit
 * digits so that its tables fit in local memory (sort_radix_groups). */
#include "common.h"
#include "sluice/streams.h"

#include <stdlib.h>
#include <string.h>

#define RADIX 256u
#define RADIX_PASSES 4u

/* Chunks per compute unit: enough that uneven chunks even out across the
 * cores, few enough that the RADIX x chunks table stays small. */
#define CHUNKS_PER_UNIT 8u
/* Records below which a chunk is not worth its histogram table. */
#define MIN_CHUNK 16384u
/* The scatter writes whole output lines with non-temporal stores once the
 * output (keys and values) reaches this fraction of the device's cache:
 * measured on a 32 MiB L3 (bench/README.md), they gained from 4 MiB of
 * output up and lost a little at 2 MiB. */
#define NT_CACHE_FRACTION 8u

/* The scratch of one sort: keys and values (when there are values) to
 * ping-pong with, kept by the context between sorts (sl_sort_scratch), and
 * a table of `table_bytes` of its own. */
static sluice_status radix_scratch(sluice_context *ctx, size_t n, int with_values,
                                   size_t table_bytes, cl_mem *tmp_keys, cl_mem *tmp_vals,
                                   cl_mem *table)
{
    cl_mem kv[2] = {NULL, NULL};
    sluice_status st = sl_sort_scratch(ctx, n * sizeof(cl_uint), with_values, kv);
    if (st != SLUICE_OK)
        return st;
    *tmp_keys = kv[0];
    *tmp_vals = with_values ? kv[1] : NULL;
    cl_int err = CL_SUCCESS;
    *table = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, table_bytes, NULL, &err);
    if (!*table)
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY,
                       "sluice_sort_radix: cannot allocate scratch for %zu records (%s)", n,
                       sl_cl_error_string(err));
    return SLUICE_OK;
}

/* An odd number of passes leaves the result in the scratch buffers (cur_k,
 * cur_v): copies it back to the streams. */
static sluice_status radix_copy_back(sluice_context *ctx, cl_mem cur_k, cl_mem cur_v,
                                     sluice_stream *keys, sluice_stream *values, size_t n)
{
    if (cur_k == keys->mem)
        return SLUICE_OK;
    cl_int err =
        clEnqueueCopyBuffer(ctx->queue, cur_k, keys->mem, 0, 0, n * sizeof(cl_uint), 0, NULL, NULL);
    if (err == CL_SUCCESS && values)
        err = clEnqueueCopyBuffer(ctx->queue, cur_v, values->mem, 0, 0, n * sizeof(cl_uint), 0,
                                  NULL, NULL);
    return err == CL_SUCCESS ? SLUICE_OK : sl_cl_fail(ctx, err, "copying the sorted records back");
}

/* Releases a sort's kernels and buffers (NULL entries are skipped). OpenCL
 * keeps released buffers alive until the queued work is done. */
static void radix_release(cl_kernel *k, size_t nk, cl_mem *m, size_t nm)
{
    for (size_t i = 0; i < nk; ++i)
        if (k[i])
            clReleaseKernel(k[i]);
    for (size_t i = 0; i < nm; ++i)
        if (m[i])
            clReleaseMemObject(m[i]);
}

/* The GPU layout's sort (kernels/sort_radix.cl, radix_wg_*): 4-bit digits,
 * work-groups of ctx->group on tiles of RG_ROUNDS rounds of a key per
 * work-item. */
#define RG_BINS 16u
#define RG_PASSES 8u
#define RG_ROUNDS 8u

static sluice_status sort_radix_groups(sluice_context *ctx, sluice_stream *keys,
                                       sluice_stream *values, size_t n)
{
    const size_t group = ctx->group;
    const cl_uint nn = (cl_uint)n, tile = (cl_uint)(group * RG_ROUNDS);
    const cl_uint tiles = (cl_uint)((n + tile - 1) / tile), count = RG_BINS * tiles;
    const cl_uint has_values = values ? 1u : 0u;
    cl_kernel k_all = NULL, k_hist = NULL, k_scan = NULL, k_scatter = NULL;
    cl_mem tmp_keys = NULL, tmp_vals = NULL, table = NULL, totals = NULL;
    cl_uint host_totals[RG_PASSES * RG_BINS];
    cl_int err = CL_SUCCESS;
    sluice_status st = SLUICE_OK;
    st = radix_scratch(ctx, n, values != NULL, (size_t)count * sizeof(cl_uint), &tmp_keys,
                       &tmp_vals, &table);
    if (st == SLUICE_OK) {
        totals = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, sizeof host_totals, NULL, &err);
        if (!totals)
            st = sl_cl_fail(ctx, err, "sluice_sort_radix: allocating the digit totals");
    }
    if (st != SLUICE_OK)
        goto done;
    st = sl_embedded_cl_kernel(ctx, "sort_radix.cl", "radix_wg_hist_all", &k_all);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "sort_radix.cl", "radix_wg_hist", &k_hist);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "sort_radix.cl", "radix_wg_scan", &k_scan);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "sort_radix.cl", "radix_wg_scatter", &k_scatter);
    if (st != SLUICE_OK)
        goto done;
    /* Every digit's totals, to skip the passes that would only copy: the
     * one point where the sort waits. */
    static const cl_uint zero[RG_PASSES * RG_BINS];
    err = clEnqueueWriteBuffer(ctx->queue, totals, CL_FALSE, 0, sizeof zero, zero, 0, NULL, NULL);
    if (err != CL_SUCCESS) {
        st = sl_cl_fail(ctx, err, "clearing the radix totals");
        goto done;
    }
    st = sl_set_args(ctx, k_all, "radix_wg_hist_all", 4,
                     SIZES(sizeof(cl_mem), sizeof nn, sizeof tile, sizeof(cl_mem)),
                     VALUES(&keys->mem, &nn, &tile, &totals));
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, k_all, "radix_hist_all", (size_t)tiles * group, group,
                            SL_RAW_IO(nn, 4));
    if (st != SLUICE_OK)
        goto done;
    err = clEnqueueReadBuffer(ctx->queue, totals, CL_TRUE, 0, sizeof host_totals, host_totals, 0,
                              NULL, NULL);
    if (err != CL_SUCCESS) {
        st = sl_cl_fail(ctx, err, "reading the radix totals");
        goto done;
    }
    cl_mem cur_k = keys->mem, alt_k = tmp_keys;
    cl_mem cur_v = values ? values->mem : keys->mem, alt_v = values ? tmp_vals : tmp_keys;
    for (cl_uint p = 0; p < RG_PASSES && st == SLUICE_OK; ++p) {
        int skip = 0;
        for (cl_uint d = 0; d < RG_BINS && !skip; ++d)
            skip = host_totals[p * RG_BINS + d] == nn;
        if (skip)
            continue;
        cl_uint shift = 4u * p;
        st = sl_set_args(ctx, k_hist, "radix_wg_hist", 6,
                         SIZES(sizeof(cl_mem), sizeof nn, sizeof tile, sizeof shift, sizeof(cl_mem),
                               sizeof tiles),
                         VALUES(&cur_k, &nn, &tile, &shift, &table, &tiles));
        if (st == SLUICE_OK)
            st = sl_enqueue_raw(ctx, k_hist, "radix_hist", (size_t)tiles * group, group,
                                SL_RAW_IO(nn, 4));
        if (st == SLUICE_OK) {
            sl_set_arg(k_scan, 0, sizeof(cl_mem), &table, &err);
            sl_set_arg(k_scan, 1, sizeof count, &count, &err);
            sl_set_arg(k_scan, 2, (group + 1) * sizeof(cl_uint), NULL, &err);
            st = err == CL_SUCCESS
                     ? sl_enqueue_raw(ctx, k_scan, "radix_scan", group, group, SL_RAW_IO(count, 8))
                     : sl_cl_fail(ctx, err, "setting radix_wg_scan's arguments");
        }
        if (st == SLUICE_OK)
            st = sl_set_args(ctx, k_scatter, "radix_wg_scatter", 10,
                             SIZES(sizeof(cl_mem), sizeof(cl_mem), sizeof(cl_mem), sizeof(cl_mem),
                                   sizeof has_values, sizeof nn, sizeof tile, sizeof shift,
                                   sizeof(cl_mem), sizeof tiles),
                             VALUES(&cur_k, &cur_v, &alt_k, &alt_v, &has_values, &nn, &tile, &shift,
                                    &table, &tiles));
        if (st == SLUICE_OK)
            st = sl_enqueue_raw(ctx, k_scatter,
                                values ? "radix_scatter_pairs" : "radix_scatter_keys",
                                (size_t)tiles * group, group, SL_RAW_IO(nn, values ? 16 : 8));
        cl_mem t_k = cur_k, t_v = cur_v;
        cur_k = alt_k;
        cur_v = alt_v;
        alt_k = t_k;
        alt_v = t_v;
    }
    if (st == SLUICE_OK)
        st = radix_copy_back(ctx, cur_k, cur_v, keys, values, n);
done:;
    cl_kernel ks[] = {k_all, k_hist, k_scan, k_scatter};
    cl_mem ms[] = {table, totals}; /* the context keeps tmp_keys, tmp_vals */
    radix_release(ks, 4, ms, 2);
    return st;
}

sluice_status sluice_sort_radix(sluice_context *ctx, sluice_stream *keys, sluice_stream *values)
{
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    size_t n = 0, nv = 0;
    sluice_status st = sl_check_u32_stream(ctx, keys, "sluice_sort_radix", "keys", &n);
    if (st != SLUICE_OK)
        return st;
    if (values) {
        if (values == keys)
            return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                           "sluice_sort_radix: keys and values are the same stream");
        st = sl_check_u32_stream(ctx, values, "sluice_sort_radix", "values", &nv);
        if (st != SLUICE_OK)
            return st;
        if (nv < n)
            return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                           "sluice_sort_radix: %zu values for %zu keys", nv, n);
    }
    if (n < 2)
        return SLUICE_OK;
    if (ctx->layout == SLUICE_LAYOUT_INTERLEAVED)
        return sort_radix_groups(ctx, keys, values, n);

    cl_uint chunks = ctx->info.compute_units * CHUNKS_PER_UNIT;
    if (chunks < 1)
        chunks = 1;
    if (n / MIN_CHUNK < chunks)
        chunks = (cl_uint)(n / MIN_CHUNK > 0 ? n / MIN_CHUNK : 1);
    const cl_uint table_len = RADIX * chunks; /* one digit-major table */
    const cl_uint nn = (cl_uint)n;
    const uint64_t out_bytes = (uint64_t)n * (values ? 8u : 4u);
    const cl_uint nt =
        ctx->info.cache_bytes > 0 && out_bytes >= ctx->info.cache_bytes / NT_CACHE_FRACTION;

    cl_kernel k_all = NULL, k_hist = NULL, k_scan = NULL, k_scatter = NULL;
    cl_mem tmp_keys = NULL, tmp_vals = NULL, table = NULL;
    cl_uint *host_table = NULL;
    cl_int err = CL_SUCCESS;

    host_table = malloc((size_t)RADIX_PASSES * table_len * sizeof *host_table);
    if (!host_table) {
        st = sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
        goto done;
    }
    st = radix_scratch(ctx, n, values != NULL, (size_t)RADIX_PASSES * table_len * sizeof(cl_uint),
                       &tmp_keys, &tmp_vals, &table);
    if (st != SLUICE_OK)
        goto done;
    st = sl_embedded_cl_kernel(ctx, "sort_radix.cl", "radix_hist_all", &k_all);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "sort_radix.cl", "radix_hist", &k_hist);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "sort_radix.cl", "radix_scan", &k_scan);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "sort_radix.cl",
                                   values ? "radix_scatter_pairs" : "radix_scatter_keys",
                                   &k_scatter);
    if (st != SLUICE_OK)
        goto done;

    /* All four histograms in one read; the host needs their totals to skip
     * passes, so this is the one point where the sort waits. */
    st = sl_set_args(ctx, k_all, "radix_hist_all", 4,
                     SIZES(sizeof(cl_mem), sizeof nn, sizeof chunks, sizeof(cl_mem)),
                     VALUES(&keys->mem, &nn, &chunks, &table));
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, k_all, "radix_hist_all", chunks, 1, SL_RAW_IO(nn, 4));
    if (st != SLUICE_OK)
        goto done;
    err = clEnqueueReadBuffer(ctx->queue, table, CL_TRUE, 0,
                              (size_t)RADIX_PASSES * table_len * sizeof(cl_uint), host_table, 0,
                              NULL, NULL);
    if (err != CL_SUCCESS) {
        st = sl_cl_fail(ctx, err, "reading the radix histograms");
        goto done;
    }

    cl_mem cur_k = keys->mem, alt_k = tmp_keys;
    cl_mem cur_v = values ? values->mem : NULL, alt_v = tmp_vals;
    int first = 1;
    for (cl_uint p = 0; p < RADIX_PASSES; ++p) {
        /* Skip the pass if one digit holds every key: it would be a copy. */
        const cl_uint *t = host_table + (size_t)p * table_len;
        int skip = 0;
        for (cl_uint d = 0; d < RADIX && !skip; ++d) {
            size_t sum = 0;
            for (cl_uint c = 0; c < chunks; ++c)
                sum += t[d * chunks + c];
            skip = sum == n;
        }
        if (skip)
            continue;
        cl_uint shift = 8u * p, offset = p * table_len;
        if (!first) {
            st = sl_set_args(ctx, k_hist, "radix_hist", 6,
                             SIZES(sizeof(cl_mem), sizeof nn, sizeof chunks, sizeof shift,
                                   sizeof(cl_mem), sizeof offset),
                             VALUES(&cur_k, &nn, &chunks, &shift, &table, &offset));
            if (st == SLUICE_OK)
                st = sl_enqueue_raw(ctx, k_hist, "radix_hist", chunks, 1, SL_RAW_IO(nn, 4));
        }
        first = 0;
        if (st == SLUICE_OK)
            st = sl_set_args(ctx, k_scan, "radix_scan", 3,
                             SIZES(sizeof(cl_mem), sizeof offset, sizeof table_len),
                             VALUES(&table, &offset, &table_len));
        if (st == SLUICE_OK)
            st = sl_enqueue_raw(ctx, k_scan, "radix_scan", 1, 1, SL_RAW_IO(table_len, 8));
        if (st == SLUICE_OK && values)
            st = sl_set_args(
                ctx, k_scatter, "radix_scatter_pairs", 10,
                SIZES(sizeof(cl_mem), sizeof(cl_mem), sizeof(cl_mem), sizeof(cl_mem), sizeof nn,
                      sizeof chunks, sizeof shift, sizeof(cl_mem), sizeof offset, sizeof nt),
                VALUES(&cur_k, &cur_v, &alt_k, &alt_v, &nn, &chunks, &shift, &table, &offset, &nt));
        else if (st == SLUICE_OK)
            st = sl_set_args(ctx, k_scatter, "radix_scatter_keys", 8,
                             SIZES(sizeof(cl_mem), sizeof(cl_mem), sizeof nn, sizeof chunks,
                                   sizeof shift, sizeof(cl_mem), sizeof offset, sizeof nt),
                             VALUES(&cur_k, &alt_k, &nn, &chunks, &shift, &table, &offset, &nt));
        if (st == SLUICE_OK)
            st = sl_enqueue_raw(ctx, k_scatter,
                                values ? "radix_scatter_pairs" : "radix_scatter_keys", chunks, 1,
                                SL_RAW_IO(nn, values ? 16 : 8)); /* read and written */
        if (st != SLUICE_OK)
            goto done;
        cl_mem t_k = cur_k, t_v = cur_v;
        cur_k = alt_k;
        cur_v = alt_v;
        alt_k = t_k;
        alt_v = t_v;
    }
    st = radix_copy_back(ctx, cur_k, cur_v, keys, values, n);

done:;
    cl_kernel ks[] = {k_all, k_hist, k_scan, k_scatter};
    cl_mem ms[] = {table}; /* the context keeps tmp_keys, tmp_vals */
    radix_release(ks, 4, ms, 1);
    free(host_table);
    return st;
}
