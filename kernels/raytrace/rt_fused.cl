/*
 * rt_fused.cl: the `fused` execution mode. One kernel takes a ray all the way
 * through the grid, alternating traversal and intersection in a loop: the
 * MIMD form Purcell contrasts with the multipass form (thesis 4.1.2 and 5.2.2,
 * "branching"). It runs exactly the functions of rt_trace.cl, in the same
 * order as the stream mode's passes, so both find the same hits.
 * Counters: 0 voxels visited, 1 triangle tests, 2 rays finished.
 */

/* Traces one ray to its nearest hit (or, for a shadow ray, to any hit before
 * tmax). Returns the voxels visited and the triangles tested. */
inline void rt_trace_one(const rt_grid_args *g, global const uint *cell_start,
                         global const uint *cell_tris, global const float *tv, const rt_rayp *r,
                         rt_best *best, uint *steps_out, uint *tests_out)
{
    uint steps = 0u, tests = 0u;
    int3 c;
    if (rt_grid_enter(g, r, &c)) {
        for (;;) {
            ++steps;
            uint ci = rt_cell_index(g, c);
            uint a = cell_start[ci], b = cell_start[ci + 1u];
            int axis;
            float te = rt_voxel_exit(g, r, c, &axis);
            if (a < b) {
                tests += b - a;
                float limit = r->any_hit ? r->tmax : rt_voxel_limit(te, r->tmax);
                rt_intersect_list(cell_tris, tv, a, b, r, limit, best);
                if (best->tri != RT_NO_HIT)
                    break;
            }
            if (te >= r->tmax || !rt_voxel_step(g, r, &c, axis))
                break;
        }
    }
    *steps_out = steps;
    *tests_out = tests;
}

/* ------------------------------------------------------------------ */
/* Packets: 16 rays in the lanes of one work-item                      */
/* ------------------------------------------------------------------ */

/* PoCL runs the work-items of a group one after another on a CPU core, and a
 * loop whose trip count differs per ray (the DDA) keeps it from vectorising
 * across them. So each work-item traces its rays 16 at a time itself, one ray
 * per lane of 16-wide vectors: every lane runs exactly the scalar functions'
 * operations (same order, no contraction), so the hits and the counts are the
 * stream mode's bit for bit. Lanes advance in lockstep, one voxel per round;
 * a lane whose voxel is empty, or whose ray is done, idles (masked). When all
 * active lanes are in one voxel (coherent rays in a small scene), its list
 * bounds are read with scalar loads. The lanes that test triangles are
 * grouped by voxel: the lists of the first RT_GROUPS voxels are read with
 * scalar loads and their triangles broadcast to the lanes in them, and only
 * lanes left over gather a triangle each (RT_GROUPS 4 against 0: 18% faster
 * on cornell, 16% on bunny, 512x512 primary rays, one process). Loads of
 * per-lane addresses are AVX-512 gathers where the compiler offers them. The
 * watertight intersector keeps the scalar loop (rt_trace_one). */
#if !defined(RT_WATERTIGHT) && !defined(RT_FUSED_SCALAR)
#define RT_PACKET 16
#ifndef RT_GROUPS
#define RT_GROUPS 4
#endif

#if defined(SLUICE_AVX512_) && __has_builtin(__builtin_ia32_gathersiv16sf) &&                      \
    __has_builtin(__builtin_ia32_gathersiv16si)
#define RT_GATHER512_ 1
#endif

/* p[idx] in the lanes where m is set (0 elsewhere; nothing is read there). */
inline float16 rt_gather_f(global const float *p, int16 idx, int16 m)
{
#ifdef RT_GATHER512_
    return __builtin_ia32_gathersiv16sf((float16)0.0f, (const void *)(size_t)p, idx,
                                        sluice_mask16(m), 4);
#else
    int ix[16], mk[16];
    float r[16];
    vstore16(idx, 0, ix);
    vstore16(m, 0, mk);
    for (int k = 0; k < 16; ++k)
        r[k] = mk[k] ? p[ix[k]] : 0.0f;
    return vload16(0, r);
#endif
}

