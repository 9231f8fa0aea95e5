/*
 * A uniform grid over points (photons), built on the device (Purcell, thesis
 * 6.2.2). Same layout conventions as the triangle grid (grid.h): the box
 * rt_grid_desc.lo .. hi cut into dims[0] x dims[1] x dims[2] cells, cell
 * c = x + nx * (y + ny * z); a point outside the box belongs to the nearest
 * boundary cell (its coordinates are clamped), and a point with a
 * non-finite coordinate is dropped (counted in the statistics).
 *
 * Result, the same for every build:
 *   order         point indices, each cell's in ascending index order
 *   cell_start    cells records: cell c's points are
 *                 order[cell_start[c] .. cell_start[c] + cell_count[c])
 *   cell_count    cells records: points stored in the cell
 *   cell_arrived  cells records: points that fell into the cell; more than
 *                 cell_count only where the stencil build dropped some
 *                 (the photon mapper scales stored power by
 *                 arrived / stored: Purcell's power redistribution)
 *
 * Builds (sr_point_grid_build):
 *   BITONIC  Purcell Fig. 6.4: (cell, index) pairs sorted with
 *            sluice_sort_bitonic, cell starts by sluice_cell_index_search.
 *   STENCIL  Purcell's stencil routing: at most `slots` points per cell,
 *            routed by sluice_route_bounded_sparse into fixed footprints
 *            (cell_start[c] = c * slots). Deterministic: an overfull cell
 *            keeps its `slots` lowest point indices, which is what Purcell's
 *            stencil keeps when photons are drawn in index order.
 *   COUNT    counting sort: histogram (sluice_cell_index_count), scan,
 *            scatter. The fast default.
 * The object keeps its kernels and scratch streams between builds (a
 * progressive photon map is rebuilt every pass); streams only grow.
 *
 * Layouts. The dense grid above has a record per cell of the box, so cells
 * of about a search radius over a box much larger than the radius (a small
 * lit object before a distant wall) need more cells than the photons
 * justify, and sr_point_grid_desc_auto makes them coarser instead: a search
 * then walks many more photons per cell. The hashed layout
 * (sr_point_grid_build_hashed; Purcell 6.4.4, after Wald et al. 2002, and
 * the hash grid of Hachisuka et al.'s progressive photon mapping as
 * Davidovic's thesis 4.5.1 builds it) keeps cubes of about the radius: cell
 * (ix, iy, iz) of an unbounded lattice goes to bucket hash(ix, iy, iz) of a
 * power-of-two table of a few buckets per point (kernels/render/pg_types.h),
 * and the same builds run over bucket ids. The result is the representation
 * above with buckets for cells: a bucket's points in ascending index order,
 * possibly from several cells (collisions), which a search must tell apart
 * (the kNN search's radius mode does: apps/photonmap/knn.h).
 * sr_point_grid_plan_auto chooses between the two.
 */
#ifndef SLUICE_SR_POINT_GRID_H
#define SLUICE_SR_POINT_GRID_H

#include "grid.h"
#include "sluice/sluice.h"

#include <stddef.h>
#include <stdint.h>

/** How sr_point_grid_build bins the points. */
typedef enum sr_point_grid_build_kind {
    SR_POINT_GRID_COUNT = 0,   /**< counting sort (default) */
    SR_POINT_GRID_BITONIC = 1, /**< bitonic sort + binary search (Purcell Fig. 6.4) */
    SR_POINT_GRID_STENCIL = 2  /**< bounded routing into m*m places per cell */
} sr_point_grid_build_kind;

/** Most points one build takes (keys and indices stay below 2^32 - 1). */
#define SR_POINT_GRID_MAX_POINTS ((size_t)1 << 30)

/** Most cells x slots of the stencil build's footprints (1 GiB of order). */
#define SR_POINT_GRID_MAX_FOOTPRINT ((size_t)1 << 28)

/** Most places per cell of the stencil build (Purcell uses m = 16: 256). */
#define SR_POINT_GRID_MAX_SLOTS 65536u

/** Cell edge over search radius that sr_point_grid_desc_auto aims at.
 *  Measured with bench_knn --edge (65,000 photons on Cornell-box surfaces,
 *  65,536 queries, count build, radius = the mean k-photon radius, 2 cores):
 *  edges of 0.5, 0.75, 1 and 1.5 radii; 0.75 was best or within about 10%
 *  of the best for k = 32, 64 and 500 in both modes. Finer cells make
 *  Purcell's atleast estimate tighter (its first k photons lie nearer) but
 *  cost more empty cells per shell. */
