/*
 * pm_render.cl: the photon mapper's half of rendering (Purcell 6.2.4): the
 * ray tracer's Whitted shading (kernels/raytrace/rt_shade.cl, built with
 * RT_GATHER) leaves a gather point at every diffuse or glossy hit; these
 * kernels turn the points into kNN-grid queries and add the radiance
 * estimate, f_r * sum(Phi) / (pi r^2), to the film.
 * Counters: 0 estimates added, 1 estimates with no photon, 2 non-finite.
 */
#include "sluice.cl"

/* Query i is gather point i (the search does not read the id). */
__kernel void pm_gather_queries(SLUICE_PARAMS, global const rt_gather *g, global pm_query *q)
{
    SLUICE_FOR_EACH (i) {
        rt_gather p = g[i];
        pm_query r;
        r.px = p.px;
        r.py = p.py;
        r.pz = p.pz;
        r.nx = p.nx;
        r.ny = p.ny;
        r.nz = p.nz;
        r.id = i;
        q[i] = r;
    }
}

/* Adds gather point i's estimate to its pixel (the weight already holds the
 * path throughput times albedo / pi). Points from `answered` on have no
 * current result (an intermediate image of a batched search) and add
 * nothing. The area is pi r^2 of the photons found, or pi fixed_r2 when that
 * is not 0 (progressive photon mapping's radius search: the disc searched,
 * not the photons' extent, Knaus and Zwicker 2011). */
__kernel void pm_gather_add(SLUICE_PARAMS, global const rt_gather *g,
                            global const pm_knn_result *res, global long *accum, uint answered,
                            float fixed_r2)
{
    SLUICE_FOR_EACH (i) {
        rt_gather p = g[i];
        pm_knn_result r = res[i];
        if (fixed_r2 > 0.0f)
            r.r2 = fixed_r2;
        int some = i < answered && r.count > 0u && r.r2 > 0.0f;
        SLUICE_COUNT(0, some);
        SLUICE_COUNT(1, !some);
        if (some) {
            float3 c =
                (float3)(p.wr, p.wg, p.wb) * (float3)(r.sr, r.sg, r.sb) * (1.0f / (RT_PI * r.r2));
            SLUICE_COUNT(2, rt_add(accum, p.pixel, c));
        }
    }
}