inline int16 rt_gather_i(global const uint *p, int16 idx, int16 m)
{
#ifdef RT_GATHER512_
    return __builtin_ia32_gathersiv16si((int16)0, (const void *)(size_t)p, idx, sluice_mask16(m),
                                        4);
#else
    int ix[16], mk[16], r[16];
    vstore16(idx, 0, ix);
    vstore16(m, 0, mk);
    for (int k = 0; k < 16; ++k)
        r[k] = mk[k] ? (int)p[ix[k]] : 0;
    return vload16(0, r);
#endif
}

/* The value of x in the first lane set in mask am (am != 0). */
inline int rt_first_lane(int16 x, ushort am)
{
#ifdef SLUICE_AVX512_
    int16 c = __builtin_ia32_compresssi512_mask(x, (int16)0, am);
    return c.s0;
#else
    int l[16];
    vstore16(x, 0, l);
    return l[31 - clz((uint)am & (0u - (uint)am))];
#endif
}

/* Whether any lane of a mask (lanes 0 or -1) is set: one mask test on
 * AVX-512 (the generic any() tests sign bits lane by lane there). */
inline int rt_any16(int16 m)
{
#ifdef SLUICE_AVX512_
    return sluice_mask16(m) != 0;
#else
    return any(m);
#endif
}

/* The rays of a packet, one per lane (as rt_rayp), and the best hits. */
typedef struct rt_packet {
    float16 ox, oy, oz, dx, dy, dz, ix, iy, iz, tmin, tmax;
    int16 any_hit;
    int16 tri; /* RT_NO_HIT as -1 */
    float16 t, u, v;
} rt_packet;

/* The smallest and the largest value of x in the lanes where m is set. */
inline int2 rt_minmax16(int16 x, int16 m)
{
    int16 lo = select((int16)INT_MAX, x, m), hi = select((int16)INT_MIN, x, m);
    int8 l8 = min(lo.lo, lo.hi), h8 = max(hi.lo, hi.hi);
    int4 l4 = min(l8.lo, l8.hi), h4 = max(h8.lo, h8.hi);
    int2 l2 = min(l4.lo, l4.hi), h2 = max(h4.lo, h4.hi);
    return (int2)(min(l2.x, l2.y), max(h2.x, h2.y));
}

/* The Moller-Trumbore test of rt_intersect_tri in the lanes where m is set,
 * against the triangle (v0, e1, e2) of each lane; keeps hits in P. */
__attribute__((always_inline)) inline void
rt_intersect16_core(int16 tri, int16 m, rt_packet *P, float16 limit, float16 v0x, float16 v0y,
                    float16 v0z, float16 e1x, float16 e1y, float16 e1z, float16 e2x, float16 e2y,
                    float16 e2z)
{
    float16 pvx = P->dy * e2z - P->dz * e2y, pvy = P->dz * e2x - P->dx * e2z,
            pvz = P->dx * e2y - P->dy * e2x;
    float16 det = e1x * pvx + e1y * pvy + e1z * pvz;
    m &= det != 0.0f;
    float16 inv = 1.0f / det;
    float16 sx = P->ox - v0x, sy = P->oy - v0y, sz = P->oz - v0z;
    float16 u = (sx * pvx + sy * pvy + sz * pvz) * inv;
    m &= ~((u < 0.0f) | (u > 1.0f));
    float16 qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
    float16 v = (P->dx * qx + P->dy * qy + P->dz * qz) * inv;
    m &= ~((v < 0.0f) | (u + v > 1.0f));
    float16 t = (e2x * qx + e2y * qy + e2z * qz) * inv;
    m &= (t >= P->tmin) & (t <= limit) & (t < P->t);
    P->tri = select(P->tri, tri, m);
    P->t = select(P->t, t, m);
    P->u = select(P->u, u, m);
    P->v = select(P->v, v, m);
}

