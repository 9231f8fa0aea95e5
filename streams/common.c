/* Helpers shared by the stream algorithms (see common.h). */
#include "common.h"

#include <stdio.h>
#include <string.h>

sluice_status sl_check_u32_stream(sluice_context *ctx, sluice_stream *s, const char *fn,
                                  const char *what, size_t *n)
{
    if (!s || s->ctx != ctx)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: %s is NULL or belongs to another context", fn, what);
    if (s->record_size != 4)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: %s has records of %zu bytes; uint32 records (4 bytes) are needed", fn,
                       what, s->record_size);
    if (!n)
        return SLUICE_OK;
    char prefix[96];
    snprintf(prefix, sizeof prefix, "%s: %s ", fn, what);
    sluice_status st = sl_stream_length(s, prefix); /* an overflowed stream is an error */
    *n = s->len;
    return st;
}

sluice_status sl_read_flagged(sluice_context *ctx, cl_mem buf, size_t at, void *value,
                              sluice_stream *in, const char *fn, const char *what)
{
    uint32_t back[2];
    cl_int err =
        clEnqueueReadBuffer(ctx->queue, buf, CL_TRUE, at * 4, sizeof back, back, 0, NULL, NULL);
    char prefix[96];
    if (err != CL_SUCCESS) {
        snprintf(prefix, sizeof prefix, "%s: reading the %s", fn, what);
        return sl_cl_fail(ctx, err, prefix);
    }
    if (back[1]) {
        snprintf(prefix, sizeof prefix, "%s: the input ", fn);
        return sl_stream_overflowed(in, prefix);
    }
    memcpy(value, back, 4);
    return SLUICE_OK;
}

sluice_status sl_set_args(sluice_context *ctx, cl_kernel k, const char *name, unsigned count,
                          const size_t *sizes, const void *const *values)
{
    for (unsigned i = 0; i < count; ++i) {
        cl_int err = clSetKernelArg(k, i, sizes[i], values[i]);
        if (err != CL_SUCCESS) {
            char what[96];
            snprintf(what, sizeof what, "setting argument %u of %s", i, name);
            return sl_cl_fail(ctx, err, what);
        }
    }
    return SLUICE_OK;
}
