/*
 * The kNN-grid radiance estimate (Purcell, thesis 6.2.3, Fig. 6.6): a
 * variant of Elias's search (Cleary 1979) over the uniform point grid
 * (apps/render/point_grid.h). Cells are explored in concentric shells
 * around the query's cell, one shell per pass; a query that is done leaves
 * the stream of live queries, so a pass costs only the queries still
 * searching (Purcell 6.3.3 and 6.4.3: his tiles and occlusion queries; here
 * a sluice_loop watching the live stream's length). Shells without photons
 * are jumped over (a summed-count table over the cells tells); shells that
 * the same table says cannot bring a query to k photons are swept as one
 * box, row by row, since every photon they hold that passes is taken in any
 * order; and once a query holds k photons the rest of its search, a radius
 * search then, sweeps every cell left within its radius in one step, row by
 * row, instead of shell after shell: all three change the number of passes,
 * never the photons of the estimate (the sweeps can change the order of the
 * power sums: the last bits). Queries are taken in the order of their cells (sorted per call), so
 * that consecutive ones read the same photons from cache. With every shell in one pass
 * (PM_KNN_ALL_SHELLS, at-least mode) the queries of one cell search side by side up to their k-th
 * photons, whose radius is then fixed, and every photon within it is summed 16 queries at a time:
 * each photon is read once for the queries beside it, and the estimates are the same.
 *
 * Modes:
 *   PM_KNN_ATLEAST  Purcell's rule. A photon beyond the maximum radius is
 *                   rejected; while fewer than k are in the estimate every
 *                   photon examined is added and the radius grows to take it
 *                   in; once k are in, the radius is frozen and only photons
 *                   inside it are added. Done when (count >= k and the
 *                   explored cube's inscribed radius d_s >= the radius), or
 *                   d_s >= the maximum radius, or the shells cover the grid.
 *                   The estimate is then exactly the photons within its
 *                   radius: at least min(k, photons within the maximum
 *                   radius) of them.
 *   PM_KNN_EXACT    Jensen's k nearest: a max-heap of k (distance, photon)
 *                   per query; done when the heap is full and d_s >= its
 *                   largest distance, or d_s >= the maximum radius, or the
 *                   shells cover the grid. The radius is the k-th distance.
 *                   The heaps take 8 k bytes per query; queries run in
 *                   batches of at most PM_KNN_EXACT_HEAP_BYTES of heaps.
 *
 * A hashed point grid (sr_point_grid_build_hashed; Purcell 6.4.4) serves
 * the radius mode only: each query looks up, in one pass, the lattice cells
 * its sphere overlaps (about 3 across each axis with cells of the radius,
 * as sr_point_hash_desc_auto makes them; cells much finer than the radius
 * make many lookups) and skips the photons of other cells that share a
 * bucket. It finds exactly the photons the dense grid's radius mode finds
 * (the same distance test, the same r2; only the order of the power sums
 * differs). The k-nearest modes need the dense grid: their radius is not
 * known before the search, so no cell size can be chosen for it, and their
 * shells are bounded and jumped over by the dense grid's summed counts,
 * which a table of buckets has no counterpart of.
 *
 * Photons are pm_photon records (kernels/photonmap/pm_types.h); the grid
 * must have been built over that stream (stride 40). Each photon's power is
 * scaled by its cell's arrived / stored count, Purcell's power
 * redistribution for the stencil build (exactly 1 for the other builds).
 * d_s is shrunk by a small margin (see pm_knn_params.margin) so that float
 * rounding in the cell function can only cost an extra shell, never a
 * photon.
 */
#ifndef SLUICE_PM_KNN_H
#define SLUICE_PM_KNN_H

#include "point_grid.h"
#include "sluice/sluice.h"

#include "../../kernels/render/rt_types.h"
#include "../../kernels/photonmap/pm_types.h"

#include <stddef.h>
#include <stdint.h>

/** The search's rule. */
typedef enum pm_knn_mode {
    PM_KNN_ATLEAST = 0, /**< Purcell's kNN-grid: all photons within the final radius */
    PM_KNN_EXACT = 1,   /**< Jensen's k nearest (max-heap) */
    PM_KNN_RADIUS = 2   /**< every photon within max_radius (k is not read):
                             progressive photon mapping's search */
} pm_knn_mode;

/** Most photons sought per query. */
#define PM_KNN_MAX_K (1u << 20)

/** Most bytes of heaps the exact mode holds at once (64 MiB): queries run in
 *  batches of 64 MiB / (8 k). */
#define PM_KNN_EXACT_HEAP_BYTES ((size_t)64 << 20)

/** Passes recorded per call in pm_knn_stats.live (the first ones). */
#define PM_KNN_STATS_PASSES 64

/**
 * Called after every pass (Purcell 6.3.4: intermediate results). Results
 * [0, answered) are current (answered is the call's n: every result is
 * zeroed before the first pass, and a batch takes its queries from all over
 * the input): a query still searching holds the photons found so far and, in atleast mode, the
 * radius that takes them in (exact mode sums its heap only when the query is done). `pass` counts
 * the passes of the call over all batches, from 0. A non-OK return stops the search with that
 * status.
 */
