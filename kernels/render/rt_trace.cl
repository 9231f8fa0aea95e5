/*
 * rt_trace.cl: the math of grid traversal and ray-triangle intersection that
 * both execution modes run (one copy, so `stream` and `fused` find the same
 * hits): Purcell's traverser and intersector (thesis ch. 3.2, Fig. 3.1 and
 * 3.2), written as inline functions over one ray.
 *
 * Build options read here:
 *   RT_WATERTIGHT   use the watertight intersector of Woop, Benthin and Wald
 *                   (JCGT 2013) instead of Moller-Trumbore.
 *
 * Floating point: contraction into fused multiply-adds is off, so every
 * kernel (and the plain C references in the tests and the benchmark) rounds
 * the same way. The Moller-Trumbore test does use fused multiply-adds, but
 * written out with fma() at fixed places (rt_cross, rt_dot here, the same
 * order in rt_lanes.cl and in apps/render/mt_ref.h), so the rounding is
 * still the same everywhere: 12 of its 27 multiplies fold into an add, which
 * made the fused mode 7% (cornell) and 20% (bunny) faster (512x512 primary
 * rays, one process) and rounds once where it rounded twice.
 *
 * Triangle records (`tv`, 9 floats per triangle, de-indexed by the tracer):
 * for Moller-Trumbore (v0, e1 = v1 - v0, e2 = v2 - v0), the edges computed
 * once on the host with the same float subtraction the test would do, so
 * the hits are unchanged and every test saves six subtractions and the
 * shuffles around them (fused mode: 5-14% faster, 512x512 primary rays); for
 * the watertight test (v0, v1, v2), whose no-leak guarantee needs the
 * vertices exactly (v0 + e1 need not round to v1). rt_tri_edges reads
 * either.
 */
#include "sluice.cl"

#pragma OPENCL FP_CONTRACT OFF

/* A ray ready for traversal and intersection (private memory). */
typedef struct rt_rayp {
    float3 o, d;
    float3 inv; /* 1 / d; 0 where d is 0 (those axes are never stepped) */
    float tmin, tmax;
    uint any_hit;
#ifdef RT_WATERTIGHT
    int kx, ky, kz;   /* axis permutation: kz the dominant axis of d */
    float sx, sy, sz; /* shear constants */
#endif
} rt_rayp;

/* The nearest hit found so far. */
typedef struct rt_best {
    uint tri;
    float t, u, v;
} rt_best;

inline float rt_comp(float3 a, int k)
{
    return k == 0 ? a.x : (k == 1 ? a.y : a.z);
}

/* a x b, each component as fma(a_i, b_j, -(a_j b_i)) (see the top). */
inline float3 rt_cross(float3 a, float3 b)
{
    return (float3)(fma(a.y, b.z, -(a.z * b.y)), fma(a.z, b.x, -(a.x * b.z)),
                    fma(a.x, b.y, -(a.y * b.x)));
}

/* a . b as fma(a.z, b.z, fma(a.y, b.y, a.x b.x)) (see the top). */
inline float rt_dot(float3 a, float3 b)
{
    return fma(a.z, b.z, fma(a.y, b.y, a.x * b.x));
}

