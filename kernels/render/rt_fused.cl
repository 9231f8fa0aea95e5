/*
 * rt_fused.cl: the `fused` execution mode. One kernel takes a ray all the way
 * through the grid, alternating traversal and intersection in a loop: the
 * MIMD form Purcell contrasts with the multipass form (thesis 4.1.2 and 5.2.2,
 * "branching"). It runs exactly the functions of rt_trace.cl, in the same
 * order as the stream mode's passes, so both find the same hits.
 * Counters: 0 voxels visited, 1 triangle tests, 2 rays finished; with
 * coherent packets slice by slice, 3 the slices they crossed and 4 those
 * crossed through empty macro cells (per packet, not per ray).
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
/* Packets: 16 rays in the lanes of one work-item (rt_lanes.cl)        */
/* ------------------------------------------------------------------ */

/* A work-item traces its rays 16 at a time, one per lane, so the hits (and,
 * but for the slices below, the counts) are the stream mode's bit for bit.
 * Lanes advance in lockstep; a lane whose voxel is empty, or whose ray is
 * done, idles (masked). Three ways, chosen by the host for the scene
 * (tracer.c, choose_fused_path):
 *
 *   a voxel at a time (dense grids such as the Cornell box): each round
 *   reads the voxel's list bounds, tests, then steps. When all active lanes
 *   are in one voxel (coherent rays in a small scene), the bounds are read
 *   with scalar loads; the lists are tested by rt_intersect16_lists (lanes
 *   grouped by voxel, triangles broadcast).
 *
 *   walking ahead (RT_FUSED_WALK, sparse grids): each round steps every lane
 *   RT_FUSED_WALK voxels, then tests those voxels in order, each group of
 *   lanes with the same list the cheaper of two ways
 *   (rt_intersect16_lists_either). On bunny (6% of voxels occupied) a ray
 *   crosses about 12 voxels and tests in 2; waiting on each voxel's bounds
 *   before stepping on cost more than the tests.
 *
 *   slice by slice (RT_FUSED_SLICES, with RT_FUSED_WALK): a coherent packet
 *   (eye rays, rays to a light) crosses the grid a slice of voxels at a
 *   time (rt_trace_slices); packets that are not coherent walk ahead. The
 *   hits are the same; the counts are the slices crossed and the tests
 *   after a cull.
 *
 * The watertight intersector keeps the scalar loop (rt_trace_one). */
#if !defined(RT_WATERTIGHT) && !defined(RT_FUSED_SCALAR)
#define RT_PACKET 16

#ifdef RT_FUSED_SLICES
/* The smallest and the largest of x over the lanes of m (rt_minmax16 for
 * floats). The last step compares: scalar fmin and fmax became library
 * calls in PoCL's code. */
inline float2 rt_fminmax16(float16 x, int16 m)
{
    float16 a = select((float16)INFINITY, x, m), b = select((float16)(-INFINITY), x, m);
    float8 a8 = fmin(a.lo, a.hi), b8 = fmax(b.lo, b.hi);
    float4 a4 = fmin(a8.lo, a8.hi), b4 = fmax(b8.lo, b8.hi);
    float2 a2 = fmin(a4.lo, a4.hi), b2 = fmax(b4.lo, b4.hi);
    return (float2)(a2.x < a2.y ? a2.x : a2.y, b2.x > b2.y ? b2.x : b2.y);
}

/* Component k (0, 1, 2) of three, for a k the same in every lane. */
#define RT_PICK3_(k, a, b, c) ((k) == 0 ? (a) : ((k) == 1 ? (b) : (c)))

/* The widest footprint, in voxels of one slice, for which a packet goes
 * slice by slice: wider than any eye packet's measured (bench/README.md),
 * narrower than most bounce packets'. */
#ifndef RT_SLICE_AREA
#define RT_SLICE_AREA 6.0f
#endif

/* Floor of x clamped to [0, n - 1] (truncation is floor from 0 up; the
 * library floor expanded to a dozen instructions). Past n - 1 the clamp
 * comes first: a float beyond INT_MAX has no int. */
inline int rt_cell_floor(float x, int n)
{
    return x <= 0.0f ? 0 : (x >= (float)(n - 1) ? n - 1 : (int)x);
}

/* Whether a triangle (v0, e1, e2) may have a point in the box [bl, bh]: its
 * own box, v0 + min(0, e1, e2) .. v0 + max(0, e1, e2), is the least and the
 * greatest of v0, v0 + e1, v0 + e2 as rounded (rounding is monotonic). One
 * macro for one triangle and for 16, so both cull alike. */