#define SR_POINT_GRID_AUTO_EDGE 0.75

/** Most cells sr_point_grid_desc_auto makes: 2^22, and at most
 *  SR_POINT_GRID_AUTO_CELLS_PER_POINT per point (at least 64): past that,
 *  empty cells cost more to walk than the photons they separate. */
#define SR_POINT_GRID_AUTO_MAX_CELLS (1u << 22)
#define SR_POINT_GRID_AUTO_CELLS_PER_POINT 4u

/** How the cells are laid out in memory. */
typedef enum sr_point_grid_layout {
    SR_POINT_GRID_DENSE = 0,      /**< a record per cell of the box (rt_grid_desc) */
    SR_POINT_GRID_HASHED = 1,     /**< lattice cells hashed into buckets (sr_point_hash_desc) */
    SR_POINT_GRID_LAYOUT_AUTO = 2 /**< only as a request to sr_point_grid_plan_auto */
} sr_point_grid_layout;

/** The hashed layout: cubes of edge `cell` from `lo`, hashed into `buckets`. */
typedef struct sr_point_hash_desc {
    float lo[3];      /**< the lattice's origin (points below it clamp to coordinate 0) */
    float cell;       /**< cube edge, > 0 and finite */
    uint32_t buckets; /**< a power of two, 1 .. SR_POINT_HASH_MAX_BUCKETS */
} sr_point_hash_desc;

/** Most buckets of a hashed grid (2^27, as RT_GRID_MAX_CELLS). */
#define SR_POINT_HASH_MAX_BUCKETS (1u << 27)

/** Buckets per point that sr_point_hash_desc_auto aims at: the table is the
 *  smallest power of two of at least this many per point (so 2 to 4), at
 *  least 64: few collisions (a bucket then holds on average under one
 *  occupied cell besides its own), little memory (20 bytes per bucket over
 *  the build and the search). */
#define SR_POINT_HASH_BUCKETS_PER_POINT 2u

/** Cell edge over search radius of sr_point_hash_desc_auto. At one radius a
 *  search visits 3 cells across an axis (rarely 4: its reach is widened for
 *  rounding), 3 radii wide on average; coarser cells mean fewer bucket
 *  lookups but more photons examined per cell (at 2 radii: 2 cells, 4 radii
 *  wide). bench/README.md has the measurements behind it. */
#define SR_POINT_HASH_EDGE 1.0

/** Most lattice cells along an axis that sr_point_hash_desc_auto makes
 *  across the points' box: cells grow past the asked edge beyond it, so
 *  coordinates stay well inside PG_HASH_MAX_COORD and float rounding of the
 *  cell function stays far below a cell. */
#define SR_POINT_HASH_MAX_SIDE (1u << 21)

/** Statistics of the last build. */
typedef struct sr_point_grid_stats {
    size_t points;            /**< points given */
    size_t cells;             /**< cells of the grid (hashed: buckets) */
    size_t stored;            /**< points stored in the grid (listed in order) */
    size_t dropped_nonfinite; /**< points with a non-finite coordinate (dropped) */
    size_t occupied_cells;    /**< cells (hashed: buckets) with at least one stored point */
    uint32_t max_per_cell;    /**< most points that arrived in one cell (bucket) */
    double mean_per_occupied; /**< arrived points / occupied cells (buckets) */
    size_t overflow_points;   /**< stencil: points that arrived but were not stored */
    size_t overfull_cells;    /**< stencil: cells with more points than slots */
    double build_seconds;     /**< host wall time of the build, waited for */
} sr_point_grid_stats;

/** What the grid holds after a build (the streams stay the grid's: do not
 *  destroy them; they change at the next build). */
typedef struct sr_point_grid_view {
    sr_point_grid_layout layout; /**< SR_POINT_GRID_DENSE or SR_POINT_GRID_HASHED */
    rt_grid_desc desc;           /**< dense: the grid (all zero when hashed) */
    sr_point_hash_desc hash;     /**< hashed: the lattice and table (all zero when dense) */
    uint32_t cells;              /**< dense: dims[0] * dims[1] * dims[2]; hashed: buckets */
    sr_point_grid_build_kind kind;
    uint32_t slots;              /**< stencil: places per cell; 0 otherwise */
    size_t points;               /**< points the grid was built over (indices below this) */
    sluice_stream *order;        /**< uint32 point indices */
    sluice_stream *cell_start;   /**< uint32, cells (buckets) + 1 records */
    sluice_stream *cell_count;   /**< uint32, cells (buckets) records */
    sluice_stream *cell_arrived; /**< uint32, cells (buckets) records */
    uint64_t build; /**< changes with every build call: what a search derived from the grid
                         and its points (the kNN search's cell-ordered copy) is current while
                         this stays the same */
} sr_point_grid_view;