/* rt_intersect16 for one triangle that every lane of m tests (broadcast). */
__attribute__((always_inline)) inline void rt_intersect16_one(global const float *tv, uint tri,
                                                              int16 m, rt_packet *P, float16 limit)
{
    global const float *q = tv + 9u * (size_t)tri;
    /* v0, e1, e2 one float at a time: each is a broadcast load */
    rt_intersect16_core((int16)(int)tri, m, P, limit, (float16)q[0], (float16)q[1], (float16)q[2],
                        (float16)q[3], (float16)q[4], (float16)q[5], (float16)q[6], (float16)q[7],
                        (float16)q[8]);
}

/* rt_intersect_tri (Moller-Trumbore) in the lanes where m is set. When all of
 * them test the same triangle (coherent rays), its vertices are read once
 * and broadcast instead of gathered. */
__attribute__((always_inline)) inline void rt_intersect16(global const float *tv, int16 tri,
                                                          int16 m, rt_packet *P, float16 limit)
{
    float16 v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z;
    int2 mm = rt_minmax16(tri, m);
    if (mm.x == mm.y) {
        rt_intersect16_one(tv, (uint)mm.x, m, P, limit);
        return;
    } else {
        int16 at = tri * 9;
        v0x = rt_gather_f(tv, at, m);
        v0y = rt_gather_f(tv, at + 1, m);
        v0z = rt_gather_f(tv, at + 2, m);
        e1x = rt_gather_f(tv, at + 3, m);
        e1y = rt_gather_f(tv, at + 4, m);
        e1z = rt_gather_f(tv, at + 5, m);
        e2x = rt_gather_f(tv, at + 6, m);
        e2y = rt_gather_f(tv, at + 7, m);
        e2z = rt_gather_f(tv, at + 8, m);
    }
    rt_intersect16_core(tri, m, P, limit, v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z);
}

/* Traces rays [first, first + count) (count <= 16) as one packet and writes
 * their hits. Adds the voxels and tests to *steps_sum and *tests_sum. */