#define RT_TRI_IN_BOX_(T, x, y, z, e1x, e1y, e1z, e2x, e2y, e2z, bl, bh)                           \
    T lx = e1x < e2x ? e1x : e2x, hx = e1x < e2x ? e2x : e1x;                                      \
    T ly = e1y < e2y ? e1y : e2y, hy = e1y < e2y ? e2y : e1y;                                      \
    T lz = e1z < e2z ? e1z : e2z, hz = e1z < e2z ? e2z : e1z;                                      \
    lx = lx < 0.0f ? lx : 0.0f;                                                                    \
    ly = ly < 0.0f ? ly : 0.0f;                                                                    \
    lz = lz < 0.0f ? lz : 0.0f;                                                                    \
    hx = hx > 0.0f ? hx : 0.0f;                                                                    \
    hy = hy > 0.0f ? hy : 0.0f;                                                                    \
    hz = hz > 0.0f ? hz : 0.0f;                                                                    \
    return !(x + lx > bh[0] || x + hx < bl[0] || y + ly > bh[1] || y + hy < bl[1] ||               \
             z + lz > bh[2] || z + hz < bl[2]);

inline int rt_tri_in_box(float x, float y, float z, float e1x, float e1y, float e1z, float e2x,
                         float e2y, float e2z, const float *bl, const float *bh)
{
    RT_TRI_IN_BOX_(float, x, y, z, e1x, e1y, e1z, e2x, e2y, e2z, bl, bh)
}

inline int16 rt_tri_in_box16(float16 x, float16 y, float16 z, float16 e1x, float16 e1y, float16 e1z,
                             float16 e2x, float16 e2y, float16 e2z, const float *bl,
                             const float *bh)
{
    RT_TRI_IN_BOX_(float16, x, y, z, e1x, e1y, e1z, e2x, e2y, e2z, bl, bh)
}

/* Macro cells: blocks of 2^RT_MACRO_SHIFT voxels a side (the host's
 * choice, tracer.c), one byte each, set when any of the block's voxels
 * holds triangles (rt_macro_cells). */
#ifndef RT_MACRO_SHIFT
#error "RT_FUSED_SLICES needs RT_MACRO_SHIFT"
#endif
/* Macro cells along an axis of n voxels. */
#define RT_MACRO_DIM_(n) (((n) + (1 << RT_MACRO_SHIFT) - 1) >> RT_MACRO_SHIFT)

/* The packet's footprint in voxels (umin, umax, vmin, vmax) between the
 * planes at fractions f0 and f1 of the way from its first plane to its last,
 * on the chords (ua, ub), (va, vb); padded by a thousandth of a voxel
 * against rounding. Each bound is monotonic in f, so a range of slices'
 * footprint holds each of its slices'. */
inline float4 rt_slice_footprint(float2 ua, float2 ub, float2 va, float2 vb, float f0, float f1)
{
    float a0 = ua.x + (ub.x - ua.x) * f0, a1 = ua.x + (ub.x - ua.x) * f1;
    float b0 = ua.y + (ub.y - ua.y) * f0, b1 = ua.y + (ub.y - ua.y) * f1;
    float umin = (a0 < a1 ? a0 : a1) - 1e-3f, umax = (b0 > b1 ? b0 : b1) + 1e-3f;
    a0 = va.x + (vb.x - va.x) * f0;
    a1 = va.x + (vb.x - va.x) * f1;
    b0 = va.y + (vb.y - va.y) * f0;
    b1 = va.y + (vb.y - va.y) * f1;
    return (float4)(umin, umax, (a0 < a1 ? a0 : a1) - 1e-3f, (b0 > b1 ? b0 : b1) + 1e-3f);
}

