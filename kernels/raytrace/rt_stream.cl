/*
 * rt_stream.cl: the `stream` execution mode, Purcell's multipass ray tracer
 * (thesis ch. 3.1 and 4.1.2): traversal setup, a traverse kernel and an
 * intersect kernel, each of which moves every ray on by a bounded amount of
 * work, and a route kernel that sorts the rays into the "traverse" and
 * "intersect" streams with conditional outputs. Rays that are done (a hit,
 * or out of the grid) write their hit record, indexed by ray, for the shader.
 *
 * The heavy kernels (traverse, intersect) write a mapped output and emit
 * nothing, so their bodies run once; the route kernel is the cheap one that
 * emits (README.md "Writing a kernel": a body that emits runs twice).
 *
 * Build options: RT_UNROLL_STEPS (k, voxels per traverse pass) and
 * RT_UNROLL_TESTS (m, triangles per intersect pass), Purcell 5.2.2.
 * Counters: 0 voxels visited, 1 triangle tests, 2 rays finished.
 */
#ifndef RT_UNROLL_STEPS
#define RT_UNROLL_STEPS 1
#endif
#ifndef RT_UNROLL_TESTS
#define RT_UNROLL_TESTS 1
#endif

inline void rt_state_best(const rt_state *s, rt_best *b)
{
    b->tri = s->best_tri;
    b->t = s->best_t;
    b->u = s->best_u;
    b->v = s->best_v;
}

/* Eye-ray (or any ray) setup: clip to the grid; rays that miss its box are
 * done at once, the others enter the traverse stream at their first voxel. */
__kernel void rt_setup(SLUICE_PARAMS, global const rt_ray *rays, global rt_state *trav,
                       global rt_hit *hits, global uint *maxima, const rt_grid_args g)
{
    SLUICE_FOR_EACH (i) {
        rt_rayp r = rt_prepare(&rays[i]);
        int3 c = (int3)(0, 0, 0);
        int in = rt_grid_enter(&g, &r, &c);
        if (!in && SLUICE_WRITING) {
            rt_best b = rt_no_hit(&r);
            rt_finish_hit(hits, i, &b, 0u, 0u, maxima);
        }
        rt_state s;
        s.ray = i;
        s.cx = c.x;
        s.cy = c.y;
        s.cz = c.z;
        s.pos = 0u;
        s.best_tri = RT_NO_HIT;
        s.best_t = r.tmax;
        s.best_u = 0.0f;
        s.best_v = 0.0f;
        s.steps = 0u;
        s.tests = 0u;
        s.next = RT_NEXT_TRAVERSE;
        SLUICE_EMIT_IF(0, trav, s, in);
        SLUICE_COUNT(2, !in);
    }
}

/* Up to RT_UNROLL_STEPS voxels: a non-empty voxel sends the ray to the
 * intersector (empty voxels never reach it); leaving the grid, or passing
 * the ray's end, finishes it as a miss. */
__kernel void rt_traverse(SLUICE_PARAMS, global const rt_state *in, global rt_state *out,
                          global const rt_ray *rays, global rt_hit *hits, global uint *maxima,
                          global const uint *cell_start, const rt_grid_args g)
{
    SLUICE_FOR_EACH (i) {
        rt_state s = in[i];
        rt_rayp r = rt_prepare(&rays[s.ray]);
        int3 c = (int3)(s.cx, s.cy, s.cz);
        uint visited = 0u;
        s.next = RT_NEXT_TRAVERSE;
        for (int k = 0; k < RT_UNROLL_STEPS; ++k) {
            ++visited;
            uint ci = rt_cell_index(&g, c);
            uint a = cell_start[ci], b = cell_start[ci + 1u];
            if (a < b) {
                s.pos = a;
                s.next = RT_NEXT_INTERSECT;
                break;
            }
            int axis;
            float te = rt_voxel_exit(&g, &r, c, &axis);
            if (te >= r.tmax || !rt_voxel_step(&g, &r, &c, axis)) {
                s.next = RT_NEXT_DONE;
                break;
            }
        }
        s.steps += visited;
        s.cx = c.x;
        s.cy = c.y;
        s.cz = c.z;
        if (s.next == RT_NEXT_DONE) {
            rt_best b;
            rt_state_best(&s, &b);
            rt_finish_hit(hits, s.ray, &b, s.steps, s.tests, maxima);
        }
        out[i] = s;
        SLUICE_COUNT(0, visited);
        SLUICE_COUNT(2, s.next == RT_NEXT_DONE);
    }
}

/* Up to RT_UNROLL_TESTS triangles of the ray's voxel. When the voxel's list
 * is done: a hit inside the voxel finishes the ray (hits beyond the voxel's
 * exit were rejected, so the first voxel with a hit holds the nearest one);
 * otherwise the ray steps to the next voxel and goes back to traversal. */
__kernel void rt_intersect(SLUICE_PARAMS, global const rt_state *in, global rt_state *out,
                           global const rt_ray *rays, global rt_hit *hits, global uint *maxima,
                           global const uint *cell_start, global const uint *cell_tris,
                           global const float *tv, const rt_grid_args g)
{
    SLUICE_FOR_EACH (i) {
        rt_state s = in[i];
        rt_rayp r = rt_prepare(&rays[s.ray]);
        int3 c = (int3)(s.cx, s.cy, s.cz);
        uint ci = rt_cell_index(&g, c);
        uint end = cell_start[ci + 1u];
        int axis;
        float te = rt_voxel_exit(&g, &r, c, &axis);
        float limit = r.any_hit ? r.tmax : rt_voxel_limit(te, r.tmax);
        uint stop = min(end, s.pos + (uint)RT_UNROLL_TESTS);
        rt_best b;
        rt_state_best(&s, &b);
        rt_intersect_list(cell_tris, tv, s.pos, stop, &r, limit, &b);
        uint tested = stop - s.pos;
        s.tests += tested;
        s.pos = stop;
        s.best_tri = b.tri;
        s.best_t = b.t;
        s.best_u = b.u;
        s.best_v = b.v;
        if (stop < end) {
            s.next = RT_NEXT_INTERSECT;
        } else if (b.tri != RT_NO_HIT || te >= r.tmax || !rt_voxel_step(&g, &r, &c, axis)) {
            s.next = RT_NEXT_DONE;
            rt_finish_hit(hits, s.ray, &b, s.steps, s.tests, maxima);
        } else {
            s.next = RT_NEXT_TRAVERSE;
            s.cx = c.x;
            s.cy = c.y;
            s.cz = c.z;
        }
        out[i] = s;
        SLUICE_COUNT(1, tested);
        SLUICE_COUNT(2, s.next == RT_NEXT_DONE);
    }
}

/* The conditional outputs: slot 0 the traverse stream, slot 1 the intersect
 * stream. Finished rays go nowhere: their hit is already written. */
__kernel void rt_route(SLUICE_PARAMS, global const rt_state *in, global rt_state *trav,
                       global rt_state *isect)
{
    SLUICE_FOR_EACH (i) {
        rt_state s = in[i];
        SLUICE_EMIT_IF(0, trav, s, s.next == RT_NEXT_TRAVERSE);
        SLUICE_EMIT_IF(1, isect, s, s.next == RT_NEXT_INTERSECT);
    }
}
