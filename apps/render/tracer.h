/*
 * The ray tracer's device half: a scene uploaded to the device, its uniform
 * grid, the kernels of Purcell's streaming ray tracer (thesis ch. 3, Fig.
 * 3.1) built for that scene, and the two ways of running traversal and
 * intersection over a stream of rays:
 *
 *   RT_EXEC_STREAM  multipass (Purcell 3.1 and 4.1.2): a traverse kernel and
 *                   an intersect kernel, each a bounded step per pass (k
 *                   voxels, m tests), ray ids routed between a "traverse"
 *                   and an "intersect" stream by conditional outputs, ray
 *                   state kept by ray and updated in place; an oracle
 *                   picks the next pass from the stream lengths
 *                   (intersect once at least
 *                   `intersect_threshold` of the live rays need it).
 *   RT_EXEC_FUSED   one kernel takes each ray through the whole grid (the
 *                   MIMD form, Purcell 5.2.2 "branching").
 *
 * Both run the same functions (kernels/render/rt_trace.cl) and find the
 * same hits. The renderer (render.h) drives whole images with this; tests
 * call rt_tracer_trace() on rays of their own.
 *
 * Conventions are those of <sluice/sluice.h>: functions return a
 * sluice_status, never abort or print; messages go to `err` (create) or to
 * the context's error (sluice_context_error) afterwards.
 */
#ifndef SLUICE_RT_TRACER_H
#define SLUICE_RT_TRACER_H

#include "../../kernels/render/rt_types.h"
#include "device_scene.h"
#include "grid.h"
#include "scene.h"
#include "sluice/sluice.h"

#include <stddef.h>
#include <stdint.h>

/** How traversal and intersection run. */
typedef enum rt_exec { RT_EXEC_STREAM = 0, RT_EXEC_FUSED = 1 } rt_exec;

/** Which ray-triangle test. */
typedef enum rt_intersector {
    RT_ISECT_MT = 0,        /**< Moller-Trumbore (Purcell Fig. 3.2) */
    RT_ISECT_WATERTIGHT = 1 /**< Woop, Benthin and Wald 2013: no leaks at edges */
} rt_intersector;

/** How the grid is built. */
typedef enum rt_grid_build {
    RT_GRID_BUILD_DEVICE = 0, /**< with the stream algorithms (rt_grid_build_device) */
    RT_GRID_BUILD_HOST = 1    /**< in plain C, then uploaded */
} rt_grid_build;

/** How the fused mode's packets move through the grid (kernels/render/rt_fused.cl). */
typedef enum rt_fused_walk {
    RT_WALK_AUTO = 0,  /**< RT_WALK_SLICES when at most half of the voxels hold
                            triangles, else RT_WALK_OFF */
    RT_WALK_OFF = 1,   /**< a voxel at a time: each voxel's tests before the next step */
    RT_WALK_ON = 2,    /**< walk ahead: step 4 voxels, then test them in order */
    RT_WALK_SLICES = 3 /**< coherent packets (eye rays, rays to a point) slice by
                            slice of the grid, the others walking ahead. Same
                            hits; a ray's counts are then the slices it crossed
                            and the triangles left to test after a cull */
} rt_fused_walk;

/** Largest copy of the triangle records in list order that a tracer makes by
 *  default (rt_tracer_options.list_copy_max). */
#define RT_LIST_COPY_MAX_DEFAULT ((size_t)64 << 20)