/* Coherent packets, slice by slice: the coherent grid traversal of Wald,
 * Ize, Kensler, Knoll and Parker ("Ray tracing animated scenes using
 * coherent grid traversal", SIGGRAPH 2006). When every ray of the packet
 * moves the same way along one axis K, the packet crosses the grid one slice
 * of voxels (one K index) at a time. The rays' extent across a slice is
 * known from two reductions made once per packet (below), so the empty
 * voxels of a slice cost one scalar read of their list bounds each, where
 * the walk ahead gathers them lane by lane and steps every lane with a few
 * dozen vector instructions. A voxel that holds triangles is tested by the
 * lanes whose rays cross it (a slab test), its triangles broadcast, each
 * first checked against the part of the voxel the packet's rays cross in
 * the slice (its box, from its v0, e1, e2): a triangle with no point there
 * has no hit there, and its hits elsewhere are found in the voxels that hold
 * them. With the list copy the check takes 16 triangles at a time. Where
 * the footprint over the rest of a block of slices (a macro cell's slab)
 * falls in empty macro cells, the packet crosses those slices at once
 * (bench/README.md has what each of these saves).
 *
 * A lane stops after the slice where its nearest hit so far lies within the
 * slice (so no voxel further on can hold a nearer one), as a ray of
 * rt_trace_one stops in the voxel of its hit. Each hit is accepted only
 * within its voxel's limit (rt_voxel_limit16, the exit computed as
 * rt_voxel_exit does), so the hits are those of the other paths; the counts
 * are not: a lane's voxels are the slices it crossed, its tests the
 * triangles tested against it after the cull.
 *
 * Returns 0, having done nothing, when the packet is not coherent: no axis
 * along which all its rays move the same way, two rays moving opposite ways
 * along either other axis, or a footprint wider than RT_SLICE_AREA voxels at
 * either end (bounce rays). */