inline rt_rayp rt_prepare(global const rt_ray *ray)
{
    rt_rayp r;
    r.o = (float3)(ray->ox, ray->oy, ray->oz);
    r.d = (float3)(ray->dx, ray->dy, ray->dz);
    r.inv =
        (float3)(ray->dx != 0.0f ? 1.0f / ray->dx : 0.0f, ray->dy != 0.0f ? 1.0f / ray->dy : 0.0f,
                 ray->dz != 0.0f ? 1.0f / ray->dz : 0.0f);
    r.tmin = ray->tmin;
    r.tmax = ray->tmax;
    r.any_hit = (ray->flags & RT_FLAG_ANY_HIT) != 0u;
#ifdef RT_WATERTIGHT
    /* Woop et al. 2013, section 3: translate to the origin, permute so that
     * the largest component of d is z (keeping the winding), then shear so
     * that the ray becomes the +z axis. */
    float3 ad = fabs(r.d);
    int kz = (ad.x >= ad.y && ad.x >= ad.z) ? 0 : (ad.y >= ad.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (rt_comp(r.d, kz) < 0.0f) {
        int s = kx;
        kx = ky;
        ky = s;
    }
    r.kx = kx;
    r.ky = ky;
    r.kz = kz;
    float dz = rt_comp(r.d, kz);
    r.sx = rt_comp(r.d, kx) / dz;
    r.sy = rt_comp(r.d, ky) / dz;
    r.sz = 1.0f / dz;
#endif
    return r;
}

/* ------------------------------------------------------------------ */
/* 3D-DDA over the uniform grid (Amanatides and Woo 1987; Purcell 3.2)  */
/* ------------------------------------------------------------------ */

/* Clips the ray's segment to the grid's box. Writes the entry voxel and
 * returns 1 when the ray meets the box, 0 when it misses (done at once). */
inline int rt_grid_enter(const rt_grid_args *g, const rt_rayp *r, int3 *cell)
{
    float t0 = r->tmin, t1 = r->tmax;
    float o[3] = {r->o.x, r->o.y, r->o.z}, d[3] = {r->d.x, r->d.y, r->d.z};
    float inv[3] = {r->inv.x, r->inv.y, r->inv.z};
    for (int k = 0; k < 3; ++k) {
        if (d[k] == 0.0f) {
            /* parallel to the slab: inside it for every t, or never */
            if (o[k] < g->lo[k] || o[k] > g->hi[k])
                return 0;
            continue;
        }
        float ta = (g->lo[k] - o[k]) * inv[k], tb = (g->hi[k] - o[k]) * inv[k];
        t0 = fmax(t0, fmin(ta, tb));
        t1 = fmin(t1, fmax(ta, tb));
    }
    if (!(t0 <= t1))
        return 0;
    int c[3];
    for (int k = 0; k < 3; ++k) {
        float p = o[k] + d[k] * t0;
        int v = (int)floor((p - g->lo[k]) * g->inv_cell[k]);
        c[k] = clamp(v, 0, g->dims[k] - 1);
    }
    *cell = (int3)(c[0], c[1], c[2]);
    return 1;
}

/* The ray parameter where the ray leaves voxel `c`, and the axis it leaves
 * through (ties: x before y before z). Computed from the voxel's index, not
 * accumulated step by step, so both execution modes (and every pass of the
 * stream mode) get exactly the same value. */
inline float rt_voxel_exit(const rt_grid_args *g, const rt_rayp *r, int3 c, int *axis)
{
    float bx = g->lo[0] + (float)(c.x + (r->d.x > 0.0f)) * g->cell[0];
    float by = g->lo[1] + (float)(c.y + (r->d.y > 0.0f)) * g->cell[1];
    float bz = g->lo[2] + (float)(c.z + (r->d.z > 0.0f)) * g->cell[2];
    float tx = r->d.x != 0.0f ? (bx - r->o.x) * r->inv.x : INFINITY;
    float ty = r->d.y != 0.0f ? (by - r->o.y) * r->inv.y : INFINITY;
    float tz = r->d.z != 0.0f ? (bz - r->o.z) * r->inv.z : INFINITY;
    int a = 0;
    float t = tx;
    if (ty < t) {
        t = ty;
        a = 1;
    }
    if (tz < t) {
        t = tz;
        a = 2;
    }
    *axis = a;
    return t;
}

/* One step of the DDA: into the neighbour through face `axis`. Returns 0 when
 * that leaves the grid. */
inline int rt_voxel_step(const rt_grid_args *g, const rt_rayp *r, int3 *c, int axis)
{
    if (axis == 0) {
        c->x += r->d.x > 0.0f ? 1 : -1;
        return c->x >= 0 && c->x < g->dims[0];
    }
    if (axis == 1) {
        c->y += r->d.y > 0.0f ? 1 : -1;
        return c->y >= 0 && c->y < g->dims[1];
    }
    c->z += r->d.z > 0.0f ? 1 : -1;
    return c->z >= 0 && c->z < g->dims[2];
}

inline uint rt_cell_index(const rt_grid_args *g, int3 c)
{
    return (uint)c.x + (uint)g->dims[0] * ((uint)c.y + (uint)g->dims[1] * (uint)c.z);
}

/* How far along the ray a hit may lie to count in the current voxel: its exit
 * (with a relative slack of about 8 ulps, so that a hit exactly on the face
 * is not lost to rounding between the two computations of that face), and
 * never past the ray's own end. */
inline float rt_voxel_limit(float t_exit, float tmax)
{
    return fmin(t_exit + fabs(t_exit) * 1e-6f, tmax);
}

/* rt_voxel_limit in 16 lanes (the fused mode's packets). */
inline float16 rt_voxel_limit16(float16 t_exit, float16 tmax)
{
    return fmin(t_exit + fabs(t_exit) * 1e-6f, tmax);
}

/* ------------------------------------------------------------------ */
/* Ray-triangle intersection                                           */
/* ------------------------------------------------------------------ */

/* Tests triangle `tri` (from the triangle records, 9 floats per triangle)
 * and keeps it in `best` when it is hit in [tmin, limit] and nearer than
 * what `best` holds. Two-sided. */
inline void rt_intersect_tri(global const float *tv, uint tri, const rt_rayp *r, float limit,
                             rt_best *best)
{
    global const float *p = tv + 9u * (size_t)tri;
#ifndef RT_WATERTIGHT
    /* Moller and Trumbore 1997: the barycentrics and t by Cramer's rule, as
     * in Purcell's intersector (Fig. 3.2), with the edges from the record. */
    float3 v0 = vload3(0, p), e1 = vload3(1, p), e2 = vload3(2, p);
    float3 pv = rt_cross(r->d, e2);
    float det = rt_dot(e1, pv);
    if (det == 0.0f)
        return;
    float inv = 1.0f / det;
    float3 s = r->o - v0;
    float u = rt_dot(s, pv) * inv;
    if (u < 0.0f || u > 1.0f)
        return;
    float3 q = rt_cross(s, e1);
    float v = rt_dot(r->d, q) * inv;
    if (v < 0.0f || u + v > 1.0f)
        return;
    float t = rt_dot(e2, q) * inv;
    if (t >= r->tmin && t <= limit && t < best->t) {
        best->tri = tri;
        best->t = t;
        best->u = u;
        best->v = v;
    }
#else
    float3 v0 = vload3(0, p), v1 = vload3(1, p), v2 = vload3(2, p);
    /* Woop, Benthin and Wald 2013: edge functions of the sheared triangle.
     * An edge shared by two triangles gives the same value (with opposite
     * sign) in both, so a ray through it hits at least one: no leaks. */
    float3 a = v0 - r->o, b = v1 - r->o, c = v2 - r->o;
    float az = rt_comp(a, r->kz), bz = rt_comp(b, r->kz), cz = rt_comp(c, r->kz);
    float ax = rt_comp(a, r->kx) - r->sx * az, ay = rt_comp(a, r->ky) - r->sy * az;
    float bx = rt_comp(b, r->kx) - r->sx * bz, by = rt_comp(b, r->ky) - r->sy * bz;
    float cx = rt_comp(c, r->kx) - r->sx * cz, cy = rt_comp(c, r->ky) - r->sy * cz;
    float U = cx * by - cy * bx, V = ax * cy - ay * cx, W = bx * ay - by * ax;
#ifdef cl_khr_fp64
    if (U == 0.0f || V == 0.0f || W == 0.0f) {
        /* on an edge to float precision: decide in double (section 4.2) */
        U = (float)((double)cx * (double)by - (double)cy * (double)bx);
        V = (float)((double)ax * (double)cy - (double)ay * (double)cx);
        W = (float)((double)bx * (double)ay - (double)by * (double)ax);
    }
#endif
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f))
        return;
    float det = U + V + W;
    if (det == 0.0f)
        return;
    float T = U * (r->sz * az) + V * (r->sz * bz) + W * (r->sz * cz);
    float inv = 1.0f / det;
    float t = T * inv;
    if (t >= r->tmin && t <= limit && t < best->t) {
        best->tri = tri;
        best->t = t;
        best->u = V * inv;
        best->v = W * inv;
    }
