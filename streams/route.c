/* Bounded routing (Purcell, thesis 6.2.2, "stencil routing"): every record
 * goes to its bucket in a single pass, and each bucket keeps at most `slots`
 * of them. Purcell builds an approximate photon map this way with the
 * stencil buffer; per-bucket atomic counters do the stencil's job here
 * (kernels/route.cl). Which records of an overfull bucket survive depends on
 * the order in which the work-items reach the counter. */
#include "common.h"
#include "sluice/streams.h"

/* Both forms; `fn` names the caller in messages; `mark`: unused places
 * get 0xffffffff. */
static sluice_status route(sluice_context *ctx, const char *fn, int mark, sluice_stream *keys,
                           sluice_stream *values, uint32_t bucket_count, uint32_t slots,
                           sluice_stream *out, sluice_stream *fill, sluice_stream *overflow)
{
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    sluice_status st = sl_check_u32_stream(ctx, keys, fn, "keys", NULL);
    if (st == SLUICE_OK)
        st = sl_check_u32_stream(ctx, values, fn, "values", NULL);
    if (st == SLUICE_OK)
        st = sl_check_u32_stream(ctx, out, fn, "out", NULL);
    if (st == SLUICE_OK)
        st = sl_check_u32_stream(ctx, fill, fn, "fill", NULL);
    if (st == SLUICE_OK)
        st = sl_check_u32_stream(ctx, overflow, fn, "overflow", NULL);
    if (st != SLUICE_OK)
        return st;
    /* The outputs are written while the inputs are read: no sharing. */
    sluice_stream *all[5] = {keys, values, out, fill, overflow};
    for (int a = 0; a < 5; ++a)
        for (int b = a + 1; b < 5; ++b)
            if (all[a] == all[b] && b >= 2)
                return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                               "%s: an output stream is also another argument", fn);
    size_t total = (size_t)bucket_count * slots;
    if ((uint64_t)bucket_count * slots > 0xfffffff0u || out->capacity < total)
        return sl_fail(ctx, SLUICE_ERROR_OVERFLOW,
                       "%s: out holds %zu records but %u buckets x %u slots are needed", fn,
                       out->capacity, bucket_count, slots);
    if (fill->capacity < bucket_count || overflow->capacity < bucket_count)
        return sl_fail(ctx, SLUICE_ERROR_OVERFLOW, "%s: fill and overflow need %u records each", fn,
                       bucket_count);
    size_t n = 0, nv = 0;
    st = sl_check_u32_stream(ctx, keys, fn, "keys", &n);
    if (st == SLUICE_OK)
        st = sl_check_u32_stream(ctx, values, fn, "values", &nv);
    if (st != SLUICE_OK)
        return st;
    if (nv < n)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: %zu values for %zu keys", fn, nv,
                       n);

    cl_kernel k_scatter = NULL, k_finish = NULL;
    cl_uint nn = (cl_uint)n, none = 0xffffffffu, zero = 0;
    cl_int err = CL_SUCCESS;
    if (total && mark)
        err = clEnqueueFillBuffer(ctx->queue, out->mem, &none, sizeof none, 0,
                                  total * sizeof(cl_uint), 0, NULL, NULL);
    if (err == CL_SUCCESS && bucket_count)
        err = clEnqueueFillBuffer(ctx->queue, fill->mem, &zero, sizeof zero, 0,
                                  (size_t)bucket_count * sizeof(cl_uint), 0, NULL, NULL);
    if (err != CL_SUCCESS)
        return sl_cl_fail(ctx, err, "clearing the routing outputs");
    if (bucket_count) {
        st = sl_embedded_cl_kernel(ctx, "route.cl", "route_scatter", &k_scatter);
        if (st == SLUICE_OK)
            st = sl_embedded_cl_kernel(ctx, "route.cl", "route_finish", &k_finish);
        if (st == SLUICE_OK)
            st = sl_set_args(ctx, k_scatter, "route_scatter", 7,
                             SIZES(sizeof(cl_mem), sizeof(cl_mem), sizeof nn, sizeof bucket_count,
                                   sizeof slots, sizeof(cl_mem), sizeof(cl_mem)),
                             VALUES(&keys->mem, &values->mem, &nn, &bucket_count, &slots,
                                    &fill->mem, &out->mem));
        if (st == SLUICE_OK)
            st = sl_enqueue_raw(ctx, k_scatter, "route_scatter", nn, 0,
                                SL_RAW_IO(nn, 12)); /* key and value read, value written */
        if (st == SLUICE_OK)
            st = sl_set_args(
                ctx, k_finish, "route_finish", 4,
                SIZES(sizeof(cl_mem), sizeof(cl_mem), sizeof bucket_count, sizeof slots),
                VALUES(&fill->mem, &overflow->mem, &bucket_count, &slots));
        if (st == SLUICE_OK)
            st = sl_enqueue_raw(ctx, k_finish, "route_finish", bucket_count, 0,
                                SL_RAW_IO(bucket_count, 8));
    }
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(out, total);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(fill, bucket_count);
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(overflow, bucket_count);
    if (k_scatter)
        clReleaseKernel(k_scatter);
    if (k_finish)
        clReleaseKernel(k_finish);
    return st;
}

sluice_status sluice_route_bounded(sluice_context *ctx, sluice_stream *keys, sluice_stream *values,
                                   uint32_t bucket_count, uint32_t slots, sluice_stream *out,
                                   sluice_stream *fill, sluice_stream *overflow)
{
    return route(ctx, "sluice_route_bounded", 1, keys, values, bucket_count, slots, out, fill,
                 overflow);
}

sluice_status sluice_route_bounded_sparse(sluice_context *ctx, sluice_stream *keys,
                                          sluice_stream *values, uint32_t bucket_count,
                                          uint32_t slots, sluice_stream *out, sluice_stream *fill,
                                          sluice_stream *overflow)
{
    return route(ctx, "sluice_route_bounded_sparse", 0, keys, values, bucket_count, slots, out,
                 fill, overflow);
}
