/* Prefix sums of scalar streams: reduce-then-scan over contiguous chunks
 * (kernels/scan.cl). Each work-item owns one chunk of records and walks it in
 * a plain loop, which is what runs fast on a CPU device; the chunk sums are
 * scanned by a single work-item in between. With the GPU layout
 * (SLUICE_LAYOUT_INTERLEAVED) a work-group owns each chunk and its
 * work-items read neighbouring records, and a work-group scans the sums. */
#include "common.h"
#include "sluice/streams.h"

#include <string.h>

/* Work-items per work-group of the scan launches. */
#define SCAN_LOCAL 8u
/* Vectors of 4 records per work-item in a round of the GPU layout's pass 3
 * (SCAN_Q_ in kernels/scan.cl): its local memory holds one sum per vector. */
#define SCAN_Q 4u

/* Records per chunk for an input of at most `bound` records: about
 * sqrt(bound) records (at least 1024, a multiple of 64), so that there are a
 * few thousand chunks for large inputs (both cores busy, a small pass 2) and
 * float sums go through short chains of additions (chunk + chunk count). */
static size_t scan_chunk(size_t bound)
{
    size_t c = 1024;
    while (c * c < bound)
        c *= 2;
    return c;
}

/* Everything one scan or reduce call needs about its input: the length (known
 * on the host, or only on the device) and the chunking derived from it. */
typedef struct scan_input {
    cl_uint n_fixed; /* length, or SL_NONE when it is only on the device */
    cl_uint in_var;
    cl_uint limit; /* capacity: clamps a device-side length */
    size_t bound;  /* most records the input may have */
    size_t chunk, global;
    /* the GPU layout: one work-group of `group` work-items per chunk, and
     * `chunks` chunk sums (else group 1, chunks = global) */
    size_t group, chunks;
} scan_input;

static void scan_input_init(sluice_stream *in, scan_input *si)
{
    sluice_context *ctx = in->ctx;
    si->in_var = in->var;
    si->limit = (cl_uint)in->capacity;
    if (in->len_known) {
        si->bound = in->len; /* not past the capacity: checked first */
        si->n_fixed = (cl_uint)si->bound;
    } else {
        si->bound = in->capacity;
        si->n_fixed = SL_NONE;
    }
    si->chunk = scan_chunk(si->bound);
    size_t chunks = (si->bound + si->chunk - 1) / si->chunk;
    /* groups of one (a device that allows no more) take the per-work-item kernels */
    if (ctx->layout == SLUICE_LAYOUT_INTERLEAVED && ctx->group > 1) {
        si->group = ctx->group;
        si->chunks = chunks ? chunks : 1;
        si->global = si->chunks * si->group;
    } else {
        si->group = 1;
        si->global = sl_round_up(chunks ? chunks : 1, SCAN_LOCAL);
        si->chunks = si->global;
    }
}

