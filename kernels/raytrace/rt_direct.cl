/*
 * rt_direct.cl: the fused mode's direct light from area lights. In the
 * stream form (rt_shade.cl) a hit's light samples leave as shadow rays, a
 * stream that is written, traced (the tracer's own pass) and read back by
 * rt_shadow_resolve, and the shading kernel, which emits them, runs its
 * sampling twice (count pass, write pass). Here, in the fused mode (the MIMD
 * form of Purcell 5.2.2, one kernel taking a ray all the way), a hit's
 * samples are made and traced where they are: the same rays (rt_light_block8
 * and rt_shadow_ray, sample for sample), 16 at a time as one packet through
 * the tracer's rt_packet_trace (rt_fused.cl), each one that reaches its
 * light adding what it carries. The pixel's sum is taken in fixed point, as
 * rt_shadow_resolve takes it, so the image is the stream form's bit for bit.
 *
 * Build options: those of rt_shade.cl with RT_DIRECT_FUSED (which leaves
 * area lights to this kernel), and the tracer's (rt_tracer_build_options).
 * Counters: 0 shadow rays, 1 non-finite contributions dropped, 2 voxels
 * visited, 3 triangle tests, 4 slices crossed, 5 of those through empty
 * macro cells (rt_fused.cl).
 */

/* A hit's shadow rays waiting for their packet: directions, lengths and
 * what each carries; the origin is the hit's, the same for all. */
typedef struct rt_direct_batch {
    float dx[RT_PACKET], dy[RT_PACKET], dz[RT_PACKET], tmax[RT_PACKET];
    float wr[RT_PACKET], wg[RT_PACKET], wb[RT_PACKET];
    uint n;
} rt_direct_batch;

/* Traces the batch's rays from o as one packet; the unblocked ones add what
 * they carry to *run (fixed point), non-finite ones are counted in *bad and
 * dropped (rt_shadow_resolve's rule). */
inline void rt_direct_flush(rt_direct_batch *B, float3 o, const rt_grid_args *g,
                            global uint *maxima, global const uint *cell_start,
                            global const uint *cell_tris, global const float *tv,
                            global const float *lists, global const uchar *macro, long3 *run,
                            uint *bad, uint *voxels, uint *tests, uint *slices)
{
    if (!B->n)
        return;
    const int16 lane = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    int16 live = lane < (int)B->n;
    for (uint l = B->n; l < RT_PACKET; ++l) {
        B->dx[l] = B->dy[l] = B->dz[l] = 0.0f;
        B->tmax[l] = 0.0f;
    }
    rt_packet P;
    P.ox = (float16)(o.x);
    P.oy = (float16)(o.y);
    P.oz = (float16)(o.z);
    P.dx = vload16(0, B->dx);
    P.dy = vload16(0, B->dy);
    P.dz = vload16(0, B->dz);
    P.tmin = (float16)(0.0f);
    P.tmax = vload16(0, B->tmax);
    rt_packet_start_(&P, (int16)((int)RT_FLAG_ANY_HIT));
    uint16 st, ts;
    rt_packet_trace(g, &P, live, cell_start, cell_tris, tv, lists, macro, &st, &ts, slices);
    int tri[RT_PACKET];
    uint sa[RT_PACKET], ta[RT_PACKET];
    vstore16(P.tri, 0, tri);
    vstore16(st, 0, sa);
    vstore16(ts, 0, ta);
    uint ms = 0u, mt = 0u;
    for (uint l = 0; l < B->n; ++l) {
        *voxels += sa[l];
        *tests += ta[l];
        ms = max(ms, sa[l]);
        mt = max(mt, ta[l]);
        if (tri[l] != -1)
            continue; /* blocked */
        float3 c = (float3)(B->wr[l], B->wg[l], B->wb[l]);
        if (!(isfinite(c.x) && isfinite(c.y) && isfinite(c.z))) {
            ++*bad;
            continue;
        }
        *run += rt_fixed(c);
    }
    rt_maxima_add(maxima, ms, mt);
    B->n = 0u;
}

/* Adds one shadow ray (direction d, length tmax, carrying w) to the batch,
 * tracing the batch when full. */
