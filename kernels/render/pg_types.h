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

#endif /* SLUICE_PG_TYPES_H */