/** Options of rt_tracer_create(); start from rt_tracer_options_default(). */
typedef struct rt_tracer_options {
    rt_exec exec;
    rt_intersector intersector;
    rt_grid_build grid_build;
    unsigned grid_min_dim;     /**< voxels along the shortest axis (Purcell 5.2.1);
                                    RT_GRID_AUTO_MIN_DIM (0): chosen from the scene,
                                    RT_GRID_AUTO_DENSITY_SPARSE voxels per triangle
                                    for meshes of RT_GRID_SPARSE_MIN_TRIANGLES or
                                    more where most voxels stay empty, else
                                    RT_GRID_AUTO_DENSITY (rt_grid_auto_min_dim_density,
                                    with the floor of rt_grid_edge_quartile) */
    float intersect_threshold; /**< stream mode: intersect when I >= this * live */
    unsigned unroll_steps;     /**< stream mode: voxels per traverse pass (k) */
    unsigned unroll_tests;     /**< stream mode: triangle tests per intersect pass (m) */
    int ordered;               /**< stream mode: ORDERED outputs (else UNORDERED) */
    /** Fused mode, Moller-Trumbore: slices, walk ahead or a voxel at a time.
     *  All give the same hits, the last two the same counts; walking ahead
     *  is faster on sparse grids (bunny 10-20%, teapotahedron 20%), slower
     *  on dense ones (cornell 25%), and slices faster again for coherent
     *  rays on sparse grids, slower on cornell: RT_WALK_AUTO's rule
     *  (bench_raytrace; bench/README.md has the figures). */
    rt_fused_walk fused_walk;
    /** Moller-Trumbore, fused mode walking ahead or stream mode: the most
     *  bytes of the list-order copy of the triangle records (40 per grid
     *  entry) that their turned tests read; past this, they gather through
     *  the lists instead (bunny about 8% slower fused, 2-6% stream). */
    size_t list_copy_max;
} rt_tracer_options;

/** Defaults: stream, Moller-Trumbore, device grid, RT_GRID_AUTO_MIN_DIM,
 *  threshold 0.2 (Purcell 4.1.2), k = 32 voxels and m = 64 triangle tests
 *  per pass (Purcell's own k = m = 1 passes are 2-10x more: measured slower
 *  here; k = 32, m = 64 against 16 and 32 measured 14-27% faster on bunny,
 *  teapotahedron and spheres:1000, cornell within noise, tracer.c),
 *  unordered, RT_WALK_AUTO, RT_LIST_COPY_MAX_DEFAULT. */
rt_tracer_options rt_tracer_options_default(void);

/** What tracing has cost so far (Purcell Fig. 5.2, Tables 5.2 and 5.4). */
typedef struct rt_trace_stats {
    uint64_t rays;   /**< rays traced */
    uint64_t voxels; /**< voxels visited, all rays (v = voxels / rays) */
    uint64_t tests;  /**< triangle tests, all rays (t = tests / rays) */
    uint64_t passes; /**< stream mode: traverse + intersect passes */
    uint64_t traverse_passes, intersect_passes;
    uint64_t calls;           /**< trace calls (ray streams traced) */
    double live_fraction_sum; /**< stream mode: sum over passes of the share of
                                   live rays the pass processed */
    uint64_t slices;          /**< fused mode, coherent packets slice by slice
                                   (RT_WALK_SLICES): slices the packets crossed,
                                   counted per packet, not per ray */
    uint64_t slices_skipped;  /**< of those, slices crossed in one step through
                                   blocks of 4x4x4 voxels with no triangles */
    uint32_t max_steps;       /**< most voxels one ray visited */
    uint32_t max_tests;       /**< most triangle tests one ray did */
    double seconds;           /**< host wall time spent tracing */
} rt_trace_stats;

typedef struct rt_tracer rt_tracer;

/**
 * Uploads `scene`, builds its grid and the kernels. The context and the scene
 * must outlive the tracer. On failure `*out` is NULL and `err` says why.
 */
sluice_status rt_tracer_create(sluice_context *ctx, const sr_scene *scene,
                               const rt_tracer_options *opt, rt_tracer **out, char *err,
                               size_t err_size);

/** Frees the tracer and its device memory (NULL is fine). */
void rt_tracer_destroy(rt_tracer *t);

/**
 * Traces `n` rays held on the host and writes their hits (rt_hit.tri is
 * RT_NO_HIT for a miss). Rays with RT_FLAG_ANY_HIT stop at any hit in
 * [tmin, tmax]; the others find the nearest. For tests and tools.
 */
sluice_status rt_tracer_trace(rt_tracer *t, const rt_ray *rays, size_t n, rt_hit *hits);