inline void rt_trace_packet(const rt_grid_args *g, global const rt_ray *rays, uint first,
                            uint count, global rt_hit *hits, global uint *maxima,
                            global const uint *cell_start, global const uint *cell_tris,
                            global const float *tv, uint *steps_sum, uint *tests_sum)
{
    /* rt_prepare and rt_grid_enter, lane by lane the same operations */
    int16 lane = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    int16 live = lane < (int)count;
    global const float *rf = (global const float *)(rays + first);
    int16 at = lane * (int)(sizeof(rt_ray) / sizeof(float));
    rt_packet P;
    P.ox = rt_gather_f(rf, at, live);
    P.oy = rt_gather_f(rf, at + 1, live);
    P.oz = rt_gather_f(rf, at + 2, live);
    P.dx = rt_gather_f(rf, at + 3, live);
    P.dy = rt_gather_f(rf, at + 4, live);
    P.dz = rt_gather_f(rf, at + 5, live);
    P.tmin = rt_gather_f(rf, at + 6, live);
    P.tmax = rt_gather_f(rf, at + 7, live);
    int16 flags = rt_gather_i((global const uint *)rf, at + 13, live);
    int16 nzx = P.dx != 0.0f, nzy = P.dy != 0.0f, nzz = P.dz != 0.0f;
    P.ix = select((float16)0.0f, 1.0f / P.dx, nzx);
    P.iy = select((float16)0.0f, 1.0f / P.dy, nzy);
    P.iz = select((float16)0.0f, 1.0f / P.dz, nzz);
    P.any_hit = (flags & (int)RT_FLAG_ANY_HIT) != 0;
    P.tri = (int16)(-1);
    P.t = P.tmax;
    P.u = (float16)0.0f;
    P.v = (float16)0.0f;
    float16 t0 = P.tmin, t1 = P.tmax;
    int16 active = live;
    {
        float16 ta = (g->lo[0] - P.ox) * P.ix, tb = (g->hi[0] - P.ox) * P.ix;
        t0 = select(t0, fmax(t0, fmin(ta, tb)), nzx);
        t1 = select(t1, fmin(t1, fmax(ta, tb)), nzx);
        active &= nzx | ~((P.ox < g->lo[0]) | (P.ox > g->hi[0]));
        ta = (g->lo[1] - P.oy) * P.iy;
        tb = (g->hi[1] - P.oy) * P.iy;
        t0 = select(t0, fmax(t0, fmin(ta, tb)), nzy);
        t1 = select(t1, fmin(t1, fmax(ta, tb)), nzy);
        active &= nzy | ~((P.oy < g->lo[1]) | (P.oy > g->hi[1]));
        ta = (g->lo[2] - P.oz) * P.iz;
        tb = (g->hi[2] - P.oz) * P.iz;
        t0 = select(t0, fmax(t0, fmin(ta, tb)), nzz);
        t1 = select(t1, fmin(t1, fmax(ta, tb)), nzz);
        active &= nzz | ~((P.oz < g->lo[2]) | (P.oz > g->hi[2]));
        active &= t0 <= t1;
    }
    int16 cx = clamp(convert_int16(floor((P.ox + P.dx * t0 - g->lo[0]) * g->inv_cell[0])), 0,
                     g->dims[0] - 1);
    int16 cy = clamp(convert_int16(floor((P.oy + P.dy * t0 - g->lo[1]) * g->inv_cell[1])), 0,
                     g->dims[1] - 1);
    int16 cz = clamp(convert_int16(floor((P.oz + P.dz * t0 - g->lo[2]) * g->inv_cell[2])), 0,
                     g->dims[2] - 1);
    /* rt_voxel_exit's far faces: c + (d > 0) (a vector compare is -1 for true) */
    int16 fx = -(P.dx > 0.0f), fy = -(P.dy > 0.0f), fz = -(P.dz > 0.0f);
    int16 sx = select((int16)(-1), (int16)1, P.dx > 0.0f);
    int16 sy = select((int16)(-1), (int16)1, P.dy > 0.0f);
    int16 sz = select((int16)(-1), (int16)1, P.dz > 0.0f);
    int nx = g->dims[0], ny = g->dims[1], nz = g->dims[2];
    uint16 steps = (uint16)0u, tests = (uint16)0u;
    while (rt_any16(active)) {
        steps -= as_uint16(active);
        int16 ci = as_int16(as_uint16(cx) + (uint)nx * (as_uint16(cy) + (uint)ny * as_uint16(cz)));
        /* coherent rays: when every active lane is in the same voxel, its
         * list is read once (no gathers) */
        ushort am = sluice_mask16(active);
        int ci0 = rt_first_lane(ci, am);
        int uniform = sluice_mask16(active & (ci == ci0)) == am;
        int16 a, b;
        if (uniform) {
            a = (int16)(int)cell_start[ci0];
            b = (int16)(int)cell_start[ci0 + 1];
        } else {
            a = rt_gather_i(cell_start, ci, active);
            b = rt_gather_i(cell_start, ci + 1, active);
        }
        /* rt_voxel_exit */
        float16 bx = g->lo[0] + convert_float16(cx + fx) * g->cell[0];
        float16 by = g->lo[1] + convert_float16(cy + fy) * g->cell[1];
        float16 bz = g->lo[2] + convert_float16(cz + fz) * g->cell[2];
        float16 tx = select((float16)INFINITY, (bx - P.ox) * P.ix, nzx);
        float16 ty = select((float16)INFINITY, (by - P.oy) * P.iy, nzy);
        float16 tz = select((float16)INFINITY, (bz - P.oz) * P.iz, nzz);
        int16 my = ty < tx;
        float16 te = select(tx, ty, my);
        int16 mz = tz < te;
        te = select(te, tz, mz);
        int16 axis = select(select((int16)0, (int16)1, my), (int16)2, mz);
        int16 full = active & (as_uint16(a) < as_uint16(b));
        if (rt_any16(full)) {
            tests += as_uint16(select((int16)0, b - a, full));
            float16 limit = select(rt_voxel_limit16(te, P.tmax), P.tmax, P.any_hit);
            /* lanes grouped by voxel (see above); a lane tests its list in
             * order either way, so the hits do not depend on the grouping */
            int16 m = full;
            for (int grp = 0; grp < RT_GROUPS; ++grp) {
                ushort pm = sluice_mask16(m);
                int c0 = rt_first_lane(ci, pm);
                int16 in = m & (ci == c0);
                uint ka = (uint)rt_first_lane(a, pm), kb = (uint)rt_first_lane(b, pm);
                for (uint k = ka; k < kb; ++k)
                    rt_intersect16_one(tv, cell_tris[k], in, &P, limit);
                m &= ~in;
                if (!rt_any16(m))
                    break;
            }
            if (rt_any16(m)) {
                int16 k = a;
                do {
                    int16 tri = rt_gather_i(cell_tris, k, m);
                    rt_intersect16(tv, tri, m, &P, limit);
                    k += 1;
                    m &= k < b;
                } while (rt_any16(m));
            }
        }
        int16 done = (P.tri != -1) | (te >= P.tmax);
        int16 go = active & ~done;
        cx += select((int16)0, sx, go & (axis == 0));
        cy += select((int16)0, sy, go & (axis == 1));
        cz += select((int16)0, sz, go & (axis == 2));
        int16 inside = (cx >= 0) & (cx < nx) & (cy >= 0) & (cy < ny) & (cz >= 0) & (cz < nz);
        active = go & inside;
    }
    uint a_steps[16], a_tests[16];
    int a_tri[16];
    float a_t[16], a_u[16], a_v[16];
    vstore16(steps, 0, a_steps);
    vstore16(tests, 0, a_tests);
    vstore16(P.tri, 0, a_tri);
    vstore16(P.t, 0, a_t);
    vstore16(P.u, 0, a_u);
    vstore16(P.v, 0, a_v);
    uint ss = 0u, ts = 0u;
    for (uint k = 0; k < count; ++k) {
        rt_best best;
        best.tri = (uint)a_tri[k];
        best.t = a_t[k];
        best.u = a_u[k];
        best.v = a_v[k];
        rt_finish_hit(hits, first + k, &best, a_steps[k], a_tests[k], maxima);
        ss += a_steps[k];
        ts += a_tests[k];
    }
    *steps_sum += ss;
    *tests_sum += ts;
}
#endif /* RT_PACKET */

__kernel void rt_trace_fused(SLUICE_PARAMS, global const rt_ray *rays, global rt_hit *hits,
                             global uint *maxima, global const uint *cell_start,
                             global const uint *cell_tris, global const float *tv,
                             const rt_grid_args g)
{
#ifdef RT_PACKET
    SLUICE_FOR_EACH_RANGE (b, e) {
        uint steps = 0u, tests = 0u;
        for (uint p = b; p < e; p += 16u)
            rt_trace_packet(&g, rays, p, min(16u, e - p), hits, maxima, cell_start, cell_tris, tv,
                            &steps, &tests);
        SLUICE_COUNT(0, steps);
        SLUICE_COUNT(1, tests);
        SLUICE_COUNT(2, e - b);
    }
#else
    SLUICE_FOR_EACH (i) {
        rt_rayp r = rt_prepare(&rays[i]);
        rt_best best = rt_no_hit(&r);
        uint steps, tests;
        rt_trace_one(&g, cell_start, cell_tris, tv, &r, &best, &steps, &tests);
        rt_finish_hit(hits, i, &best, steps, tests, maxima);
        SLUICE_COUNT(0, steps);
        SLUICE_COUNT(1, tests);
        SLUICE_COUNT(2, 1u);
    }
#endif
}
