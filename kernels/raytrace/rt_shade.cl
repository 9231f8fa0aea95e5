/*
 * rt_shade.cl: the ray tracer's shading, the last kernel of Purcell's Fig.
 * 3.1, for the cast, shadow, Whitted and path modes (eye rays come from
 * kernels/render/camera.cl).
 *
 * A shade pass reads each ray with its hit and adds what it can to the pixel
 * at once (emission, a cast-mode headlight), and emits new rays for what it
 * cannot: shadow rays that carry the light they would add if nothing blocks
 * them (output 0) and reflection, refraction or path rays that carry their
 * weight (output 1). Those streams go through traversal and intersection
 * again, so there is no recursion anywhere (Purcell 3.1, "shading").
 * Pixels accumulate through kernels/render/film.cl.
 *
 * Build options: RT_HAS_MIRROR, RT_HAS_GLASS (reflection and refraction code
 * is compiled only when the scene has such materials), RT_HAS_NORMALS,
 * RT_WATERTIGHT (the layout of the triangle records), RT_GATHER (the photon
 * mapper's renderer: diffuse and glossy hits in the whitted mode also emit a
 * gather point, output 2, where the radiance estimate is added),
 * RT_DIRECT_FUSED (the fused mode: direct light, point lights and area-light
 * samples, is left to rt_direct.cl, which traces its shadow rays where it
 * makes them).
 * Shade counters: 0 shading calculations, 1 shadow rays, 2 reflection rays,
 * 3 refraction rays, 4 path rays, 5 non-finite contributions dropped.
 */
#include "sluice.cl"

#define RT_EMIT_SHADOW(cond, ray) SLUICE_EMIT_IF(0, shadow, ray, cond)
#define RT_EMIT_SECONDARY(cond, ray) SLUICE_EMIT_IF(1, secondary, ray, cond)
#define RT_EMIT_GATHER(cond, g) SLUICE_EMIT_IF(2, gather, g, cond)

/* What an area-light sample at L (from the shading point, offset) adds when
 * unblocked: f cos cos_l / d^2 over the sample's pdf (per_sample: the
 * lights' area over the samples taken); lc is the light's normal, not of
 * unit length. */
inline float3 rt_area_light_weight(const rt_surface *s, float3 wo, float3 w, float3 L, float3 lc,
                                   float3 le, float per_sample)
{
    float d2 = dot(L, L), dist = sqrt(d2);
    float3 wi = L / dist;
    float c = dot(s->n, wi), cl = -dot(normalize(lc), wi);
    return w * rt_brdf(&s->m, s->n, wi, wo) * le * (c * cl / d2 * per_sample);
}

/* Light samples taken side by side: the area-light loop of rt_shade works
 * on this many at a time, in vectors (the work-group vectorizer cannot
 * widen a loop whose length varies from hit to hit), and on the rest (a
 * scene's 1 or 4, or what is left of its 32) one at a time, where a block
 * would mostly compute lanes it throws away. */
#define RT_LIGHT_LANES 8u

/* A function the compiler keeps apart (Clang's attribute; elsewhere a
 * hint left out, the same code inlined). */
#if defined(__clang__)
#define RT_NOINLINE __attribute__((noinline))
#else
#define RT_NOINLINE
#endif

/* What a hit's area-light samples start from (rt_shade, rt_direct.cl):
 * its shadow rays' origin o (the point, offset by off), the ray's weight w
 * and its way back wo, what the BRDF can pass (reach), each sample's share
 * of the lights' area (per_sample), the key of its samples, its triangle
 * (no light from itself), and how many samples: nl, the first `full` of
 * them in blocks of RT_LIGHT_LANES (the last block's lanes from `full` on
 * unused), the rest one at a time. */
typedef struct rt_light_ctx {
    float3 off, o, w, wo, reach;
    float per_sample;
    uint skey, tri, nl, full;
} rt_light_ctx;

