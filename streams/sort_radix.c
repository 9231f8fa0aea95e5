/* Stable LSD radix sort of uint32 keys with optional uint32 values
 * (kernels/sort_radix.cl). Purcell (6.2.2) sorts photons into grid cells
 * with a bitonic sort because the GPUs of 2004 could not scatter; a device
 * that can scatter does the same job with a radix sort in O(n) work.
 *
 * Design for PoCL on a CPU: a few large contiguous chunks, one work-item per
 * chunk (work-groups of one), so each pass is a serial histogram and a
 * serial, stable scatter per chunk with only a small table scan between. The
 * first launch counts all four digits at once; passes in which every key has
 * the same digit would only copy, so they are skipped. */
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

    cl_uint chunks = ctx->info.compute_units * CHUNKS_PER_UNIT;
    if (chunks < 1)
        chunks = 1;
    if (n / MIN_CHUNK < chunks)
        chunks = (cl_uint)(n / MIN_CHUNK > 0 ? n / MIN_CHUNK : 1);
    const cl_uint table_len = RADIX * chunks; /* one digit-major table */
    const cl_uint nn = (cl_uint)n;

    cl_kernel k_all = NULL, k_hist = NULL, k_scan = NULL, k_scatter = NULL;
    cl_mem tmp_keys = NULL, tmp_vals = NULL, table = NULL;
    cl_uint *host_table = NULL;
    cl_int err = CL_SUCCESS;

    host_table = malloc((size_t)RADIX_PASSES * table_len * sizeof *host_table);
    if (!host_table) {
        st = sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
        goto done;
    }
    tmp_keys = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, n * sizeof(cl_uint), NULL, &err);
    if (tmp_keys && values)
        tmp_vals = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, n * sizeof(cl_uint), NULL, &err);
    if (tmp_keys && (tmp_vals || !values))
        table = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE,
                               (size_t)RADIX_PASSES * table_len * sizeof(cl_uint), NULL, &err);
    if (!table) {
        st = sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY,
                     "sluice_sort_radix: cannot allocate scratch for %zu records (%s)", n,
                     sl_cl_error_string(err));
        goto done;
    }
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
                ctx, k_scatter, "radix_scatter_pairs", 9,
                SIZES(sizeof(cl_mem), sizeof(cl_mem), sizeof(cl_mem), sizeof(cl_mem), sizeof nn,
                      sizeof chunks, sizeof shift, sizeof(cl_mem), sizeof offset),
                VALUES(&cur_k, &cur_v, &alt_k, &alt_v, &nn, &chunks, &shift, &table, &offset));
        else if (st == SLUICE_OK)
            st = sl_set_args(ctx, k_scatter, "radix_scatter_keys", 7,
                             SIZES(sizeof(cl_mem), sizeof(cl_mem), sizeof nn, sizeof chunks,
                                   sizeof shift, sizeof(cl_mem), sizeof offset),
                             VALUES(&cur_k, &alt_k, &nn, &chunks, &shift, &table, &offset));
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
    /* An odd number of passes leaves the result in the scratch buffers. */
    if (cur_k != keys->mem) {
        err = clEnqueueCopyBuffer(ctx->queue, cur_k, keys->mem, 0, 0, n * sizeof(cl_uint), 0, NULL,
                                  NULL);
        if (err == CL_SUCCESS && values)
            err = clEnqueueCopyBuffer(ctx->queue, cur_v, values->mem, 0, 0, n * sizeof(cl_uint), 0,
                                      NULL, NULL);
        if (err != CL_SUCCESS)
            st = sl_cl_fail(ctx, err, "copying the sorted records back");
    }

done:
    /* OpenCL keeps released buffers alive until the queued work is done. */
    if (k_all)
        clReleaseKernel(k_all);
    if (k_hist)
        clReleaseKernel(k_hist);
    if (k_scan)
        clReleaseKernel(k_scan);
    if (k_scatter)
        clReleaseKernel(k_scatter);
    if (tmp_keys)
        clReleaseMemObject(tmp_keys);
    if (tmp_vals)
        clReleaseMemObject(tmp_vals);
    if (table)
        clReleaseMemObject(table);
    free(host_table);
    return st;
}