inline void rt_direct_add(rt_direct_batch *B, float3 d, float tmax, float3 w, float3 o,
                          const rt_grid_args *g, global uint *maxima, global const uint *cell_start,
                          global const uint *cell_tris, global const float *tv,
                          global const float *lists, global const uchar *macro, long3 *run,
                          uint *bad, uint *voxels, uint *tests, uint *slices)
{
    uint l = B->n++;
    B->dx[l] = d.x;
    B->dy[l] = d.y;
    B->dz[l] = d.z;
    B->tmax[l] = tmax;
    B->wr[l] = w.x;
    B->wg[l] = w.y;
    B->wb[l] = w.z;
    if (B->n == RT_PACKET)
        rt_direct_flush(B, o, g, maxima, cell_start, cell_tris, tv, lists, macro, run, bad, voxels,
                        tests, slices);
}

/* The area-light samples of rays [base, base + count) of a wave (launched
 * over count), traced where they are made: rt_shade's, with RT_DIRECT_FUSED,
 * leaves them out. */
__kernel void rt_direct(SLUICE_PARAMS, global const rt_ray *rays, global const rt_hit *hits,
                        uint base, global long *accum, global const float *stv,
                        global const uint *indices, global const float *normals,
                        global const uint *tri_mat, global const rt_material *mats,
                        global const uint *area_tris, global const float *area_cdf,
                        const rt_frame f, global uint *maxima, global const uint *cell_start,
                        global const uint *cell_tris, global const float *tv, const rt_grid_args g,
                        global const float *lists, global const uchar *macro)
{
    SLUICE_FOR_EACH (id) {
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
        if (!nl)
            continue;
        float3 d = (float3)(ray.dx, ray.dy, ray.dz);
        float3 wo = -d;
        float3 w = (float3)(ray.wr, ray.wg, ray.wb);
        float3 off = s.ng * f.scene_eps;
        float per_sample = f.area_total / (float)f.light_samples;
        float3 reach = w * rt_brdf_support(&s.m);
        float3 o = s.p + off;
        uint skey = rt_key(ray.key, 16u);
        uint full = nl / RT_LIGHT_LANES * RT_LIGHT_LANES;
        rt_direct_batch B;
        B.n = 0u;
        long3 run = (long3)(0);
        uint shadow = 0u, bad = 0u, voxels = 0u, tests = 0u, slices[2] = {0u, 0u};
        for (uint k0 = 0u; k0 < full; k0 += RT_LIGHT_LANES) {
            int gos[RT_LIGHT_LANES];
            float dir[3][RT_LIGHT_LANES], tmax[RT_LIGHT_LANES], wl[3][RT_LIGHT_LANES];
            rt_light_block8(k0, skey, &s, o, w, wo, reach, per_sample, h.tri, 1, &f, area_tris,
                            area_cdf, stv, tri_mat, mats, gos, dir, tmax, wl);
            for (uint l = 0u; l < RT_LIGHT_LANES; ++l) {
                if (!gos[l])
                    continue;
                /* rt_spawn's ray: from o, along dir, to tmax */
                ++shadow;
                rt_direct_add(&B, (float3)(dir[0][l], dir[1][l], dir[2][l]), tmax[l],
                              (float3)(wl[0][l], wl[1][l], wl[2][l]), o, &g, maxima, cell_start,
                              cell_tris, tv, lists, macro, &run, &bad, &voxels, &tests, slices);
            }
        }
        for (uint k = full; k < nl; ++k) {
            /* the rest one at a time, as rt_shade takes them */
            float3 q, lc, le;
            if (!rt_light_one(k, skey, &s, o, reach, h.tri, &f, area_tris, area_cdf, stv, tri_mat,
                              mats, &q, &lc, &le))
                continue;
            ++shadow;
            rt_ray sr = rt_shadow_ray(s.p, off, q, 0.99999f,
                                      rt_area_light_weight(&s, wo, w, q - o, lc, le, per_sample),
                                      ray.pixel, RT_KIND_SHADOW | RT_FLAG_ANY_HIT);
            rt_direct_add(&B, (float3)(sr.dx, sr.dy, sr.dz), sr.tmax, (float3)(sr.wr, sr.wg, sr.wb),
                          o, &g, maxima, cell_start, cell_tris, tv, lists, macro, &run, &bad,
                          &voxels, &tests, slices);
        }
        rt_direct_flush(&B, o, &g, maxima, cell_start, cell_tris, tv, lists, macro, &run, &bad,
                        &voxels, &tests, slices);
        rt_add_fixed(accum, ray.pixel, run);
        SLUICE_COUNT(0, shadow);
        SLUICE_COUNT(1, bad);
        SLUICE_COUNT(2, voxels);
        SLUICE_COUNT(3, tests);
        SLUICE_COUNT(4, slices[0]);
        SLUICE_COUNT(5, slices[1]);
    }
}