inline rt_light_ctx rt_light_ctx_at(const rt_surface *s, const rt_ray *ray, uint tri,
                                    const rt_frame *f, uint nl)
{
    rt_light_ctx c;
    c.off = s->ng * f->scene_eps;
    c.o = s->p + c.off;
    c.w = (float3)(ray->wr, ray->wg, ray->wb);
    c.wo = -(float3)(ray->dx, ray->dy, ray->dz);
    c.reach = c.w * rt_brdf_support(&s->m);
    c.per_sample = f->area_total / (float)f->light_samples;
    c.skey = rt_key(ray->key, 16u);
    c.tri = tri;
    c.nl = nl;
    /* a rest of two samples or more takes a block too, its other lanes
     * unused: cheaper than the samples one at a time, which one alone is
     * not (measured, bench/README.md); a block's lanes compute the same
     * rays as rt_light_one and rt_light_one_ray */
    c.full = nl % RT_LIGHT_LANES >= 2u ? nl : nl / RT_LIGHT_LANES * RT_LIGHT_LANES;
    return c;
}

/* Light samples k0 .. k0 + 7 of a hit (surface s, samples from c): which
 * can add light (gos) and, when `writing`, each one's shadow ray direction,
 * length and weight. Not inlined: in the shading kernel its vectors would
 * weigh on the code of every hit, also of scenes that take one sample
 * (measured). */
RT_NOINLINE void rt_light_block8(uint k0, const rt_light_ctx *c, const rt_surface *s, int writing,
                                 const rt_frame *f, global const uint *area_tris,
                                 global const float *area_cdf, global const float *tv,
                                 global const uint *tri_mat, global const rt_material *mats,
                                 int *gos, float dir[3][RT_LIGHT_LANES], float *tmax,
                                 float wl[3][RT_LIGHT_LANES])
{
    uint skey = c->skey, tri = c->tri;
    float3 o = c->o, w = c->w, wo = c->wo, reach = c->reach;
    float per_sample = c->per_sample;
    /* pick an emissive triangle by area, then a uniform point on it;
     * the hit's samples stratified over the lights together */
    uint8 k = (uint8)(k0) + (uint8)(0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u);
    float8 u0, u1, q[3], lc[3];
    uint8 lt;
    rt_sobol2_8(k, skey, &u0, &u1);
    rt_area_light_point8(u0, u1, f->area_lights, area_tris, area_cdf, tv, q, lc, &lt);
    float8 le[3];
#ifndef RT_LIGHT_GATHER
    uint ta, tb;
    int8 on_b;
    if (rt_two_of8(lt, &ta, &tb, &on_b)) { /* one or two triangles: read once */
        rt_material ma = mats[tri_mat[ta]], mb = mats[tri_mat[tb]];
        le[0] = select((float8)(ma.er), (float8)(mb.er), on_b);
        le[1] = select((float8)(ma.eg), (float8)(mb.eg), on_b);
        le[2] = select((float8)(ma.eb), (float8)(mb.eb), on_b);
    } else
#endif
    {
        uint lts[RT_LIGHT_LANES];
        float ler[RT_LIGHT_LANES], leg[RT_LIGHT_LANES], leb[RT_LIGHT_LANES];
        vstore8(lt, 0, lts);
        for (uint l = 0u; l < RT_LIGHT_LANES; ++l) {
            rt_material lm = mats[tri_mat[lts[l]]];
            ler[l] = lm.er;
            leg[l] = lm.eg;
            leb[l] = lm.eb;
        }
        le[0] = vload8(0, ler);
        le[1] = vload8(0, leg);
        le[2] = vload8(0, leb);
    }
    float8 L[3] = {q[0] - o.x, q[1] - o.y, q[2] - o.z};
    /* whether a sample can add light, from signs and colours alone:
     * the count pass (an emitting body runs twice) stops here, and
     * only the writing pass normalizes and weighs */
    int8 go = (lt != (uint8)(tri)) & (s->n.x * L[0] + s->n.y * L[1] + s->n.z * L[2] > 0.0f) &
              (lc[0] * L[0] + lc[1] * L[1] + lc[2] * L[2] < 0.0f) &
              (s->ng.x * L[0] + s->ng.y * L[1] + s->ng.z * L[2] > 0.0f) &
              (fmax(reach.x * le[0], fmax(reach.y * le[1], reach.z * le[2])) > 0.0f);
    vstore8(go, 0, gos);
    if (writing) {
        /* f cos cos_l / d^2 over the sample's pdf (the lights' area
         * over the samples taken) */
        float8 d2 = L[0] * L[0] + L[1] * L[1] + L[2] * L[2], dist = sqrt(d2);
        float8 wi[3] = {L[0] / dist, L[1] / dist, L[2] / dist};
        float8 ll = sqrt(lc[0] * lc[0] + lc[1] * lc[1] + lc[2] * lc[2]);
        float8 cs = s->n.x * wi[0] + s->n.y * wi[1] + s->n.z * wi[2];
        float8 cl = -((lc[0] / ll) * wi[0] + (lc[1] / ll) * wi[1] + (lc[2] / ll) * wi[2]);
        float8 scale = cs * cl / d2 * per_sample;
        /* the BRDF, the same in every direction but a glossy surface's */
        float3 fb = rt_brdf(&s->m, s->n, s->n, wo);
        float8 fv[3] = {(float8)(fb.x), (float8)(fb.y), (float8)(fb.z)};
        if (s->m.kind == 3u) {
            float fr[3][RT_LIGHT_LANES];
            for (uint l = 0u; l < RT_LIGHT_LANES; ++l) {
                float3 wil =
                    (float3)(RT_LANE8_(wi[0], l), RT_LANE8_(wi[1], l), RT_LANE8_(wi[2], l));
                float3 fl = rt_brdf(&s->m, s->n, wil, wo);
                fr[0][l] = fl.x;
                fr[1][l] = fl.y;
                fr[2][l] = fl.z;
            }
            for (int a = 0; a < 3; ++a)
                fv[a] = vload8(0, fr[a]);
        }
        float wa[3] = {w.x, w.y, w.z};
        for (int a = 0; a < 3; ++a) {
            vstore8(wi[a], 0, dir[a]);
            vstore8(wa[a] * fv[a] * le[a] * scale, 0, wl[a]);
        }
        /* stop just short of the light's own surface: by a relative
         * 1e-5, far above the rounding of t (1e-7) and far below any
         * gap a scene would model (0.001 let light through walls it
         * sat just outside of: test_stress's leak case) */
        vstore8(dist * 0.99999f, 0, tmax);
    }
}

