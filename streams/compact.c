/* Compaction, split and partition (kernels/compact.cl). These are ordinary
 * stream kernels with conditional outputs, launched through the same
 * sluice_kernel machinery as user kernels: the runtime chunks the input,
 * reserves output room per chunk and keeps input order for ORDERED outputs.
 *
 * Outputs are cleared first (the kernels append to them). An output whose
 * capacity is at least the input's length cannot overflow and the call
 * returns once queued; otherwise it waits for the result and returns
 * SLUICE_ERROR_OVERFLOW if too many records went to that output (its length
 * is then above its capacity, as after any overflowing kernel). An input
 * that overflowed is SLUICE_ERROR_OVERFLOW at once when its length is known
 * on the host; when it is only on the device, the outputs are void and
 * reading them reports the overflow (kernels/sluice.cl). */
#include "internal.h"
#include "sluice/streams.h"

/* Most records the input may hold: its length when the host knows it, else
 * its capacity. */
static size_t input_bound(const sluice_stream *in)
{
    if (!in->len_known)
        return in->capacity;
    return in->len < in->capacity ? in->len : in->capacity;
}

/* Checks that `aux` (flags or buckets: uint32 records, one per input record)
 * covers the input. Reads the input's device-side length only when its
 * capacity alone is not enough to decide. */
static sluice_status check_aux(sluice_context *ctx, const char *fn, const char *what,
                               sluice_stream *in, sluice_stream *aux)
{
    if (aux->ctx != ctx)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: the %s stream belongs to another "
                       "context",
                       fn, what);
    if (aux->record_size != 4)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: %s records must be 4 bytes, not %zu", fn, what, aux->record_size);
    char prefix[64];
    snprintf(prefix, sizeof prefix, "%s: the %s ", fn, what);
    sluice_status st = sl_stream_check_known(aux, prefix);
    if (st != SLUICE_OK)
        return st;
    size_t n = input_bound(in);
    size_t have = aux->len_known ? aux->len : aux->capacity;
    if (have < n && !in->len_known) {
        snprintf(prefix, sizeof prefix, "%s: the input ", fn);
        st = sl_stream_length(in, prefix);
        if (st != SLUICE_OK)
            return st;
        n = input_bound(in);
    }
    if (have < n)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: the %s stream has %zu records but the input has %zu", fn, what, have,
                       n);
    return SLUICE_OK;
}

/* Checks one output stream against the input. */
static sluice_status check_out(sluice_context *ctx, const char *fn, sluice_stream *in,
                               sluice_stream *out, size_t record_size, const char *what)
{
    if (!out)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: NULL %s stream", fn, what);
    if (out->ctx != ctx)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: the %s stream belongs to another context", fn, what);
    if (out == in)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: the %s stream may not be the input stream", fn, what);
    if (out->record_size != record_size)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: %s records are %zu bytes but the input's are %zu", fn, what,
                       out->record_size, record_size);
    return SLUICE_OK;
}

/* Checks the input stream: in this context, records of 4*k bytes, not
 * known to have overflowed. */
static sluice_status check_in(sluice_context *ctx, const char *fn, sluice_stream *in)
{
    if (!in)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: NULL input stream", fn);
    if (in->ctx != ctx)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: the input stream belongs to another context", fn);
    if (in->record_size % 4 != 0)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "%s: records of %zu bytes are not a multiple of 4 bytes", fn,
                       in->record_size);
    char prefix[64];
    snprintf(prefix, sizeof prefix, "%s: the input ", fn);
    return sl_stream_check_known(in, prefix);
}

static sluice_status check_mode(sluice_context *ctx, const char *fn, sluice_output_mode mode)
{
    if (mode != SLUICE_ORDERED && mode != SLUICE_UNORDERED)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: bad output mode %d", fn, (int)mode);
    return SLUICE_OK;
}