/**
 * Traces the first `n` records of the device stream `rays` (its device length
 * must be n) and writes hit i to record i of `hits` (capacity >= the
 * capacity of `rays`). Queues the work; the stream mode waits for its pass
 * counts. For the renderer.
 */
sluice_status rt_tracer_trace_stream(rt_tracer *t, sluice_stream *rays, size_t n,
                                     sluice_stream *hits);

/** Reads the largest per-ray voxel and test counts of the traces since the
 *  last call into the statistics (max_steps, max_tests). A blocking read:
 *  rt_tracer_trace_stream leaves it to the caller, once per image or pass. */
sluice_status rt_tracer_collect_maxima(rt_tracer *t);

/** Statistics since creation or the last reset. */
const rt_trace_stats *rt_tracer_stats(const rt_tracer *t);

/** Forgets the statistics. */
void rt_tracer_reset_stats(rt_tracer *t);

/** The grid (its description, cell and triangle-reference counts, bytes). */
const rt_grid_device *rt_tracer_grid(const rt_tracer *t);

/** The grid's minimum dimension: the options' grid_min_dim, or the one the
 *  tracer chose for RT_GRID_AUTO_MIN_DIM (0 for a NULL tracer). */
unsigned rt_tracer_grid_min_dim(const rt_tracer *t);

/** Device bytes the scene's data take (vertices, triangles, materials,
 *  lights, and the tracer's list-order copy of the triangle records), and
 *  those the tracer's own streams take now. */
size_t rt_tracer_scene_bytes(const rt_tracer *t);
size_t rt_tracer_stream_bytes(const rt_tracer *t);

/** The scene on the device that the tracer uploaded (its triangle records in
 *  the layout its intersector reads), for the renderers that shade its hits. */
const sr_device_scene *rt_tracer_scene(const rt_tracer *t);

/** The options the tracer was created with. */
const rt_tracer_options *rt_tracer_get_options(const rt_tracer *t);

/** How the fused mode traverses this scene's grid, e.g. "walk ahead 4
 *  voxels (6% of voxels hold triangles), list copy 7.7 MB"; "" for the
 *  stream mode. */
const char *rt_tracer_fused_path(const rt_tracer *t);

/**
 * Tracing inside another kernel, as the renderers' fused direct light does
 * (kernels/raytrace/rt_direct.cl: a hit's shadow rays made and traced in
 * registers, never written to a stream). Such a program takes the tracer's
 * sources (rt_trace.cl, rt_lanes.cl, rt_fused.cl) with the build options
 * below, and its kernel calls rt_packet_trace (rt_fused.cl) on packets of
 * 16 rays. rt_tracer_packets: whether this tracer can serve it (the fused
 * mode with the Moller-Trumbore test, whose packets rt_packet_trace takes).
 */
int rt_tracer_packets(const rt_tracer *t);

/** The build options of the tracer's kernels (its path through this scene's
 *  grid), to add to those of a program that calls rt_packet_trace. */
const char *rt_tracer_build_options(const rt_tracer *t);

/** Binds what rt_packet_trace reads to arguments first .. first + 6 of `k`:
 *  the maxima stream (global uint *), the grid's cell starts and triangle
 *  lists (global const uint *), the triangle records (global const float *),
 *  the grid (rt_grid_args by value), the list-order records (global const
 *  float *) and the macro cells (global const uchar *). */
sluice_status rt_tracer_bind_packets(rt_tracer *t, sluice_kernel *k, unsigned first);

/** Adds to the statistics what such a kernel traced: rays, voxels visited,
 *  triangle tests, and the slices crossed and crossed through empty macro
 *  cells (rt_trace_stats). */
void rt_tracer_add_traced(rt_tracer *t, uint64_t rays, uint64_t voxels, uint64_t tests,
                          uint64_t slices, uint64_t slices_skipped);

/** A text listing what the tracer skips (sr_skipped_add), e.g. "empty voxels
 *  (never sent to the intersector)". */
const char *rt_tracer_skipped(const rt_tracer *t);

#endif /* SLUICE_RT_TRACER_H */
