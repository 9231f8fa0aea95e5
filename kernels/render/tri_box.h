/*
 * Triangle-voxel overlap for the uniform grid (Purcell 3.2, 5.2.1), written
 * once for both builds of the grid: grid_host.c includes this file as C, and
 * the device build prepends it to grid.cl as OpenCL C (sr_program_create).
 *
 * The test is the separating axis test of Akenine-Moeller ("Fast 3D
 * triangle-box overlap testing", 2001): a triangle and a box are disjoint
 * exactly when one of 13 axes separates their projections: the three box
 * face normals, the triangle's normal, and the nine cross products of a box
 * edge direction with a triangle edge. Touching counts as overlapping.
 *
 * Why both builds agree bit for bit: the code uses only +, -, * and
 * comparisons on float (no division, no square root, whose OpenCL precision
 * is looser than IEEE), in the same order on both sides, and contraction of
 * a*b+c into a fused multiply-add is off on both sides (it would round once
 * instead of twice). A C compiler that could contract or that evaluates
 * float in wider precision is refused below.
 *
 * Conservative voxels: every voxel is tested as its box enlarged on every
 * side by RT_GRID_EPS times its edge. A triangle that lies on a voxel face,
 * edge or corner, or misses a voxel by less than the rounding of the
 * arithmetic, is therefore listed in every voxel it touches; the tracer,
 * which decides in float arithmetic of its own which voxel a hit point is
 * in, finds it wherever rounding puts that point.
 */
#ifndef RT_TRI_BOX_H
#define RT_TRI_BOX_H

#ifdef __OPENCL_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#ifndef SLUICE_RT_TYPES_H /* the renderers' shared program has it already */
typedef uint rt_u32;
#endif
#define RT_ABS(x) fabs(x)
#define RT_FLOOR(x) floor(x)
#else
#include <float.h>
#include <math.h>
#include <stdint.h>
typedef uint32_t rt_u32;
#define RT_ABS(x) fabsf(x)
#define RT_FLOOR(x) floorf(x)
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__) && !defined(__STRICT_ANSI__) && defined(__FP_FAST_FMAF)
/* GCC contracts by default outside ISO C mode (-std=c11 turns it off). */
#error "tri_box.h must be compiled with -ffp-contract=off (or -std=c11)"
#endif
#if !defined(FLT_EVAL_METHOD) || FLT_EVAL_METHOD != 0
#error "tri_box.h needs float arithmetic evaluated in float (FLT_EVAL_METHOD 0)"
#endif
#endif

/* The qualifier of every function here: file-local and inlinable in both
 * languages (OpenCL C 1.2 accepts static functions). */
#define RT_FN static inline

/** Enlargement of each voxel on every side, as a fraction of its edge
 *  (0.2 %): well above the relative rounding error of the test for grids of
 *  up to a few thousand voxels along an axis, small enough that the few
 *  triangles listed in a neighbour by it cost nothing measurable. */
#define RT_GRID_EPS (1.0f / 512.0f)

/** What the voxel arithmetic needs of a grid (a kernel argument by value:
 *  4-byte fields only, so C and OpenCL C lay it out alike). */
typedef struct rt_grid_params {
    float lo[3];       /**< the grid's low corner */
    float cell[3];     /**< voxel edge per axis */
    float inv_cell[3]; /**< 1 / cell, only for first guesses (see rt_axis_range) */
    rt_u32 dims[3];    /**< voxels per axis */
} rt_grid_params;

/** A triangle prepared for many voxel tests: its corners, edges, normal and
 *  bounding box, computed once. `valid` is 0 when a coordinate is not
 *  finite (such a triangle overlaps nothing). Scalar fields rather than
 *  arrays: OpenCL compilers keep them in registers more readily. */
typedef struct rt_tri {
    float p0x, p0y, p0z, p1x, p1y, p1z, p2x, p2y, p2z; /**< corners */
    float e0x, e0y, e0z, e1x, e1y, e1z, e2x, e2y, e2z; /**< e0 = p1-p0, e1 = p2-p1, e2 = p0-p2 */
    float nx, ny, nz;    /**< e0 x e1 (zero for a degenerate triangle) */
    float nax, nay, naz; /**< |e0| x |e1|: the size of n's terms (rounding bound) */
    float bmin[3], bmax[3];
    int valid;
} rt_tri;

