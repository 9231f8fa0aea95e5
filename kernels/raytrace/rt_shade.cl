/*
 * rt_shade.cl: eye-ray generation and shading, the first and last kernels of
 * Purcell's Fig. 3.1, and the counter-based random numbers they use.
 *
 * A shade pass reads each ray with its hit and adds what it can to the pixel
 * at once (emission, a cast-mode headlight), and emits new rays for what it
 * cannot: shadow rays that carry the light they would add if nothing blocks
 * them (output 0) and reflection, refraction or path rays that carry their
 * weight (output 1). Those streams go through traversal and intersection
 * again, so there is no recursion anywhere (Purcell 3.1, "shading").
 *
 * Pixels accumulate in 64-bit fixed point (RT_FIXED_SCALE) with atomic adds:
 * integer sums do not depend on the order in which rays finish, so the same
 * seed gives the same image bit for bit.
 *
 * Build options: RT_HAS_MIRROR, RT_HAS_GLASS (reflection and refraction code
 * is compiled only when the scene has such materials), RT_HAS_NORMALS.
 * Shade counters: 0 shading calculations, 1 shadow rays, 2 reflection rays,
 * 3 refraction rays, 4 path rays, 5 non-finite contributions dropped.
 */
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable

#define RT_PI 3.14159265358979323846f

/* ------------------------------------------------------------------ */
/* Random numbers: a hash of (key, dimension), no state, no atomics     */
/* ------------------------------------------------------------------ */

