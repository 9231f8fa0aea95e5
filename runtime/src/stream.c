/* Streams: device buffers of fixed-size records with a device-side length. */
#include "internal.h"

#include <stdio.h>
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
    sl_clear_error(ctx);
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
        st = sl_vars_alloc(ctx, 2, &s->var);
    if (st != SLUICE_OK) {
        sluice_stream_destroy(s);
        return st;
    }
    s->len_known = true;
    s->len = 0;
    s->next_live = ctx->streams;
    ctx->streams = s;
    *out = s;
    return SLUICE_OK;
}

void sluice_stream_destroy(sluice_stream *s)
{
    if (!s)
        return;
    for (sluice_stream **p = &s->ctx->streams; *p; p = &(*p)->next_live) {
        if (*p == s) {
            *p = s->next_live;
            break;
        }
    }
    if (s->mem)
        clReleaseMemObject(s->mem);
    if (s->var != SL_NONE)
        sl_vars_free(s->ctx, s->var, 2);
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

void sl_stream_written(sluice_stream *s, sl_writer_kind kind, unsigned index, const char *name)
{
    s->writer_kind = kind;
    s->writer_index = index;
    size_t n = strlen(name); /* every launch: no formatting here */
    n = n < sizeof s->writer ? n : sizeof s->writer - 1;
    memcpy(s->writer, name, n);
    s->writer[n] = '\0';
}

/* Names what last wrote the length of `s` ("output slot 1 of kernel k"). */
static void describe_writer(const sluice_stream *s, char *buf, size_t size)
{
    switch (s->writer_kind) {
    case SL_WRITER_OUTPUT:
        snprintf(buf, size, "output slot %u of kernel %s", s->writer_index, s->writer);
        break;
    case SL_WRITER_MAPPED:
        snprintf(buf, size, "the mapped output (argument %u) of kernel %s", s->writer_index,
                 s->writer);
        break;
    case SL_WRITER_ALGORITHM:
        snprintf(buf, size, "the output of %s", s->writer);
        break;
    default:
        snprintf(buf, size, "a stream");
        break;
    }
}

void sl_describe_overflow(sluice_context *ctx, cl_uint var, char *buf, size_t size)
{
    sluice_stream *o = ctx->streams;
    while (o && o->var != var)
        o = o->next_live;
    if (!o) {
        snprintf(buf, size, "a stream that has since been destroyed had overflowed");
        return;
    }
    char who[128];
    describe_writer(o, who, sizeof who);
    cl_uint n = (cl_uint)(o->len_known ? o->len : 0);
    if (!o->len_known && sl_vars_read(ctx, var, 1, &n) != SLUICE_OK)
        n = 0;
    if (n > o->capacity && n != SL_LEN_VOID)
        snprintf(buf, size, "%u records were emitted into %s, a stream of capacity %zu", n, who,
                 o->capacity);
    else
        snprintf(buf, size,
                 "more records were emitted into %s than its capacity of %zu (its length has "
                 "been reset since)",
                 who, o->capacity);
}

/* Fails with SLUICE_ERROR_OVERFLOW for `s`, whose length is known and past
 * its capacity, naming the kernel and output and the counts. */
static sluice_status overflow(sluice_stream *s, const char *prefix)
{
    char what[640];
    if (s->len != SL_LEN_VOID) {
        char who[128];
        describe_writer(s, who, sizeof who);
        snprintf(what, sizeof what, "%zu records were emitted into %s, a stream of capacity %zu",
                 s->len, who, s->capacity);
    } else {
        /* Void: written by a launch whose input had overflowed. The second
         * variable says which stream overflowed. */
        cl_uint origin = SL_NONE;
        char first[384], who[128];
        if (sl_vars_read(s->ctx, s->var + 1, 1, &origin) == SLUICE_OK)
            sl_describe_overflow(s->ctx, origin, first, sizeof first);
        else
            snprintf(first, sizeof first, "an input stream had overflowed");
        describe_writer(s, who, sizeof who);
        snprintf(what, sizeof what, "%s; %s, written from it, is void", first, who);
    }
    return sl_fail(s->ctx, SLUICE_ERROR_OVERFLOW, "%sstream overflowed: %s", prefix, what);
}

sluice_status sl_stream_check_known(sluice_stream *s, const char *prefix)
{
    return s->len_known && s->len > s->capacity ? overflow(s, prefix) : SLUICE_OK;
}

/* Makes the length of `s` known on the host, reading it when it is only on
 * the device; s->len may then be past the capacity. */
static sluice_status read_length(sluice_stream *s)
{
    if (!s->len_known) {
        cl_uint v;
        sluice_status st = sl_vars_read(s->ctx, s->var, 1, &v);
        if (st != SLUICE_OK)
            return st;
        s->len = v;
        s->len_known = true;
    }
    return SLUICE_OK;
}

sluice_status sl_stream_length(sluice_stream *s, const char *prefix)
{
    sluice_status st = read_length(s);
    return st == SLUICE_OK ? sl_stream_check_known(s, prefix) : st;
}

sluice_status sl_stream_overflowed(sluice_stream *s, const char *prefix)
{
    s->len_known = false;
    sluice_status st = sl_stream_length(s, prefix);
    return st == SLUICE_OK ? sl_fail(s->ctx, SLUICE_ERROR_OVERFLOW,
                                     "%sstream overflowed before it was read", prefix)
                           : st;
}

sluice_status sluice_stream_length(sluice_stream *s, size_t *length)
{
    if (!s || !length)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(s->ctx);
    sluice_status st = sl_stream_length(s, "");
    if (st == SLUICE_OK || st == SLUICE_ERROR_OVERFLOW)
        *length = s->len == SL_LEN_VOID ? 0 : s->len;
    return st;
}

sluice_status sluice_stream_set_length(sluice_stream *s, size_t length)
{
    if (!s)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(s->ctx);
    if (length > s->capacity)
        return sl_fail(s->ctx, SLUICE_ERROR_OVERFLOW,
                       "length %zu exceeds the stream's capacity of %zu records", length,
                       s->capacity);
    /* A length known on the host is the device's too (every command that
     * may change it marks it unknown when queued): a launch that maps an
     * output of the length it had queues no command for it. */
    if (s->len_known && s->len == length)
        return SLUICE_OK;
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
    sl_clear_error(s ? s->ctx : NULL);
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

sluice_status sluice_stream_fill(sluice_stream *s, const void *record, size_t count)
{
    sl_clear_error(s ? s->ctx : NULL);
    if (!s || !record)
        return s ? sl_fail(s->ctx, SLUICE_ERROR_INVALID_ARGUMENT, "sluice_stream_fill: NULL record")
                 : SLUICE_ERROR_INVALID_ARGUMENT;
    if (count > s->capacity)
        return sl_fail(s->ctx, SLUICE_ERROR_OVERFLOW,
                       "filling %zu records into a stream of capacity %zu", count, s->capacity);
    size_t rs = s->record_size;
    cl_command_queue q = s->ctx->queue;
    cl_int err = CL_SUCCESS;
    if (count && rs <= 128 && (rs & (rs - 1)) == 0) {
        /* OpenCL's fill takes patterns of 1, 2, 4, ... 128 bytes */
        err = clEnqueueFillBuffer(q, s->mem, record, rs, 0, count * rs, 0, NULL, NULL);
    } else if (count) {
        /* any other record size: one record written, then copied onto the
         * next records in doubling blocks (log2(count) copies, no host
         * buffer of the stream's size) */
        err = clEnqueueWriteBuffer(q, s->mem, CL_TRUE, 0, rs, record, 0, NULL, NULL);
        for (size_t done = 1; err == CL_SUCCESS && done < count;) {
            size_t n = count - done < done ? count - done : done;
            err = clEnqueueCopyBuffer(q, s->mem, s->mem, 0, done * rs, n * rs, 0, NULL, NULL);
            done += n;
        }
    }
    if (err != CL_SUCCESS)
        return sl_cl_fail(s->ctx, err, "filling a stream");
    return sluice_stream_set_length(s, count);
}

sluice_status sluice_stream_download(sluice_stream *s, void *records, size_t max, size_t *count)
{
    if (!s || (max && !records))
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(s->ctx);
    /* An overflowed stream still gives the records it holds (none when void). */
    sluice_status st = sl_stream_length(s, "");
    if (st != SLUICE_OK && st != SLUICE_ERROR_OVERFLOW)
        return st;
    size_t n = s->len == SL_LEN_VOID ? 0 : s->len < s->capacity ? s->len : s->capacity;
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
    return st;
}

sluice_status sluice_stream_grow(sluice_stream *s, size_t capacity)
{
    if (!s)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(s->ctx);
    if (capacity <= s->capacity)
        return SLUICE_OK;
    cl_mem m;
    sluice_status st = alloc_records(s->ctx, s->record_size, capacity, &m);
    if (st != SLUICE_OK)
        return st;
    /* An overflowed stream holds only part of what was emitted into it: it
     * is grown empty, to be filled again. */
    st = read_length(s);
    size_t len = s->len > s->capacity ? 0 : s->len;
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
    sl_clear_error(a->ctx);
    if (a->record_size != b->record_size)
        return sl_fail(a->ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "cannot swap streams with records of %zu and %zu bytes", a->record_size,
                       b->record_size);
    sluice_stream *link_a = a->next_live, *link_b = b->next_live;
    sluice_stream t = *a;
    *a = *b;
    *b = t;
    a->next_live = link_a;
    b->next_live = link_b;
    return SLUICE_OK;
}

void *sluice_stream_cl_mem(sluice_stream *s)
{
    return s ? (void *)s->mem : NULL;
}
