/*
 * pm_photon.cl: photon tracing as streams (Purcell 6.2.1). Photons leave the
 * lights as rays of kind RT_KIND_PHOTON, go through the same tracer as every
 * other ray (kernels/render/rt_*.cl), and a bounce pass over each photon with
 * its hit decides whether it is stored (a pm_photon at a diffuse or glossy
 * surface), bounced (the next photon ray) or dropped (left the scene,
 * absorbed by Russian roulette, past the depth limit); a routing pass moves
 * them by conditional outputs (stored: output 0, bounced: output 1). The
 * host loops until the bounced stream is empty.
 *
 * Power: a photon carries the flux of its light divided by the probability
 * of choosing that light, point and direction; the host divides the stored
 * powers by the number of photons emitted (pm_photon_map), so the map holds
 * flux per photon, Phi / N (Jensen 2001, ch. 5).
 *
 * Photons are stored at diffuse and glossy surfaces (not on emitters, which
 * the shading lights by their emission) and only after at least one bounce: direct light is
 * computed with shadow rays (Purcell 6.2.4), so the map holds indirect light
 * and caustics, and direct light is not counted twice.
 *
 * Build options: RT_HAS_MIRROR, RT_HAS_GLASS, RT_HAS_NORMALS, RT_WATERTIGHT
 * as for the ray tracer's shading. Counters: 0 stored, 1 bounced, 2 left the
 * scene, 3 absorbed (Russian roulette or black surface), 4 past the depth
 * limit, 5 non-finite power dropped, 6 caustic photons stored.
 */
#include "sluice.cl"

/* Emits photon i of the batch: from an area light (a point by area, a
 * cosine-weighted direction about its normal or one toward the mirrors and
 * glass: flux Le cos A / (p_area pdf), Le pi A / p_area without them) or a
 * point light (a uniform direction or one toward the mirrors and glass:
 * flux I n_point / ((1 - p_area) pdf)).
 *
 * Jensen's projection map, as a mixture: the batch's first `cone_count`
 * photons go into the cone from the emission point to the mirrors' and
 * glass's bounding sphere (where caustics start), the rest as the light
 * emits. The share is fixed, not drawn, and the power divides by the
 * mixture's pdf with that share: Veach's multi-sample model with the
 * balance heuristic (thesis 9.2), unbiased, without the noise of drawing
 * each photon's strategy. A point inside the sphere, or an area light whose
 * front cannot see it, emits as the light does.
 *
 * Emission points and directions are quasi-random: each an Owen-scrambled
 * Sobol 2D sequence over the batch (directions one per strategy), keyed by
 * the batch, so the photons of a pass cover the lights and the cone evenly
 * where independent ones would clump (Keller's quasi-Monte Carlo photon
 * tracing; the scrambles keep every photon uniform, so nothing is biased). */
