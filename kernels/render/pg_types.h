/*
 * The uniform point grid (apps/render/point_grid.h) as the kernels see it,
 * shared by the host (C11) and the kernels (OpenCL C 1.2): the grid's
 * description passed by value, and the one function that puts a point in a
 * cell. The host's reference (sr_point_grid_cell_of) and every kernel that
 * bins or searches points (point_grid.cl, kernels/photonmap/pm_knn.cl) call
 * this same text, so a point lands in the same cell bit for bit: only float
 * subtraction and multiplication (correctly rounded in both languages, no
 * division), with contraction into fused multiply-adds off on both sides.
 *
 * Needs rt_types.h (rt_u32) first.
 */
#ifndef SLUICE_PG_TYPES_H
#define SLUICE_PG_TYPES_H

#ifdef __OPENCL_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#define PG_FN static inline
#else
#define PG_FN static inline
#endif

/** The grid as the kernels need it (4-byte fields only). */
typedef struct pg_params {
    float lo[3];       /**< low corner of the box the cells tile */
    float cell[3];     /**< cell edge per axis */
    float inv_cell[3]; /**< 1 / cell, computed once on the host */
    rt_u32 dims[3];    /**< cells per axis */
    rt_u32 cells;      /**< dims[0] * dims[1] * dims[2]; also the key of a dropped point */
    rt_u32 stride;     /**< floats per point record (position in the first 3) */
    rt_u32 slots;      /**< stencil build: places per cell (0 for the compact builds) */
} pg_params;

/** Non-zero when x is finite (x - x is NaN for an infinity or a NaN). */
PG_FN int pg_finite(float x)
{
    return x - x == 0.0f;
}

/** The cell coordinate of x along an axis of n cells, clamped into [0, n-1]
 *  (points outside the box belong to the nearest boundary cell). */
PG_FN rt_u32 pg_axis(float x, float lo, float inv_cell, rt_u32 n)
{
    float f = (x - lo) * inv_cell;
    if (!(f > 0.0f))
        return 0u;
    if (f >= (float)(n - 1u))
        return n - 1u;
    return (rt_u32)f; /* truncation is floor for f > 0 */
}

/** The cell c = x + nx * (y + ny * z) of the point (px, py, pz), or
 *  g->cells when a coordinate is not finite (such points are dropped). */
PG_FN rt_u32 pg_cell(float px, float py, float pz, const pg_params *g)
{
    if (!pg_finite(px) || !pg_finite(py) || !pg_finite(pz))
        return g->cells;
    rt_u32 x = pg_axis(px, g->lo[0], g->inv_cell[0], g->dims[0]);
    rt_u32 y = pg_axis(py, g->lo[1], g->inv_cell[1], g->dims[1]);
    rt_u32 z = pg_axis(pz, g->lo[2], g->inv_cell[2], g->dims[2]);
    return x + g->dims[0] * (y + g->dims[1] * z);
}

/*
 * The hashed layout (Purcell 6.4.4, after Wald et al. 2002): cell
 * (ix, iy, iz) of an unbounded lattice of cubes of edge `cell` from `lo` is
 * bucket pg_hash_bucket(ix, iy, iz) of a table of a power-of-two size, so
 * only the cells that hold photons cost memory. Coordinates are clamped into
 * [0, PG_HASH_MAX_COORD] (a point beyond belongs to the boundary cell, as in
 * the dense grid): integer conversion stays defined, and
 * (x - lo) / cell stays within 2^22, where float rounding misplaces a point
 * by far less than a cell. Every point of one cell lands in one bucket; a
 * bucket may hold several cells (collisions), which the search tells apart
 * by recomputing each photon's cell with pg_hash_axis.
 */

/** Largest lattice coordinate of the hashed layout (2^22 - 1). */
#define PG_HASH_MAX_COORD 4194303u

/** The hashed layout as the kernels need it (4-byte fields only). */
typedef struct pg_hash_params {
    float lo[3];    /**< the lattice's origin: cell (0, 0, 0) starts here */
    float cell;     /**< cube edge */
    float inv_cell; /**< 1 / cell, computed once on the host */
    rt_u32 mask;    /**< buckets - 1 (the table is a power of two) */
    rt_u32 buckets; /**< also the key of a dropped (non-finite) point */
    rt_u32 stride;  /**< floats per point record (position in the first 3) */
} pg_hash_params;

/** The lattice coordinate of x along an axis, clamped into
 *  [0, PG_HASH_MAX_COORD]; monotone in x (a float subtraction and a
 *  multiplication by a positive constant, both correctly rounded). */
PG_FN rt_u32 pg_hash_axis(float x, float lo, float inv_cell)
{
    float f = (x - lo) * inv_cell;
    if (!(f > 0.0f))
        return 0u;
    if (f >= (float)PG_HASH_MAX_COORD)
        return PG_HASH_MAX_COORD;
    return (rt_u32)f; /* truncation is floor for f > 0 */
}

#ifdef __OPENCL_VERSION__
typedef ulong pg_u64;
#else
typedef uint64_t pg_u64;
#endif

/** The bucket of lattice cell (x, y, z): the 22-bit coordinates packed into
 *  one 64-bit key (no two cells share a key), mixed by the finalizer of
 *  Steele et al.'s SplitMix64 (every key bit reaches the low bits, which the
 *  mask keeps), so neighbouring cells scatter over the table. */
PG_FN rt_u32 pg_hash_bucket(rt_u32 x, rt_u32 y, rt_u32 z, rt_u32 mask)
{
    pg_u64 k = (pg_u64)x | ((pg_u64)y << 22) | ((pg_u64)z << 44);
    k = (k ^ (k >> 30)) * (pg_u64)0xbf58476d1ce4e5b9UL;
    k = (k ^ (k >> 27)) * (pg_u64)0x94d049bb133111ebUL;
    k ^= k >> 31;
    return (rt_u32)k & mask;
}

/** The bucket of the point (px, py, pz), or h->buckets when a coordinate is
 *  not finite (such points are dropped). */
PG_FN rt_u32 pg_hash_point(float px, float py, float pz, const pg_hash_params *h)
{
    if (!pg_finite(px) || !pg_finite(py) || !pg_finite(pz))
        return h->buckets;
    return pg_hash_bucket(pg_hash_axis(px, h->lo[0], h->inv_cell),
                          pg_hash_axis(py, h->lo[1], h->inv_cell),
                          pg_hash_axis(pz, h->lo[2], h->inv_cell), h->mask);
}

#endif /* SLUICE_PG_TYPES_H */