inline int rt_trace_slices(const rt_grid_args *g, rt_packet *P, float16 t0, float16 t1,
                           int16 active, int16 cx, int16 cy, int16 cz,
                           global const uint *cell_start, global const uint *cell_tris,
                           global const float *tv, global const float *lists,
                           global const uchar *macro, uint16 *steps, uint16 *tests, uint *slices)
{
    ushort am = sluice_mask16(active);
    if (!am)
        return 1;
    /* K: of the axes along which every ray moves the same way, the one the
     * first ray moves fastest along */
    float16 dk3[3] = {P->dx, P->dy, P->dz};
    int K = -1;
    float best = 0.0f;
    for (int k = 0; k < 3; ++k) {
        int same = sluice_mask16(active & (dk3[k] > 0.0f)) == am ||
                   sluice_mask16(active & (dk3[k] < 0.0f)) == am;
        float d = fabs(as_float(rt_first_lane(as_int16(dk3[k]), am)));
        if (same && (K < 0 || d > best)) {
            K = k;
            best = d;
        }
    }
    if (K < 0)
        return 0;
    int U = K == 2 ? 0 : K + 1, V = U == 2 ? 0 : U + 1;
    /* Along U and V too, no two rays may move opposite ways: a slice's
     * voxels are then visited in the order each ray's 3D-DDA enters them
     * (each step adds 1 to u or to v), so that of two hits at the same t the
     * same one is kept. */
    int su = sluice_mask16(active & (dk3[U] < 0.0f)) ? -1 : 1;
    int sv = sluice_mask16(active & (dk3[V] < 0.0f)) ? -1 : 1;
    if ((su < 0 && sluice_mask16(active & (dk3[U] > 0.0f))) ||
        (sv < 0 && sluice_mask16(active & (dk3[V] > 0.0f))))
        return 0;
    float16 oK = RT_PICK3_(K, P->ox, P->oy, P->oz), dK = RT_PICK3_(K, P->dx, P->dy, P->dz);
    float16 iK = RT_PICK3_(K, P->ix, P->iy, P->iz);
    float16 oU = RT_PICK3_(U, P->ox, P->oy, P->oz), dU = RT_PICK3_(U, P->dx, P->dy, P->dz);
    float16 oV = RT_PICK3_(V, P->ox, P->oy, P->oz), dV = RT_PICK3_(V, P->dx, P->dy, P->dz);
    float16 iU = RT_PICK3_(U, P->ix, P->iy, P->iz), iV = RT_PICK3_(V, P->ix, P->iy, P->iz);
    int16 cK = RT_PICK3_(K, cx, cy, cz);
    int sgn = as_float(rt_first_lane(as_int16(dK), am)) > 0.0f ? 1 : -1;
    int nK = g->dims[K], nU = g->dims[U], nV = g->dims[V];
    float loK = g->lo[K], cellK = g->cell[K], invK = g->inv_cell[K];
    float loU = g->lo[U], cellU = g->cell[U], invU = g->inv_cell[U];
    float loV = g->lo[V], cellV = g->cell[V], invV = g->inv_cell[V];
    /* the slices from the first ray's entry to the last one's exit */
    int16 eK = clamp(convert_int16(floor((oK + dK * t1 - loK) * invK)), 0, nK - 1);
    int2 kr = rt_minmax16(cK, active), er = rt_minmax16(eK, active);
    int s0 = sgn > 0 ? kr.x : kr.y, s1 = sgn > 0 ? er.y : er.x;
    int ns = (s1 - s0) * sgn + 1;
    if (ns <= 0)
        return 0; /* no slice (only with NaN): the walk decides */
    /* Each ray's U and V (in voxels) are linear in the position of a K
     * plane, so their least over the rays is concave in it and their
     * greatest convex: the chords between the first and the last plane
     * bound them on every plane between. */
    float pa = loK + (float)(s0 + (sgn < 0)) * cellK;
    float pb = loK + (float)(s1 + (sgn > 0)) * cellK;
    float16 ta = (pa - oK) * iK, tb = (pb - oK) * iK;
    float2 ua = rt_fminmax16((oU + dU * ta - loU) * invU, active);
    float2 ub = rt_fminmax16((oU + dU * tb - loU) * invU, active);
    float2 va = rt_fminmax16((oV + dV * ta - loV) * invV, active);
    float2 vb = rt_fminmax16((oV + dV * tb - loV) * invV, active);
    if (!((ua.y - ua.x + 1.0f) * (va.y - va.x + 1.0f) <= RT_SLICE_AREA &&
          (ub.y - ub.x + 1.0f) * (vb.y - vb.x + 1.0f) <= RT_SLICE_AREA))
        return 0;
    /* a lane parallel to U or V stays in one slab of it: the footprint
     * already holds that slab */
    int16 nzU = dU != 0.0f, nzV = dV != 0.0f;
    float16 inf = (float16)INFINITY;
    /* a hit is accepted up to rt_voxel_limit16, past the voxel's exit by at
     * most 1e-6 of the distance from the origin: at most `reach` (bounded
     * through |o| + |p| for a point p of the grid, twice over for rounding) */
    float reach = rt_fminmax16(fabs(P->ox) + fabs(P->oy) + fabs(P->oz), active).y;
    for (int j = 0; j < 3; ++j)
        reach += fabs(g->lo[j]) > fabs(g->hi[j]) ? fabs(g->lo[j]) : fabs(g->hi[j]);
    reach *= 2e-6f;
    float inv_ns = 1.0f / (float)ns;
#ifdef RT_LIST_COPY
    int16 lane = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
#else
    (void)lists;
#endif
    /* strides of the voxels and of the macro cells along K, U and V */
    uint vs[3] = {1u, (uint)g->dims[0], (uint)(g->dims[0] * g->dims[1])};
    uint sK = vs[K], sU = vs[U], sV = vs[V];
    uint mx = (uint)RT_MACRO_DIM_(g->dims[0]);
    uint ms3[3] = {1u, mx, mx * (uint)RT_MACRO_DIM_(g->dims[1])};
    uint mK = ms3[K], mU = ms3[U], mV = ms3[V];
    int16 alive = active, last = eK; /* last: the slice where a lane stopped */
    int k = 0;
    while (k < ns) {
        /* the slices left in this macro cell's slab, in one step when the
         * footprint over them holds no triangles */
        int s = s0 + sgn * k, ms = s >> RT_MACRO_SHIFT;
        int n = sgn > 0 ? ((ms + 1) << RT_MACRO_SHIFT) - s : s - (ms << RT_MACRO_SHIFT) + 1;
        n = n < ns - k ? n : ns - k;
        float4 fp = rt_slice_footprint(ua, ub, va, vb, (float)k * inv_ns, (float)(k + n) * inv_ns);
        int mu0 = rt_cell_floor(fp.x, nU) >> RT_MACRO_SHIFT;
        int mu1 = rt_cell_floor(fp.y, nU) >> RT_MACRO_SHIFT;
        int mv0 = rt_cell_floor(fp.z, nV) >> RT_MACRO_SHIFT;
        int mv1 = rt_cell_floor(fp.w, nV) >> RT_MACRO_SHIFT;
        uint full = 0u;
        for (int v = mv0; v <= mv1; ++v)
            for (int u = mu0; u <= mu1; ++u)
                full |= macro[(uint)ms * mK + (uint)u * mU + (uint)v * mV];
        if (!full) {
            slices[1] += (uint)n;
            k += n;
            continue;
        }
        int kend = k + n, stop = 0;
        for (; k < kend; ++k) {
            s = s0 + sgn * k;
            fp = rt_slice_footprint(ua, ub, va, vb, (float)k * inv_ns, (float)(k + 1) * inv_ns);
            float umin = fp.x, umax = fp.y, vmin = fp.z, vmax = fp.w;
            int u0 = rt_cell_floor(umin, nU), u1 = rt_cell_floor(umax, nU);
            int v0 = rt_cell_floor(vmin, nV), v1 = rt_cell_floor(vmax, nV);
            int tested = 0;
            float16 tkin = (float16)0.0f, tkout = (float16)0.0f;
            for (int jv = 0; jv <= v1 - v0; ++jv)
                for (int ju = 0; ju <= u1 - u0; ++ju) {
                    int u = su > 0 ? u0 + ju : u1 - ju, v = sv > 0 ? v0 + jv : v1 - jv;
                    uint ci = (uint)s * sK + (uint)u * sU + (uint)v * sV;
                    uint a = cell_start[ci], b = cell_start[ci + 1u];
                    if (a >= b)
                        continue;
                    /* the lanes whose rays cross the voxel, and where they leave
                     * it: each face's parameter as rt_voxel_exit computes it */
                    if (!tested) {
                        tkin = (loK + (float)(s + (sgn < 0)) * cellK - oK) * iK;
                        tkout = (loK + (float)(s + (sgn > 0)) * cellK - oK) * iK;
                    }
                    float16 fa = (loU + (float)u * cellU - oU) * iU;
                    float16 fb = (loU + (float)(u + 1) * cellU - oU) * iU;
                    float16 tn = fmax(tkin, select(-inf, fmin(fa, fb), nzU));
                    float16 te = fmin(tkout, select(inf, fmax(fa, fb), nzU));
                    fa = (loV + (float)v * cellV - oV) * iV;
                    fb = (loV + (float)(v + 1) * cellV - oV) * iV;
                    tn = fmax(tn, select(-inf, fmin(fa, fb), nzV));
                    te = fmin(te, select(inf, fmax(fa, fb), nzV));
                    int16 m = alive & (tn <= te + fabs(te) * 1e-5f) & (te >= t0) & (tn <= t1);
                    if (!rt_any16(m))
                        continue;
                    tested = 1;
                    float16 limit = select(rt_voxel_limit16(te, P->tmax), P->tmax, P->any_hit);
                    /* the box the packet's rays cross in this voxel, padded
                     * by a thousandth of a voxel and by `reach` */
                    int c[3];
                    c[K] = s;
                    c[U] = u;
                    c[V] = v;
                    float bl[3], bh[3];
                    for (int j = 0; j < 3; ++j) {
                        bl[j] = g->lo[j] + (float)c[j] * g->cell[j];
                        bh[j] = bl[j] + g->cell[j];
                    }
                    float w = loU + umin * cellU;
                    bl[U] = w > bl[U] ? w : bl[U];
                    w = loU + umax * cellU;
                    bh[U] = w < bh[U] ? w : bh[U];
                    w = loV + vmin * cellV;
                    bl[V] = w > bl[V] ? w : bl[V];
                    w = loV + vmax * cellV;
                    bh[V] = w < bh[V] ? w : bh[V];
                    for (int j = 0; j < 3; ++j) {
                        bl[j] -= 1e-3f * g->cell[j] + reach;
                        bh[j] += 1e-3f * g->cell[j] + reach;
                    }
#ifdef RT_LIST_COPY
                    if (lists) {
                        /* 16 neighbours of the list copy culled at once: one
                         * load per plane, where the loop below reads each
                         * record through cell_tris */
                        for (uint j = a; j < b; j += 16u) {
                            global const float *q = lists + j;
                            uint keep = (uint)sluice_mask16(
                                (lane < (int)(b - j)) &
                                rt_tri_in_box16(vload16(0, q), vload16(0, q + RT_LIST_STRIDE),
                                                vload16(0, q + 2 * RT_LIST_STRIDE),
                                                vload16(0, q + 3 * RT_LIST_STRIDE),
                                                vload16(0, q + 4 * RT_LIST_STRIDE),
                                                vload16(0, q + 5 * RT_LIST_STRIDE),
                                                vload16(0, q + 6 * RT_LIST_STRIDE),
                                                vload16(0, q + 7 * RT_LIST_STRIDE),
                                                vload16(0, q + 8 * RT_LIST_STRIDE), bl, bh));
                            while (keep) {
                                global const float *r = q + rt_lowest_bit(keep);
                                keep &= keep - 1u;
                                *tests -= as_uint16(m);
                                rt_intersect16_copy_one(r, m, P, limit, 0);
                            }
                        }
                        continue;
                    }
#endif
                    for (uint j = a; j < b; ++j) {
                        uint tri = cell_tris[j];
                        global const float *q = tv + 9u * (size_t)tri;
                        float x = q[0], y = q[1], z = q[2], e1x = q[3], e1y = q[4], e1z = q[5],
                              e2x = q[6], e2y = q[7], e2z = q[8];
                        if (!rt_tri_in_box(x, y, z, e1x, e1y, e1z, e2x, e2y, e2z, bl, bh))
                            continue;
                        *tests -= as_uint16(m);
                        rt_intersect16_core((int16)(int)tri, m, P, limit, (float16)x, (float16)y,
                                            (float16)z, (float16)e1x, (float16)e1y, (float16)e1z,
                                            (float16)e2x, (float16)e2y, (float16)e2z, 0);
                    }
                }
            if (tested) {
                float16 tout = fmin(t1, tkout);
                int16 done =
                    alive & (((P->tri != -1) &
                              ((P->any_hit != 0) | (P->t <= rt_voxel_limit16(tout, P->tmax)))) |
                             (tout >= t1));
                last = select(last, (int16)s, done);
                alive &= ~done;
                if (!rt_any16(alive)) {
                    stop = 1;
                    break;
                }
            }
        }
        if (stop)
            break;
    }
    slices[0] += (uint)(k < ns ? k + 1 : ns);
    *steps += as_uint16(select((int16)0, as_int16(abs_diff(last, cK)) + 1, active));
    return 1;
}
#endif /* RT_FUSED_SLICES */

