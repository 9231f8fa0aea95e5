/*
 * The tracer's insides, shared by tracer.c (creation, scene upload),
 * stream_mode.c, fused_mode.c and render.c. Not part of the tracer's API.
 */
#ifndef SLUICE_RT_TRACER_INTERNAL_H
#define SLUICE_RT_TRACER_INTERNAL_H

#include "tracer.h"

/* Counters of the trace kernels (rt_stream.cl, rt_fused.cl). */
enum {
    RT_CTR_VOXELS = 0,
    RT_CTR_TESTS = 1,
    RT_CTR_DONE = 2,
    RT_CTR_SLICES = 3,         /* fused, slice by slice: slices packets crossed */
    RT_CTR_SLICES_SKIPPED = 4, /* of those, crossed through empty macro cells */
    RT_CTR_ENTERED = 5,        /* stream: rays that entered the grid (rt_setup) */
    RT_CTR_TRACE_COUNT = 6
};

struct rt_tracer {
    sluice_context *ctx;
    const sr_scene *scene;
    rt_tracer_options opt;
    rt_grid_device grid;
    unsigned grid_min_dim;            /* the grid's minimum dimension (chosen, or given) */
    size_t grid_cells, grid_occupied; /* voxels, and those with triangles (0, 0: not counted) */
    rt_grid_args grid_args;

    /* the scene on the device: its triangle records are in the layout the
     * intersector reads (SR_TRI_EDGES for Moller-Trumbore) */
    sr_device_scene *ds;
    size_t list_copy_bytes; /* the list-order copy below */

    /* fused mode walking ahead (rt_fused.cl): the list-order copy of the
     * triangle records (NULL when the walk gathers instead) */
    int walks_ahead;
    int slices;                 /* coherent packets slice by slice (RT_FUSED_SLICES) */
    sluice_stream *macro_cells; /* uchar per block of voxels (rt_macro_cells) */
    sluice_stream *voxel_bits;  /* a bit per voxel, set when it holds triangles (rt_voxel_bits) */
    sluice_stream *list_records;
    size_t list_stride; /* floats per plane of list_records */
    char fused_path[192];
    char build_options[384]; /* the trace kernels' build options */

    sluice_program *program;
    sluice_kernel *k_setup, *k_traverse, *k_intersect, *k_route_t, *k_route_i, *k_route_setup,
        *k_fused;
    sluice_counters *counters; /* RT_CTR_* */
    sluice_stream *maxima;     /* uint x2: largest per-ray steps and tests */

    /* stream mode: the traverse and intersect streams of ray ids (ping-pong
     * pairs), the codes the heavy kernels write (a mapped output) and the
     * per-ray walk state (rt_walk, indexed by ray) */
    sluice_stream *trav_in, *trav_out, *isect_in, *isect_out, *codes, *walk;
    size_t state_capacity;
    sluice_loop *loop;
    sluice_stream *watched[2]; /* what the loop watches: trav_in, isect_in */

    /* rt_tracer_trace: host rays in, host hits out */
    sluice_stream *host_rays, *host_hits;

    rt_trace_stats stats;
    char skipped[256];
};

/* The execution modes (stream_mode.c, fused_mode.c). Same contract as
 * rt_tracer_trace_stream; both add to t->stats. */
sluice_status rt_stream_trace(rt_tracer *t, sluice_stream *rays, size_t n, sluice_stream *hits);
sluice_status rt_fused_trace(rt_tracer *t, sluice_stream *rays, size_t n, sluice_stream *hits);

/* Frees the stream mode's loop and streams (stream_mode.c). */
void rt_stream_release(rt_tracer *t);

#endif