sluice_status sluice_scan(sluice_context *ctx, sluice_stream *in, sluice_stream *out,
                          sluice_scalar_type type, int inclusive, void *total)
{
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    if (!in || !out)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "sluice_scan: NULL %s stream",
                       !in ? "input" : "output");
    if (in->ctx != ctx || out->ctx != ctx)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_scan: a stream belongs to another context");
    if (in == out)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_scan: the output may not be the input stream");
    if (type != SLUICE_U32 && type != SLUICE_F32)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "sluice_scan: bad scalar type %d",
                       (int)type);
    if (in->record_size != 4 || out->record_size != 4)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_scan: records must be 4 bytes (input has %zu, output %zu)",
                       in->record_size, out->record_size);

    static const char in_prefix[] = "sluice_scan: the input ";
    sluice_status st0 = sl_stream_check_known(in, in_prefix);
    if (st0 != SLUICE_OK)
        return st0;
    scan_input si;
    scan_input_init(in, &si);
    if (out->capacity < si.bound) {
        /* The input may still fit once its device-side length is known. */
        sluice_status st = sl_stream_length(in, in_prefix);
        if (st != SLUICE_OK)
            return st;
        scan_input_init(in, &si);
        if (out->capacity < si.bound)
            return sl_fail(ctx, SLUICE_ERROR_OVERFLOW,
                           "sluice_scan: output capacity %zu is too small for the %zu input "
                           "records",
                           out->capacity, si.bound);
    }

    if (si.n_fixed == 0) { /* empty input: nothing to launch */
        sluice_status st = sluice_stream_set_length(out, 0);
        if (st == SLUICE_OK && total)
            memset(total, 0, 4);
        return st;
    }

    const char *sfx = type == SLUICE_U32 ? "u32" : "f32";
    char names[3][32];
    snprintf(names[0], sizeof names[0], "scan_sums_%s", sfx);
    snprintf(names[1], sizeof names[1], "scan_chunks_%s", sfx);
    snprintf(names[2], sizeof names[2], "scan_apply_%s", sfx);
    cl_kernel k[3] = {NULL, NULL, NULL};
    cl_mem sums = NULL;
    sluice_status st = SLUICE_OK;
    for (int i = 0; i < 3 && st == SLUICE_OK; ++i) {
        /* the GPU layout's passes 1 and 3 (profiled under the same names) */
        char kname[40];
        snprintf(kname, sizeof kname, "%.*s%s%s", (int)(strlen(names[i]) - 3), names[i],
                 si.group > 1 && i != 1 ? "wg_" : "", sfx);
        st = sl_embedded_cl_kernel(ctx, "scan.cl", kname, &k[i]);
    }
    cl_int err = CL_SUCCESS;
    if (st == SLUICE_OK) {
        /* The chunk sums, the total and the overflow flag (scan.cl). */
        sums = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, (si.chunks + 2) * 4, NULL, &err);
        if (!sums)
            st = sl_cl_fail(ctx, err, "sluice_scan: allocating chunk sums");
    }
    if (st == SLUICE_OK) {
        cl_uint chunk = (cl_uint)si.chunk, m = (cl_uint)si.chunks, incl = inclusive ? 1u : 0u;
        size_t part = (si.group + 1) * 4; /* local memory of each pass */
        cl_uint out_var = out->var;
        /* Pass 1. */
        sl_set_arg(k[0], 0, sizeof(cl_mem), &ctx->vars, &err);
        sl_set_arg(k[0], 1, sizeof(cl_uint), &si.in_var, &err);
        sl_set_arg(k[0], 2, sizeof(cl_uint), &si.n_fixed, &err);
        sl_set_arg(k[0], 3, sizeof(cl_uint), &si.limit, &err);
        sl_set_arg(k[0], 4, sizeof(cl_uint), &chunk, &err);
        sl_set_arg(k[0], 5, sizeof(cl_mem), &in->mem, &err);
        sl_set_arg(k[0], 6, sizeof(cl_mem), &sums, &err);
        if (si.group > 1)
            sl_set_arg(k[0], 7, part, NULL, &err);
        /* Pass 2. */
        sl_set_arg(k[1], 0, sizeof(cl_mem), &ctx->vars, &err);
        sl_set_arg(k[1], 1, sizeof(cl_uint), &si.in_var, &err);
        sl_set_arg(k[1], 2, sizeof(cl_uint), &si.n_fixed, &err);
        sl_set_arg(k[1], 3, sizeof(cl_uint), &si.limit, &err);
        sl_set_arg(k[1], 4, sizeof(cl_uint), &out_var, &err);
        sl_set_arg(k[1], 5, sizeof(cl_mem), &sums, &err);
        sl_set_arg(k[1], 6, sizeof(cl_uint), &m, &err);
        sl_set_arg(k[1], 7, part, NULL, &err);
        /* Pass 3. */
        sl_set_arg(k[2], 0, sizeof(cl_mem), &ctx->vars, &err);
        sl_set_arg(k[2], 1, sizeof(cl_uint), &si.in_var, &err);
        sl_set_arg(k[2], 2, sizeof(cl_uint), &si.n_fixed, &err);
        sl_set_arg(k[2], 3, sizeof(cl_uint), &si.limit, &err);
        sl_set_arg(k[2], 4, sizeof(cl_uint), &chunk, &err);
        sl_set_arg(k[2], 5, sizeof(cl_mem), &in->mem, &err);
        sl_set_arg(k[2], 6, sizeof(cl_mem), &out->mem, &err);
        sl_set_arg(k[2], 7, sizeof(cl_mem), &sums, &err);
        sl_set_arg(k[2], 8, sizeof(cl_uint), &incl, &err);
        if (si.group > 1)
            sl_set_arg(k[2], 9, SCAN_Q * si.group * 4, NULL, &err);
        if (err != CL_SUCCESS)
            st = sl_cl_fail(ctx, err, "sluice_scan: setting kernel arguments");
    }
    /* For the profile: pass 1 reads the records, pass 2 reads and writes the
     * chunk sums, pass 3 reads and writes the records. */
    const sl_raw_io io_sums = {si.n_fixed, si.in_var, si.limit, 4};
    const sl_raw_io io_apply = {si.n_fixed, si.in_var, si.limit, 8};
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, k[0], names[0], si.global, si.group > 1 ? si.group : SCAN_LOCAL,
                            &io_sums);
    if (st == SLUICE_OK) {
        st = sl_enqueue_raw(ctx, k[1], names[1], si.group, si.group, SL_RAW_IO(si.chunks, 8));
        /* Pass 2 writes the output's length on the device. */
        out->len_known = si.n_fixed != SL_NONE;
        out->len = si.n_fixed != SL_NONE ? si.n_fixed : 0;
        sl_stream_written(out, SL_WRITER_ALGORITHM, 0, "sluice_scan");
    }
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, k[2], names[2], si.global, si.group > 1 ? si.group : SCAN_LOCAL,
                            &io_apply);
    if (st == SLUICE_OK && total)
        st = sl_read_flagged(ctx, sums, si.chunks, total, in, "sluice_scan", "total");
    if (sums)
        clReleaseMemObject(sums);
    for (int i = 0; i < 3; ++i)
        if (k[i])
            clReleaseKernel(k[i]);
    return st;
}
