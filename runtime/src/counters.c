/* Counters: named device-side uint32 counts bumped by kernels. */
#include "internal.h"

#include <stdlib.h>
#include <string.h>

sluice_status sluice_counters_create(sluice_context *ctx, size_t count, const char *const *names,
                                     sluice_counters **out)
{
    sl_clear_error(ctx);
    if (out)
        *out = NULL;
    if (!ctx || !out)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_counters_create: NULL context or out");
    if (count == 0 || count > SLUICE_MAX_COUNTERS)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "a counter set holds 1 to %d counters, not %zu", SLUICE_MAX_COUNTERS, count);
    sluice_counters *c = calloc(1, sizeof *c);
    if (!c)
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
    c->ctx = ctx;
    c->count = count;
    c->var = SL_NONE;
    c->names = calloc(count, sizeof *c->names);
    sluice_status st = c->names ? SLUICE_OK : SLUICE_ERROR_OUT_OF_MEMORY;
    for (size_t i = 0; st == SLUICE_OK && i < count; ++i) {
        char def[16];
        snprintf(def, sizeof def, "c%zu", i);
        c->names[i] = sl_strdup(names && names[i] ? names[i] : def);
        if (!c->names[i])
            st = SLUICE_ERROR_OUT_OF_MEMORY;
    }
    if (st != SLUICE_OK) {
        sluice_counters_destroy(c);
        return sl_fail(ctx, st, "out of host memory");
    }
    st = sl_vars_alloc(ctx, count + 1, &c->var); /* + the overflow note */
    if (st != SLUICE_OK) {
        sluice_counters_destroy(c);
        return st;
    }
    *out = c;
    return SLUICE_OK;
}

void sluice_counters_destroy(sluice_counters *c)
{
    if (!c)
        return;
    if (c->var != SL_NONE)
        sl_vars_free(c->ctx, c->var, c->count + 1);
    if (c->names)
        for (size_t i = 0; i < c->count; ++i)
            free(c->names[i]);
    free(c->names);
    free(c);
}

size_t sluice_counters_count(const sluice_counters *c)
{
    return c ? c->count : 0;
}

int sluice_counters_index(const sluice_counters *c, const char *name)
{
    if (!c || !name)
        return -1;
    for (size_t i = 0; i < c->count; ++i)
        if (strcmp(c->names[i], name) == 0)
            return (int)i;
    return -1;
}

sluice_status sluice_counters_reset(sluice_counters *c)
{
    if (!c)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(c->ctx);
    sluice_status st = sl_vars_fill(c->ctx, c->var, c->count + 1, 0);
    if (st == SLUICE_OK)
        memset(c->base, 0, sizeof c->base);
    return st;
}

void sl_counters_advance(sluice_counters *c, const uint32_t *counts)
{
    for (size_t i = 0; i < c->count; ++i)
        c->base[i] += counts[i]; /* modulo 2^32, as the reads subtract */
}

sluice_status sl_counters_check(sluice_counters *c, cl_uint note)
{
    if (!note)
        return SLUICE_OK;
    char what[384];
    sl_describe_overflow(c->ctx, note - 1, what, sizeof what);
    return sl_fail(c->ctx, SLUICE_ERROR_OVERFLOW,
                   "stream overflowed: %s; a kernel counting into these counters read it, so "
                   "the counts are void",
                   what);
}

/* Reads the counts since the last reset or restart; restarts them when
 * `restart`. */
static sluice_status read_counts(sluice_counters *c, uint32_t *values, int restart)
{
    if (!c || !values)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(c->ctx);
    cl_uint v[SLUICE_MAX_COUNTERS + 1];
    sluice_status st = sl_vars_read(c->ctx, c->var, c->count + 1, v);
    if (st != SLUICE_OK)
        return st;
    for (size_t i = 0; i < c->count; ++i)
        values[i] = v[i] - c->base[i]; /* modulo 2^32: a wrapped counter still subtracts */
    if (!restart)
        return sl_counters_check(c, v[c->count]);
    sl_counters_advance(c, values);
    /* the note was the restarted counts': cleared (a command, only then;
     * should it fail, the next read reports the note again) */
    if (v[c->count])
        (void)sl_vars_fill(c->ctx, c->var + (cl_uint)c->count, 1, 0);
    return sl_counters_check(c, v[c->count]);
}

sluice_status sluice_counters_read(sluice_counters *c, uint32_t *values)
{
    return read_counts(c, values, 0);
}

sluice_status sluice_counters_read_restart(sluice_counters *c, uint32_t *values)
{
    return read_counts(c, values, 1);
}
