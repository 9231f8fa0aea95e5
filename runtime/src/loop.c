/* Multipass loops driven by device-side counts (Purcell 4.1.2): the host
 * reads the watched counts after each pass, as the occlusion query did, and
 * stops when they are all zero or when the oracle says so. */
#include "internal.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define SL_LOOP_DEFAULT_MAX 100000u

struct sluice_loop {
    sluice_context *ctx;
    sluice_loop_desc desc;
    sluice_pass_stats *passes;
    unsigned pass_count, pass_cap;
    uint32_t *values;
    size_t value_count;
    int counters_fresh; /* read_batched already read the counters */
};

static double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

sluice_status sluice_loop_create(sluice_context *ctx, const sluice_loop_desc *desc,
                                 sluice_loop **out)
{
    sl_clear_error(ctx);
    if (out)
        *out = NULL;
    if (!ctx || !desc || !out || !desc->pass)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_loop_create: NULL context, descriptor, out or pass function");
    if (desc->stream_count && !desc->streams)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_loop_create: stream_count is %zu but streams is NULL",
                       desc->stream_count);
    for (size_t i = 0; i < desc->stream_count; ++i)
        if (!desc->streams[i] || desc->streams[i]->ctx != ctx)
            return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                           "sluice_loop_create: watched stream %zu is NULL or of another context",
                           i);
    if (!desc->oracle && desc->stream_count == 0 && !desc->counters)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_loop_create: a loop without an oracle must watch a stream or a "
                       "counter, or it could never stop");
    sluice_loop *l = calloc(1, sizeof *l);
    if (!l)
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
    l->ctx = ctx;
    l->desc = *desc;
    if (!l->desc.max_passes)
        l->desc.max_passes = SL_LOOP_DEFAULT_MAX;
    l->value_count = desc->stream_count + (desc->counters ? desc->counters->count : 0);
    l->values = calloc(l->value_count ? l->value_count : 1, sizeof *l->values);
    if (!l->values) {
        free(l);
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
    }
    *out = l;
    return SLUICE_OK;
}

void sluice_loop_destroy(sluice_loop *l)
{
    if (!l)
        return;
    free(l->passes);
    free(l->values);
    free(l);
}

/* Most variables one batched read covers. */
#define SL_LOOP_BATCH 256u

/* Reads the lengths of watched streams not known on the host and the
 * counters (with their overflow note) in ONE read of the context's variable
 * pool when they lie within SL_LOOP_BATCH entries of each other (the usual
 * case: they were made together), so a pass costs one round trip to the
 * device instead of one per watched value. */
static sluice_status read_batched(sluice_loop *l)
{
    l->counters_fresh = 0;
    cl_uint lo = UINT32_MAX, hi = 0;
    for (size_t i = 0; i < l->desc.stream_count; ++i) {
        const sluice_stream *s = l->desc.streams[i];
        if (!s->len_known) {
            lo = s->var < lo ? s->var : lo;
            hi = s->var > hi ? s->var : hi;
        }
    }
    const sluice_counters *c = l->desc.counters;
    if (c && c->count) {
        cl_uint note = c->var + (cl_uint)c->count;
        lo = c->var < lo ? c->var : lo;
        hi = note > hi ? note : hi;
    }
    if (lo > hi || hi - lo >= SL_LOOP_BATCH)
        return SLUICE_OK; /* nothing to read, or too far apart: read one by one */
    cl_uint v[SL_LOOP_BATCH];
    sluice_status st = sl_vars_read(l->ctx, lo, hi - lo + 1, v);
    if (st != SLUICE_OK)
        return st;
    for (size_t i = 0; i < l->desc.stream_count; ++i) {
        sluice_stream *s = l->desc.streams[i];
        if (!s->len_known) {
            s->len = v[s->var - lo];
            s->len_known = true;
        }
    }
    if (c && c->count) {
        for (size_t i = 0; i < c->count; ++i)
            l->values[l->desc.stream_count + i] = v[c->var - lo + i] - c->base[i];
        l->counters_fresh = 1;
        return sl_counters_check(l->desc.counters, v[c->var - lo + c->count]);
    }
    return SLUICE_OK;
}

