/* See tracer.h. Creation: scene upload, grid, program and kernels. */
#include "clock.h"
#include "tracer_internal.h"
#include "app_error.h"

#include "kernels.h"
#include "skipped.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

rt_tracer_options rt_tracer_options_default(void)
{
    rt_tracer_options o;
    memset(&o, 0, sizeof o);
    o.exec = RT_EXEC_STREAM;
    o.intersector = RT_ISECT_MT;
    o.grid_build = RT_GRID_BUILD_DEVICE;
    o.grid_min_dim = RT_GRID_AUTO_MIN_DIM;
    o.intersect_threshold = 0.2f;
    /* k = 32, m = 256: fewer, longer intersect passes; measured against
     * other k and m in bench/README.md ("The stream mode's 3x") */
    o.unroll_steps = 32;
    o.unroll_tests = 256;
    o.ordered = 0;
    o.fused_walk = RT_WALK_AUTO;
    o.list_copy_max = RT_LIST_COPY_MAX_DEFAULT;
    return o;
}

/* Voxels of the grid in t->grid and how many of them hold triangles. */
static sluice_status grid_occupancy(rt_tracer *t, size_t *cells_out, size_t *occupied_out,
                                    char *err, size_t err_size)
{
    const rt_grid_desc *d = &t->grid.desc;
    size_t cells = (size_t)d->dims[0] * d->dims[1] * d->dims[2], occupied = 0;
    uint32_t *start = malloc((cells + 1) * sizeof *start);
    if (!start) {
        sr_set_error(err, err_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    sluice_status st = sluice_stream_download(t->grid.cell_start, start, cells + 1, NULL);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "grid download: %s", sluice_context_error(t->ctx));
        free(start);
        return st;
    }
    for (size_t c = 0; c < cells; ++c)
        occupied += start[c] < start[c + 1];
    free(start);
    t->grid_cells = cells;
    t->grid_occupied = occupied;
    *cells_out = cells;
    *occupied_out = occupied;
    return SLUICE_OK;
}

static sluice_status build_grid_dim(rt_tracer *t, unsigned min_dim, char *err, size_t err_size)
{
    const sr_scene_stats *ss = sr_scene_statistics(t->scene);
    rt_grid_desc desc;
    size_t nt = sr_scene_triangle_count(t->scene);
    sluice_status st =
        rt_grid_choose(ss->bounds_min, ss->bounds_max, min_dim, &desc, err, err_size);
    if (st != SLUICE_OK)
        return st;
    t->grid_min_dim = min_dim;
    t->grid_cells = t->grid_occupied = 0;
    if (t->opt.grid_build == RT_GRID_BUILD_DEVICE) {
        st = rt_grid_build_device(t->ctx, &desc, t->ds->positions, t->ds->indices, nt, &t->grid);
        if (st != SLUICE_OK)
            sr_set_error(err, err_size, "grid: %s", sluice_context_error(t->ctx));
    } else {
        rt_grid_host h;
        memset(&h, 0, sizeof h);
        st = rt_grid_build_host(&desc, sr_scene_positions(t->scene), sr_scene_indices(t->scene), nt,
                                &h, err, err_size);
        if (st == SLUICE_OK) {
            st = rt_grid_upload(t->ctx, &h, &t->grid);
            if (st != SLUICE_OK)
                sr_set_error(err, err_size, "grid upload: %s", sluice_context_error(t->ctx));
        }
        rt_grid_host_free(&h);
    }
    return st;
}

/* The grid at the given minimum dimension, or for RT_GRID_AUTO_MIN_DIM the
 * scene's: with RT_GRID_SPARSE_MIN_TRIANGLES triangles or more, first at
 * RT_GRID_AUTO_DENSITY_SPARSE voxels per triangle; when that grid is not
 * sparse (more than half its voxels hold triangles, where the fused mode
 * goes a voxel at a time), and for smaller scenes, at RT_GRID_AUTO_DENSITY.
 * Both keep voxels no smaller than the lower quartile of the triangles'
 * edges (rt_grid_edge_quartile). */
