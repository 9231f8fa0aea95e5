/*
 * rt_stream.cl: the `stream` execution mode, Purcell's multipass ray tracer
 * (thesis ch. 3.1 and 4.1.2): traversal setup, a traverse kernel and an
 * intersect kernel, each of which moves every ray of its stream on by a
 * bounded amount of work, and a route kernel that sorts the rays into the
 * "traverse" and "intersect" streams with conditional outputs. Setup also
 * runs the first traverse pass, so that it reads the rays once for both.
 *
 * The streams carry 4-byte ray ids. What a ray has done so far lives in
 * buffers indexed by ray, as Purcell keeps it in textures: its voxel and list
 * position (rt_walk) and its best hit and work counts (its rt_hit record,
 * which is also what the shader reads when the ray is done). A pass touches
 * each ray of its stream from exactly one work-item, so the state is updated
 * in place without races.
 *
 * The heavy kernels (setup, traverse, intersect) emit nothing: they write the
 * ray's next stream as a code in a mapped output aligned with their input
 * (RT_NEXT_*), so their bodies run once. The route kernels are the cheap ones
 * that emit (README.md "Writing a kernel": a body that emits runs twice),
 * 16 ids at a time with SLUICE_EMIT16.
 *
 * Build options: RT_UNROLL_STEPS (k, voxels per traverse pass) and
 * RT_UNROLL_TESTS (m, triangles per intersect pass), Purcell 5.2.2.
 * Counters: 0 voxels visited, 1 triangle tests, 2 rays finished, 5 rays that
 * entered the grid (rt_setup).
 */
#ifndef RT_UNROLL_STEPS
#define RT_UNROLL_STEPS 1
#endif
#ifndef RT_UNROLL_TESTS
#define RT_UNROLL_TESTS 1
#endif

#pragma OPENCL FP_CONTRACT OFF

/* Blocks of 16 rays run in lanes as rt_packet (rt_lanes.cl): a CPU's
 * vector units. On a GPU the lanes are the work-items, and a work-item's
 * 16-lane vectors live in memory (clang for NVPTX gave rt_setup,
 * rt_traverse and rt_intersect stack frames of 1.8-2.7 KB, and none
 * without them), so the tracer builds for devices other than CPUs with
 * RT_PER_RAY: every ray goes through the one-ray code that CPUs use for a
 * chunk's last rays. -DRT_NO_PER_RAY (SLUICE_BUILD_OPTIONS) keeps the
 * blocks there, for measuring. */
#if defined(RT_PER_RAY) && !defined(RT_NO_PER_RAY)
#define RT_BLOCKS16 0
#else
#define RT_BLOCKS16 1
#endif

/* The rays ids and their walk state (rt_walk: cx, cy, cz, pos), gathered. */
inline void rt_walk16_load(global const rt_ray *rays, global const rt_walk *walk, uint16 ids,
                           rt_packet *r, int16 *cx, int16 *cy, int16 *cz, uint16 *pos)
{
#ifdef RT_AOS16_
    /* ids in a run (a pass's stream keeps most of its chunks' order): the
     * rays are neighbours, read as whole lines (rt_packet_load_run) */
    const uint16 lane = SLUICE_LANE16;
    if (sluice_mask16(as_int16(ids == (uint16)ids.s0 + lane)) == (ushort)0xffffu)
        rt_packet_load_run(rays, ids.s0, r);
    else
#endif
        rt_packet_load(rays, as_int16(ids), (int16)-1, r);
    global const uint *w = (global const uint *)walk;
    int16 at = as_int16(ids) * 4;
    *cx = rt_gather_i(w, at, (int16)-1);
    *cy = rt_gather_i(w, at + 1, (int16)-1);
    *cz = rt_gather_i(w, at + 2, (int16)-1);
    *pos = as_uint16(rt_gather_i(w, at + 3, (int16)-1));
}

/* The lanes' walk states, lane by lane: wc[0..2][l] the voxel, wc[3][l] the
 * list position. */
inline void rt_walk16_spill(int16 cx, int16 cy, int16 cz, uint16 pos, int (*wc)[16])
{
    vstore16(cx, 0, wc[0]);
    vstore16(cy, 0, wc[1]);
    vstore16(cz, 0, wc[2]);
    vstore16(as_int16(pos), 0, wc[3]);
}

/* rt_voxel_step in the lanes of go, through face `axis`: returns the lanes
 * that left the grid. */
