/* Cell-start index of keys (Purcell, thesis 6.2.2, figure 6.4): after the
 * photons are sorted by grid cell, start[c] is the first photon of cell c and
 * cell c's photons are [start[c], start[c+1]). Purcell finds the starts by a
 * binary search per cell (sluice_cell_index_search); counting the keys of
 * each cell and scanning the counts gives the same index without needing
 * sorted keys (sluice_cell_index_count). Kernels: kernels/cell_index.cl. */
#include "common.h"
#include "sluice/streams.h"

/* Scan blocks per compute unit: a few per core so uneven blocks even out. */
#define SCAN_BLOCKS_PER_UNIT 8u
/* Smallest block worth a work-item of its own. */
#define SCAN_MIN_BLOCK 4096u

/* Common checks: keys and start are uint32 streams, start can hold
 * cell_count + 1 records. Returns the number of keys in *n. */
static sluice_status prepare(sluice_context *ctx, const char *fn, sluice_stream *keys,
                             uint32_t cell_count, sluice_stream *start, size_t *n)
{
    sluice_status st = sl_check_u32_stream(ctx, keys, fn, "keys", NULL);
    if (st == SLUICE_OK)
        st = sl_check_u32_stream(ctx, start, fn, "start", NULL);
    if (st != SLUICE_OK)
        return st;
    if (keys == start)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: keys and start are the same stream",
                       fn);
    if (start->capacity < (size_t)cell_count + 1)
        return sl_fail(ctx, SLUICE_ERROR_OVERFLOW,
                       "%s: start holds %zu records but %zu are needed (cell_count + 1)", fn,
                       start->capacity, (size_t)cell_count + 1);
    return sl_check_u32_stream(ctx, keys, fn, "keys", n);
}

sluice_status sluice_cell_index_search(sluice_context *ctx, sluice_stream *sorted_keys,
                                       uint32_t cell_count, sluice_stream *start)
{
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    size_t n = 0;
    sluice_status st = prepare(ctx, "sluice_cell_index_search", sorted_keys, cell_count, start, &n);
    if (st != SLUICE_OK)
        return st;
    cl_kernel k = NULL;
    cl_uint nn = (cl_uint)n, cells = cell_count + 1u;
    st = sl_embedded_cl_kernel(ctx, "cell_index.cl", "cell_search", &k);
    if (st == SLUICE_OK)
        st = sl_set_args(ctx, k, "cell_search", 4,
                         SIZES(sizeof(cl_mem), sizeof nn, sizeof cells, sizeof(cl_mem)),
                         VALUES(&sorted_keys->mem, &nn, &cells, &start->mem));
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, k, "cell_search", cells, 0, SL_RAW_IO(cells, 4));
    if (k)
        clReleaseKernel(k);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(start, (size_t)cell_count + 1);
    return st;
}

sluice_status sluice_cell_index_count(sluice_context *ctx, sluice_stream *keys, uint32_t cell_count,
                                      sluice_stream *start)
{
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    size_t n = 0;
    sluice_status st = prepare(ctx, "sluice_cell_index_count", keys, cell_count, start, &n);
    if (st != SLUICE_OK)
        return st;
    cl_uint nn = (cl_uint)n, cells = cell_count, len = cell_count + 1u;
    cl_uint blocks = ctx->info.compute_units * SCAN_BLOCKS_PER_UNIT;
    if (len / SCAN_MIN_BLOCK < blocks)
        blocks = len / SCAN_MIN_BLOCK > 0 ? len / SCAN_MIN_BLOCK : 1u;
    cl_kernel k_hist = NULL, k_sums = NULL, k_offsets = NULL, k_apply = NULL;
    cl_mem sums = NULL;
    cl_int err;

    /* Counts in start[0 .. cell_count), and start[cell_count] = 0, so the
     * exclusive scan of all cell_count + 1 entries ends with the number of
     * keys below cell_count: keys >= cell_count come after the last cell. */
    cl_uint zero = 0;
    err = clEnqueueFillBuffer(ctx->queue, start->mem, &zero, sizeof zero, 0,
                              (size_t)len * sizeof(cl_uint), 0, NULL, NULL);
    if (err != CL_SUCCESS) {
        st = sl_cl_fail(ctx, err, "clearing the cell counts");
        goto done;
    }
    sums = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, blocks * sizeof(cl_uint), NULL, &err);
    if (!sums) {
        st = sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "sluice_cell_index_count: scratch: %s",
                     sl_cl_error_string(err));
        goto done;
    }
    st = sl_embedded_cl_kernel(ctx, "cell_index.cl", "cell_hist", &k_hist);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "cell_index.cl", "cell_scan_sums", &k_sums);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "cell_index.cl", "cell_scan_offsets", &k_offsets);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "cell_index.cl", "cell_scan_apply", &k_apply);
    if (st == SLUICE_OK)
        st = sl_set_args(ctx, k_hist, "cell_hist", 4,
                         SIZES(sizeof(cl_mem), sizeof nn, sizeof cells, sizeof(cl_mem)),
                         VALUES(&keys->mem, &nn, &cells, &start->mem));
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, k_hist, "cell_hist", nn, 0, SL_RAW_IO(nn, 4));
    if (st == SLUICE_OK)
        st = sl_set_args(ctx, k_sums, "cell_scan_sums", 4,
                         SIZES(sizeof(cl_mem), sizeof len, sizeof blocks, sizeof(cl_mem)),
                         VALUES(&start->mem, &len, &blocks, &sums));
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, k_sums, "cell_scan_sums", blocks, 1, SL_RAW_IO(len, 4));
    if (st == SLUICE_OK)
        st = sl_set_args(ctx, k_offsets, "cell_scan_offsets", 2,
                         SIZES(sizeof(cl_mem), sizeof blocks), VALUES(&sums, &blocks));
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, k_offsets, "cell_scan_offsets", 1, 1, SL_RAW_IO(blocks, 8));
    if (st == SLUICE_OK)
        st = sl_set_args(ctx, k_apply, "cell_scan_apply", 4,
                         SIZES(sizeof(cl_mem), sizeof len, sizeof blocks, sizeof(cl_mem)),
                         VALUES(&start->mem, &len, &blocks, &sums));
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, k_apply, "cell_scan_apply", blocks, 1, SL_RAW_IO(len, 8));
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(start, len);

done:
    if (k_hist)
        clReleaseKernel(k_hist);
    if (k_sums)
        clReleaseKernel(k_sums);
    if (k_offsets)
        clReleaseKernel(k_offsets);
    if (k_apply)
        clReleaseKernel(k_apply);
    if (sums)
        clReleaseMemObject(sums);
    return st;
}