/* Area-light sample k of a hit (surface s, samples from c) taken alone:
 * the point q on the light, the light's normal lc (not of unit length) and
 * its emission le, and whether the sample can add light (rt_light_block8's
 * rule). */
inline int rt_light_one(uint k, const rt_light_ctx *c, const rt_surface *s, const rt_frame *f,
                        global const uint *area_tris, global const float *area_cdf,
                        global const float *tv, global const uint *tri_mat,
                        global const rt_material *mats, float3 *q, float3 *lc, float3 *le)
{
    float2 u = rt_sobol2(k, c->skey);
    uint lt = rt_area_light_point(u.x, u.y, f->area_lights, area_tris, area_cdf, tv, q, lc);
    rt_material lm = mats[tri_mat[lt]];
    *le = (float3)(lm.er, lm.eg, lm.eb);
    float3 L = *q - c->o;
    return lt != c->tri && dot(s->n, L) > 0.0f && dot(*lc, L) < 0.0f && dot(s->ng, L) > 0.0f &&
           rt_max3(c->reach * *le) > 0.0f;
}

/* The shadow ray of that sample (rt_light_one): from c's origin to q,
 * stopping just short of it, carrying what it adds when unblocked. */
inline rt_ray rt_light_one_ray(const rt_light_ctx *c, const rt_surface *s, float3 q, float3 lc,
                               float3 le, uint pixel)
{
    return rt_shadow_ray(s->p, c->off, q, 0.99999f,
                         rt_area_light_weight(s, c->wo, c->w, q - c->o, lc, le, c->per_sample),
                         pixel, RT_KIND_SHADOW | RT_FLAG_ANY_HIT);
}