/* Takes the rays of packet P (lanes `live`) through the grid: P's hits
 * (tri, t, u, v) as rt_trace_one finds them, and each lane's voxels visited
 * and triangle tests in *steps_out and *tests_out; the slices crossed and
 * those crossed through empty macro cells are added to slices[0] and
 * slices[1]. Shared by rt_trace_packet (rays from a stream) and the
 * renderer's fused direct light (rays made in registers, rt_direct.cl). */
inline void rt_packet_trace(const rt_grid_args *g, rt_packet *P_, int16 live,
                            global const uint *cell_start, global const uint *cell_tris,
                            global const float *tv, global const float *lists,
                            global const uchar *macro, uint16 *steps_out, uint16 *tests_out,
                            uint *slices)
{
    rt_packet P = *P_;
    /* rt_grid_enter, lane by lane the same operations */
    int16 nzx = P.dx != 0.0f, nzy = P.dy != 0.0f, nzz = P.dz != 0.0f;
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
    int16 sx = select((int16)(-1), (int16)1, P.dx > 0.0f);
    int16 sy = select((int16)(-1), (int16)1, P.dy > 0.0f);
    int16 sz = select((int16)(-1), (int16)1, P.dz > 0.0f);
    int nx = g->dims[0], ny = g->dims[1], nz = g->dims[2];
    uint16 steps = (uint16)0u, tests = (uint16)0u;
#ifdef RT_FUSED_SLICES
    if (rt_trace_slices(g, &P, t0, t1, active, cx, cy, cz, cell_start, cell_tris, tv, lists, macro,
                        &steps, &tests, slices))
        active = (int16)0; /* done; else the walk below takes the packet */
#else
    (void)macro;
    (void)slices;
#endif
#ifdef RT_FUSED_WALK
    /* Walk ahead (sparse grids): each round first steps every lane through
     * RT_FUSED_WALK voxels, reading their list bounds as it goes, then runs
     * the tests of those voxels in order. The walk has no branch that waits
     * on a load, so its gathers overlap, where the voxel-at-a-time loop below
     * waits on each one before it can tell whether to test. A lane that hits
     * in the round's voxel w has walked past it: it counts only the voxels
     * up to w, so the counts stay those of rt_trace_one. */
    while (rt_any16(active)) {
        int16 wa[RT_FUSED_WALK], wb[RT_FUSED_WALK];
        float16 wte[RT_FUSED_WALK];
        int16 run = active, walked = (int16)0;
        uint with_tests = 0u; /* bit w: some lane has triangles in its voxel w */
        for (int w = 0; w < RT_FUSED_WALK; ++w) {
            int16 ci = rt_cell_index16(g, cx, cy, cz);
            /* both list bounds in one gather of 8-byte elements: half the
             * elements of two gathers (the voxel loop below keeps two: no
             * faster there, bench/README.md) */
            int16 a, b;
            rt_cell_bounds16(cell_start, ci, run, &a, &b);
            int16 axis;
            float16 te = rt_voxel_exit16(g, &P, cx, cy, cz, &axis);
            wa[w] = a;
            wb[w] = b;
            wte[w] = te;
            with_tests |= (uint)(sluice_mask16(run & (as_uint16(a) < as_uint16(b))) != 0) << w;
            walked -= run;
            int16 adv = run & ~(te >= P.tmax);
            cx += select((int16)0, sx, adv & (axis == 0));
            cy += select((int16)0, sy, adv & (axis == 1));
            cz += select((int16)0, sz, adv & (axis == 2));
            run = adv & (cx >= 0) & (cx < nx) & (cy >= 0) & (cy < ny) & (cz >= 0) & (cz < nz);
        }
        int16 alive = active; /* no hit yet */
        while (with_tests) {
            int w = rt_lowest_bit(with_tests);
            with_tests &= with_tests - 1u;
            /* lanes that walked into voxel w (a lane that stops walks no
             * further), have no hit yet, and find triangles there */
            int16 a = wa[w], b = wb[w];
            int16 full = alive & (walked > w) & (as_uint16(a) < as_uint16(b));
            if (!rt_any16(full))
                continue;
            tests += as_uint16(select((int16)0, b - a, full));
            float16 limit = select(rt_voxel_limit16(wte[w], P.tmax), P.tmax, P.any_hit);
            rt_intersect16_lists_either(tv, lists, cell_tris, a, b, full, &P, limit);
            int16 hit = full & (P.tri != -1);
            steps += as_uint16(select((int16)0, (int16)(w + 1), hit));
            alive &= ~hit;
        }
        steps += as_uint16(select((int16)0, walked, alive));
        active = run & alive;
    }
#else
    (void)lists;
    while (rt_any16(active)) {
        steps -= as_uint16(active);
        int16 ci = rt_cell_index16(g, cx, cy, cz);
        /* coherent rays: when every active lane is in the same voxel, its
         * list bounds are read once (no gathers) */
        ushort am = sluice_mask16(active);
        int ci0 = rt_first_lane(ci, am);
        int16 a, b;
        int uniform = sluice_mask16(active & (ci == ci0)) == am;
        if (uniform) {
            a = (int16)(int)cell_start[ci0];
            b = (int16)(int)cell_start[ci0 + 1];
        } else {
            a = rt_gather_i(cell_start, ci, active);
            b = rt_gather_i(cell_start, ci + 1, active);
        }
        int16 axis;
        float16 te = rt_voxel_exit16(g, &P, cx, cy, cz, &axis);
        /* the next voxel does not wait for the tests: a lane with a hit
         * steps too, but stops below. Taking the tests off the chain from
         * one voxel to the next made cornell 8% faster (bunny within 2%). */
        int16 adv = active & ~(te >= P.tmax);
        cx += select((int16)0, sx, adv & (axis == 0));
        cy += select((int16)0, sy, adv & (axis == 1));
        cz += select((int16)0, sz, adv & (axis == 2));
        int16 full = active & (as_uint16(a) < as_uint16(b));
        if (rt_any16(full)) {
            tests += as_uint16(select((int16)0, b - a, full));
            float16 limit = select(rt_voxel_limit16(te, P.tmax), P.tmax, P.any_hit);
            /* one voxel: its list straight (no grouping; 4-6% on cornell) */
            if (uniform)
                for (uint k = (uint)a.s0, kb = (uint)b.s0; k < kb; ++k)
                    rt_intersect16_one(tv, cell_tris[k], full, &P, limit, 1);
            else
                rt_intersect16_lists(tv, cell_tris, a, b, full, &P, limit);
        }
        int16 inside = (cx >= 0) & (cx < nx) & (cy >= 0) & (cy < ny) & (cz >= 0) & (cz < nz);
        active = adv & inside & (P.tri == -1);
    }
#endif
    *P_ = P;
    *steps_out = steps;
    *tests_out = tests;
}