RT_FN float rt_tri_min3(float a, float b, float c)
{
    float m = a < b ? a : b;
    return m < c ? m : c;
}

RT_FN float rt_tri_max3(float a, float b, float c)
{
    float m = a > b ? a : b;
    return m > c ? m : c;
}

/** Centre of voxel `i` along an axis. Monotone in i (every step rounds
 *  monotonically), which rt_axis_range relies on. */
RT_FN float rt_voxel_center(float lo, float cell, rt_u32 i)
{
    return lo + ((float)i + 0.5f) * cell;
}

/** Half the edge of the enlarged voxel along an axis. */
RT_FN float rt_voxel_half(float cell)
{
    return cell * (0.5f + RT_GRID_EPS);
}

/** Non-zero when x is finite: x - x is 0 for a finite x and NaN for an
 *  infinity or a NaN. */
RT_FN int rt_finite(float x)
{
    return x - x == 0.0f;
}

/** Prepares triangle `t` from its corners (3 floats each). */
RT_FN void rt_tri_setup(rt_tri *t, const float *p0, const float *p1, const float *p2)
{
    t->p0x = p0[0];
    t->p0y = p0[1];
    t->p0z = p0[2];
    t->p1x = p1[0];
    t->p1y = p1[1];
    t->p1z = p1[2];
    t->p2x = p2[0];
    t->p2y = p2[1];
    t->p2z = p2[2];
    t->valid = rt_finite(t->p0x) & rt_finite(t->p0y) & rt_finite(t->p0z) & rt_finite(t->p1x) &
               rt_finite(t->p1y) & rt_finite(t->p1z) & rt_finite(t->p2x) & rt_finite(t->p2y) &
               rt_finite(t->p2z);
    t->e0x = t->p1x - t->p0x;
    t->e0y = t->p1y - t->p0y;
    t->e0z = t->p1z - t->p0z;
    t->e1x = t->p2x - t->p1x;
    t->e1y = t->p2y - t->p1y;
    t->e1z = t->p2z - t->p1z;
    t->e2x = t->p0x - t->p2x;
    t->e2y = t->p0y - t->p2y;
    t->e2z = t->p0z - t->p2z;
    t->nx = t->e0y * t->e1z - t->e0z * t->e1y;
    t->ny = t->e0z * t->e1x - t->e0x * t->e1z;
    t->nz = t->e0x * t->e1y - t->e0y * t->e1x;
    t->nax = RT_ABS(t->e0y * t->e1z) + RT_ABS(t->e0z * t->e1y);
    t->nay = RT_ABS(t->e0z * t->e1x) + RT_ABS(t->e0x * t->e1z);
    t->naz = RT_ABS(t->e0x * t->e1y) + RT_ABS(t->e0y * t->e1x);
    t->bmin[0] = rt_tri_min3(t->p0x, t->p1x, t->p2x);
    t->bmin[1] = rt_tri_min3(t->p0y, t->p1y, t->p2y);
    t->bmin[2] = rt_tri_min3(t->p0z, t->p1z, t->p2z);
    t->bmax[0] = rt_tri_max3(t->p0x, t->p1x, t->p2x);
    t->bmax[1] = rt_tri_max3(t->p0y, t->p1y, t->p2y);
    t->bmax[2] = rt_tri_max3(t->p0z, t->p1z, t->p2z);
}

/** The relative rounding bound of the projections below: 2^-21, eight
 *  times the unit roundoff of float (2^-24); each projection rounds at most
 *  four times (corner minus centre, two products, a difference). */
#define RT_TRI_BOX_ROUNDING (1.0f / 2097152.0f)

/* One projected interval test: the corners project to a, b, c and the box
 * to [-r, r]; 1 when they are disjoint. */
RT_FN int rt_separated(float a, float b, float c, float r)
{
    return rt_tri_min3(a, b, c) > r || rt_tri_max3(a, b, c) < -r;
}

/* The three axes (unit x) x e = (0, -ez, ey), (unit y) x e = (ez, 0, -ex)
 * and (unit z) x e = (-ey, ex, 0) of one triangle edge e; 1 when one of them
 * separates. All three corners are projected (two coincide in exact
 * arithmetic, not after rounding); m* are the largest corner distances per
 * axis, for the rounding bound. */