typedef sluice_status (*pm_knn_pass_fn)(void *user, unsigned pass, size_t answered);

/** What to search for. */
typedef struct pm_knn_options {
    uint32_t k;             /**< photons sought (1 .. PM_KNN_MAX_K; radius mode: unused) */
    float max_radius;       /**< photons farther than this are never used (> 0, may be INFINITY) */
    pm_knn_mode mode;       /**< PM_KNN_ATLEAST, PM_KNN_EXACT or PM_KNN_RADIUS */
    int normal_filter;      /**< non-zero: only photons arriving on the side the
                                 query's normal faces (dot(n, d) < 0) */
    pm_knn_pass_fn on_pass; /**< NULL, or called after every pass */
    void *on_pass_user;     /**< passed to on_pass */
    uint32_t shells_per_pass; /**< shells holding photons each pass explores per
                                   query: 0 or 1 (Purcell's one), N, or
                                   PM_KNN_ALL_SHELLS (one pass: the search runs
                                   to its end in one launch; in at-least mode
                                   the same photons, radius and count as with
                                   one shell a pass, the power summed in
                                   another order) */
} pm_knn_options;

/** pm_knn_options.shells_per_pass: every shell in one pass. */
#define PM_KNN_ALL_SHELLS UINT32_MAX

/** Statistics of the last query call. */
typedef struct pm_knn_stats {
    size_t queries;                     /**< queries answered */
    unsigned passes;                    /**< passes over all batches */
    unsigned batches;                   /**< batches (1 unless exact mode splits) */
    uint32_t live[PM_KNN_STATS_PASSES]; /**< live queries after pass i (summed over batches) */
    double mean_count;                  /**< photons per estimate */
    double mean_radius;                 /**< sqrt(r2) per estimate with photons */
    size_t hit_max_radius;              /**< queries flagged PM_KNN_HIT_MAX_RADIUS */
    size_t empty;                       /**< queries that found no photon */
    double seconds;                     /**< host wall time of the call, waited for */
} pm_knn_stats;

typedef struct pm_knn pm_knn;

/** Creates the search on `ctx`: its program, kernels and loop, kept for
 *  every call. */
sluice_status pm_knn_create(sluice_context *ctx, pm_knn **out);

/** Frees the search and its scratch (NULL is fine). */
void pm_knn_destroy(pm_knn *knn);

/**
 * Answers the first `n` queries of `queries` (pm_query records) against
 * the photons of `photons` (pm_photon records, the stream `grid` was last
 * built over) into results[0 .. n) (pm_knn_result records; capacity >= n;
 * length set to n). Waits for the answer. `stats` may be NULL (otherwise the
 * results are read back to fill it). Over a hashed grid the search is one
 * pass (on_pass is called once, with every result final), each result's
 * `shells` holds the cells it looked up, and its flags are PM_KNN_DONE |
 * PM_KNN_HIT_MAX_RADIUS. Errors: SLUICE_ERROR_INVALID_ARGUMENT for NULL
 * arguments, wrong record sizes, n above a stream's length or the results'
 * capacity, a grid not built or built over fewer photons than it lists, bad
 * options, a hashed grid with a mode other than PM_KNN_RADIUS or an
 * infinite max_radius; the runtime's errors otherwise. pm_knn_error says
 * why.
 *
 * The search reads the photons through a copy in cell order that it makes
 * once per build of the grid: later calls with the same grid, unchanged
 * since (sr_point_grid_view.build), and the same photon stream reuse it (a
 * frame's waves of queries, the samples of a map traced once). Photons
 * changed in place must be followed by a new build of the grid.
 */
sluice_status pm_knn_query(pm_knn *knn, const sr_point_grid *grid, sluice_stream *photons,
                           sluice_stream *queries, size_t n, sluice_stream *results,
                           const pm_knn_options *options, pm_knn_stats *stats);

/**
 * pm_knn_query that also lists, per query, the photon indices of its
 * estimate (a debug path for tests against other kNN libraries): query q's
 * are indices[q * cap .. q * cap + min(count, cap)) (uint32 records,
 * capacity >= n * cap; length set to n * cap), in the order they were added
 * (atleast) or heap order (exact). A query with more than `cap` gets
 * PM_KNN_INDICES_CUT. cap >= 1.
 */
sluice_status pm_knn_query_indices(pm_knn *knn, const sr_point_grid *grid, sluice_stream *photons,
                                   sluice_stream *queries, size_t n, sluice_stream *results,
                                   const pm_knn_options *options, sluice_stream *indices,
                                   uint32_t cap, pm_knn_stats *stats);

/** Why the last call failed ("" after a success). */
const char *pm_knn_error(const pm_knn *knn);

#endif /* SLUICE_PM_KNN_H */
