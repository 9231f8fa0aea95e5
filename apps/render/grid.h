/*
 * The uniform grid of Purcell's ray tracer (thesis ch. 3.2 and 5.2.1): the
 * scene's bounding box cut into nx x ny x nz voxels, each with the list of
 * triangles that overlap it (an exact triangle-box overlap test, not the
 * triangles' bounding boxes).
 *
 * Layout (identical on the host and on the device, so the C reference and the
 * device build can be compared element by element):
 *   cell index   c = x + nx * (y + ny * z)
 *   cell_start   nx*ny*nz + 1 uint32: the triangles of cell c are
 *                cell_tris[cell_start[c] .. cell_start[c+1]), in ascending
 *                triangle index
 *   cell_tris    cell_start[nx*ny*nz] uint32 triangle indices
 *
 * Resolution (Purcell 5.2.1): voxels as near cubic as possible, with at least
 * `min_dim` voxels along the shortest axis of the box: the voxel edge is
 * (shortest extent) / min_dim and every other axis gets
 * ceil(extent / edge) voxels (clamped to >= 1), so each voxel is a cube of
 * that edge except that the box is stretched to a whole number of voxels.
 * A flat box (an extent of 0) is first padded (see rt_grid_choose).
 */
#ifndef SLUICE_RT_GRID_H
#define SLUICE_RT_GRID_H

#include "sluice/sluice.h"

#include <stddef.h>
#include <stdint.h>

/** Purcell's fixed minimum grid dimension (his setting for most scenes):
 *  what rt_grid_choose callers pass when they want a fixed rule. The ray
 *  tracer's default is RT_GRID_AUTO_MIN_DIM. */
#define RT_GRID_DEFAULT_MIN_DIM 32u

/** A minimum dimension of 0 given to the ray tracer (rt_tracer_options)
 *  means "choose it from the scene" with rt_grid_auto_min_dim. */
#define RT_GRID_AUTO_MIN_DIM 0u

/** Voxels per triangle that rt_grid_auto_min_dim aims at (lambda). Chosen by
 *  measurement of the fused mode (512x512 primary rays, 2 cores): the best
 *  minimum dimension of cornell, cornell-point, teapotahedron, bunny,
 *  spheres:1000 and million lay at about 2.5 to 7 voxels per triangle, and
 *  5 came within about 10% of the best on each. */
#define RT_GRID_AUTO_DENSITY 5.0

/** The coarser density the ray tracer tries first (rt_tracer_create) for
 *  meshes of at least RT_GRID_SPARSE_MIN_TRIANGLES triangles: where most
 *  voxels stay empty, its traversal walks ahead over them and tests a
 *  voxel's list 16 triangles at a time (rt_lanes.cl), so longer lists cost
 *  little and fewer voxels save steps. Scenes of a few thousand triangles
 *  with large walls or floors (glassball, ring) measured slower with it.
 *  bench/README.md has the figures. */
#define RT_GRID_AUTO_DENSITY_SPARSE 1.5
#define RT_GRID_SPARSE_MIN_TRIANGLES 16384u

/** Largest number of voxels a grid may have. */
#define RT_GRID_MAX_CELLS (1u << 27)

/** Largest number of voxels along one axis (voxel indices stay exact in
 *  float arithmetic). */
#define RT_GRID_MAX_SIDE (1u << 20)

/** Largest number of (voxel, triangle) entries a grid may list: 512 MiB of
 *  cell_tris, and four times that as scratch during the device build. */
#define RT_GRID_MAX_PAIRS (1u << 27)

/** An axis whose extent is at most this fraction of the largest extent is
 *  flat (a planar scene, or rounding noise around one): it is left out when
 *  the voxel edge is chosen, and gets as few voxels as cover it (usually
 *  one). Without this, Purcell's rule would cut the other axes into
 *  min_dim / (this fraction) voxels. */
#define RT_GRID_FLAT_RATIO (1.0 / 1024.0)

/** Where the grid is and how it is cut. */
typedef struct rt_grid_desc {
    float lo[3], hi[3]; /**< the box the voxels tile exactly */
    uint32_t dims[3];   /**< nx, ny, nz */
    float cell[3];      /**< voxel edge per axis: (hi - lo) / dims */
} rt_grid_desc;