static sluice_status build_grid(rt_tracer *t, char *err, size_t err_size)
{
    const sr_scene_stats *ss = sr_scene_statistics(t->scene);
    size_t nt = sr_scene_triangle_count(t->scene);
    unsigned min_dim = t->opt.grid_min_dim;
    sluice_status st;
    if (min_dim != RT_GRID_AUTO_MIN_DIM)
        st = build_grid_dim(t, min_dim, err, err_size);
    else {
        double edge =
            rt_grid_edge_quartile(sr_scene_positions(t->scene), sr_scene_indices(t->scene), nt);
        unsigned dense = rt_grid_auto_min_dim_edge(ss->bounds_min, ss->bounds_max, nt, edge);
        unsigned sparse = nt >= RT_GRID_SPARSE_MIN_TRIANGLES
                              ? rt_grid_auto_min_dim_density(ss->bounds_min, ss->bounds_max, nt,
                                                             edge, RT_GRID_AUTO_DENSITY_SPARSE)
                              : dense;
        st = build_grid_dim(t, sparse, err, err_size);
        size_t cells = 0, occupied = 0;
        if (st == SLUICE_OK && dense != sparse)
            st = grid_occupancy(t, &cells, &occupied, err, err_size);
        if (st == SLUICE_OK && dense != sparse && 2 * occupied > cells) {
            rt_grid_device_free(&t->grid);
            memset(&t->grid, 0, sizeof t->grid);
            st = build_grid_dim(t, dense, err, err_size);
        }
    }
    if (st != SLUICE_OK)
        return st;
    rt_grid_args *g = &t->grid_args;
    memset(g, 0, sizeof *g);
    for (int k = 0; k < 3; ++k) {
        g->lo[k] = t->grid.desc.lo[k];
        g->hi[k] = t->grid.desc.hi[k];
        g->cell[k] = t->grid.desc.cell[k];
        g->inv_cell[k] = 1.0f / t->grid.desc.cell[k];
        g->dims[k] = (rt_i32)t->grid.desc.dims[k];
    }
    return SLUICE_OK;
}

/* Voxels the fused mode's packets walk before they test (rt_fused.cl): 4
 * measured best on bunny against 2 and 8 (bench_raytrace). */
#define RT_WALK_VOXELS 4

/* Blocks of 4x4x4 voxels for the slices' macro cells: faster than 8 on
 * the bunny views, where finer blocks skip more often (bench/README.md). */
#define RT_MACRO_SHIFT 2

/* How the fused mode will traverse (tracer.h, rt_fused_walk). Walking ahead
 * pays where rays cross many empty voxels between tests: bunny,
 * teapotahedron, spheres and ring have 5-35% of their voxels occupied, the
 * Cornell box 94%, whose rays test in almost every voxel they enter. */
