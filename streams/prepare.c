/* sluice_streams_prepare: the algorithms' kernels built ahead of their first
 * use. */
#include "sluice/streams.h"

#include "internal.h"

/* Each algorithm's kernel source (as embedded; kernels/). */
static const struct {
    unsigned bit;
    const char *source;
} sources[] = {
    {SLUICE_ALG_SCAN, "scan.cl"},
    {SLUICE_ALG_REDUCE, "reduce.cl"},
    {SLUICE_ALG_COMPACT, "compact.cl"},
    {SLUICE_ALG_SORT_BITONIC, "sort_bitonic.cl"},
    {SLUICE_ALG_SORT_RADIX, "sort_radix.cl"},
    {SLUICE_ALG_CELL_INDEX, "cell_index.cl"},
    {SLUICE_ALG_ROUTE, "route.cl"},
};

sluice_status sluice_streams_prepare(sluice_context *ctx, unsigned algorithms)
{
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    if (algorithms & ~(unsigned)SLUICE_ALG_ALL)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_streams_prepare: unknown algorithm bits %#x",
                       algorithms & ~(unsigned)SLUICE_ALG_ALL);
    sluice_status st = SLUICE_OK;
    for (size_t i = 0; st == SLUICE_OK && i < sizeof sources / sizeof *sources; ++i) {
        sluice_program *p;
        if (algorithms & sources[i].bit)
            st = sl_embedded_program(ctx, sources[i].source, &p);
    }
    /* compaction, split and partition write ordered outputs too */
    if (st == SLUICE_OK && (algorithms & SLUICE_ALG_COMPACT))
        st = sl_ordered_ready(ctx);
    return st;
}