/**
 * Chooses the grid for the scene bounds [lo, hi] by Purcell's rule above.
 * The box is padded by a small relative margin on every side so that
 * triangles on the faces are inside, and a flat axis gets a positive extent.
 * Fails (SLUICE_ERROR_INVALID_ARGUMENT) for non-finite bounds or min_dim 0,
 * and SLUICE_ERROR_LIMIT when the grid would exceed RT_GRID_MAX_CELLS.
 *
 * Details: the margin is 2^-12 of the largest extent plus 2^-20 of the
 * largest coordinate magnitude (so that it survives rounding to float far
 * from the origin); a box that is a single point at the origin gets a margin
 * of 1. Flat axes (RT_GRID_FLAT_RATIO) do not choose the edge; when every
 * axis is flat the grid is one voxel. The box is then stretched about its
 * centre to dims * edge along every axis, so voxels are cubes up to float
 * rounding, and cell = (hi - lo) / dims in float. Also
 * SLUICE_ERROR_INVALID_ARGUMENT when lo > hi on an axis, and
 * SLUICE_ERROR_LIMIT when an axis would exceed RT_GRID_MAX_SIDE voxels.
 */
sluice_status rt_grid_choose(const float lo[3], const float hi[3], unsigned min_dim,
                             rt_grid_desc *out, char *err, size_t err_size);

/**
 * The minimum dimension (for rt_grid_choose) that gives a grid of about
 * RT_GRID_AUTO_DENSITY voxels per triangle (Cleary and Wyvill; Wald et al.:
 * a voxel edge of (lambda N / V)^(-1/3)) for the scene bounds [lo, hi] and
 * `triangles` triangles: the shortest non-flat extent divided by that edge,
 * rounded, at least 1. Flat axes (RT_GRID_FLAT_RATIO) are left out of the
 * volume (an area or a length then). The result is capped so that the grid
 * stays within RT_GRID_AUTO_MAX_CELLS voxels and 1024 per shortest axis. For
 * non-finite or empty bounds, or no triangles, it returns
 * RT_GRID_DEFAULT_MIN_DIM (rt_grid_choose then reports bad bounds).
 */
unsigned rt_grid_auto_min_dim(const float lo[3], const float hi[3], size_t triangles);

/**
 * rt_grid_auto_min_dim with voxels no smaller than `min_edge` (0: no floor).
 * The density rule assumes triangles small against voxels; where they are
 * not (cornell: walls and boxes), finer voxels only list each triangle in
 * more voxels and test it again in each. The ray tracer passes
 * rt_grid_edge_quartile: 512x512 primary rays of cornell and cornell-point
 * then run on min dim 3 instead of 6 and 5, 8-12% faster (fused mode, one
 * process); the floor is below the density rule's edge for the large meshes
 * (bunny, teapotahedron, spheres:N, million), which keep their grids.
 */
unsigned rt_grid_auto_min_dim_edge(const float lo[3], const float hi[3], size_t triangles,
                                   double min_edge);

/**
 * rt_grid_auto_min_dim_edge aiming at `density` voxels per triangle instead
 * of RT_GRID_AUTO_DENSITY (a density that is not positive and finite means
 * RT_GRID_AUTO_DENSITY).
 */
unsigned rt_grid_auto_min_dim_density(const float lo[3], const float hi[3], size_t triangles,
                                      double min_edge, double density);

/**
 * The lower quartile of the triangles' edge lengths, from at most 4096
 * triangles spread evenly over the mesh (3 floats per vertex, 3 indices per
 * triangle, trusted to be in range). 0 when there are no triangles or no
 * finite edges.
 */
double rt_grid_edge_quartile(const float *positions, const uint32_t *indices, size_t triangles);

/** Most voxels rt_grid_auto_min_dim aims at (64 MiB of cell_start). */
#define RT_GRID_AUTO_MAX_CELLS (1u << 24)

/**
 * Checks a grid description as the builds need it: dims >= 1, at most
 * RT_GRID_MAX_SIDE per axis and RT_GRID_MAX_CELLS in all, lo and cell
 * finite, cell > 0. Writes the number of voxels to `*cells` (may be NULL).
 * SLUICE_ERROR_INVALID_ARGUMENT or SLUICE_ERROR_LIMIT otherwise.
 */
sluice_status rt_grid_desc_check(const rt_grid_desc *desc, size_t *cells, char *err,
                                 size_t err_size);

/** A grid built on the host (the plain C reference). */
typedef struct rt_grid_host {
    rt_grid_desc desc;
    uint32_t *cell_start; /**< cells + 1 entries */
    uint32_t *cell_tris;  /**< cell_start[cells] entries */
} rt_grid_host;