static sluice_status choose_fused_path(rt_tracer *t, char *err, size_t err_size)
{
    t->walks_ahead = 0;
    t->slices = 0;
    t->fused_path[0] = '\0';
    /* ten planes padded so that a 16-wide load from any entry stays inside */
    size_t stride = ((t->grid.cell_tri_count + 15) & ~(size_t)15) + 16;
    size_t bytes = 10 * sizeof(float) * stride;
    if (t->opt.exec != RT_EXEC_FUSED) {
        /* the stream mode's intersect passes use turned tests on any grid */
        if (t->opt.intersector == RT_ISECT_MT && bytes <= t->opt.list_copy_max)
            t->list_stride = stride;
        return SLUICE_OK;
    }
    if (t->opt.intersector != RT_ISECT_MT) {
        snprintf(t->fused_path, sizeof t->fused_path, "one ray at a time (watertight test)");
        return SLUICE_OK;
    }
    /* counted already when build_grid compared two densities */
    size_t cells = t->grid_cells, occupied = t->grid_occupied;
    sluice_status st = cells ? SLUICE_OK : grid_occupancy(t, &cells, &occupied, err, err_size);
    if (st != SLUICE_OK)
        return st;
    double pct = cells ? 100.0 * (double)occupied / (double)cells : 0.0;
    t->walks_ahead = t->opt.fused_walk == RT_WALK_ON || t->opt.fused_walk == RT_WALK_SLICES ||
                     (t->opt.fused_walk == RT_WALK_AUTO && 2 * occupied <= cells);
    t->slices = t->walks_ahead && t->opt.fused_walk != RT_WALK_ON;
    if (!t->walks_ahead) {
        snprintf(t->fused_path, sizeof t->fused_path,
                 "a voxel at a time (%.0f%% of voxels hold triangles)", pct);
        return SLUICE_OK;
    }
    t->list_stride = bytes <= t->opt.list_copy_max ? stride : 0;
    int w = snprintf(t->fused_path, sizeof t->fused_path,
                     "%swalk ahead %d voxels (%.0f%% of voxels hold triangles), ",
                     t->slices ? "coherent packets slice by slice, the others " : "",
                     RT_WALK_VOXELS, pct);
    if (w > 0 && (size_t)w < sizeof t->fused_path) {
        if (t->list_stride)
            snprintf(t->fused_path + w, sizeof t->fused_path - (size_t)w, "list copy %.2f MB",
                     (double)bytes / 1048576.0);
        else
            snprintf(t->fused_path + w, sizeof t->fused_path - (size_t)w,
                     "no list copy (%.2f MB > %.2f MB)", (double)bytes / 1048576.0,
                     (double)t->opt.list_copy_max / 1048576.0);
    }
    return SLUICE_OK;
}

/* The macro cells the slices skip by (rt_macro_cells), one byte per block
 * of 2^RT_MACRO_SHIFT voxels a side. */
static sluice_status build_macro_cells(rt_tracer *t)
{
    if (!t->slices)
        return SLUICE_OK;
    size_t n = 1;
    for (int k = 0; k < 3; ++k)
        n *= (t->grid.desc.dims[k] + (1u << RT_MACRO_SHIFT) - 1u) >> RT_MACRO_SHIFT;
    sluice_kernel *k = NULL;
    sluice_status st = sluice_stream_create(t->ctx, 1, n, &t->macro_cells);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(t->program, "rt_macro_cells", &k);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 0, t->grid.cell_start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 1, sizeof t->grid_args, &t->grid_args);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 2, t->macro_cells, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, n);
    if (st == SLUICE_OK)
        st = sluice_context_finish(t->ctx);
    sluice_kernel_destroy(k);
    return st;
}

/* One bit per voxel, set where the voxel holds triangles (rt_voxel_bits):
 * what the stream mode's walks test at each voxel. */
static sluice_status build_voxel_bits(rt_tracer *t)
{
    size_t cells = (size_t)t->grid.desc.dims[0] * t->grid.desc.dims[1] * t->grid.desc.dims[2];
    size_t words = (cells + 31u) / 32u;
    uint32_t n = (uint32_t)cells;
    sluice_kernel *k = NULL;
    sluice_status st = sluice_stream_create(t->ctx, sizeof(uint32_t), words, &t->voxel_bits);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(t->program, "rt_voxel_bits", &k);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 0, t->grid.cell_start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 1, sizeof n, &n);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 2, t->voxel_bits, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, words);
    if (st == SLUICE_OK)
        st = sluice_context_finish(t->ctx);
    sluice_kernel_destroy(k);
    return st;
}

/* The list-order copy of the triangle records (rt_list_records). */
static sluice_status build_list_copy(rt_tracer *t)
{
    if (!t->list_stride)
        return SLUICE_OK;
    sluice_kernel *k = NULL;
    uint32_t entries = (uint32_t)t->grid.cell_tri_count;
    sluice_status st =
        sluice_stream_create(t->ctx, sizeof(float), 10 * t->list_stride, &t->list_records);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(t->program, "rt_list_records", &k);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 0, t->grid.cell_tris, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 1, t->ds->tri_records, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 2, sizeof entries, &entries);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 3, t->list_records, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, t->list_stride);
    if (st == SLUICE_OK)
        st = sluice_context_finish(t->ctx);
    sluice_kernel_destroy(k);
    if (st == SLUICE_OK)
        t->list_copy_bytes = 10 * sizeof(float) * t->list_stride;
    return st;
}