RT_FN int rt_edge_separates(float ex, float ey, float ez, float v0x, float v0y, float v0z,
                            float v1x, float v1y, float v1z, float v2x, float v2y, float v2z,
                            float hx, float hy, float hz, float mx, float my, float mz)
{
    float ax = RT_ABS(ex), ay = RT_ABS(ey), az = RT_ABS(ez);
    float r = hy * az + hz * ay;
    r = r + RT_TRI_BOX_ROUNDING * (ay * (mz + hz) + az * (my + hy));
    if (rt_separated(ey * v0z - ez * v0y, ey * v1z - ez * v1y, ey * v2z - ez * v2y, r))
        return 1;
    r = hx * az + hz * ax;
    r = r + RT_TRI_BOX_ROUNDING * (az * (mx + hx) + ax * (mz + hz));
    if (rt_separated(ez * v0x - ex * v0z, ez * v1x - ex * v1z, ez * v2x - ex * v2z, r))
        return 1;
    r = hx * ay + hy * ax;
    r = r + RT_TRI_BOX_ROUNDING * (ax * (my + hy) + ay * (mx + hx));
    return rt_separated(ex * v0y - ey * v0x, ex * v1y - ey * v1x, ex * v2y - ey * v2x, r);
}

/**
 * Non-zero when triangle `t` overlaps the box of centre `c` and half-size
 * `h` (closed sets: touching counts). The axes go cheapest first: box faces,
 * triangle plane, then the nine edge cross products.
 *
 * Rounding never separates: each projected interval is widened by a bound
 * on its rounding error (RT_TRI_BOX_ROUNDING times the sizes of the terms
 * that were rounded). That matters for slivers: the normal of a nearly
 * degenerate triangle is a difference of nearly equal products, as large as
 * its own rounding error, and a plane test that trusted it would cut the
 * triangle off voxels it runs through. The box-face tests need no widening:
 * a corner minus a centre rounds by a relative 2^-24, far inside the
 * voxel's enlargement by RT_GRID_EPS.
 */
RT_FN int rt_tri_box_overlap(const rt_tri *t, const float *c, const float *h)
{
    if (!t->valid)
        return 0;
    const float hx = h[0], hy = h[1], hz = h[2];
    /* The corners relative to the box centre. */
    const float v0x = t->p0x - c[0], v0y = t->p0y - c[1], v0z = t->p0z - c[2];
    const float v1x = t->p1x - c[0], v1y = t->p1y - c[1], v1z = t->p1z - c[2];
    const float v2x = t->p2x - c[0], v2y = t->p2y - c[1], v2z = t->p2z - c[2];
    /* Box face normals: the triangle's bounding box against the box. Since
     * x -> x - c rounds monotonically, min(v) here equals bmin - c as
     * rt_axis_range computes it, so both agree on every voxel. */
    if (rt_separated(v0x, v1x, v2x, hx) || rt_separated(v0y, v1y, v2y, hy) ||
        rt_separated(v0z, v1z, v2z, hz))
        return 0;
    /* Largest corner distance per axis, for the rounding bounds. */
    const float mx = rt_tri_max3(RT_ABS(v0x), RT_ABS(v1x), RT_ABS(v2x));
    const float my = rt_tri_max3(RT_ABS(v0y), RT_ABS(v1y), RT_ABS(v2y));
    const float mz = rt_tri_max3(RT_ABS(v0z), RT_ABS(v1z), RT_ABS(v2z));
    /* Triangle normal: the box projects onto n as [-r, r], the triangle as
     * the single value n . v0. The error of n's components is bounded by
     * na's (the sizes of their terms), which also bound |n|. */
    {
        float r = hx * RT_ABS(t->nx) + hy * RT_ABS(t->ny) + hz * RT_ABS(t->nz);
        float s = t->nx * v0x + t->ny * v0y + t->nz * v0z;
        float m = RT_TRI_BOX_ROUNDING * 2.0f *
                  (t->nax * (RT_ABS(v0x) + hx) + t->nay * (RT_ABS(v0y) + hy) +
                   t->naz * (RT_ABS(v0z) + hz));
        r = r + m;
        if (s > r || s < -r)
            return 0;
    }
    /* The nine edge cross products. */
    if (rt_edge_separates(t->e0x, t->e0y, t->e0z, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, hx,
                          hy, hz, mx, my, mz))
        return 0;
    if (rt_edge_separates(t->e1x, t->e1y, t->e1z, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, hx,
                          hy, hz, mx, my, mz))
        return 0;
    return !rt_edge_separates(t->e2x, t->e2y, t->e2z, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z,
                              hx, hy, hz, mx, my, mz);
}

