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

__kernel void rt_trace_fused(SLUICE_PARAMS, global const rt_ray *rays, global rt_hit *hits,
                             global uint *maxima, global const uint *cell_start,
                             global const uint *cell_tris, global const float *tv,
                             const rt_grid_args g)
{
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
}