/** Builds the grid in plain C, single-threaded (tests and benchmarks).
 *  `positions` are 3 floats per vertex, `indices` 3 per triangle (trusted to
 *  be in range: the vertex count is not known here). For each triangle the
 *  voxels of its bounding box (clamped to the grid) are tested with the
 *  exact overlap test of kernels/render/tri_box.h, each voxel enlarged by
 *  RT_GRID_EPS of its edge on every side, so a triangle on a shared face,
 *  edge or corner is listed in every voxel that touches it. Fails with
 *  SLUICE_ERROR_INVALID_ARGUMENT for a bad description or a triangle with a
 *  non-finite corner, SLUICE_ERROR_LIMIT beyond RT_GRID_MAX_PAIRS entries,
 *  SLUICE_ERROR_OUT_OF_MEMORY; `*out` is then all zero. */
sluice_status rt_grid_build_host(const rt_grid_desc *desc, const float *positions,
                                 const uint32_t *indices, size_t triangles, rt_grid_host *out,
                                 char *err, size_t err_size);

/** rt_grid_build_host with a lower limit on the (voxel, triangle) entries:
 *  at most `max_pairs` (0, or anything above RT_GRID_MAX_PAIRS, means
 *  RT_GRID_MAX_PAIRS), e.g. to bound memory. */
sluice_status rt_grid_build_host_limit(const rt_grid_desc *desc, const float *positions,
                                       const uint32_t *indices, size_t triangles, size_t max_pairs,
                                       rt_grid_host *out, char *err, size_t err_size);

/** Frees what rt_grid_build_host allocated (the struct itself is the
 *  caller's). */
void rt_grid_host_free(rt_grid_host *g);

/** A grid on the device: two streams in the layout above. */
typedef struct rt_grid_device {
    rt_grid_desc desc;
    sluice_stream *cell_start; /**< uint32, cells + 1 records */
    sluice_stream *cell_tris;  /**< uint32 */
    size_t cell_tri_count;     /**< records in cell_tris */
    size_t bytes;              /**< device memory the grid holds */
    /** Why rt_grid_build_device or rt_grid_upload failed ("" after success):
     *  these have no error buffer argument, and a failure of the build's own
     *  (a limit, a bad triangle) is not a context error. */
    char message[256];
} rt_grid_device;

/**
 * Builds the grid on the device with the stream algorithms: a kernel counts
 * the voxels each triangle overlaps (exact test, over the voxels of its
 * bounding box), a scan gives each triangle its place in a (cell, triangle)
 * pair stream, a second kernel writes the pairs, a radix sort by cell orders
 * them (stable, so triangles stay ascending within a cell) and the cell index
 * (by counting) gives cell_start. `positions` and `indices` are device
 * streams (float x3 per vertex and uint32 x3 per triangle records).
 *
 * The result equals rt_grid_build_host's element by element (same test, same
 * float operations). Errors: SLUICE_ERROR_INVALID_ARGUMENT for bad
 * arguments (record sizes other than 12, fewer index records than
 * `triangles`), an index past the positions' length or a non-finite corner;
 * SLUICE_ERROR_LIMIT when the grid would list more than RT_GRID_MAX_PAIRS
 * entries (checked before the pair streams are allocated); the runtime's
 * errors otherwise. `out->message` says why; on failure nothing is kept and
 * the other fields of `*out` are zero. The kernels are compiled at every
 * call (PoCL caches the binaries on disk; loading them costs about 25 ms
 * here).
 */
sluice_status rt_grid_build_device(sluice_context *ctx, const rt_grid_desc *desc,
                                   sluice_stream *positions, sluice_stream *indices,
                                   size_t triangles, rt_grid_device *out);

/** rt_grid_build_device with a lower limit on the (voxel, triangle)
 *  entries: at most `max_pairs` (0, or anything above RT_GRID_MAX_PAIRS,
 *  means RT_GRID_MAX_PAIRS), e.g. to fit the device's memory; the count is
 *  known before the pair streams are allocated. */
sluice_status rt_grid_build_device_limit(sluice_context *ctx, const rt_grid_desc *desc,
                                         sluice_stream *positions, sluice_stream *indices,
                                         size_t triangles, size_t max_pairs, rt_grid_device *out);

/** Uploads a host-built grid into device streams (same layout), e.g. to
 *  render with the C reference grid. On failure nothing is kept and
 *  `out->message` says why. */
sluice_status rt_grid_upload(sluice_context *ctx, const rt_grid_host *host, rt_grid_device *out);

/** Destroys the grid's streams. */
void rt_grid_device_free(rt_grid_device *g);

#endif /* SLUICE_RT_GRID_H */
