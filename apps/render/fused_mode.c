/* The `fused` execution mode: one launch of rt_trace_fused over the ray
 * stream takes every ray through the whole grid (Purcell 5.2.2: the MIMD
 * alternative to one pass per step). */
#include "tracer_internal.h"

/* The arguments rt_packet_trace reads, from argument `first` of k on. */
static sluice_status bind_packets(rt_tracer *t, sluice_kernel *k, unsigned first)
{
    sluice_status st = sluice_kernel_set_stream(k, first, t->maxima, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, first + 1, t->grid.cell_start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, first + 2, t->grid.cell_tris, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, first + 3, t->ds->tri_records, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, first + 4, sizeof t->grid_args, &t->grid_args);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, first + 5,
                                      t->list_records ? t->list_records : t->ds->tri_records, 0);
    if (st == SLUICE_OK) /* any stream where the kernel reads no macro cells */
        st = sluice_kernel_set_stream(k, first + 6,
                                      t->macro_cells ? t->macro_cells : t->grid.cell_start, 0);
    return st;
}

sluice_status rt_fused_trace(rt_tracer *t, sluice_stream *rays, size_t n, sluice_stream *hits)
{
    sluice_kernel *k = t->k_fused;
    /* the counters are read and restarted after the launch, not reset
     * before it: one command less a frame (nothing else counts into them in
     * a fused tracer) */
    sluice_status st = sluice_kernel_set_input(k, 0, rays);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, hits, 1);
    if (st == SLUICE_OK)
        st = bind_packets(t, k, 2);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(k);
    uint32_t c[RT_CTR_TRACE_COUNT];
    if (st == SLUICE_OK)
        st = sluice_counters_read_restart(t->counters, c);
    if (st != SLUICE_OK)
        return st;
    (void)n;
    t->stats.voxels += c[RT_CTR_VOXELS];
    t->stats.tests += c[RT_CTR_TESTS];
    t->stats.slices += c[RT_CTR_SLICES];
    t->stats.slices_skipped += c[RT_CTR_SLICES_SKIPPED];
    t->stats.passes += 1;
    return SLUICE_OK;
}

int rt_tracer_packets(const rt_tracer *t)
{
    return t && t->opt.exec == RT_EXEC_FUSED && t->opt.intersector == RT_ISECT_MT;
}

const char *rt_tracer_build_options(const rt_tracer *t)
{
    return t ? t->build_options : "";
}

sluice_status rt_tracer_bind_packets(rt_tracer *t, sluice_kernel *k, unsigned first)
{
    if (!rt_tracer_packets(t) || !k)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    return bind_packets(t, k, first);
}

void rt_tracer_add_traced(rt_tracer *t, uint64_t rays, uint64_t voxels, uint64_t tests,
                          uint64_t slices, uint64_t slices_skipped)
{
    if (!t)
        return;
    t->stats.rays += rays;
    t->stats.voxels += voxels;
    t->stats.tests += tests;
    t->stats.slices += slices;
    t->stats.slices_skipped += slices_skipped;
}