typedef struct sr_point_grid sr_point_grid;

/** Creates a point grid builder on `ctx`: compiles its program and creates
 *  its kernels once. */
sluice_status sr_point_grid_create(sluice_context *ctx, sr_point_grid **out);

/** Frees the builder and its streams (NULL is fine). */
void sr_point_grid_destroy(sr_point_grid *g);

/** Builds now the kernels of the stream algorithms that builds of `kind`
 *  use (sluice_streams_prepare), so that the first build does not pay for
 *  them: setup, not a build's time. */
sluice_status sr_point_grid_prepare(sr_point_grid *g, sr_point_grid_build_kind kind);

/**
 * (Re)builds the grid described by `desc` (see rt_grid_desc_check for what a
 * description must satisfy) over the first `n` records of `points`, whose
 * records are `stride` bytes and start with 3 floats (x, y, z): a pm_photon
 * stream can be passed as it is. `slots` is the stencil build's places per
 * cell (1 .. SR_POINT_GRID_MAX_SLOTS; ignored by the others). Waits for the
 * build (it reads back its counters). Errors: SLUICE_ERROR_INVALID_ARGUMENT
 * for NULL arguments, a stride that is not a multiple of 4 or below 12 or
 * not the stream's record size, n above the stream's length, a bad
 * description, an unknown kind or bad slots; SLUICE_ERROR_LIMIT for n above
 * SR_POINT_GRID_MAX_POINTS or a stencil footprint above
 * SR_POINT_GRID_MAX_FOOTPRINT; the runtime's errors otherwise. On failure
 * the previous grid is gone (the view is empty) and sr_point_grid_error
 * says why.
 */
sluice_status sr_point_grid_build(sr_point_grid *g, const rt_grid_desc *desc, sluice_stream *points,
                                  size_t stride, size_t n, sr_point_grid_build_kind kind,
                                  uint32_t slots);

/**
 * (Re)builds the grid in the hashed layout `desc` over the first `n` records
 * of `points` (as sr_point_grid_build): the same count and bitonic builds
 * over bucket ids instead of cell ids, so the view lists each bucket's points
 * in ascending index order. The stencil build is refused
 * (SLUICE_ERROR_INVALID_ARGUMENT): its power redistribution scales a cell's
 * stored points by the cell's arrivals, and a bucket mixes cells (Purcell
 * 6.4.4 names this problem). Other errors as sr_point_grid_build, and
 * SLUICE_ERROR_INVALID_ARGUMENT for a bad description (cell not finite or
 * not positive, lo not finite, buckets not a power of two, 0 or above
 * SR_POINT_HASH_MAX_BUCKETS). On failure the previous grid is gone.
 */
sluice_status sr_point_grid_build_hashed(sr_point_grid *g, const sr_point_hash_desc *desc,
                                         sluice_stream *points, size_t stride, size_t n,
                                         sr_point_grid_build_kind kind);

/** The grid of the last successful build (all zero before one). */
sluice_status sr_point_grid_get(const sr_point_grid *g, sr_point_grid_view *view);

/** Statistics of the last build (occupancy and the largest cell are read
 *  back at the build). */
sluice_status sr_point_grid_statistics(const sr_point_grid *g, sr_point_grid_stats *stats);

/** Why the last call failed ("" after a success). */
const char *sr_point_grid_error(const sr_point_grid *g);

/** The cell of a point by the same arithmetic as the device builds
 *  (kernels/render/pg_types.h): the C reference of the tests. Returns the
 *  cell count for a point with a non-finite coordinate. `desc` is trusted
 *  (rt_grid_desc_check). */
uint32_t sr_point_grid_cell_of(const rt_grid_desc *desc, const float p[3]);

