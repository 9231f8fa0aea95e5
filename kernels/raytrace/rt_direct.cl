/*
 * rt_direct.cl: the fused mode's direct light, from point lights and area
 * lights. In the stream form (rt_shade.cl) a hit's shadow rays leave as a
 * stream that is written, traced (the tracer's own pass) and read back by
 * rt_shadow_resolve, and the shading kernel, which emits them, runs its
 * light sampling twice (count pass, write pass). Here, in the fused mode
 * (the MIMD form of Purcell 5.2.2, one kernel taking a ray all the way), a
 * hit's shadow rays are made and traced where they are: the same rays
 * (rt_point_light_ray, rt_light_block8 and rt_light_one_ray, ray for ray),
 * 16 at a time as one packet through the tracer's rt_packet_trace
 * (rt_fused.cl; a packet takes the rays of the work-item's hits in turn, as
 * the stream's packets do, so that scenes with few rays a hit fill it too),
 * each one that reaches its light adding what it carries. A pixel's sum is
 * taken in fixed point, as rt_shadow_resolve takes it, so the image is the
 * stream form's bit for bit.
 *
 * Build options: those of rt_shade.cl with RT_DIRECT_FUSED (which leaves
 * direct light to this kernel), and the tracer's (rt_tracer_build_options).
 * Counters: 0 shadow rays, 1 non-finite contributions dropped, 2 voxels
 * visited, 3 triangle tests, 4 slices crossed, 5 of those through empty
 * macro cells (rt_fused.cl).
 */

/* Shadow rays waiting for their packet: origins, directions, lengths, what
 * each carries and its pixel; and the pixel whose fixed-point sum is being
 * taken (a hit's rays come one after another: one atomic add a run of them,
 * as in rt_shadow_resolve). */
typedef struct rt_direct_batch {
    float ox[RT_PACKET], oy[RT_PACKET], oz[RT_PACKET];
    float dx[RT_PACKET], dy[RT_PACKET], dz[RT_PACKET], tmax[RT_PACKET];
    float wr[RT_PACKET], wg[RT_PACKET], wb[RT_PACKET];
    uint pixel[RT_PACKET];
    uint n;
    uint run_pixel;
    long3 run;
    /* counts: non-finite contributions, voxels, tests, slices (rt_fused.cl) */
    uint bad, voxels, tests, slices[2];
} rt_direct_batch;

/* The tracer's buffers and grid, as rt_packet_trace takes them. */
typedef struct rt_direct_grid {
    rt_grid_args g;
    global uint *maxima;
    global const uint *cell_start, *cell_tris;
    global const float *tv, *lists;
    global const uchar *macro;
} rt_direct_grid;

/* Adds what the run holds to its pixel, and starts a run for `pixel`. */
inline void rt_direct_run(rt_direct_batch *B, global long *accum, uint pixel)
{
    if (B->run_pixel != pixel) {
        if (B->run_pixel != 0xffffffffu)
            rt_add_fixed(accum, B->run_pixel, B->run);
        B->run_pixel = pixel;
        B->run = (long3)(0);
    }
}

/* Traces the batch's rays as one packet; the unblocked ones add what they
 * carry to their pixels (fixed point), non-finite ones are counted and
 * dropped (rt_shadow_resolve's rule). */
inline void rt_direct_flush(rt_direct_batch *B, const rt_direct_grid *G, global long *accum)
{
    if (!B->n)
        return;
    const int16 lane = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    int16 live = lane < (int)B->n;
    for (uint l = B->n; l < RT_PACKET; ++l) {
        B->ox[l] = B->oy[l] = B->oz[l] = 0.0f;
        B->dx[l] = B->dy[l] = B->dz[l] = 0.0f;
        B->tmax[l] = 0.0f;
    }
    rt_packet P;
    P.ox = vload16(0, B->ox);
    P.oy = vload16(0, B->oy);
    P.oz = vload16(0, B->oz);
    P.dx = vload16(0, B->dx);
    P.dy = vload16(0, B->dy);
    P.dz = vload16(0, B->dz);
    P.tmin = (float16)(0.0f);
    P.tmax = vload16(0, B->tmax);
    rt_packet_start_(&P, (int16)((int)RT_FLAG_ANY_HIT));
    uint16 st, ts;
    rt_packet_trace(&G->g, &P, live, G->cell_start, G->cell_tris, G->tv, G->lists, G->macro, &st,
                    &ts, B->slices);
    int tri[RT_PACKET];
    uint sa[RT_PACKET], ta[RT_PACKET];
    vstore16(P.tri, 0, tri);
    vstore16(st, 0, sa);
    vstore16(ts, 0, ta);
    uint ms = 0u, mt = 0u;
    for (uint l = 0; l < B->n; ++l) {
        B->voxels += sa[l];
        B->tests += ta[l];
        ms = max(ms, sa[l]);
        mt = max(mt, ta[l]);
        if (tri[l] != -1)
            continue; /* blocked */
        float3 c = (float3)(B->wr[l], B->wg[l], B->wb[l]);
        if (!(isfinite(c.x) && isfinite(c.y) && isfinite(c.z))) {
            B->bad++;
            continue;
        }
        rt_direct_run(B, accum, B->pixel[l]);
        B->run += rt_fixed(c);
    }
    rt_maxima_add(G->maxima, ms, mt);
    B->n = 0u;
}

/* Adds one shadow ray (from o, direction d, length tmax, carrying w, for
 * `pixel`) to the batch, tracing the batch when full. */