inline int16 rt_step16(const rt_grid_args *g, const rt_packet *r, int16 go, int16 axis, int16 *cx,
                       int16 *cy, int16 *cz)
{
    int16 sx = go & (axis == 0), sy = go & (axis == 1), sz = go & (axis == 2);
    *cx += select((int16)0, select((int16)-1, (int16)1, r->dx > 0.0f), sx);
    *cy += select((int16)0, select((int16)-1, (int16)1, r->dy > 0.0f), sy);
    *cz += select((int16)0, select((int16)-1, (int16)1, r->dz > 0.0f), sz);
    return (sx & ((*cx < 0) | (*cx >= g->dims[0]))) | (sy & ((*cy < 0) | (*cy >= g->dims[1]))) |
           (sz & ((*cz < 0) | (*cz >= g->dims[2])));
}

/* Up to RT_UNROLL_STEPS voxels of the rays in the lanes of `active`, from
 * voxel (cx, cy, cz) on, as rt_traverse_one takes them: a non-empty voxel
 * sets the lane in *found and its list's start in *pos; leaving the grid, or
 * passing the ray's end, sets it in *done. Adds the voxels visited. Each
 * step reads the voxel's bit (rt_voxel_bits), a map small enough to stay in
 * the first-level cache, and the lanes that stopped read their list starts
 * once at the end; reading both list bounds at every step was slower
 * (bench/README.md). Inlined, so that the state stays in registers. */
