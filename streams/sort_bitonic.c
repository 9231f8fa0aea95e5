/* Bitonic merge sort of uint32 keys with optional uint32 values, for any
 * length (kernels/sort_bitonic.cl). Purcell (thesis 6.2.2) builds the photon
 * grid by bitonic-sorting photons by cell on the GPU; this is that sort with
 * the first merges of every block, and the last steps of every later merge,
 * run in local memory: log2(2W) * (log2(2W) + 1) / 2 steps in one launch, and
 * one launch per remaining merge instead of one per step. */
#include "common.h"
#include "sluice/streams.h"

#include <string.h>

/* Largest work-group used for the local-memory stages (2x as many keys). */
#define BITONIC_MAX_LOCAL 256u

/* Queues bitonic_local over the blocks of 2w positions that hold records;
 * `io` is what it reads and writes, for the profile. */
static sluice_status run_local(sluice_context *ctx, cl_kernel k, cl_uint n, cl_uint w, cl_uint k_lo,
                               cl_uint k_hi, const sl_raw_io *io)
{
    cl_int err = clSetKernelArg(k, 4, sizeof k_lo, &k_lo);
    if (err == CL_SUCCESS)
        err = clSetKernelArg(k, 5, sizeof k_hi, &k_hi);
    if (err != CL_SUCCESS)
        return sl_cl_fail(ctx, err, "setting the merge sizes of bitonic_local");
    size_t blocks = ((size_t)n + 2u * w - 1u) / (2u * w);
    return sl_enqueue_raw(ctx, k, "bitonic_local", blocks * w, w, io);
}

sluice_status sluice_sort_bitonic(sluice_context *ctx, sluice_stream *keys, sluice_stream *values)
{
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    size_t n = 0, nv = 0;
    sluice_status st = sl_check_u32_stream(ctx, keys, "sluice_sort_bitonic", "keys", &n);
    if (st != SLUICE_OK)
        return st;
    if (values) {
        if (values == keys)
            return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                           "sluice_sort_bitonic: keys and values are the same stream");
        st = sl_check_u32_stream(ctx, values, "sluice_sort_bitonic", "values", &nv);
        if (st != SLUICE_OK)
            return st;
        if (nv < n)
            return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                           "sluice_sort_bitonic: %zu values for %zu keys", nv, n);
    }
    if (n < 2)
        return SLUICE_OK;
    /* The network has P = next power of two >= n positions; uint indices. */
    if (n > ((size_t)1 << 31))
        return sl_fail(ctx, SLUICE_ERROR_LIMIT,
                       "sluice_sort_bitonic: %zu records; at most 2^31 can be sorted", n);
    cl_uint nn = (cl_uint)n, P = 1;
    while (P < nn)
        P <<= 1;

    cl_kernel k_step = NULL, k_local = NULL;
    st = sl_embedded_cl_kernel(ctx, "sort_bitonic.cl", "bitonic_step", &k_step);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "sort_bitonic.cl", "bitonic_local", &k_local);
    if (st != SLUICE_OK)
        goto done;

    /* Work-group size of the local stages: a power of two that the kernel,
     * local memory and the network allow. */
    size_t wg = 0;
    clGetKernelWorkGroupInfo(k_local, ctx->device, CL_KERNEL_WORK_GROUP_SIZE, sizeof wg, &wg, NULL);
    cl_uint w = BITONIC_MAX_LOCAL;
    while (w > 1 && (w > wg || (size_t)w * 4u * sizeof(cl_uint) > ctx->info.local_mem_bytes))
        w >>= 1;
    if (w > P / 2)
        w = P / 2;

    cl_uint has_vals = values ? 1u : 0u;
    cl_mem vmem = values ? values->mem : keys->mem; /* never touched without values */
    st = sl_set_args(ctx, k_step, "bitonic_step", 4,
                     SIZES(sizeof(cl_mem), sizeof(cl_mem), sizeof has_vals, sizeof nn),
                     VALUES(&keys->mem, &vmem, &has_vals, &nn));
    if (st == SLUICE_OK)
        st = sl_set_args(ctx, k_local, "bitonic_local", 4,
                         SIZES(sizeof(cl_mem), sizeof(cl_mem), sizeof has_vals, sizeof nn),
                         VALUES(&keys->mem, &vmem, &has_vals, &nn));
    if (st == SLUICE_OK) {
        cl_int err = clSetKernelArg(k_local, 6, 2u * w * sizeof(cl_uint), NULL);
        if (err == CL_SUCCESS)
            err = clSetKernelArg(k_local, 7, (values ? 2u * w : 1u) * sizeof(cl_uint), NULL);
        if (err != CL_SUCCESS)
            st = sl_cl_fail(ctx, err, "setting the local memory of bitonic_local");
    }
    /* Every launch reads and writes each record: its key, and its value. */
    const sl_raw_io *io = SL_RAW_IO(nn, values ? 16 : 8);
    /* Sort every block of 2w positions in local memory. */
    if (st == SLUICE_OK)
        st = run_local(ctx, k_local, nn, w, 2u, 2u * w, io);
    /* Then each larger merge: its strides >= 2w in global memory, one launch
     * per step, and the rest in local memory. */
    for (cl_uint k = 4u * w; st == SLUICE_OK && k != 0 && k <= P; k <<= 1) {
        for (cl_uint j = k >> 1; st == SLUICE_OK && j >= 2u * w; j >>= 1) {
            cl_int err = clSetKernelArg(k_step, 4, sizeof k, &k);
            if (err == CL_SUCCESS)
                err = clSetKernelArg(k_step, 5, sizeof j, &j);
            st = err == CL_SUCCESS ? sl_enqueue_raw(ctx, k_step, "bitonic_step", P / 2, 0, io)
                                   : sl_cl_fail(ctx, err, "setting the step of bitonic_step");
        }
        if (st == SLUICE_OK)
            st = run_local(ctx, k_local, nn, w, k, k, io);
    }

done:
    if (k_step)
        clReleaseKernel(k_step);
    if (k_local)
        clReleaseKernel(k_local);
    return st;
}