/* A 32-bit integer hash with good avalanche (the "lowbias32" constants). */
inline uint rt_hash(uint x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

inline uint rt_key(uint a, uint b)
{
    return rt_hash(a ^ rt_hash(b + 0x9e3779b9u));
}

/* A uniform number in [0, 1) for dimension `dim` of the path keyed `key`. */
inline float rt_rand(uint key, uint dim)
{
    return (float)(rt_key(key, dim) >> 8) * (1.0f / 16777216.0f);
}

/* ------------------------------------------------------------------ */
/* Accumulation                                                         */
/* ------------------------------------------------------------------ */

/* Adds colour `c` to pixel `p`; non-finite values are dropped (and counted
 * by the caller), so no NaN or Inf ever reaches the image. */
inline int rt_add(global long *accum, uint p, float3 c)
{
    if (!(isfinite(c.x) && isfinite(c.y) && isfinite(c.z)))
        return 1;
    c = clamp(c, 0.0f, 1.0e6f);
    if (c.x > 0.0f)
        atom_add(&accum[3u * p + 0u], (long)(c.x * RT_FIXED_SCALE));
    if (c.y > 0.0f)
        atom_add(&accum[3u * p + 1u], (long)(c.y * RT_FIXED_SCALE));
    if (c.z > 0.0f)
        atom_add(&accum[3u * p + 2u], (long)(c.z * RT_FIXED_SCALE));
    return 0;
}

/* ------------------------------------------------------------------ */
/* Eye rays                                                            */
/* ------------------------------------------------------------------ */

/* One eye ray per pixel, in 8x8 tiles so that neighbouring rays (which take
 * nearly the same path through the grid) are neighbours in the stream. The
 * launch covers whole tiles; positions outside the image emit nothing.
 * Output 0 (ordered) receives the rays. */
__kernel void rt_raygen(SLUICE_PARAMS, global rt_ray *rays, const rt_frame f)
{
    SLUICE_FOR_EACH (i) {
        uint tiles_x = (f.width + 7u) / 8u;
        uint tile = i / 64u, within = i % 64u;
        uint x = (tile % tiles_x) * 8u + within % 8u;
        uint y = (tile / tiles_x) * 8u + within / 8u;
        int inside = x < f.width && y < f.height;
        uint at = SLUICE_EMIT_INDEX(0, inside);
        if (SLUICE_WRITING && inside) {
            uint pixel = y * f.width + x;
            uint key = rt_key(rt_key(f.seed, pixel), f.sample);
            float jx = 0.5f, jy = 0.5f;
            if (f.jitter) {
                jx = rt_rand(key, 0u);
                jy = rt_rand(key, 1u);
            }
            float px = (float)x + jx, py = (float)y + jy;
            float3 d = (float3)(f.corner[0] + f.du[0] * px + f.dv[0] * py,
                                f.corner[1] + f.du[1] * px + f.dv[1] * py,
                                f.corner[2] + f.du[2] * px + f.dv[2] * py);
            d = normalize(d);
            rt_ray r;
            r.ox = f.eye[0];
            r.oy = f.eye[1];
            r.oz = f.eye[2];
            r.dx = d.x;
            r.dy = d.y;
            r.dz = d.z;
            r.tmin = 0.0f;
            r.tmax = INFINITY;
            r.wr = r.wg = r.wb = 1.0f;
            r.pixel = pixel;
            r.key = key;
            r.flags = RT_KIND_EYE | RT_FLAG_COUNT_EMIT;
            r.pad0 = r.pad1 = 0u;
            rays[at] = r;
        }
    }
}

/* ------------------------------------------------------------------ */
/* Shading                                                             */
/* ------------------------------------------------------------------ */

/* Everything about the surface at a hit. */
typedef struct rt_surface {
    float3 p;  /* hit point */
    float3 ng; /* geometric normal, facing the incoming ray */
    float3 n;  /* shading normal, facing the incoming ray */
    int front; /* the ray hit the front side (the emitting side) */
    rt_material m;
} rt_surface;

inline rt_surface rt_surface_at(const rt_ray *ray, const rt_hit *h, global const float *tv,
                                global const uint *indices, global const float *normals,
                                global const uint *tri_mat, global const rt_material *mats)
{
    rt_surface s;
    float3 o = (float3)(ray->ox, ray->oy, ray->oz), d = (float3)(ray->dx, ray->dy, ray->dz);
    float3 v0, e1, e2;
    rt_tri_edges(tv, h->tri, &v0, &e1, &e2);
    s.p = o + d * h->t;
    float3 ng = normalize(cross(e1, e2));
    s.front = dot(ng, d) < 0.0f;
    float3 n = ng;
#ifdef RT_HAS_NORMALS
    uint3 idx = vload3(h->tri, indices);
    float3 n0 = vload3(idx.x, normals), n1 = vload3(idx.y, normals), n2 = vload3(idx.z, normals);
    if (dot(n0, n0) > 0.0f && dot(n1, n1) > 0.0f && dot(n2, n2) > 0.0f) {
        float3 ns = n0 * (1.0f - h->u - h->v) + n1 * h->u + n2 * h->v;
        if (dot(ns, ns) > 0.0f)
            n = normalize(ns);
    }
#else
    (void)indices;
    (void)normals;
#endif
    if (!s.front) {
        ng = -ng;
        n = -n;
    }
    /* an interpolated normal facing away from the viewer is not usable */
    if (dot(n, d) >= 0.0f)
        n = ng;
    s.ng = ng;
    s.n = n;
    s.m = mats[tri_mat[h->tri]];
    return s;
}

inline float3 rt_albedo(const rt_material *m)
{
    return (float3)(m->ar, m->ag, m->ab);
}

inline float3 rt_specular(const rt_material *m)
{
    return (float3)(m->sr, m->sg, m->sb);
}

/* The BRDF for direct light from `wi` seen from `wo` (both away from the
 * surface). Mirrors and glass, which a shadow ray cannot light, are shaded as
 * diffuse surfaces of their tint in the modes that do not trace them. */
inline float3 rt_brdf(const rt_material *m, float3 n, float3 wi, float3 wo)
{
    if (m->kind == 3u) { /* glossy: modified Blinn-Phong (scene.h) */
        float3 h = normalize(wi + wo);
        float c = fmax(dot(n, h), 0.0f);
        return rt_albedo(m) / RT_PI +
               rt_specular(m) * ((m->exponent + 2.0f) / (2.0f * RT_PI) * pow(c, m->exponent));
    }
    if (m->kind == 1u || m->kind == 2u)
        return rt_specular(m) / RT_PI;
    return rt_albedo(m) / RT_PI;
}

/* A ray from `p` in direction `d`, offset along `ng` (towards the side the
 * ray leaves) so that it does not hit its own surface. */
inline rt_ray rt_spawn(float3 p, float3 off, float3 d, float tmax, float3 w, uint pixel, uint key,
                       uint flags)
{
    rt_ray r;
    float3 o = p + off;
    r.ox = o.x;
    r.oy = o.y;
    r.oz = o.z;
    r.dx = d.x;
    r.dy = d.y;
    r.dz = d.z;
    r.tmin = 0.0f;
    r.tmax = tmax;
    r.wr = w.x;
    r.wg = w.y;
    r.wb = w.z;
    r.pixel = pixel;
    r.key = key;
    r.flags = flags;
    r.pad0 = r.pad1 = 0u;
    return r;
}

inline float rt_max3(float3 v)
{
    return fmax(v.x, fmax(v.y, v.z));
}

/* Schlick's approximation of the Fresnel reflectance of a dielectric. */
inline float rt_fresnel(float cos_i, float cos_t, int entering, float ior)
{
    float r0 = (1.0f - ior) / (1.0f + ior);
    r0 *= r0;
    float c = 1.0f - (entering ? cos_i : cos_t);
    return r0 + (1.0f - r0) * c * c * c * c * c;
}

#define RT_EMIT_SHADOW(cond, ray) SLUICE_EMIT_IF(0, shadow, ray, cond)
#define RT_EMIT_SECONDARY(cond, ray) SLUICE_EMIT_IF(1, secondary, ray, cond)

/* Shades rays [base, base + count) of a wave (launched over count). */
__kernel void rt_shade(SLUICE_PARAMS, global const rt_ray *rays, global const rt_hit *hits,
                       uint base, global rt_ray *shadow, global rt_ray *secondary,
                       global long *accum, global const float *tv, global const uint *indices,
                       global const float *normals, global const uint *tri_mat,
                       global const rt_material *mats, global const rt_point_light *plights,
                       global const uint *area_tris, global const float *area_cdf, const rt_frame f)
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
        for (uint l = 0u; l < (lit ? f.point_lights : 0u); ++l) {
            rt_point_light pl = plights[l];
            float3 L = (float3)(pl.px, pl.py, pl.pz) - s.p;
            float d2 = dot(L, L), dist = sqrt(d2);
            float3 wi = L / dist;
            float c = dot(s.n, wi);
            float3 contrib =
                w * rt_brdf(&s.m, s.n, wi, wo) * (float3)(pl.ir, pl.ig, pl.ib) * (c / d2);
            int go = lit && c > 0.0f && dot(s.ng, wi) > 0.0f && rt_max3(contrib) > 0.0f;
            RT_EMIT_SHADOW(go, rt_spawn(s.p, off, wi, dist * 0.999f, contrib, ray.pixel, 0u,
                                        RT_KIND_SHADOW | RT_FLAG_ANY_HIT));
            SLUICE_COUNT(1, go);
        }
        uint nl = (lit && f.area_lights) ? f.light_samples : 0u;
        for (uint k = 0u; k < nl; ++k) {
            /* pick an emissive triangle by area, then a uniform point on it */
            float u0 = rt_rand(ray.key, 16u + 3u * k), u1 = rt_rand(ray.key, 17u + 3u * k),
                  u2 = rt_rand(ray.key, 18u + 3u * k);
            uint lo = 0u, hi = f.area_lights - 1u;
            while (lo < hi) {
                uint mid = (lo + hi) / 2u;
                if (area_cdf[mid] >= u0)
                    hi = mid;
                else
                    lo = mid + 1u;
            }
            uint lt = area_tris[lo];
            float3 a, e1, e2;
            rt_tri_edges(tv, lt, &a, &e1, &e2);
            float su = sqrt(u1);
            /* uniform on the triangle (Shirley and Chiu's square-to-triangle map) */
            float3 q = a + e1 * (su * (1.0f - u2)) + e2 * (su * u2);
            float3 lnc = cross(e1, e2);
            float3 ln = normalize(lnc);
            rt_material lm = mats[tri_mat[lt]];
            float3 L = q - s.p;
            float d2 = dot(L, L), dist = sqrt(d2);
            float3 wi = L / dist;
            float c = dot(s.n, wi), cl = -dot(ln, wi);
            float3 le = (float3)(lm.er, lm.eg, lm.eb);
            float3 contrib = w * rt_brdf(&s.m, s.n, wi, wo) * le *
                             (c * cl / d2 * f.area_total / (float)f.light_samples);
            int go = lit && lt != h.tri && c > 0.0f && cl > 0.0f && dot(s.ng, wi) > 0.0f &&
                     rt_max3(contrib) > 0.0f;
            RT_EMIT_SHADOW(go, rt_spawn(s.p, off, wi, dist * 0.999f, contrib, ray.pixel, 0u,
                                        RT_KIND_SHADOW | RT_FLAG_ANY_HIT));
            SLUICE_COUNT(1, go);
        }
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
            float3 n = s.n;
            float sign = n.z >= 0.0f ? 1.0f : -1.0f;
            float a = -1.0f / (sign + n.z), b = n.x * n.y * a;
            float3 t1 = (float3)(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
            float3 t2 = (float3)(b, sign + n.y * n.y * a, -n.y);
            float phi = 2.0f * RT_PI * r1, sr = sqrt(r2);
            float3 wi = normalize(t1 * (cos(phi) * sr) + t2 * (sin(phi) * sr) +
                                  n * sqrt(fmax(0.0f, 1.0f - r2)));
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
    SLUICE_FOR_EACH (i) {
        if (hits[i].tri != RT_NO_HIT)
            continue;
        rt_ray r = rays[i];
        int bad = rt_add(accum, r.pixel, (float3)(r.wr, r.wg, r.wb));
        SLUICE_COUNT(5, bad);
    }
}
