/*
 * surface.cl: what a renderer knows about the surface at a hit (position,
 * geometric and shading normals, material), the BRDFs, Fresnel reflectance,
 * direction sampling and spawning rays off a surface. Shared by the ray
 * tracer's shading and the photon mapper's photon tracing and shading, so
 * both see the same materials (apps/common/scene.h describes them).
 */
#ifndef SR_SURFACE_CL
#define SR_SURFACE_CL

#define RT_PI 3.14159265358979323846f

/* Everything about the surface at a hit. */
typedef struct rt_surface {
    float3 p;  /* hit point */
    float3 ng; /* geometric normal, facing the incoming ray */
    float3 n;  /* shading normal, facing the incoming ray */
    int front; /* the ray hit the front side (the emitting side) */
    rt_material m;
} rt_surface;

/* Inlined where the build asks (RT_SURFACE_INLINE: the fused mode's shading
 * and direct light, the photons' bounces): called, it returns the surface
 * through the stack, and the caller's first read of it stalled (perf
 * annotate of rt_shade). The stream mode's shading, which samples the
 * lights in the same loop, measured no faster inlined (bench/README.md). */
#ifdef RT_SURFACE_INLINE
__attribute__((always_inline))
#endif
inline rt_surface
rt_surface_at(const rt_ray *ray, const rt_hit *h, global const float *tv,
              global const uint *indices, global const float *normals, global const uint *tri_mat,
              global const rt_material *mats)
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

/* A shadow ray from the surface point `p` to the light point `q`, ending
 * at the fraction `stop` of the way. Its origin is offset by `off` (as
 * rt_spawn does), so it is aimed and measured from there: aimed from `p`
 * with p's distance, the offset carried it onto the light's own surface
 * wherever the offset exceeded what it stopped short by (scene_eps is 1e-4
 * of the scene's diagonal: lit points near an area light came out in
 * shadow). */
inline rt_ray rt_shadow_ray(float3 p, float3 off, float3 q, float stop, float3 w, uint pixel,
                            uint flags)
{
    float3 l = q - (p + off);
    float dist = length(l);
    return rt_spawn(p, off, l / dist, dist * stop, w, pixel, 0u, flags);
}

inline float rt_max3(float3 v)
{
    return fmax(v.x, fmax(v.y, v.z));
}

/* A colour that is zero exactly where rt_brdf is zero in every direction
 * (its terms are non-negative): what decides, before any normalizing,
 * whether direct light can reach the eye through the surface. */
inline float3 rt_brdf_support(const rt_material *m)
{
    if (m->kind == 3u)
        return rt_albedo(m) + rt_specular(m);
    return (m->kind == 1u || m->kind == 2u) ? rt_specular(m) : rt_albedo(m);
}

/* The Fresnel reflectance of a dielectric for unpolarised light, from
 * Fresnel's equations (the mean of the s and p reflectances) with the
 * incident and transmitted cosines; `entering`: from outside (index 1)
 * into the material (index ior). Schlick's approximation, used here before,
 * reflects 0.042 instead of 0.050 at 45 degrees for ior 1.5: glassball's
 * highlights came out 5-7% darker than Mitsuba's (bench/README.md). */
inline float rt_fresnel(float cos_i, float cos_t, int entering, float ior)
{
    float n1 = entering ? 1.0f : ior, n2 = entering ? ior : 1.0f;
    float rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    float rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    return 0.5f * (rs * rs + rp * rp);
}

/* The direction at angle 2 pi `turn` about the unit axis `n` whose sine and
 * cosine to it are `st` and `ct`; the tangent frame is Duff et al.'s (JCGT
 * 2017). The angle goes in turns to sinpi and cospi, whose reduction of
 * the argument is exact and cheap: sin and cos of 2 pi u took the slow
 * path of a full argument reduction (measured, bench/README.md). */
inline float3 rt_about(float3 n, float turn, float st, float ct)
{
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z), b = n.x * n.y * a;
    float3 t1 = (float3)(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    float3 t2 = (float3)(b, sign + n.y * n.y * a, -n.y);
    return normalize(t1 * (cospi(2.0f * turn) * st) + t2 * (sinpi(2.0f * turn) * st) + n * ct);
}

/* A cosine-weighted direction about the unit normal `n` (pdf cos / pi), from
 * two uniform numbers. */
inline float3 rt_cosine_dir(float3 n, float r1, float r2)
{
    return rt_about(n, r1, sqrt(r2), sqrt(fmax(0.0f, 1.0f - r2)));
}

#endif