__kernel void pm_emit(SLUICE_PARAMS, global rt_ray *rays, global const float *tv,
                      global const uint *tri_mat, global const rt_material *mats,
                      global const rt_point_light *plights, global const uint *area_tris,
                      global const float *area_cdf, const pm_emit_args a)
{
    uint bkey = rt_key(rt_key(a.seed, 0x5eb0u), a.base);
    /* 16 photons at a time: their keys and quasi-random numbers in vectors
     * (integer hashes that ran scalar, one photon a loop turn), the same
     * numbers as one at a time; the rest photon by photon */
    SLUICE_FOR_EACH_RANGE (b, e) {
        for (uint i0 = b; i0 < e; i0 += 16u) {
            uint16 iv = (uint16)(i0) + SLUICE_LANE16;
            int16 cone_v = iv < (uint16)(a.cone_count);
            /* index in its strategy's sequence */
            uint16 jv = select(iv - a.cone_count, iv, as_uint16(cone_v));
            float keys_r0[16], u[4][16];
            uint keys[16];
            uint16 kv = rt_key16((uint16)(rt_key(a.seed, 0x9407u)), (uint16)(a.base) + iv);
            vstore16(kv, 0, keys);
            vstore16(rt_rand16(kv, 0u), 0, keys_r0);
            float16 p0, p1, c0, c1, s0, s1;
            rt_sobol2_16(rt_owen16(iv, rt_key(bkey, 1u)), rt_key(bkey, 2u), &p0, &p1);
            rt_sobol2_16(rt_owen16(jv, rt_key(bkey, 3u)), rt_key(bkey, 5u), &c0, &c1);
            rt_sobol2_16(rt_owen16(jv, rt_key(bkey, 4u)), rt_key(bkey, 6u), &s0, &s1);
            vstore16(p0, 0, u[0]);
            vstore16(p1, 0, u[1]);
            vstore16(select(s0, c0, cone_v), 0, u[2]);
            vstore16(select(s1, c1, cone_v), 0, u[3]);
            for (uint l = 0; l < min(16u, e - i0); ++l) {
                uint i = i0 + l, key = keys[l];
                int cone_range = i < a.cone_count;
                float2 up = (float2)(u[0][l], u[1][l]);
                float2 ud = (float2)(u[2][l], u[3][l]);
                float3 o, d, power;
                float3 off;
                float3 to;
                float ps = 0.0f, omc = 0.0f;
                int area = a.area_lights && keys_r0[l] < a.area_prob;
                float3 ln = (float3)(0.0f), le;
                if (area) {
                    float3 q;
                    uint lt = rt_area_light_sample(up.x, up.y, a.area_lights, area_tris, area_cdf,
                                                   tv, &q, &ln);
                    rt_material m = mats[tri_mat[lt]];
                    le = (float3)(m.er, m.eg, m.eb);
                    o = q;
                    off = ln * a.scene_eps;
                } else {
                    uint l = min((uint)(up.x * (float)a.point_lights), a.point_lights - 1u);
                    rt_point_light pl = plights[l];
                    o = (float3)(pl.px, pl.py, pl.pz);
                    off = (float3)(0.0f);
                    le = (float3)(pl.ir, pl.ig, pl.ib);
                }
                to = (float3)(a.spec_x, a.spec_y, a.spec_z) - o;
                float dist2 = dot(to, to), r2 = a.spec_r * a.spec_r;
                float3 axis = (float3)(0.0f, 0.0f, 1.0f);
                if (a.spec_prob > 0.0f && dist2 > r2) {
                    float x = r2 / dist2;
                    omc = x / (1.0f + sqrt(1.0f - x)); /* 1 - cos of the half-angle */
                    axis = to * rsqrt(dist2);
                    /* an area light's cone must reach its front side */
                    ps = !area || dot(axis, ln) > -sqrt(x) ? a.spec_prob : 0.0f;
                }
                int in_cone = 0;
                if (ps > 0.0f && cone_range) {
                    d = rt_cone_dir(axis, omc, ud.x, ud.y);
                    in_cone = 1;
                } else {
                    d = area ? rt_cosine_dir(ln, ud.x, ud.y) : rt_uniform_sphere(ud.x, ud.y);
                    in_cone = ps > 0.0f && dot(d, axis) >= 1.0f - omc;
                }
                float cone_pdf = in_cone ? ps / (2.0f * RT_PI * omc) : 0.0f;
                if (area) {
                    /* Le cos A_total / (p_area pdf): Le pi A / p_area without the cone */
                    float c = fmax(dot(d, ln), 0.0f);
                    float pdf = (1.0f - ps) * c * (1.0f / RT_PI) + cone_pdf;
                    power =
                        pdf > 0.0f ? le * (c * a.area_total / (a.area_prob * pdf)) : (float3)(0.0f);
                } else {
                    float pdf = (1.0f - ps) / (4.0f * RT_PI) + cone_pdf;
                    power = le * ((float)a.point_lights / ((1.0f - a.area_prob) * pdf));
                }
                /* the flight gets a key of its own: the bounce reads dimensions 1-4,
                 * which emission used to choose this photon's light and direction */
                rays[i] = rt_spawn(o, off, d, INFINITY, power, 0u, rt_key(key, 0x51u),
                                   RT_KIND_PHOTON | PM_RAY_SPECULAR);
            }
        }
    }
}

/* One bounce of every photon of the stream, worked out once: the photon as
 * it would be stored, the ray it would go on as, and where it goes (bit 0:
 * stored, bit 1: bounced; neither: dropped), all at the photon's own index.
 * pm_route then moves them to the stored and bounced streams. Emitting here
 * would run this body twice, once to count and once to write (ordered
 * outputs, sluice.cl), for outputs a cheap kernel can route. */
