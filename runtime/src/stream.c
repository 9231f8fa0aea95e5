/* Streams: device buffers of fixed-size records with a device-side length. */
#include "internal.h"

#include <stdlib.h>
#include <string.h>

/* Stream lengths are uint32 on the device. */
#define SL_MAX_RECORDS 0xfffffff0u

static sluice_status alloc_records(sluice_context *ctx, size_t record_size, size_t capacity,
                                   cl_mem *out)
{
    if (capacity > SL_MAX_RECORDS)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "stream capacity %zu exceeds the limit of %u records", capacity,
                       SL_MAX_RECORDS);
    size_t bytes = (capacity + 1) * record_size;
    if (bytes / record_size != capacity + 1 || bytes > ctx->info.max_alloc_bytes)
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY,
                       "a stream of %zu records of %zu bytes needs %zu bytes; the device allows "
                       "at most %llu in one buffer",
                       capacity, record_size, bytes, (unsigned long long)ctx->info.max_alloc_bytes);
    cl_int err;
    *out = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, bytes, NULL, &err);
    if (!*out)
        return sl_cl_fail(ctx, err, "allocating a stream");
    return SLUICE_OK;
}

sluice_status sluice_stream_create(sluice_context *ctx, size_t record_size, size_t capacity,
                                   sluice_stream **out)
{
    if (out)
        *out = NULL;
    if (!ctx || !out || record_size == 0)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_stream_create: NULL context or out, or record size 0");
    sluice_stream *s = calloc(1, sizeof *s);
    if (!s)
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
    s->ctx = ctx;
    s->record_size = record_size;
    s->capacity = capacity;
    s->var = SL_NONE;
    sluice_status st = alloc_records(ctx, record_size, capacity, &s->mem);
    if (st == SLUICE_OK)
        st = sl_vars_alloc(ctx, 1, &s->var);
    if (st != SLUICE_OK) {
        sluice_stream_destroy(s);
        return st;
    }
    s->len_known = true;
    s->len = 0;
    *out = s;
    return SLUICE_OK;
}

void sluice_stream_destroy(sluice_stream *s)
{
    if (!s)
        return;
    if (s->mem)
        clReleaseMemObject(s->mem);
    sl_vars_free(s->ctx, s->var, 1);
    free(s);
}

size_t sluice_stream_record_size(const sluice_stream *s)
{
    return s ? s->record_size : 0;
}

size_t sluice_stream_capacity(const sluice_stream *s)
{
    return s ? s->capacity : 0;
}

sluice_status sluice_stream_length(sluice_stream *s, size_t *length)
{
    if (!s || !length)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (!s->len_known) {
        cl_uint v;
        sluice_status st = sl_vars_read(s->ctx, s->var, 1, &v);
        if (st != SLUICE_OK)
            return st;
        s->len = v;
        s->len_known = true;
    }
    *length = s->len;
    return SLUICE_OK;
}

sluice_status sluice_stream_set_length(sluice_stream *s, size_t length)
{
    if (!s)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (length > s->capacity)
        return sl_fail(s->ctx, SLUICE_ERROR_OVERFLOW,
                       "length %zu exceeds the stream's capacity of %zu records", length,
                       s->capacity);
    sluice_status st = sl_vars_fill(s->ctx, s->var, 1, (cl_uint)length);
    if (st == SLUICE_OK) {
        s->len = length;
        s->len_known = true;
    }
    return st;
}

sluice_status sluice_stream_clear(sluice_stream *s)
{
    return sluice_stream_set_length(s, 0);
}

sluice_status sluice_stream_upload(sluice_stream *s, const void *records, size_t count)
{
    if (!s || (count && !records))
        return s ? sl_fail(s->ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                           "sluice_stream_upload: NULL records")
                 : SLUICE_ERROR_INVALID_ARGUMENT;
    if (count > s->capacity)
        return sl_fail(s->ctx, SLUICE_ERROR_OVERFLOW,
                       "uploading %zu records into a stream of capacity %zu", count, s->capacity);
    if (count) {
        cl_int err = clEnqueueWriteBuffer(s->ctx->queue, s->mem, CL_TRUE, 0, count * s->record_size,
                                          records, 0, NULL, NULL);
        if (err != CL_SUCCESS)
            return sl_cl_fail(s->ctx, err, "uploading a stream");
    }
    return sluice_stream_set_length(s, count);
}

sluice_status sluice_stream_download(sluice_stream *s, void *records, size_t max, size_t *count)
{
    if (!s || (max && !records))
        return SLUICE_ERROR_INVALID_ARGUMENT;
    size_t len;
    sluice_status st = sluice_stream_length(s, &len);
    if (st != SLUICE_OK)
        return st;
    size_t n = len < s->capacity ? len : s->capacity;
    if (n > max)
        n = max;
    if (n) {
        cl_int err = clEnqueueReadBuffer(s->ctx->queue, s->mem, CL_TRUE, 0, n * s->record_size,
                                         records, 0, NULL, NULL);
        if (err != CL_SUCCESS)
            return sl_cl_fail(s->ctx, err, "downloading a stream");
    }
    if (count)
        *count = n;
    if (len > s->capacity)
        return sl_fail(s->ctx, SLUICE_ERROR_OVERFLOW,
                       "stream overflowed: %zu records were emitted into a capacity of %zu", len,
                       s->capacity);
    return SLUICE_OK;
}

sluice_status sluice_stream_grow(sluice_stream *s, size_t capacity)
{
    if (!s)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (capacity <= s->capacity)
        return SLUICE_OK;
    cl_mem m;
    sluice_status st = alloc_records(s->ctx, s->record_size, capacity, &m);
    if (st != SLUICE_OK)
        return st;
    size_t len;
    st = sluice_stream_length(s, &len);
    if (st == SLUICE_OK && len > s->capacity)
        len = s->capacity;
    if (st == SLUICE_OK && len) {
        cl_int err = clEnqueueCopyBuffer(s->ctx->queue, s->mem, m, 0, 0, len * s->record_size, 0,
                                         NULL, NULL);
        if (err != CL_SUCCESS)
            st = sl_cl_fail(s->ctx, err, "copying a stream while growing it");
    }
    if (st != SLUICE_OK) {
        clReleaseMemObject(m);
        return st;
    }
    clReleaseMemObject(s->mem);
    s->mem = m;
    s->capacity = capacity;
    return sluice_stream_set_length(s, len);
}

sluice_status sluice_stream_swap(sluice_stream *a, sluice_stream *b)
{
    if (!a || !b || a->ctx != b->ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (a->record_size != b->record_size)
        return sl_fail(a->ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "cannot swap streams with records of %zu and %zu bytes", a->record_size,
                       b->record_size);
    sluice_stream t = *a;
    *a = *b;
    *b = t;
    return SLUICE_OK;
}

void *sluice_stream_cl_mem(sluice_stream *s)
{
    return s ? (void *)s->mem : NULL;
}