/* Point light pl for a hit (surface s, its shadow rays offset by off, seen
 * along wo, weight w): what it adds when unblocked (*contrib), and whether
 * it can add anything. */
inline int rt_point_light_go(const rt_surface *s, float3 off, float3 w, float3 wo,
                             rt_point_light pl, float3 *contrib)
{
    float3 L = (float3)(pl.px, pl.py, pl.pz) - (s->p + off);
    float d2 = dot(L, L), dist = sqrt(d2);
    float3 wi = L / dist;
    float c = dot(s->n, wi);
    *contrib = w * rt_brdf(&s->m, s->n, wi, wo) * (float3)(pl.ir, pl.ig, pl.ib) * (c / d2);
    return c > 0.0f && dot(s->ng, wi) > 0.0f && rt_max3(*contrib) > 0.0f;
}

/* Its shadow ray: all the way to the light, which has no surface to stop
 * short of (an occluder just in front of it, a wall it sits outside of,
 * must still block). */
inline rt_ray rt_point_light_ray(const rt_surface *s, float3 off, rt_point_light pl, float3 contrib,
                                 uint pixel)
{
    return rt_shadow_ray(s->p, off, (float3)(pl.px, pl.py, pl.pz), 1.0f, contrib, pixel,
                         RT_KIND_SHADOW | RT_FLAG_ANY_HIT);
}