/* The kernel suffix for records of `record_size` bytes (see compact.cl). */
static const char *word_suffix(size_t record_size)
{
    switch (record_size) {
    case 4:
        return "w1";
    case 8:
        return "w2";
    case 16:
        return "w4";
    default:
        return "words";
    }
}

/* Creates kernel `prefix_suffix` of the embedded compact.cl. */
static sluice_status make_kernel(sluice_context *ctx, const char *prefix, const char *suffix,
                                 sluice_kernel **out)
{
    sluice_program *p;
    sluice_status st = sl_embedded_program(ctx, "compact.cl", &p);
    if (st != SLUICE_OK)
        return st;
    char name[48];
    snprintf(name, sizeof name, "%s_%s", prefix, suffix);
    return sluice_kernel_create(p, name, out);
}

/* After the launch: when an output could overflow (its capacity is below
 * the input bound), waits for its length and reports an overflow (a void
 * output, from an overflowed input, as the runtime words it). */
static sluice_status check_overflow(sluice_context *ctx, const char *fn, size_t bound,
                                    sluice_stream *const *outs, const char *const *what,
                                    unsigned count)
{
    for (unsigned k = 0; k < count; ++k) {
        if (outs[k]->capacity >= bound)
            continue;
        sluice_status st = sl_stream_length(outs[k], "");
        if (st == SLUICE_ERROR_OVERFLOW && outs[k]->len != SL_LEN_VOID)
            return sl_fail(ctx, SLUICE_ERROR_OVERFLOW,
                           "%s: %s capacity %zu is too small: %zu records went to it", fn, what[k],
                           outs[k]->capacity, outs[k]->len);
        if (st != SLUICE_OK)
            return st;
    }
    return SLUICE_OK;
}

sluice_status sluice_compact(sluice_context *ctx, sluice_stream *in, sluice_stream *flags,
                             sluice_stream *out, sluice_output_mode mode)
{
    static const char fn[] = "sluice_compact";
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    sluice_status st = check_in(ctx, fn, in);
    if (st == SLUICE_OK && !flags)
        st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: NULL flags stream", fn);
    if (st == SLUICE_OK)
        st = check_out(ctx, fn, in, out, in->record_size, "output");
    if (st == SLUICE_OK && out == flags)
        st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                     "%s: the output stream may not be the flags stream", fn);
    if (st == SLUICE_OK)
        st = check_mode(ctx, fn, mode);
    if (st == SLUICE_OK)
        st = check_aux(ctx, fn, "flags", in, flags);
    if (st != SLUICE_OK)
        return st;

    sluice_kernel *k = NULL;
    cl_uint words = (cl_uint)(in->record_size / 4);
    st = make_kernel(ctx, "compact", word_suffix(in->record_size), &k);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(k, 0, in);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, flags, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 2, 0, out, mode);
    if (st == SLUICE_OK && words != 1 && words != 2 && words != 4)
        st = sluice_kernel_set_arg(k, 3, sizeof words, &words);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(out);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(k);
    sluice_kernel_destroy(k);
    if (st == SLUICE_OK) {
        static const char *const what[] = {"output"};
        st = check_overflow(ctx, fn, input_bound(in), &out, what, 1);
    }
    return st;
}