__kernel void pm_bounce(SLUICE_PARAMS, global const rt_ray *rays, global const rt_hit *hits,
                        global pm_photon *photon_at, global rt_ray *ray_at, global uint *route,
                        global const float *tv, global const uint *indices,
                        global const float *normals, global const uint *tri_mat,
                        global const rt_material *mats, uint max_depth, float scene_eps)
{
    SLUICE_FOR_EACH (i) {
        rt_ray ray = rays[i];
        rt_hit h = hits[i];
        int hit = h.tri != RT_NO_HIT;
        SLUICE_COUNT(2, !hit);
        rt_surface s;
        uint depth = (ray.flags & RT_DEPTH_MASK) >> RT_DEPTH_SHIFT;
        int specular_path = (ray.flags & PM_RAY_SPECULAR) != 0u;
        float3 d = (float3)(ray.dx, ray.dy, ray.dz);
        float3 w = (float3)(ray.wr, ray.wg, ray.wb);
        int store = 0, go = 0, bad = 0;
        float3 wb = (float3)(0.0f), dir = d, off = (float3)(0.0f);
        uint kind = 0u;
        if (hit) {
            s = rt_surface_at(&ray, &h, tv, indices, normals, tri_mat, mats);
            kind = s.m.kind;
            int specular = kind == 1u || kind == 2u;
            float3 wo = -d;
            off = s.ng * scene_eps;
            bad = !(isfinite(w.x) && isfinite(w.y) && isfinite(w.z));
            /* stored where the estimate reads it: diffuse and glossy surfaces,
             * after at least one bounce (direct light has shadow rays) */
            store = (kind == 0u || kind == 3u) && depth >= 1u && !bad; /* not on lights */
            float cos_i = dot(s.n, wo);
            float3 refl = d + s.n * (2.0f * cos_i);
            if (!specular) {
                /* Russian roulette on the albedo (Jensen 2001, 5.3): survive
                 * with the probability of the largest channel of f cos / pdf */
                float3 wi = rt_cosine_dir(s.n, rt_rand(ray.key, 1u), rt_rand(ray.key, 2u));
                float3 a = rt_brdf(&s.m, s.n, wi, wo) * RT_PI;
                float q = fmin(rt_max3(a), 1.0f);
                go = rt_rand(ray.key, 3u) < q && dot(s.ng, wi) > 0.0f;
                wb = w * a / fmax(q, 1e-20f);
                dir = wi;
            }
#ifdef RT_HAS_MIRROR
            if (kind == 1u) {
                wb = w * rt_specular(&s.m);
                dir = refl;
                go = 1;
            }
#endif
#ifdef RT_HAS_GLASS
            if (kind == 2u) {
                float eta = s.front ? 1.0f / s.m.ior : s.m.ior;
                float k2 = 1.0f - eta * eta * (1.0f - cos_i * cos_i);
                int tir = k2 < 0.0f;
                float cos_t = tir ? 0.0f : sqrt(k2);
                float fr = tir ? 1.0f : rt_fresnel(cos_i, cos_t, s.front, s.m.ior);
                int pick_r = rt_rand(ray.key, 4u) < fr;
                wb = w * rt_specular(&s.m);
                dir = pick_r ? refl : normalize(d * eta + s.n * (eta * cos_i - cos_t));
                off = pick_r ? off : -off;
                go = 1;
            }
#endif
            go = go && !bad && rt_max3(wb) > 0.0f;
            SLUICE_COUNT(3, !go && !bad);
        }
        int deeper = depth + 1u <= max_depth;
        SLUICE_COUNT(4, go && !deeper);
        go = go && deeper;
        SLUICE_COUNT(5, bad);
        pm_photon ph;
        if (hit) {
            ph.px = s.p.x;
            ph.py = s.p.y;
            ph.pz = s.p.z;
        } else {
            ph.px = ph.py = ph.pz = 0.0f;
        }
        ph.pr = w.x;
        ph.pg = w.y;
        ph.pb = w.z;
        ph.dx = d.x;
        ph.dy = d.y;
        ph.dz = d.z;
        ph.flags = min(depth, 255u) | (specular_path ? PM_PHOTON_CAUSTIC : 0u);
        photon_at[i] = ph;
        SLUICE_COUNT(0, store);
        SLUICE_COUNT(6, store && specular_path);
        uint spec_bit = (specular_path && (kind == 1u || kind == 2u)) ? PM_RAY_SPECULAR : 0u;
        ray_at[i] = rt_spawn(hit ? s.p : (float3)(0.0f), off, dir, INFINITY, wb, 0u,
                             rt_key(ray.key, depth + 7u),
                             RT_KIND_PHOTON | spec_bit | ((depth + 1u) << RT_DEPTH_SHIFT));
        route[i] = (store ? 1u : 0u) | (go ? 2u : 0u);
        SLUICE_COUNT(1, go);
    }
}

/* Moves pm_bounce's results by their route: photons to be stored to
 * output 0, photons that bounce on to output 1 (both ordered). Only the
 * routes are read to count. */
__kernel void pm_route(SLUICE_PARAMS, global const uint *route, global const pm_photon *photon_at,
                       global const rt_ray *ray_at, global pm_photon *stored,
                       global rt_ray *bounced)
{
    SLUICE_FOR_EACH (i) {
        uint r = route[i];
        SLUICE_EMIT_IF(0, stored, photon_at[i], (r & 1u) != 0u);
        SLUICE_EMIT_IF(1, bounced, ray_at[i], (r & 2u) != 0u);
    }
}

/* Multiplies the power of every photon by `s` (1 / photons emitted). */
__kernel void pm_scale_power(SLUICE_PARAMS, global pm_photon *ph, float s)
{
    SLUICE_FOR_EACH (i) {
        ph[i].pr *= s;
        ph[i].pg *= s;
        ph[i].pb *= s;
    }
}
