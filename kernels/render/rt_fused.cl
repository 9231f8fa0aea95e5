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
/* Packets: 16 rays in the lanes of one work-item (rt_lanes.cl)        */
/* ------------------------------------------------------------------ */

/* A work-item traces its rays 16 at a time, one per lane, so the hits and
 * the counts are the stream mode's bit for bit. Lanes advance in lockstep;
 * a lane whose voxel is empty, or whose ray is done, idles (masked). Two
 * ways, chosen by the host for the scene (tracer.c, choose_fused_path):
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
 * The watertight intersector keeps the scalar loop (rt_trace_one). */
#if !defined(RT_WATERTIGHT) && !defined(RT_FUSED_SCALAR)
#define RT_PACKET 16

/* Traces rays [first, first + count) (count <= 16) as one packet and writes
 * their hits. Adds the voxels and tests to *steps_sum and *tests_sum. */
inline void rt_trace_packet(const rt_grid_args *g, global const rt_ray *rays, uint first,
                            uint count, global rt_hit *hits, global uint *maxima,
                            global const uint *cell_start, global const uint *cell_tris,
                            global const float *tv, global const float *lists, uint *steps_sum,
                            uint *tests_sum)
{
    int16 lane = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    int16 live = lane < (int)count;
    rt_packet P;
    rt_packet_load(rays, (int)first + lane, live, &P);
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
            int16 a = rt_gather_i(cell_start, ci, run), b = rt_gather_i(cell_start, ci + 1, run);
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
                    rt_intersect16_one(tv, cell_tris[k], full, &P, limit);
            else
                rt_intersect16_lists(tv, cell_tris, a, b, full, &P, limit);
        }
        int16 inside = (cx >= 0) & (cx < nx) & (cy >= 0) & (cy < ny) & (cz >= 0) & (cz < nz);
        active = adv & inside & (P.tri == -1);
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

__kernel void rt_trace_fused(SLUICE_PARAMS, global const rt_ray *rays, global rt_hit *hits,
                             global uint *maxima, global const uint *cell_start,
                             global const uint *cell_tris, global const float *tv,
                             const rt_grid_args g, global const float *lists)
{
#ifdef RT_PACKET
    SLUICE_FOR_EACH_RANGE (b, e) {
        uint steps = 0u, tests = 0u;
        for (uint p = b; p < e; p += 16u)
            rt_trace_packet(&g, rays, p, min(16u, e - p), hits, maxima, cell_start, cell_tris, tv,
                            lists, &steps, &tests);
        SLUICE_COUNT(0, steps);
        SLUICE_COUNT(1, tests);
        SLUICE_COUNT(2, e - b);
    }
#else
    (void)lists;
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