/* Shades rays [base, base + count) of a wave (launched over count). */
__kernel void rt_shade(SLUICE_PARAMS, global const rt_ray *rays, global const rt_hit *hits,
                       uint base, global rt_ray *shadow, global rt_ray *secondary,
                       global long *accum, global const float *tv, global const uint *indices,
                       global const float *normals, global const uint *tri_mat,
                       global const rt_material *mats, global const rt_point_light *plights,
                       global const uint *area_tris, global const float *area_cdf, const rt_frame f,
                       global rt_gather *gather)
{
    SLUICE_FOR_EACH (id) {
        uint i = base + id;
        rt_ray ray = rays[i];
        rt_hit h = hits[i];
        if (h.tri == RT_NO_HIT)
            continue; /* the background is black */
        SLUICE_COUNT(0, 1u);
        rt_surface s = rt_surface_at(&ray, &h, tv, indices, normals, tri_mat, mats);
        float3 d = (float3)(ray.dx, ray.dy, ray.dz);
        float3 wo = -d;
        float3 w = (float3)(ray.wr, ray.wg, ray.wb);
        uint depth = (ray.flags & RT_DEPTH_MASK) >> RT_DEPTH_SHIFT;
        float3 direct = (float3)(0.0f);
        float3 emission = (float3)(s.m.er, s.m.eg, s.m.eb);
        if ((ray.flags & RT_FLAG_COUNT_EMIT) && s.front)
            direct += w * emission;
        float3 off = s.ng * f.scene_eps;
        uint kind = s.m.kind;
        int specular = kind == 1u || kind == 2u;
        if (f.mode == RT_MODE_CAST) {
            /* a headlight at the eye: |cos| with the ray */
            float3 col = specular ? rt_specular(&s.m) : rt_albedo(&s.m);
            direct += w * col * fabs(dot(s.n, wo));
        }
        /* Direct light: one shadow ray per point light and light_samples per
         * area light, each carrying what it adds when unblocked. Mirrors and
         * glass get no direct light where their reflections are traced. */
        int lit = f.mode == RT_MODE_SHADOW || (!specular && f.mode != RT_MODE_CAST);
#ifdef RT_DIRECT_FUSED
        (void)plights; /* rt_direct (rt_direct.cl) takes every light */
#else
        for (uint l = 0u; l < (lit ? f.point_lights : 0u); ++l) {
            float3 contrib;
            int go = rt_point_light_go(&s, off, w, wo, plights[l], &contrib); /* lit here */
            RT_EMIT_SHADOW(go, rt_point_light_ray(&s, off, plights[l], contrib, ray.pixel));
            SLUICE_COUNT(1, go);
        }
#endif
#ifdef RT_DIRECT_FUSED
        uint nl = 0u; /* area lights: rt_direct (rt_direct.cl) */
        (void)lit;
#else
        uint nl = (lit && f.area_lights) ? f.light_samples : 0u;
#endif
        rt_light_ctx lx = rt_light_ctx_at(&s, &ray, h.tri, &f, nl);
        for (uint k0 = 0u; k0 < lx.full; k0 += RT_LIGHT_LANES) {
            int gos[RT_LIGHT_LANES];
            float dir[3][RT_LIGHT_LANES], tmax[RT_LIGHT_LANES], wl[3][RT_LIGHT_LANES];
            rt_light_block8(k0, &lx, &s, SLUICE_WRITING, &f, area_tris, area_cdf, tv, tri_mat, mats,
                            gos, dir, tmax, wl);
            for (uint l = 0u; l < min((uint)RT_LIGHT_LANES, lx.full - k0); ++l) {
                RT_EMIT_SHADOW(gos[l], rt_spawn(s.p, off, (float3)(dir[0][l], dir[1][l], dir[2][l]),
                                                tmax[l], (float3)(wl[0][l], wl[1][l], wl[2][l]),
                                                ray.pixel, 0u, RT_KIND_SHADOW | RT_FLAG_ANY_HIT));
                SLUICE_COUNT(1, gos[l] != 0);
            }
        }
        for (uint k = lx.full; k < nl; ++k) {
            /* the same, one sample at a time */
            float3 q, lc, le;
            int go = lit && rt_light_one(k, &lx, &s, &f, area_tris, area_cdf, tv, tri_mat, mats, &q,
                                         &lc, &le);
            RT_EMIT_SHADOW(go, rt_light_one_ray(&lx, &s, q, lc, le, ray.pixel));
            SLUICE_COUNT(1, go);
        }
#ifdef RT_GATHER
        {
            rt_gather g;
            g.px = s.p.x;
            g.py = s.p.y;
            g.pz = s.p.z;
            g.nx = s.n.x;
            g.ny = s.n.y;
            g.nz = s.n.z;
            g.pixel = ray.pixel;
            float3 wg = w * rt_albedo(&s.m) / RT_PI;
            g.wr = wg.x;
            g.wg = wg.y;
            g.wb = wg.z;
            RT_EMIT_GATHER(!specular && f.mode == RT_MODE_WHITTED && rt_max3(wg) > 0.0f, g);
        }
#else
        (void)gather;
#endif
        uint child_depth = (depth + 1u) << RT_DEPTH_SHIFT;
        int deeper = depth + 1u <= f.max_depth;
        float cos_i = dot(s.n, wo);
        float3 refl = d + s.n * (2.0f * cos_i);
#if defined(RT_HAS_MIRROR) || defined(RT_HAS_GLASS)
        if (f.mode == RT_MODE_WHITTED || f.mode == RT_MODE_PATH) {
#ifdef RT_HAS_MIRROR
            {
                int go = deeper && kind == 1u;
                float3 wr = w * rt_specular(&s.m);
                RT_EMIT_SECONDARY(go && rt_max3(wr) > 0.0f,
                                  rt_spawn(s.p, off, refl, INFINITY, wr, ray.pixel,
                                           rt_key(ray.key, 1u),
                                           RT_KIND_REFLECT | RT_FLAG_COUNT_EMIT | child_depth));
                SLUICE_COUNT(2, go && rt_max3(wr) > 0.0f);
            }
#endif
#ifdef RT_HAS_GLASS
            {
                /* Fresnel: refraction by Snell's law, total internal
                 * reflection when there is none. Whitted traces both rays;
                 * the path tracer picks one with the Fresnel probability. */
                float eta = s.front ? 1.0f / s.m.ior : s.m.ior;
                float k2 = 1.0f - eta * eta * (1.0f - cos_i * cos_i);
                int tir = k2 < 0.0f;
                float cos_t = tir ? 0.0f : sqrt(k2);
                float3 refr = normalize(d * eta + s.n * (eta * cos_i - cos_t));
                float fr = tir ? 1.0f : rt_fresnel(cos_i, cos_t, s.front, s.m.ior);
                float3 tint = w * rt_specular(&s.m);
                int glass = deeper && kind == 2u;
                float3 wr = tint * fr, wt = tint * (1.0f - fr);
                int take_r = 1, take_t = !tir;
                if (f.mode == RT_MODE_PATH) {
                    int pick_r = rt_rand(ray.key, 8u) < fr;
                    take_r = pick_r;
                    take_t = !pick_r;
                    wr = tint;
                    wt = tint;
                }
                int gr = glass && take_r && rt_max3(wr) > 0.0f;
                int gt = glass && take_t && rt_max3(wt) > 0.0f;
                RT_EMIT_SECONDARY(gr, rt_spawn(s.p, off, refl, INFINITY, wr, ray.pixel,
                                               rt_key(ray.key, 2u),
                                               RT_KIND_REFLECT | RT_FLAG_COUNT_EMIT | child_depth));
                RT_EMIT_SECONDARY(gt, rt_spawn(s.p, -off, refr, INFINITY, wt, ray.pixel,
                                               rt_key(ray.key, 3u),
                                               RT_KIND_REFRACT | RT_FLAG_COUNT_EMIT | child_depth));
                SLUICE_COUNT(2, gr);
                SLUICE_COUNT(3, gt);
            }
#endif
        }
#endif
        if (f.mode == RT_MODE_PATH) {
            /* Diffuse (and glossy) bounce: cosine-weighted direction, weight
             * f cos / pdf = f pi; emitters it finds were counted by the
             * shadow rays already (next-event estimation), so it does not
             * count emission. Russian roulette after two bounces. */
            float r1 = rt_rand(ray.key, 4u), r2 = rt_rand(ray.key, 5u), r3 = rt_rand(ray.key, 6u);
            float3 wi = rt_cosine_dir(s.n, r1, r2);
            float3 wb = w * rt_brdf(&s.m, s.n, wi, wo) * RT_PI;
            float q = 1.0f;
            if (depth >= 2u)
                q = clamp(rt_max3(wb) / fmax(rt_max3(w), 1e-20f), 0.05f, 0.95f);
            int survive = r3 < q;
            wb /= q;
            int go = deeper && !specular && survive && dot(s.ng, wi) > 0.0f && rt_max3(wb) > 0.0f;
            RT_EMIT_SECONDARY(go, rt_spawn(s.p, off, wi, INFINITY, wb, ray.pixel,
                                           rt_key(ray.key, 4u), RT_KIND_PATH | child_depth));
            SLUICE_COUNT(4, go);
        }
        if (SLUICE_WRITING) {
            int bad = rt_add(accum, ray.pixel, direct);
            SLUICE_COUNT(5, bad);
        }
    }
}