/* Reads the watched values. A watched stream past its capacity, or
 * counters that a kernel reading an overflowed stream counted into, stop the
 * loop with SLUICE_ERROR_OVERFLOW: found in the values read anyway, at no
 * extra cost. */
static sluice_status read_values(sluice_loop *l)
{
    sluice_status batched = read_batched(l);
    if (batched != SLUICE_OK && batched != SLUICE_ERROR_OVERFLOW)
        return batched;
    size_t k = 0;
    for (size_t i = 0; i < l->desc.stream_count; ++i) {
        size_t len;
        sluice_status st = sluice_stream_length(l->desc.streams[i], &len);
        if (st != SLUICE_OK)
            return st; /* a stream's overflow names the kernel that overflowed */
        l->values[k++] = (uint32_t)len;
    }
    if (batched != SLUICE_OK)
        return batched;
    sluice_counters *c = l->desc.counters;
    if (c && !l->counters_fresh) {
        sluice_status st = sluice_counters_read(c, l->values + k);
        if (st != SLUICE_OK)
            return st;
    }
    return SLUICE_OK;
}

/* Puts "<what> <pass>: " before the message of an overflow, so that it says
 * which pass left it. */
static sluice_status name_pass(sluice_context *ctx, sluice_status st, const char *what,
                               unsigned pass)
{
    if (st != SLUICE_ERROR_OVERFLOW)
        return st;
    char msg[sizeof ctx->error];
    memcpy(msg, ctx->error, sizeof msg);
    return sl_fail(ctx, st, "%s %u: %s", what, pass, msg);
}

sluice_status sluice_loop_run(sluice_loop *l)
{
    if (!l)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(l->ctx);
    sluice_context *ctx = l->ctx;
    l->pass_count = 0;
    sluice_status st = name_pass(ctx, read_values(l), "loop, before pass", 0);
    for (unsigned pass = 0; st == SLUICE_OK; ++pass) {
        unsigned choice = 0;
        if (l->desc.oracle) {
            choice = l->desc.oracle(l->desc.user, pass, l->values, l->value_count);
            if (choice == SLUICE_LOOP_STOP)
                break;
        } else {
            int any = 0;
            for (size_t i = 0; i < l->value_count; ++i)
                any |= l->values[i] != 0;
            if (!any)
                break;
        }
        if (pass >= l->desc.max_passes)
            return sl_fail(ctx, SLUICE_ERROR_LIMIT,
                           "loop stopped after its limit of %u passes with work left",
                           l->desc.max_passes);
        if (l->pass_count == l->pass_cap) {
            unsigned cap = l->pass_cap ? l->pass_cap * 2 : 64;
            sluice_pass_stats *p = realloc(l->passes, cap * sizeof *p);
            if (!p)
                return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
            l->passes = p;
            l->pass_cap = cap;
        }
        double t0 = now_seconds();
        /* each pass counts from zero: past the counts just read (nothing
         * was queued since), at no command */
        if (l->desc.reset_counters && l->desc.counters)
            sl_counters_advance(l->desc.counters, l->values + l->desc.stream_count);
        st = l->desc.pass(l->desc.user, pass, choice);
        if (st == SLUICE_OK)
            st = read_values(l);
        sluice_pass_stats *ps = &l->passes[l->pass_count++];
        memset(ps, 0, sizeof *ps);
        ps->choice = choice;
        size_t nv = l->value_count < 16 ? l->value_count : 16;
        memcpy(ps->values, l->values, nv * sizeof *l->values);
        ps->seconds = now_seconds() - t0;
        st = name_pass(ctx, st, "loop pass", pass);
    }
    return st;
}

unsigned sluice_loop_pass_count(const sluice_loop *l)
{
    return l ? l->pass_count : 0;
}

const sluice_pass_stats *sluice_loop_pass(const sluice_loop *l, unsigned index)
{
    return (l && index < l->pass_count) ? &l->passes[index] : NULL;
}