static sluice_status build_program(rt_tracer *t, char *err, size_t err_size)
{
    char *opts = t->build_options, walk[160] = "", slices[64];
    snprintf(slices, sizeof slices, " -DRT_FUSED_SLICES -DRT_MACRO_SHIFT=%d", RT_MACRO_SHIFT);
    if (!t->walks_ahead && t->list_stride)
        snprintf(walk, sizeof walk, " -DRT_LIST_COPY -DRT_LIST_STRIDE=%zuu", t->list_stride);
    else if (t->walks_ahead && t->list_stride)
        snprintf(walk, sizeof walk, " -DRT_FUSED_WALK=%d -DRT_LIST_COPY -DRT_LIST_STRIDE=%zuu%s",
                 RT_WALK_VOXELS, t->list_stride, t->slices ? slices : "");
    else if (t->walks_ahead)
        snprintf(walk, sizeof walk, " -DRT_FUSED_WALK=%d%s", RT_WALK_VOXELS,
                 t->slices ? slices : "");
    /* off CPUs the stream kernels take one ray per work-item (rt_stream.cl) */
    sluice_device_info info;
    int cpu = sluice_context_device(t->ctx, &info) != SLUICE_OK || info.is_cpu;
    snprintf(opts, sizeof t->build_options, "-DRT_UNROLL_STEPS=%u -DRT_UNROLL_TESTS=%u%s%s%s",
             t->opt.unroll_steps, t->opt.unroll_tests,
             t->opt.intersector == RT_ISECT_WATERTIGHT ? " -DRT_WATERTIGHT" : "", walk,
             cpu ? "" : " -DRT_PER_RAY");
    /* what the scene lets the tracer leave out */
    t->skipped[0] = '\0';
    sr_skipped_add(t->skipped, sizeof t->skipped, 1,
                   "empty voxels (never sent to the intersector)");
    sr_skipped_add(
        t->skipped, sizeof t->skipped,
        t->opt.exec == RT_EXEC_STREAM && t->opt.intersector == RT_ISECT_MT && !t->list_stride,
        "list-order copy of the triangle records (over list_copy_max: intersect passes gather)");
    static const char *const names[] = {"rt_types.h",  "triangle.cl",  "rt_trace.cl",
                                        "rt_lanes.cl", "rt_stream.cl", "rt_fused.cl"};
    sluice_status st = sr_program_create(t->ctx, names, 6, opts, &t->program);
    if (st == SLUICE_OK)
        st = sluice_program_build(t->program);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "ray tracer kernels: %s", sluice_context_error(t->ctx));
        return st;
    }
    st = sluice_kernel_create(t->program, "rt_setup", &t->k_setup);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(t->program, "rt_traverse", &t->k_traverse);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(t->program, "rt_intersect", &t->k_intersect);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(t->program, "rt_route", &t->k_route_t);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(t->program, "rt_route", &t->k_route_i);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(t->program, "rt_route_setup", &t->k_route_setup);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(t->program, "rt_trace_fused", &t->k_fused);
    if (st == SLUICE_OK) /* rays through the object cost many times those that miss it */
        st = sluice_kernel_set_uneven(t->k_fused, 1);
    if (st != SLUICE_OK)
        sr_set_error(err, err_size, "ray tracer kernels: %s", sluice_context_error(t->ctx));
    return st;
}