__attribute__((always_inline)) inline void
rt_traverse16(const rt_grid_args *g, const rt_packet *r, global const uint *cell_start,
              global const uint *bits, int16 active, int16 *cx, int16 *cy, int16 *cz, uint16 *pos,
              uint16 *visited, int16 *found, int16 *done)
{
    int16 stopped = (int16)0;
#ifndef SLUICE_AVX512_
    for (int k = 0; k < RT_UNROLL_STEPS; ++k) {
        if (!rt_any16(active))
            break;
        *visited += as_uint16(active) & (uint16)1u;
        int16 ci = rt_cell_index16(g, *cx, *cy, *cz);
        int16 word = rt_gather_i(bits, ci >> 5, active);
        int16 f = active & (((word >> (ci & 31)) & 1) != 0);
        stopped |= f;
        active &= ~f;
        int16 axis;
        float16 te = rt_voxel_exit16(g, r, *cx, *cy, *cz, &axis);
        int16 leave = active & (te >= r->tmax);
        int16 go = active & ~leave;
        int16 out = rt_step16(g, r, go, axis, cx, cy, cz);
        *done |= leave | out;
        active &= ~(leave | out);
    }
    if (rt_any16(stopped)) {
#else
    /* With AVX-512 the lanes inside the grid and short of their ray's end
     * step on whether or not their voxel held triangles (a lane that found
     * one keeps that voxel in f*), so that the step, and the next bit's
     * read, need not wait for this bit's read: 3.5% faster on bunny-close
     * on Zen 4; with AVX2's 16 registers the three more vectors cost more
     * than that (bench/README.md) */
    int16 walking = active, fx = *cx, fy = *cy, fz = *cz;
    for (int k = 0; k < RT_UNROLL_STEPS; ++k) {
        if (!rt_any16(active))
            break;
        *visited += as_uint16(active) & (uint16)1u;
        int16 ci = rt_cell_index16(g, *cx, *cy, *cz);
        int16 word = rt_gather_i(bits, ci >> 5, walking);
        int16 axis;
        float16 te = rt_voxel_exit16(g, r, *cx, *cy, *cz, &axis);
        int16 leave = walking & (te >= r->tmax);
        int16 x = *cx, y = *cy, z = *cz;
        int16 out = rt_step16(g, r, walking & ~leave, axis, cx, cy, cz);
        int16 f = active & (((word >> (ci & 31)) & 1) != 0);
        fx = select(fx, x, f);
        fy = select(fy, y, f);
        fz = select(fz, z, f);
        stopped |= f;
        active &= ~f;
        *done |= active & (leave | out);
        active &= ~(leave | out);
        walking &= ~(leave | out);
    }
    if (rt_any16(stopped)) {
        *cx = select(*cx, fx, stopped);
        *cy = select(*cy, fy, stopped);
        *cz = select(*cz, fz, stopped);
#endif
        int16 ci = rt_cell_index16(g, *cx, *cy, *cz);
        *pos = select(*pos, as_uint16(rt_gather_i(cell_start, ci, stopped)), as_uint16(stopped));
        *found |= stopped;
    }
}

/* The lanes' next streams after traversal (RT_NEXT_*). */
inline uint16 rt_next16(int16 found, int16 done)
{
    return select(select((uint16)RT_NEXT_TRAVERSE, (uint16)RT_NEXT_INTERSECT, as_uint16(found)),
                  (uint16)RT_NEXT_DONE, as_uint16(done));
}

/* Ends a ray's pass: a finished ray adds its counts to the per-ray maxima
 * (Purcell Table 5.2), a live one saves its walk for the next pass. */
inline void rt_stream_retire(uint next, global uint *maxima, uint steps, uint tests,
                             global rt_walk *walk, uint id, rt_walk w)
{
    if (next == RT_NEXT_DONE)
        rt_maxima_add(maxima, steps, tests);
    else
        walk[id] = w;
}

/* rt_stream_retire's per-ray maxima for the finished lanes (done) of a
 * block at once: one reduction each. */
inline void rt_maxima_add16(global uint *maxima, uint16 steps, uint16 tests, int16 done)
{
    if (rt_any16(done))
        rt_maxima_add(maxima, (uint)rt_minmax16(as_int16(steps), done).y,
                      (uint)rt_minmax16(as_int16(tests), done).y);
}

/* One ray of rt_setup (the records after the last block of 16). Returns
 * whether it enters the grid. */
inline int rt_setup_one(const rt_grid_args *g, global const rt_ray *rays, global uint *codes,
                        global rt_walk *walk, global rt_hit *hits, uint i)
{
    rt_rayp r = rt_prepare(&rays[i]);
    int3 c = (int3)(0, 0, 0);
    int in = rt_grid_enter(g, &r, &c);
    rt_hit h;
    h.tri = RT_NO_HIT;
    h.t = r.tmax;
    h.u = 0.0f;
    h.v = 0.0f;
    h.steps = 0u;
    h.tests = 0u;
    hits[i] = h;
    rt_walk w;
    w.cx = c.x;
    w.cy = c.y;
    w.cz = c.z;
    w.pos = 0u;
    walk[i] = w;
    codes[i] = in ? RT_NEXT_TRAVERSE : RT_NEXT_DONE;
    return in;
}

/* The records of the next block of rays of a pass, ids[from .. from + 16)
 * (those below `end`): its rays, walk states and, where given, hits, one
 * line each, while this block runs (SLUICE_PREFETCH). The callers pass the
 * stream's length as `end`, so the last block of a chunk asks for the next
 * chunk's first (rt_trace_fused). */
inline void rt_stream_prefetch(global const uint *ids, uint from, uint end,
                               global const rt_ray *rays, global const rt_walk *walk,
                               global const rt_hit *hits)
{
    for (uint q = from; q < min(from + 16u, end); ++q) {
        uint id = ids[q];
        SLUICE_PREFETCH(rays + id);
        SLUICE_PREFETCH(walk + id);
        if (hits)
            SLUICE_PREFETCH(hits + id);
    }
}

/* One ray of rt_traverse (the records after the last block of 16): up to
 * RT_UNROLL_STEPS voxels. Returns the ray's next stream; adds the voxels
 * visited to *visited. */
inline uint rt_traverse_one(const rt_grid_args *g, global const rt_ray *rays, global rt_walk *walk,
                            global rt_hit *hits, global uint *maxima, global const uint *cell_start,
                            uint id, uint *visited_out)
{
    rt_rayp r = rt_prepare(&rays[id]);
    rt_walk w = walk[id];
    int3 c = (int3)(w.cx, w.cy, w.cz);
    uint visited = 0u, next = RT_NEXT_TRAVERSE;
    for (int k = 0; k < RT_UNROLL_STEPS; ++k) {
        ++visited;
        uint ci = rt_cell_index(g, c);
        uint a = cell_start[ci], b = cell_start[ci + 1u];
        if (a < b) {
            w.pos = a;
            next = RT_NEXT_INTERSECT;
            break;
        }
        int axis;
        float te = rt_voxel_exit(g, &r, c, &axis);
        if (te >= r.tmax || !rt_voxel_step(g, &r, &c, axis)) {
            next = RT_NEXT_DONE;
            break;
        }
    }
    global rt_hit *h = &hits[id];
    uint steps = h->steps + visited;
    h->steps = steps;
    w.cx = c.x;
    w.cy = c.y;
    w.cz = c.z;
    rt_stream_retire(next, maxima, steps, h->tests, walk, id, w);
    *visited_out += visited;
    return next;
}

/* Eye-ray (or any ray) setup and the first traverse pass: clip to the grid,
 * then up to RT_UNROLL_STEPS voxels as rt_traverse takes them. Every ray's
 * hit record starts as a miss with no tests; rays that miss the grid's box
 * are done at once, the others go on from their first voxel. Setup and the
 * first pass are one kernel so that the rays are read once and the walk
 * state is written once (rt_route_setup then sends the ids on, with the
 * ray's index as its id). */
__kernel void rt_setup(SLUICE_PARAMS, global const rt_ray *rays, global uint *codes,
                       global rt_walk *walk, global rt_hit *hits, global uint *maxima,
                       global const uint *cell_start, const rt_grid_args g, global const uint *bits)
{
    SLUICE_FOR_EACH_RANGE (lo, hi) {
        const uint16 lane = SLUICE_LANE16;
        uint i = lo, visited_all = 0u, done_all = 0u, entered_all = 0u;
        uint n = SLUICE_LENGTH;
        for (; RT_BLOCKS16 && i + 16u <= hi; i += 16u) {
            /* the next block's rays, one line each (SLUICE_PREFETCH), past
             * the chunk's end too (rt_trace_fused) */
            for (uint q = i + 16u; q < min(i + 32u, n); ++q)
                SLUICE_PREFETCH(rays + q);
            rt_packet r;
            rt_packet_load(rays, as_int16((uint16)i + lane), (int16)-1, &r);
            /* rt_grid_enter, lane by lane */
            float16 t0 = r.tmin, t1 = r.tmax;
            int16 miss = (int16)0;
            float16 o[3] = {r.ox, r.oy, r.oz}, d[3] = {r.dx, r.dy, r.dz};
            float16 inv[3] = {r.ix, r.iy, r.iz};
            for (int k = 0; k < 3; ++k) {
                int16 par = d[k] == 0.0f;
                miss |= par & ((o[k] < g.lo[k]) | (o[k] > g.hi[k]));
                float16 ta = (g.lo[k] - o[k]) * inv[k], tb = (g.hi[k] - o[k]) * inv[k];
                t0 = select(fmax(t0, fmin(ta, tb)), t0, par);
                t1 = select(fmin(t1, fmax(ta, tb)), t1, par);
            }
            int16 in = ~miss & (t0 <= t1);
            int16 c[3];
            for (int k = 0; k < 3; ++k) {
                float16 p = o[k] + d[k] * t0;
                int16 v = convert_int16(floor((p - g.lo[k]) * g.inv_cell[k]));
                c[k] = clamp(v, (int16)0, (int16)(g.dims[k] - 1));
            }
            int16 cx = c[0], cy = c[1], cz = c[2];
            uint16 pos = (uint16)0u, visited = (uint16)0u;
            int16 done = ~in, found = (int16)0;
            rt_traverse16(&g, &r, cell_start, bits, in, &cx, &cy, &cz, &pos, &visited, &found,
                          &done);
            uint16 next = rt_next16(found, done);
            vstore16(next, 0, codes + i);
            done_all += (uint)popcount((uint)sluice_mask16(done));
            entered_all += (uint)popcount((uint)sluice_mask16(in));
#ifdef RT_AOS16_
            /* the records whole: a finished ray's walk is never read */
            rt_store_hits16(hits + i, (int16)(-1), r.tmax, (float16)0.0f, (float16)0.0f, visited,
                            (uint16)0u);
            rt_store_walks16(walk + i, cx, cy, cz, pos);
            rt_maxima_add16(maxima, visited, (uint16)0u, done);
            visited_all += rt_sum16(visited);
#else
            int wc[4][16];
            uint vs[16], nx[16];
            float tm[16];
            vstore16(r.tmax, 0, tm);
            vstore16(visited, 0, vs);
            vstore16(next, 0, nx);
            rt_walk16_spill(cx, cy, cz, pos, wc);
            for (uint l = 0; l < 16u; ++l) {
                rt_hit h;
                h.tri = RT_NO_HIT;
                h.t = tm[l];
                h.u = 0.0f;
                h.v = 0.0f;
                h.steps = vs[l];
                h.tests = 0u;
                hits[i + l] = h;
                rt_walk w;
                w.cx = wc[0][l];
                w.cy = wc[1][l];
                w.cz = wc[2][l];
                w.pos = (uint)wc[3][l];
                rt_stream_retire(nx[l], maxima, vs[l], 0u, walk, i + l, w);
                visited_all += vs[l];
            }
#endif
        }
        for (; i < hi; ++i) {
            int in = rt_setup_one(&g, rays, codes, walk, hits, i);
            uint next = in ? RT_NEXT_TRAVERSE : RT_NEXT_DONE;
            entered_all += (uint)in;
            if (in)
                next = rt_traverse_one(&g, rays, walk, hits, maxima, cell_start, i, &visited_all);
            codes[i] = next;
            done_all += next == RT_NEXT_DONE;
        }
        SLUICE_COUNT(0, visited_all);
        SLUICE_COUNT(2, done_all);
        SLUICE_COUNT(5, entered_all);
    }
}

/* Up to RT_UNROLL_STEPS voxels: a non-empty voxel sends the ray to the
 * intersector (empty voxels never reach it); leaving the grid, or passing
 * the ray's end, finishes it as a miss. Blocks of 16 rays run in lanes. */
__kernel void rt_traverse(SLUICE_PARAMS, global const uint *ids, global uint *codes,
                          global rt_walk *walk, global const rt_ray *rays, global rt_hit *hits,
                          global uint *maxima, global const uint *cell_start, const rt_grid_args g,
                          global const uint *bits)
{
    SLUICE_FOR_EACH_RANGE (lo, hi) {
        uint i = lo, visited_all = 0u, done_all = 0u, n = SLUICE_LENGTH;
        for (; RT_BLOCKS16 && i + 16u <= hi; i += 16u) {
            uint16 idv = vload16(0, ids + i);
            uint id[16];
            vstore16(idv, 0, id);
            rt_stream_prefetch(ids, i + 16u, n, rays, walk, 0);
            int wc[4][16];
            rt_packet r;
            int16 cx, cy, cz;
            uint16 pos;
            rt_walk16_load(rays, walk, idv, &r, &cx, &cy, &cz, &pos);
            int16 done = (int16)0, found = (int16)0;
            uint16 visited = (uint16)0u;
            rt_traverse16(&g, &r, cell_start, bits, (int16)-1, &cx, &cy, &cz, &pos, &visited,
                          &found, &done);
            uint16 next = rt_next16(found, done);
            vstore16(next, 0, codes + i);
            uint vs[16], nx[16];
            vstore16(visited, 0, vs);
            vstore16(next, 0, nx);
            rt_walk16_spill(cx, cy, cz, pos, wc);
            for (uint l = 0; l < 16u; ++l) {
                global rt_hit *h = &hits[id[l]];
                uint steps = h->steps + vs[l];
                h->steps = steps;
                rt_walk w;
                w.cx = wc[0][l];
                w.cy = wc[1][l];
                w.cz = wc[2][l];
                w.pos = (uint)wc[3][l];
                rt_stream_retire(nx[l], maxima, steps, h->tests, walk, id[l], w);
            }
            visited_all += vs[0] + vs[1] + vs[2] + vs[3] + vs[4] + vs[5] + vs[6] + vs[7] + vs[8] +
                           vs[9] + vs[10] + vs[11] + vs[12] + vs[13] + vs[14] + vs[15];
            done_all += (uint)popcount((uint)sluice_mask16(done));
        }
        for (; i < hi; ++i) {
            uint next =
                rt_traverse_one(&g, rays, walk, hits, maxima, cell_start, ids[i], &visited_all);
            codes[i] = next;
            done_all += next == RT_NEXT_DONE;
        }
        SLUICE_COUNT(0, visited_all);
        SLUICE_COUNT(2, done_all);
    }
}

/* One ray of rt_intersect (the records after the last block of 16, and
 * every ray with the watertight test): up to RT_UNROLL_TESTS triangles, over
 * as many non-empty voxels as the budget reaches (see rt_intersect). Returns
 * the ray's next stream; adds the tests done to *tested_out and the voxels
 * entered to *visited_out. */
inline uint rt_intersect_one(const rt_grid_args *g, global const rt_ray *rays, global rt_walk *walk,
                             global rt_hit *hits, global uint *maxima,
                             global const uint *cell_start, global const uint *cell_tris,
                             global const float *tv, uint id, uint *tested_out, uint *visited_out)
{
    rt_rayp r = rt_prepare(&rays[id]);
    rt_walk w = walk[id];
    int3 c = (int3)(w.cx, w.cy, w.cz);
    uint end = cell_start[rt_cell_index(g, c) + 1u];
    global rt_hit *h = &hits[id];
    rt_best b;
    b.tri = h->tri;
    b.t = h->t;
    b.u = h->u;
    b.v = h->v;
    uint before = b.tri;
    float before_t = b.t;
    uint tested = 0u, visited = 0u, next;
    for (;;) {
        int axis;
        float te = rt_voxel_exit(g, &r, c, &axis);
        float limit = r.any_hit ? r.tmax : rt_voxel_limit(te, r.tmax);
        uint stop = min(end, w.pos + ((uint)RT_UNROLL_TESTS - tested));
        rt_intersect_list(cell_tris, tv, w.pos, stop, &r, limit, &b);
        tested += stop - w.pos;
        w.pos = stop;
        if (stop < end) {
            next = RT_NEXT_INTERSECT;
            break;
        }
        if (b.tri != RT_NO_HIT || te >= r.tmax || !rt_voxel_step(g, &r, &c, axis)) {
            next = RT_NEXT_DONE;
            break;
        }
        /* The next voxel: an empty one is traversal's (which enters it); a
         * non-empty one is entered here and its list goes on in this pass,
         * or in the next intersect pass when the budget is spent. */
        uint ci = rt_cell_index(g, c);
        uint a = cell_start[ci];
        end = cell_start[ci + 1u];
        if (a >= end) {
            next = RT_NEXT_TRAVERSE;
            break;
        }
        ++visited;
        w.pos = a;
        if (tested >= (uint)RT_UNROLL_TESTS) {
            next = RT_NEXT_INTERSECT;
            break;
        }
    }
    uint tests = h->tests + tested;
    h->tests = tests;
    uint steps = h->steps + visited;
    h->steps = steps;
    if (b.tri != before || b.t != before_t) {
        h->tri = b.tri;
        h->t = b.t;
        h->u = b.u;
        h->v = b.v;
    }
    w.cx = c.x;
    w.cy = c.y;
    w.cz = c.z;
    rt_stream_retire(next, maxima, steps, tests, walk, id, w);
    *tested_out += tested;
    *visited_out += visited;
    return next;
}

/* Up to RT_UNROLL_TESTS triangles per ray. When a voxel's list is done: a
 * hit inside the voxel finishes the ray (hits beyond the voxel's exit were
 * rejected, so the first voxel with a hit holds the nearest one); otherwise
 * the ray steps to the next voxel. An empty one sends the ray back to
 * traversal; a non-empty one is entered here (counted as a voxel step, as
 * traversal would) and its list goes on with the budget left, so the ray
 * stays in the intersect stream instead of ping-ponging through traversal.
 * Blocks of 16 rays run in lanes (Moller-Trumbore; the watertight test runs
 * ray by ray). `lists` is the list-order copy of the triangle records when
 * the program is built with RT_LIST_COPY (rt_intersect16_turned). */
__kernel void rt_intersect(SLUICE_PARAMS, global const uint *ids, global uint *codes,
                           global rt_walk *walk, global const rt_ray *rays, global rt_hit *hits,
                           global uint *maxima, global const uint *cell_start,
                           global const uint *cell_tris, global const float *tv,
                           const rt_grid_args g, global const float *lists)
{
    SLUICE_FOR_EACH_RANGE (lo, hi) {
        uint i = lo, tested_all = 0u, visited_all = 0u, done_all = 0u, n = SLUICE_LENGTH;
#ifndef RT_WATERTIGHT
        for (; RT_BLOCKS16 && i + 16u <= hi; i += 16u) {
            uint16 idv = vload16(0, ids + i);
            uint id[16];
            vstore16(idv, 0, id);
            rt_stream_prefetch(ids, i + 16u, n, rays, walk, hits);
            int wc[4][16];
            rt_packet r;
            int16 cx, cy, cz;
            uint16 pos;
            rt_walk16_load(rays, walk, idv, &r, &cx, &cy, &cz, &pos);
            /* the best hit so far and the tests done (rt_hit: tri, t, u, v,
             * steps, tests) */
            global const uint *hw = (global const uint *)hits;
            int16 hat = as_int16(idv) * (int)(sizeof(rt_hit) / sizeof(uint));
            r.tri = rt_gather_i(hw, hat, (int16)-1);
            r.t = as_float16(rt_gather_i(hw, hat + 1, (int16)-1));
            r.u = as_float16(rt_gather_i(hw, hat + 2, (int16)-1));
            r.v = as_float16(rt_gather_i(hw, hat + 3, (int16)-1));
            uint16 tests0 = as_uint16(rt_gather_i(hw, hat + 5, (int16)-1));
            int16 tri0 = r.tri;
            float16 t0 = r.t;
            int16 ci = rt_cell_index16(&g, cx, cy, cz);
            uint16 end = as_uint16(rt_gather_i(cell_start, ci + 1, (int16)-1));
            int16 axis;
            float16 te = rt_voxel_exit16(&g, &r, cx, cy, cz, &axis);
            float16 limit = select(rt_voxel_limit16(te, r.tmax), r.tmax, r.any_hit);
            uint16 tested = (uint16)0u, visited = (uint16)0u;
            uint16 next = (uint16)RT_NEXT_INTERSECT;
            int16 active = (int16)-1, done = (int16)0;
            while (rt_any16(active)) {
                /* the current voxel's list, as far as the budget goes */
                uint16 stop = min(end, pos + ((uint16)RT_UNROLL_TESTS - tested));
                stop = select(pos, stop, as_uint16(active));
                /* lanes of a pass seldom share a list: each group its
                 * cheaper test (5% faster on bunny than rt_intersect16_lists;
                 * the turned tests reading the list copy, 2-6% more) */
                rt_intersect16_lists_either(tv, lists, cell_tris, as_int16(pos), as_int16(stop),
                                            active, &r, limit);
                tested += stop - pos;
                pos = stop;
                /* budget spent inside the list: next intersect pass */
                active &= ~as_int16(stop < end);
                /* list done: a hit finishes the ray, else it steps on */
                int16 fin = active & ((r.tri != -1) | (te >= r.tmax));
                int16 go = active & ~fin;
                int16 out = rt_step16(&g, &r, go, axis, &cx, &cy, &cz);
                done |= fin | out;
                active &= ~(fin | out);
                if (!rt_any16(active))
                    break;
                /* the next voxel: an empty one goes to traversal (which
                 * enters it); a non-empty one is entered here */
                ci = rt_cell_index16(&g, cx, cy, cz);
                int16 ai, bi;
                rt_cell_bounds16(cell_start, ci, active, &ai, &bi);
                uint16 a = as_uint16(ai), b = as_uint16(bi);
                int16 empty = active & as_int16(a >= b);
                active &= ~empty;
                visited += as_uint16(active) & (uint16)1u;
                pos = select(pos, a, as_uint16(active));
                end = select(end, b, as_uint16(active));
                next = select(next, (uint16)RT_NEXT_TRAVERSE, as_uint16(empty));
                /* budget spent: the new list waits for the next pass */
                active &= as_int16(tested < (uint16)RT_UNROLL_TESTS);
                if (!rt_any16(active))
                    break;
                int16 ax;
                float16 te2 = rt_voxel_exit16(&g, &r, cx, cy, cz, &ax);
                axis = select(axis, ax, active);
                te = select(te, te2, active);
                limit =
                    select(limit, select(rt_voxel_limit16(te2, r.tmax), r.tmax, r.any_hit), active);
            }
            next = select(next, (uint16)RT_NEXT_DONE, as_uint16(done));
            vstore16(next, 0, codes + i);
#ifdef RT_AOS16_
            /* ids in a run (a block whose 16 rays all came on from one
             * block of the pass before): the records whole, as rt_setup
             * writes them (a finished ray's walk is never read; unchanged
             * fields are written back as read) */
            const uint16 lane16 = SLUICE_LANE16;
            if (sluice_mask16(as_int16(idv == (uint16)idv.s0 + lane16)) == (ushort)0xffffu) {
                uint16 steps = as_uint16(rt_gather_i(hw, hat + 4, (int16)-1)) + visited,
                       tests = tests0 + tested;
                rt_store_hits16(hits + idv.s0, r.tri, r.t, r.u, r.v, steps, tests);
                rt_store_walks16(walk + idv.s0, cx, cy, cz, pos);
                rt_maxima_add16(maxima, steps, tests, done);
                tested_all += rt_sum16(tested);
                visited_all += rt_sum16(visited);
                done_all += (uint)popcount((uint)sluice_mask16(done));
                continue;
            }
#endif
            uint ts[16], nx[16], tri[16], vs[16], tests[16], changed[16];
            float ft[16], fu[16], fv[16];
            vstore16(tested, 0, ts);
            vstore16(tests0 + tested, 0, tests);
            vstore16(next, 0, nx);
            vstore16(as_uint16(r.tri), 0, tri);
            vstore16(r.t, 0, ft);
            vstore16(r.u, 0, fu);
            vstore16(r.v, 0, fv);
            vstore16(as_uint16((r.tri != tri0) | (as_int16(r.t) != as_int16(t0))), 0, changed);
            rt_walk16_spill(cx, cy, cz, pos, wc);
            vstore16(visited, 0, vs);
            for (uint l = 0; l < 16u; ++l) {
                global rt_hit *h = &hits[id[l]];
                h->tests = tests[l];
                uint steps = h->steps + vs[l];
                h->steps = steps;
                if (changed[l]) {
                    h->tri = tri[l];
                    h->t = ft[l];
                    h->u = fu[l];
                    h->v = fv[l];
                }
                rt_walk w;
                w.cx = wc[0][l];
                w.cy = wc[1][l];
                w.cz = wc[2][l];
                w.pos = (uint)wc[3][l];
                rt_stream_retire(nx[l], maxima, steps, tests[l], walk, id[l], w);
                tested_all += ts[l];
                visited_all += vs[l];
            }
            done_all += (uint)popcount((uint)sluice_mask16(done));
        }
#endif
        for (; i < hi; ++i) {
            uint next = rt_intersect_one(&g, rays, walk, hits, maxima, cell_start, cell_tris, tv,
                                         ids[i], &tested_all, &visited_all);
            codes[i] = next;
            done_all += next == RT_NEXT_DONE;
        }
        SLUICE_COUNT(0, visited_all);
        SLUICE_COUNT(1, tested_all);
        SLUICE_COUNT(2, done_all);
    }
}

/* The conditional outputs: the ids of a pass's rays go by their codes to
 * slot 0, the traverse stream, or slot 1, the intersect stream; finished rays
 * go nowhere (their hit is in place). 16 at a time. */
__kernel void rt_route(SLUICE_PARAMS, global const uint *codes, global const uint *ids,
                       global uint *trav, global uint *isect)
{
    SLUICE_FOR_EACH_RANGE (b, e) {
        uint i = b;
        for (; i + 16u <= e; i += 16u) {
            uint16 x = vload16(0, ids + i), cv = vload16(0, codes + i);
            SLUICE_EMIT16(0, trav, x, sluice_mask16(as_int16(cv == (uint16)RT_NEXT_TRAVERSE)));
            SLUICE_EMIT16(1, isect, x, sluice_mask16(as_int16(cv == (uint16)RT_NEXT_INTERSECT)));
        }
        for (; i < e; ++i) {
            uint cd = codes[i];
            SLUICE_EMIT_IF(0, trav, ids[i], cd == RT_NEXT_TRAVERSE);
            SLUICE_EMIT_IF(1, isect, ids[i], cd == RT_NEXT_INTERSECT);
        }
    }
}

/* After setup: the codes are indexed by ray, so record i is ray i; slot 0
 * is the traverse stream, slot 1 the intersect stream. */
__kernel void rt_route_setup(SLUICE_PARAMS, global const uint *codes, global uint *trav,
                             global uint *isect)
{
    SLUICE_FOR_EACH_RANGE (b, e) {
        const uint16 lane = SLUICE_LANE16;
        uint i = b;
        for (; i + 16u <= e; i += 16u) {
            uint16 cv = vload16(0, codes + i), x = (uint16)i + lane;
            SLUICE_EMIT16(0, trav, x, sluice_mask16(as_int16(cv == (uint16)RT_NEXT_TRAVERSE)));
            SLUICE_EMIT16(1, isect, x, sluice_mask16(as_int16(cv == (uint16)RT_NEXT_INTERSECT)));
        }
        for (; i < e; ++i) {
            uint cd = codes[i];
            SLUICE_EMIT_IF(0, trav, i, cd == RT_NEXT_TRAVERSE);
            SLUICE_EMIT_IF(1, isect, i, cd == RT_NEXT_INTERSECT);
        }
    }
}

/* The voxel map of rt_traverse16: bit b of word i is set when voxel
 * 32i + b (of `cells`) holds triangles. */
__kernel void rt_voxel_bits(SLUICE_PARAMS, global const uint *cell_start, uint cells,
                            global uint *bits)
{
    SLUICE_FOR_EACH (i) {
        uint w = 0u;
        for (uint b = 0; b < 32u; ++b) {
            uint c = 32u * i + b;
            if (c < cells && cell_start[c] < cell_start[c + 1u])
                w |= 1u << b;
        }
        bits[i] = w;
    }
}