#endif
}

/* Tests the triangles cell_tris[from, to) of one voxel. */
inline void rt_intersect_list(global const uint *cell_tris, global const float *tv, uint from,
                              uint to, const rt_rayp *r, float limit, rt_best *best)
{
    for (uint k = from; k < to; ++k)
        rt_intersect_tri(tv, cell_tris[k], r, limit, best);
}

/* A ray is done: keep the largest per-ray step and test counts (Purcell's
 * Table 5.2 maxima), read first, so that the atomic is rare. */
inline void rt_maxima_add(global uint *maxima, uint steps, uint tests)
{
    if (steps > maxima[0])
        atomic_max(&maxima[0], steps);
    if (tests > maxima[1])
        atomic_max(&maxima[1], tests);
}

/* Writes the final hit of a ray and keeps the largest per-ray step and test
 * counts in maxima[0] and maxima[1] (read first, so the atomic is rare). */
inline void rt_finish_hit(global rt_hit *hits, uint ray, const rt_best *best, uint steps,
                          uint tests, global uint *maxima)
{
    rt_hit h;
    h.tri = best->tri;
    h.t = best->t;
    h.u = best->u;
    h.v = best->v;
    h.steps = steps;
    h.tests = tests;
    hits[ray] = h;
    rt_maxima_add(maxima, steps, tests);
}

inline rt_best rt_no_hit(const rt_rayp *r)
{
    rt_best b;
    b.tri = RT_NO_HIT;
    b.t = r->tmax;
    b.u = 0.0f;
    b.v = 0.0f;
    return b;
}