sluice_status rt_tracer_create(sluice_context *ctx, const sr_scene *scene,
                               const rt_tracer_options *opt, rt_tracer **out, char *err,
                               size_t err_size)
{
    if (out)
        *out = NULL;
    if (!ctx || !scene || !out) {
        sr_set_error(err, err_size, "rt_tracer_create: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    rt_tracer_options o = opt ? *opt : rt_tracer_options_default();
    if (o.unroll_steps == 0 || o.unroll_tests == 0 || o.unroll_steps > 4096 ||
        o.unroll_tests > 4096 || !(o.intersect_threshold >= 0.0f) || o.intersect_threshold > 1.0f ||
        (unsigned)o.fused_walk > (unsigned)RT_WALK_SLICES) {
        sr_set_error(err, err_size,
                     "rt_tracer_create: bad options (min dim %u, unroll %u/%u, threshold %g)",
                     o.grid_min_dim, o.unroll_steps, o.unroll_tests, (double)o.intersect_threshold);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    rt_tracer *t = calloc(1, sizeof *t);
    if (!t) {
        sr_set_error(err, err_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    t->ctx = ctx;
    t->scene = scene;
    t->opt = o;
    sluice_status st = sr_device_scene_create(
        ctx, scene, o.intersector == RT_ISECT_WATERTIGHT ? SR_TRI_VERTICES : SR_TRI_EDGES, &t->ds,
        err, err_size);
    if (st == SLUICE_OK)
        st = build_grid(t, err, err_size);
    if (st == SLUICE_OK)
        st = choose_fused_path(t, err, err_size);
    if (st == SLUICE_OK)
        st = build_program(t, err, err_size);
    if (st == SLUICE_OK && (st = build_list_copy(t)) != SLUICE_OK)
        sr_set_error(err, err_size, "list copy: %s", sluice_context_error(ctx));
    if (st == SLUICE_OK && (st = build_macro_cells(t)) != SLUICE_OK)
        sr_set_error(err, err_size, "macro cells: %s", sluice_context_error(ctx));
    if (st == SLUICE_OK && (st = build_voxel_bits(t)) != SLUICE_OK)
        sr_set_error(err, err_size, "voxel bits: %s", sluice_context_error(ctx));
    static const char *const ctr_names[] = {"voxels", "tests",          "done",
                                            "slices", "slices skipped", "entered"};
    if (st == SLUICE_OK)
        st = sluice_counters_create(ctx, RT_CTR_TRACE_COUNT, ctr_names, &t->counters);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, 4, 2, &t->maxima);
    if (st == SLUICE_OK) {
        static const uint32_t zero[2] = {0, 0};
        st = sluice_stream_upload(t->maxima, zero, 2);
    }
    if (st == SLUICE_OK)
        st = sluice_kernel_set_counters(t->k_fused, t->counters);
    if (st != SLUICE_OK) {
        if (err && err_size && !err[0])
            sr_set_error(err, err_size, "ray tracer: %s", sluice_context_error(ctx));
        rt_tracer_destroy(t);
        return st;
    }
    *out = t;
    return SLUICE_OK;
}

void rt_tracer_destroy(rt_tracer *t)
{
    if (!t)
        return;
    rt_stream_release(t);
    sluice_kernel_destroy(t->k_setup);
    sluice_kernel_destroy(t->k_traverse);
    sluice_kernel_destroy(t->k_intersect);
    sluice_kernel_destroy(t->k_route_t);
    sluice_kernel_destroy(t->k_route_i);
    sluice_kernel_destroy(t->k_route_setup);
    sluice_kernel_destroy(t->k_fused);
    sluice_program_destroy(t->program);
    sluice_counters_destroy(t->counters);
    sluice_stream_destroy(t->maxima);
    sluice_stream_destroy(t->host_rays);
    sluice_stream_destroy(t->host_hits);
    rt_grid_device_free(&t->grid);
    sluice_stream_destroy(t->list_records);
    sluice_stream_destroy(t->macro_cells);
    sluice_stream_destroy(t->voxel_bits);
    sr_device_scene_destroy(t->ds);
    free(t);
}

sluice_status rt_tracer_trace_stream(rt_tracer *t, sluice_stream *rays, size_t n,
                                     sluice_stream *hits)
{
    if (!t || !rays || !hits)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (n == 0)
        return SLUICE_OK;
    if (sluice_stream_record_size(rays) != sizeof(rt_ray) ||
        sluice_stream_record_size(hits) != sizeof(rt_hit) ||
        sluice_stream_capacity(hits) < sluice_stream_capacity(rays) ||
        n > sluice_stream_capacity(rays) || n > UINT32_MAX / 2)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    double t0 = sr_clock_seconds();
    sluice_status st = t->opt.exec == RT_EXEC_FUSED ? rt_fused_trace(t, rays, n, hits)
                                                    : rt_stream_trace(t, rays, n, hits);
    if (st == SLUICE_OK) {
        t->stats.rays += n;
        t->stats.calls++;
    }
    t->stats.seconds += sr_clock_seconds() - t0;
    return st;
}

sluice_status rt_tracer_collect_maxima(rt_tracer *t)
{
    uint32_t m[2];
    sluice_status st = sluice_stream_download(t->maxima, m, 2, NULL);
    if (st != SLUICE_OK)
        return st;
    if (m[0] > t->stats.max_steps)
        t->stats.max_steps = m[0];
    if (m[1] > t->stats.max_tests)
        t->stats.max_tests = m[1];
    return SLUICE_OK;
}

sluice_status rt_tracer_trace(rt_tracer *t, const rt_ray *rays, size_t n, rt_hit *hits)
{
    if (!t || (n && (!rays || !hits)))
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (n == 0)
        return SLUICE_OK;
    sluice_status st = SLUICE_OK;
    if (!t->host_rays || sluice_stream_capacity(t->host_rays) < n) {
        sluice_stream_destroy(t->host_rays);
        sluice_stream_destroy(t->host_hits);
        t->host_rays = t->host_hits = NULL;
        st = sluice_stream_create(t->ctx, sizeof(rt_ray), n, &t->host_rays);
        if (st == SLUICE_OK)
            st = sluice_stream_create(t->ctx, sizeof(rt_hit), n, &t->host_hits);
        if (st != SLUICE_OK)
            return st;
    }
    st = sluice_stream_upload(t->host_rays, rays, n);
    if (st == SLUICE_OK)
        st = rt_tracer_trace_stream(t, t->host_rays, n, t->host_hits);
    if (st == SLUICE_OK)
        st = sluice_stream_download(t->host_hits, hits, n, NULL);
    if (st == SLUICE_OK)
        st = rt_tracer_collect_maxima(t);
    return st;
}

const rt_trace_stats *rt_tracer_stats(const rt_tracer *t)
{
    return t ? &t->stats : NULL;
}

void rt_tracer_reset_stats(rt_tracer *t)
{
    if (t)
        memset(&t->stats, 0, sizeof t->stats);
}

unsigned rt_tracer_grid_min_dim(const rt_tracer *t)
{
    return t ? t->grid_min_dim : 0u;
}

const rt_grid_device *rt_tracer_grid(const rt_tracer *t)
{
    return t ? &t->grid : NULL;
}

size_t rt_tracer_scene_bytes(const rt_tracer *t)
{
    return t ? t->ds->bytes + t->list_copy_bytes : 0;
}

size_t rt_tracer_stream_bytes(const rt_tracer *t)
{
    return t ? t->state_capacity * (5 * sizeof(uint32_t) + sizeof(rt_walk)) : 0;
}

const sr_device_scene *rt_tracer_scene(const rt_tracer *t)
{
    return t ? t->ds : NULL;
}

const rt_tracer_options *rt_tracer_get_options(const rt_tracer *t)
{
    return t ? &t->opt : NULL;
}

const char *rt_tracer_fused_path(const rt_tracer *t)
{
    return t ? t->fused_path : "";
}

const char *rt_tracer_skipped(const rt_tracer *t)
{
    return t ? t->skipped : "";
}