/* Shadow rays that reached their light add what they carry. Shade counter
 * 5 counts non-finite contributions here too. */
__kernel void rt_shadow_resolve(SLUICE_PARAMS, global const rt_ray *rays, global const rt_hit *hits,
                                global long *accum)
{
    /* A hit's shadow rays come one after another (32 a pixel on Purcell's
     * cornell), so a work-item sums a run of one pixel's rays in fixed
     * point and adds the sum once: the integer sum is the same, three
     * atomics a run instead of three a ray (on GPUs, whose work-items take
     * every G-th record, a run is a ray) */
    uint run_p = 0xffffffffu;
    long3 run = (long3)(0);
    SLUICE_FOR_EACH (i) {
        if (hits[i].tri != RT_NO_HIT)
            continue;
        rt_ray r = rays[i];
        float3 c = (float3)(r.wr, r.wg, r.wb);
        int bad = !(isfinite(c.x) && isfinite(c.y) && isfinite(c.z));
        SLUICE_COUNT(5, bad);
        if (bad)
            continue;
        if (r.pixel != run_p) {
            if (run_p != 0xffffffffu)
                rt_add_fixed(accum, run_p, run);
            run_p = r.pixel;
            run = (long3)(0);
        }
        run += rt_fixed(c);
    }
    if (run_p != 0xffffffffu)
        rt_add_fixed(accum, run_p, run);
}