/* Traces rays [first, first + count) (count <= 16) as one packet and writes
 * their hits. Adds the voxels and tests to *steps_sum and *tests_sum, and,
 * slice by slice, the slices crossed and those crossed through empty macro
 * cells to slices[0] and slices[1]. */
inline void rt_trace_packet(const rt_grid_args *g, global const rt_ray *rays, uint first,
                            uint count, global rt_hit *hits, global uint *maxima,
                            global const uint *cell_start, global const uint *cell_tris,
                            global const float *tv, global const float *lists,
                            global const uchar *macro, uint *steps_sum, uint *tests_sum,
                            uint *slices)
{
    int16 lane = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    int16 live = lane < (int)count;
    rt_packet P;
#ifdef RT_AOS16_
    if (count == 16u)
        rt_packet_load_run(rays, first, &P);
    else
#endif
        rt_packet_load(rays, (int)first + lane, live, &P);
    uint16 steps, tests;
    rt_packet_trace(g, &P, live, cell_start, cell_tris, tv, lists, macro, &steps, &tests, slices);
#ifdef RT_AOS16_
    if (count == 16u) {
        rt_store_hits16(hits + first, P.tri, P.t, P.u, P.v, steps, tests);
        int16 all = (int16)(-1);
        rt_maxima_add(maxima, (uint)rt_minmax16(as_int16(steps), all).y,
                      (uint)rt_minmax16(as_int16(tests), all).y);
        *steps_sum += rt_sum16(steps);
        *tests_sum += rt_sum16(tests);
        return;
    }
#endif
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

/* The tracer's kernels; a program that only calls rt_packet_trace (the
 * renderer's, rt_direct.cl) builds with RT_PACKETS_ONLY and leaves them
 * out. */
#ifndef RT_PACKETS_ONLY
__kernel void rt_trace_fused(SLUICE_PARAMS, global const rt_ray *rays, global rt_hit *hits,
                             global uint *maxima, global const uint *cell_start,
                             global const uint *cell_tris, global const float *tv,
                             const rt_grid_args g, global const float *lists,
                             global const uchar *macro)
{
#ifdef RT_PACKET
    SLUICE_FOR_EACH_RANGE (b, e) {
        uint steps = 0u, tests = 0u, slices[2] = {0u, 0u}, n = SLUICE_LENGTH;
        for (uint p = b; p < e; p += 16u) {
            /* the next packet's rays, one line each, while this one runs;
             * past the chunk's end too: on a CPU the same thread takes the
             * next chunk next (PoCL runs a group's work-items in turn) */
            for (uint q = p + 16u; q < min(p + 32u, n); ++q)
                SLUICE_PREFETCH(rays + q);
            rt_trace_packet(&g, rays, p, min(16u, e - p), hits, maxima, cell_start, cell_tris, tv,
                            lists, macro, &steps, &tests, slices);
        }
        SLUICE_COUNT(0, steps);
        SLUICE_COUNT(1, tests);
        SLUICE_COUNT(2, e - b);
        SLUICE_COUNT(3, slices[0]);
        SLUICE_COUNT(4, slices[1]);
    }
#else
    (void)lists;
    (void)macro;
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

#ifdef RT_LIST_COPY
/* The copy of the triangle records in list order that the walk's turned
 * test reads (rt_intersect16_turned): record j of entry k at
 * lists[j * RT_LIST_STRIDE + k], the triangle index as plane 9. Launched over
 * RT_LIST_STRIDE records, so the padding past the last entry is zeros. */
__kernel void rt_list_records(SLUICE_PARAMS, global const uint *cell_tris, global const float *tv,
                              uint entries, global float *lists)
{
    SLUICE_FOR_EACH (k) {
        uint tri = k < entries ? cell_tris[k] : 0u;
        for (uint j = 0; j < 9u; ++j)
            lists[j * RT_LIST_STRIDE + k] = k < entries ? tv[9u * tri + j] : 0.0f;
        lists[9u * RT_LIST_STRIDE + k] = as_float(tri);
    }
}
#endif

#ifdef RT_FUSED_SLICES
/* The macro cells of rt_trace_slices: byte i is 1 when any voxel of block i
 * (2^RT_MACRO_SHIFT voxels a side, x fastest) holds triangles. */
__kernel void rt_macro_cells(SLUICE_PARAMS, global const uint *cell_start, const rt_grid_args g,
                             global uchar *macro)
{
    int m = 1 << RT_MACRO_SHIFT;
    uint mx = (uint)RT_MACRO_DIM_(g.dims[0]), my = (uint)RT_MACRO_DIM_(g.dims[1]);
    SLUICE_FOR_EACH (i) {
        int x0 = (int)(i % mx) << RT_MACRO_SHIFT, y0 = (int)(i / mx % my) << RT_MACRO_SHIFT;
        int z0 = (int)(i / (mx * my)) << RT_MACRO_SHIFT;
        uint full = 0u;
        for (int z = z0; z < min(z0 + m, g.dims[2]); ++z)
            for (int y = y0; y < min(y0 + m, g.dims[1]); ++y)
                for (int x = x0; x < min(x0 + m, g.dims[0]); ++x) {
                    uint c = (uint)(x + g.dims[0] * (y + g.dims[1] * z));
                    full |= cell_start[c] < cell_start[c + 1u];
                }
        macro[i] = (uchar)full;
    }
}
#endif
#endif /* RT_PACKETS_ONLY */
