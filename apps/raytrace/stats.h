/*
 * The ray tracer's statistics, in the terms of Purcell's Fig. 5.2 and Tables
 * 5.2 and 5.4: rays of each kind, v (voxels visited per ray), t (triangle
 * tests per ray), s (shading calculations per ray), P (passes), the largest
 * per-ray traversal and intersection work, the share of live rays each
 * stream pass processes, per-kernel time and launches, rays/s and memory.
 * Printed as a table (stderr) or written as JSON.
 */
#ifndef SLUICE_RT_STATS_H
#define SLUICE_RT_STATS_H

#include "render.h"
#include "tracer.h"

#include <stdio.h>

/** Everything the table and the JSON report. */
typedef struct rt_stats_report {
    const char *scene;
    const char *exec; /* "stream" or "fused" */
    const char *mode; /* "cast", ... */
    const char *intersector;
    unsigned width, height, spp;
    double seconds;    /* wall time of the samples */
    size_t bad_pixels; /* non-finite pixels found when writing the image */
    const rt_trace_stats *trace;
    const rt_render_stats *render;
    const sr_adaptive_stats *sampling;
    const rt_grid_device *grid;
    size_t scene_bytes, tracer_stream_bytes;
    const char *skipped;
    const char *fused_path; /* rt_tracer_fused_path ("" in the stream mode) */
    int interrupted;
} rt_stats_report;

/** Prints the table, with the profiler's per-kernel lines when profiling
 *  is on. */
void rt_stats_print(const rt_stats_report *r, sluice_context *ctx, FILE *out);

/** Writes the same figures as JSON to `path`. SLUICE_ERROR_IO with a message
 *  in `err` when the file cannot be written. */
sluice_status rt_stats_write_json(const rt_stats_report *r, sluice_context *ctx, const char *path,
                                  char *err, size_t err_size);

#endif