inline void rt_direct_add(rt_direct_batch *B, const rt_direct_grid *G, global long *accum, float3 o,
                          float3 d, float tmax, float3 w, uint pixel)
{
    uint l = B->n++;
    B->ox[l] = o.x;
    B->oy[l] = o.y;
    B->oz[l] = o.z;
    B->dx[l] = d.x;
    B->dy[l] = d.y;
    B->dz[l] = d.z;
    B->tmax[l] = tmax;
    B->wr[l] = w.x;
    B->wg[l] = w.y;
    B->wb[l] = w.z;
    B->pixel[l] = pixel;
    if (B->n == RT_PACKET)
        rt_direct_flush(B, G, accum);
}

/* The direct light of rays [base, base + count) of a wave (launched over
 * count): point lights, then area-light samples, traced where they are
 * made; rt_shade, with RT_DIRECT_FUSED, leaves them out. A work-item takes a run of rays (its
 * chunk), so that its packets fill with the rays of one hit after another. */
__kernel void rt_direct(SLUICE_PARAMS, global const rt_ray *rays, global const rt_hit *hits,
                        uint base, global long *accum, global const float *stv,
                        global const uint *indices, global const float *normals,
                        global const uint *tri_mat, global const rt_material *mats,
                        global const rt_point_light *plights, global const uint *area_tris,
                        global const float *area_cdf, const rt_frame f, global uint *maxima,
                        global const uint *cell_start, global const uint *cell_tris,
                        global const float *tv, const rt_grid_args g, global const float *lists,
                        global const uchar *macro)
{
    rt_direct_grid G;
    G.g = g;
    G.maxima = maxima;
    G.cell_start = cell_start;
    G.cell_tris = cell_tris;
    G.tv = tv;
    G.lists = lists;
    G.macro = macro;
    SLUICE_FOR_EACH_RANGE (b, e) {
        rt_direct_batch B;
        B.n = 0u;
        B.run_pixel = 0xffffffffu;
        B.run = (long3)(0);
        B.bad = B.voxels = B.tests = B.slices[0] = B.slices[1] = 0u;
        uint shadow = 0u;
        for (uint id = b; id < e; ++id) {
            uint i = base + id;
            rt_hit h = hits[i];
            if (h.tri == RT_NO_HIT)
                continue;
            rt_ray ray = rays[i];
            rt_surface s = rt_surface_at(&ray, &h, stv, indices, normals, tri_mat, mats);
            uint kind = s.m.kind;
            int specular = kind == 1u || kind == 2u;
            /* rt_shade's rule: which hits take direct light */
            int lit = f.mode == RT_MODE_SHADOW || (!specular && f.mode != RT_MODE_CAST);
            uint nl = (lit && f.area_lights) ? f.light_samples : 0u;
            uint np = lit ? f.point_lights : 0u;
            if (!nl && !np)
                continue;
            rt_light_ctx lx = rt_light_ctx_at(&s, &ray, h.tri, &f, nl);
            for (uint l = 0u; l < np; ++l) {
                float3 contrib;
                if (!rt_point_light_go(&s, lx.off, lx.w, lx.wo, plights[l], &contrib))
                    continue;
                ++shadow;
                rt_ray sr = rt_point_light_ray(&s, lx.off, plights[l], contrib, ray.pixel);
                rt_direct_add(&B, &G, accum, lx.o, (float3)(sr.dx, sr.dy, sr.dz), sr.tmax, contrib,
                              ray.pixel);
            }
            for (uint k0 = 0u; k0 < lx.full; k0 += RT_LIGHT_LANES) {
                int gos[RT_LIGHT_LANES];
                float dir[3][RT_LIGHT_LANES], tmax[RT_LIGHT_LANES], wl[3][RT_LIGHT_LANES];
                rt_light_block8(k0, &lx, &s, 1, &f, area_tris, area_cdf, stv, tri_mat, mats, gos,
                                dir, tmax, wl);
                for (uint l = 0u; l < min((uint)RT_LIGHT_LANES, lx.full - k0); ++l) {
                    if (!gos[l])
                        continue;
                    /* rt_spawn's ray: from o, along dir, to tmax */
                    ++shadow;
                    rt_direct_add(&B, &G, accum, lx.o, (float3)(dir[0][l], dir[1][l], dir[2][l]),
                                  tmax[l], (float3)(wl[0][l], wl[1][l], wl[2][l]), ray.pixel);
                }
            }
            for (uint k = lx.full; k < nl; ++k) {
                /* the rest one at a time, as rt_shade takes them */
                float3 q, lc, le;
                if (!rt_light_one(k, &lx, &s, &f, area_tris, area_cdf, stv, tri_mat, mats, &q, &lc,
                                  &le))
                    continue;
                ++shadow;
                rt_ray sr = rt_light_one_ray(&lx, &s, q, lc, le, ray.pixel);
                rt_direct_add(&B, &G, accum, lx.o, (float3)(sr.dx, sr.dy, sr.dz), sr.tmax,
                              (float3)(sr.wr, sr.wg, sr.wb), ray.pixel);
            }
        }
        rt_direct_flush(&B, &G, accum);
        rt_direct_run(&B, accum, 0xffffffffu);
        SLUICE_COUNT(0, shadow);
        SLUICE_COUNT(1, B.bad);
        SLUICE_COUNT(2, B.voxels);
        SLUICE_COUNT(3, B.tests);
        SLUICE_COUNT(4, B.slices[0]);
        SLUICE_COUNT(5, B.slices[1]);
    }
}