#ifndef __OPENCL_VERSION__
/** Fills the kernel-side description of a grid (host only: the device gets
 *  the result as an argument, so both builds use the same inv_cell). */
RT_FN void rt_grid_params_make(rt_grid_params *g, const float *lo, const float *cell,
                               const rt_u32 *dims)
{
    for (int a = 0; a < 3; ++a) {
        g->lo[a] = lo[a];
        g->cell[a] = cell[a];
        g->inv_cell[a] = 1.0f / cell[a];
        g->dims[a] = dims[a];
    }
}
#endif

/** A first guess at the voxel holding coordinate x along an axis, clamped
 *  to [0, n-1]; rt_axis_range corrects it. */
RT_FN rt_u32 rt_voxel_guess(float x, float lo, float inv_cell, rt_u32 n)
{
    float f = (x - lo) * inv_cell; /* truncation is floor where it is used */
    if (!(f > 0.0f))
        return 0u;
    if (f >= (float)(n - 1u))
        return n - 1u;
    return (rt_u32)f;
}

/**
 * The voxels [*first, *last] along one axis (of n >= 1 voxels) whose
 * enlarged slab meets [bmin, bmax]: exactly those for which the box-face
 * part of rt_tri_box_overlap passes on this axis. Returns 0 when there are
 * none. "Voxel i is not wholly below bmin" holds from some i on and "not
 * wholly above bmax" up to some i, both monotone, so the range is found by
 * walking from a first guess to where each condition changes: a step or
 * two, and the same answer whatever the guess.
 */
RT_FN int rt_axis_range(float bmin, float bmax, float lo, float cell, float inv_cell, rt_u32 n,
                        rt_u32 *first, rt_u32 *last)
{
    float h = rt_voxel_half(cell);
    rt_u32 a = rt_voxel_guess(bmin, lo, inv_cell, n);
    while (a > 0u && !(bmin - rt_voxel_center(lo, cell, a - 1u) > h))
        --a;
    while (a < n - 1u && bmin - rt_voxel_center(lo, cell, a) > h)
        ++a;
    rt_u32 b = rt_voxel_guess(bmax, lo, inv_cell, n);
    while (b < n - 1u && !(bmax - rt_voxel_center(lo, cell, b + 1u) < -h))
        ++b;
    while (b > 0u && bmax - rt_voxel_center(lo, cell, b) < -h)
        --b;
    *first = a;
    *last = b;
    return a <= b && !(bmin - rt_voxel_center(lo, cell, a) > h) &&
           !(bmax - rt_voxel_center(lo, cell, b) < -h);
}

/**
 * rt_tri_box_overlap for the voxels of a triangle's range, with a shortcut
 * that gives the same answer: when the voxel is the only one in the range
 * (`alone`) and the triangle's bounding box lies well inside the box (within
 * 99 % of the half-size `h`), the triangle is inside the box with room to
 * spare, so the exact test passes, and the rounded test with it (its
 * rounding bounds only ever widen). Most triangles of a fine mesh lie in
 * one voxel; they skip the 13 axes.
 */
RT_FN int rt_tri_voxel_overlap(const rt_tri *t, const float *c, const float *h, int alone)
{
    if (alone && t->valid) {
        int inside = 1;
        for (int a = 0; a < 3; ++a) {
            float in = h[a] * 0.99f;
            inside &= (t->bmin[a] - c[a] >= -in) & (t->bmax[a] - c[a] <= in);
        }
        if (inside)
            return 1;
    }
    return rt_tri_box_overlap(t, c, h);
}

/** The voxel ranges of a prepared triangle on all three axes (`first` and
 *  `last` get 3 entries each); 0 when it misses the grid or is not valid. */
RT_FN int rt_tri_voxel_range(const rt_tri *t, const rt_grid_params *g, rt_u32 *first, rt_u32 *last)
{
    if (!t->valid)
        return 0;
    for (int a = 0; a < 3; ++a)
        if (!rt_axis_range(t->bmin[a], t->bmax[a], g->lo[a], g->cell[a], g->inv_cell[a], g->dims[a],
                           &first[a], &last[a]))
            return 0;
    return 1;
}

#endif /* RT_TRI_BOX_H */