/** The bucket of a point by the same arithmetic as the device build
 *  (pg_hash_point in kernels/render/pg_types.h): the C reference of the
 *  tests. Returns desc->buckets for a point with a non-finite coordinate.
 *  `desc` is trusted. `coords` (may be NULL) receives the point's lattice
 *  cell (zeros for a non-finite point). */
uint32_t sr_point_grid_bucket_of(const sr_point_hash_desc *desc, const float p[3],
                                 uint32_t coords[3]);

/**
 * A hashed layout over the points' bounds [lo, hi] for searches of radius
 * `radius` (> 0): cubes of edge SR_POINT_HASH_EDGE * radius, grown where
 * the box would be more than SR_POINT_HASH_MAX_SIDE cells across; the lattice starts
 * at lo; SR_POINT_HASH_BUCKETS_PER_POINT buckets per point rounded up to a
 * power of two, at least 64 and at most SR_POINT_HASH_MAX_BUCKETS. Errors:
 * non-finite bounds or radius, radius <= 0, lo > hi:
 * SLUICE_ERROR_INVALID_ARGUMENT.
 */
sluice_status sr_point_hash_desc_auto(const float lo[3], const float hi[3], size_t points,
                                      float radius, sr_point_hash_desc *out, char *err,
                                      size_t err_size);

/** What sr_point_grid_plan_auto chose, and why. */
typedef struct sr_point_grid_plan {
    sr_point_grid_layout layout; /**< SR_POINT_GRID_DENSE or SR_POINT_GRID_HASHED */
    rt_grid_desc dense;          /**< the dense grid (always filled) */
    sr_point_hash_desc hash;     /**< the hashed layout (always filled) */
    double coarsening;           /**< dense cell edge over the edge aimed at (1: as aimed) */
    double wanted_cells;         /**< cells a dense grid at the edge aimed at would have */
    char why[256];               /**< one line: the choice and its reason */
} sr_point_grid_plan;

/**
 * Chooses the layout for points in [lo, hi]: the dense grid of
 * sr_point_grid_desc_auto(lo, hi, points, dense_radius) and the hashed
 * layout of sr_point_hash_desc_auto(lo, hi, points, search_radius) are both
 * made, and `request` picks one: SR_POINT_GRID_DENSE, SR_POINT_GRID_HASHED,
 * or SR_POINT_GRID_LAYOUT_AUTO, which takes the hash: in the progressive
 * photon mapper the hash's radius search was faster than the dense grid's
 * on every scene measured, most where the dense grid's cap on cells makes
 * its cells coarser than aimed at, but also where they fit
 * (bench/README.md). Only a search that can read a hashed grid should ask
 * for it or for auto (the kNN search's radius mode). `why` says which and
 * why, with the dense grid's figures.
 * Errors as the two helpers, and an unknown request
 * (SLUICE_ERROR_INVALID_ARGUMENT).
 */
sluice_status sr_point_grid_plan_auto(const float lo[3], const float hi[3], size_t points,
                                      float dense_radius, float search_radius,
                                      sr_point_grid_layout request, sr_point_grid_plan *out,
                                      char *err, size_t err_size);

/**
 * A grid over the points' bounds [lo, hi] for searches of radius `radius`
 * (> 0): cubic cells of edge SR_POINT_GRID_AUTO_EDGE * radius, made coarser
 * where the grid would have more than SR_POINT_GRID_AUTO_MAX_CELLS cells or
 * more than SR_POINT_GRID_AUTO_CELLS_PER_POINT per point (at least 64). The
 * box is padded as rt_grid_choose pads it (a flat axis gets one cell) and
 * stretched about its centre to whole cells. Errors: non-finite bounds or
 * radius, radius <= 0, lo > hi: SLUICE_ERROR_INVALID_ARGUMENT.
 */
sluice_status sr_point_grid_desc_auto(const float lo[3], const float hi[3], size_t points,
                                      float radius, rt_grid_desc *out, char *err, size_t err_size);

/**
 * A grid of exactly dims[0] x dims[1] x dims[2] cells over [lo, hi] (e.g.
 * Purcell's 250x1x250 and 25x25x50): cell = (hi - lo) / dims. An axis of zero
 * extent is padded to a positive one. Errors as rt_grid_desc_check, and
 * non-finite bounds or lo > hi.
 */
sluice_status sr_point_grid_desc_dims(const float lo[3], const float hi[3], const uint32_t dims[3],
                                      rt_grid_desc *out, char *err, size_t err_size);

#endif /* SLUICE_SR_POINT_GRID_H */