sluice_status sluice_split(sluice_context *ctx, sluice_stream *in, sluice_stream *buckets,
                           sluice_stream *const *outs, unsigned count, sluice_output_mode mode)
{
    static const char fn[] = "sluice_split";
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    sluice_status st = check_in(ctx, fn, in);
    if (st == SLUICE_OK && !buckets)
        st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: NULL buckets stream", fn);
    if (st == SLUICE_OK && !outs)
        st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: NULL output array", fn);
    if (st == SLUICE_OK && (count < 1 || count > SLUICE_MAX_OUTPUTS))
        st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: %u outputs (must be 1 .. %u)", fn,
                     count, SLUICE_MAX_OUTPUTS);
    char names[SLUICE_MAX_OUTPUTS][24];
    const char *what[SLUICE_MAX_OUTPUTS];
    for (unsigned b = 0; st == SLUICE_OK && b < count; ++b) {
        snprintf(names[b], sizeof names[b], "output %u", b);
        what[b] = names[b];
        st = check_out(ctx, fn, in, outs[b], in->record_size, what[b]);
        if (st == SLUICE_OK && outs[b] == buckets)
            st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                         "%s: output %u may not be the buckets stream", fn, b);
        for (unsigned c = 0; st == SLUICE_OK && c < b; ++c)
            if (outs[c] == outs[b])
                st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                             "%s: outputs %u and %u are the same stream", fn, c, b);
    }
    if (st == SLUICE_OK)
        st = check_mode(ctx, fn, mode);
    if (st == SLUICE_OK)
        st = check_aux(ctx, fn, "buckets", in, buckets);
    if (st != SLUICE_OK)
        return st;

    /* Arguments: in, buckets, count, o0 .. o7 [, words]. Unused slots get the
     * buckets stream as a placeholder; the kernel never writes them. */
    sluice_kernel *k = NULL;
    cl_uint words = (cl_uint)(in->record_size / 4), n_out = count;
    st = make_kernel(ctx, "split", word_suffix(in->record_size), &k);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(k, 0, in);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, buckets, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 2, sizeof n_out, &n_out);
    for (unsigned b = 0; st == SLUICE_OK && b < SLUICE_MAX_OUTPUTS; ++b)
        st = b < count ? sluice_kernel_set_output(k, 3 + b, b, outs[b], mode)
                       : sluice_kernel_set_stream(k, 3 + b, buckets, 0);
    if (st == SLUICE_OK && words != 1 && words != 2 && words != 4)
        st = sluice_kernel_set_arg(k, 3 + SLUICE_MAX_OUTPUTS, sizeof words, &words);
    for (unsigned b = 0; st == SLUICE_OK && b < count; ++b)
        st = sluice_stream_clear(outs[b]);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(k);
    sluice_kernel_destroy(k);
    if (st == SLUICE_OK)
        st = check_overflow(ctx, fn, input_bound(in), outs, what, count);
    return st;
}

sluice_status sluice_partition(sluice_context *ctx, sluice_stream *in, sluice_scalar_type type,
                               const void *threshold, sluice_stream *below, sluice_stream *above,
                               sluice_output_mode mode)
{
    static const char fn[] = "sluice_partition";
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    sluice_status st = check_in(ctx, fn, in);
    if (st == SLUICE_OK && in->record_size != 4)
        st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                     "%s: records must be 4-byte scalars, not %zu bytes", fn, in->record_size);
    if (st == SLUICE_OK && type != SLUICE_U32 && type != SLUICE_F32)
        st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: bad scalar type %d", fn, (int)type);
    if (st == SLUICE_OK && !threshold)
        st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: NULL threshold", fn);
    if (st == SLUICE_OK)
        st = check_out(ctx, fn, in, below, 4, "below");
    if (st == SLUICE_OK)
        st = check_out(ctx, fn, in, above, 4, "above");
    if (st == SLUICE_OK && below == above)
        st = sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "%s: below and above are the same stream",
                     fn);
    if (st == SLUICE_OK)
        st = check_mode(ctx, fn, mode);
    if (st != SLUICE_OK)
        return st;

    sluice_kernel *k = NULL;
    st = make_kernel(ctx, "partition", type == SLUICE_U32 ? "u32" : "f32", &k);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(k, 0, in);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 1, 4, threshold);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 2, 0, below, mode);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 3, 1, above, mode);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(below);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(above);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(k);
    sluice_kernel_destroy(k);
    if (st == SLUICE_OK) {
        sluice_stream *outs[2] = {below, above};
        static const char *const what[] = {"below", "above"};
        st = check_overflow(ctx, fn, input_bound(in), outs, what, 2);
    }
    return st;
}
