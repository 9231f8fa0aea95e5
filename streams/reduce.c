/* Reductions of scalar streams (kernels/reduce.cl): one work-item per
 * contiguous chunk reduces its records in a plain loop, then one work-item
 * reduces the per-chunk results; the host reads the single value back. With
 * the GPU layout (SLUICE_LAYOUT_INTERLEAVED) a work-group takes each chunk
 * and the per-chunk results, its work-items reading neighbouring records. */
#include "common.h"
#include "sluice/streams.h"

#include <math.h>
#include <string.h>

/* Work-items per work-group of the reduce launch. */
#define REDUCE_LOCAL 8u

/* Records per chunk for an input of at most `bound` records: about
 * sqrt(bound) (at least 1024), so that large inputs give a few thousand
 * chunks to spread over the cores and float sums go through short chains of
 * additions. */
static size_t reduce_chunk(size_t bound)
{
    size_t c = 1024;
    while (c * c < bound)
        c *= 2;
    return c;
}

/* Writes the identity of `op` for `type` to `result`. */
static void identity(sluice_scalar_type type, sluice_reduce_op op, void *result)
{
    if (type == SLUICE_U32) {
        uint32_t v = op == SLUICE_MIN ? UINT32_MAX : 0u;
        memcpy(result, &v, 4);
    } else {
        float v = op == SLUICE_MIN ? INFINITY : op == SLUICE_MAX ? -INFINITY : 0.0f;
        memcpy(result, &v, 4);
    }
}

sluice_status sluice_reduce(sluice_context *ctx, sluice_stream *in, sluice_scalar_type type,
                            sluice_reduce_op op, void *result)
{
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    if (!in || !result)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "sluice_reduce: NULL %s",
                       !in ? "input stream" : "result");
    if (in->ctx != ctx)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_reduce: the stream belongs to another context");
    if (type != SLUICE_U32 && type != SLUICE_F32)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "sluice_reduce: bad scalar type %d",
                       (int)type);
    if (op != SLUICE_SUM && op != SLUICE_MIN && op != SLUICE_MAX)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "sluice_reduce: bad operator %d",
                       (int)op);
    if (in->record_size != 4)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_reduce: records must be 4 bytes, the stream has %zu",
                       in->record_size);

    /* The length: known on the host, or read by the kernels on the device. */
    sluice_status st = sl_stream_check_known(in, "sluice_reduce: the input ");
    if (st != SLUICE_OK)
        return st;
    cl_uint in_var = in->var, limit = (cl_uint)in->capacity, n_fixed;
    size_t bound;
    if (in->len_known) {
        bound = in->len;
        n_fixed = (cl_uint)bound;
    } else {
        bound = in->capacity;
        n_fixed = SL_NONE;
    }
    if (bound == 0) {
        identity(type, op, result);
        return SLUICE_OK;
    }
    size_t chunk = reduce_chunk(bound);
    size_t chunks = (bound + chunk - 1) / chunk;
    /* the GPU layout: a work-group per chunk and for pass 2 */
    size_t group = ctx->layout == SLUICE_LAYOUT_INTERLEAVED ? ctx->group : 1;
    size_t m_parts = group > 1 ? chunks : sl_round_up(chunks, REDUCE_LOCAL);
    size_t global = group > 1 ? chunks * group : m_parts;

    static const char *const ops[] = {"sum", "min", "max"};
    char part_name[32], final_name[32];
    snprintf(part_name, sizeof part_name, "reduce_part_%s_%s", ops[op],
             type == SLUICE_U32 ? "u32" : "f32");
    snprintf(final_name, sizeof final_name, "reduce_final_%s_%s", ops[op],
             type == SLUICE_U32 ? "u32" : "f32");
    cl_kernel part = NULL, final = NULL;
    cl_mem parts = NULL;
    cl_int err = CL_SUCCESS;
    char part_kernel[40]; /* profiled as part_name either way */
    snprintf(part_kernel, sizeof part_kernel, "reduce_part_%s%s_%s", group > 1 ? "wg_" : "",
             ops[op], type == SLUICE_U32 ? "u32" : "f32");
    st = sl_embedded_cl_kernel(ctx, "reduce.cl", part_kernel, &part);
    if (st == SLUICE_OK)
        st = sl_embedded_cl_kernel(ctx, "reduce.cl", final_name, &final);
    if (st == SLUICE_OK) {
        /* The partial results, the result and the overflow flag (reduce.cl). */
        parts = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, (m_parts + 2) * 4, NULL, &err);
        if (!parts)
            st = sl_cl_fail(ctx, err, "sluice_reduce: allocating partial results");
    }
    if (st == SLUICE_OK) {
        cl_uint c = (cl_uint)chunk, m = (cl_uint)m_parts;
        sl_set_arg(part, 0, sizeof(cl_mem), &ctx->vars, &err);
        sl_set_arg(part, 1, sizeof(cl_uint), &in_var, &err);
        sl_set_arg(part, 2, sizeof(cl_uint), &n_fixed, &err);
        sl_set_arg(part, 3, sizeof(cl_uint), &limit, &err);
        sl_set_arg(part, 4, sizeof(cl_uint), &c, &err);
        sl_set_arg(part, 5, sizeof(cl_mem), &in->mem, &err);
        sl_set_arg(part, 6, sizeof(cl_mem), &parts, &err);
        if (group > 1)
            sl_set_arg(part, 7, group * 4, NULL, &err);
        sl_set_arg(final, 0, sizeof(cl_mem), &parts, &err);
        sl_set_arg(final, 1, sizeof(cl_uint), &m, &err);
        sl_set_arg(final, 2, group * 4, NULL, &err);
        if (err != CL_SUCCESS)
            st = sl_cl_fail(ctx, err, "sluice_reduce: setting kernel arguments");
    }
    const sl_raw_io io_part = {n_fixed, in_var, limit, 4}; /* for the profile */
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, part, part_name, global, group > 1 ? group : REDUCE_LOCAL,
                            &io_part);
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, final, final_name, group, group, SL_RAW_IO(m_parts, 4));
    if (st == SLUICE_OK)
        st = sl_read_flagged(ctx, parts, m_parts, result, in, "sluice_reduce", "result");
    if (parts)
        clReleaseMemObject(parts);
    if (part)
        clReleaseKernel(part);
    if (final)
        clReleaseKernel(final);
    return st;
}
