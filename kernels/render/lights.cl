/*
 * lights.cl: sampling the scene's lights, for shadow rays (direct light) and
 * for emitting photons (Purcell 6.2.1). Area lights are the emissive
 * triangles, picked by area through their cumulative table (area_cdf) and
 * sampled uniformly; point lights emit the same intensity in every direction.
 */
#ifndef SR_LIGHTS_CL
#define SR_LIGHTS_CL

#include "sluice.cl" /* sluice_mask8: the lanes' test without any()'s branches */

/* Picks an emissive triangle with probability proportional to its area (u0)
 * and a uniform point `*q` on it (Shirley and Chiu's square-to-triangle map);
 * writes its normal (the emitting side, e1 x e2: not of unit length) to
 * `*lc` and returns the triangle. `count` is the number of emissive
 * triangles (> 0). The point's first coordinate is u0 rescaled within the
 * chosen triangle's share of the CDF, so the map from (u0, u1) to the
 * lights' surface keeps areas: points stratified in the unit square stay
 * stratified on the lights (rt_sobol2). */
inline uint rt_area_light_point(float u0, float u1, uint count, global const uint *area_tris,
                                global const float *area_cdf, global const float *tv, float3 *q,
                                float3 *lc)
{
    uint lo = 0u, hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (area_cdf[mid] >= u0)
            hi = mid;
        else
            lo = mid + 1u;
    }
    float below = lo ? area_cdf[lo - 1u] : 0.0f, width = area_cdf[lo] - below;
    float ur = width > 0.0f ? clamp((u0 - below) / width, 0.0f, 1.0f) : 0.5f;
    uint lt = area_tris[lo];
    float3 a, e1, e2;
    rt_tri_edges(tv, lt, &a, &e1, &e2);
    float su = sqrt(ur);
    *q = a + e1 * (su * (1.0f - u1)) + e2 * (su * u1);
    *lc = cross(e1, e2);
    return lt;
}

/* Lane l of an 8-wide vector, and the 8 reads of p at the lanes of i as a
 * vector of type T. */
#define RT_LANE8_(v, l) (((const float *)&(v))[l])
#define RT_GATHER8_(T, p, i)                                                                       \
    (T)((p)[(i).s0], (p)[(i).s1], (p)[(i).s2], (p)[(i).s3], (p)[(i).s4], (p)[(i).s5], (p)[(i).s6], \
        (p)[(i).s7])

/* Whether the 8 lanes of t hold at most two values: the first lane's in
 * *ta, another's (or the same) in *tb, and the lanes holding *tb in *on_b.
 * A scene's lights are often a few triangles (the Cornell box's two), so
 * the 8 light samples side by side mostly hold one or two: a triangle's
 * records are then read once each and broadcast, where a gather per field
 * was half of the light sampling's time on cornell. -DRT_LIGHT_GATHER
 * (SLUICE_BUILD_OPTIONS) gathers every read, for measuring. */
inline int rt_two_of8(uint8 t, uint *ta, uint *tb, int8 *on_b)
{
    /* without branches: the least value other than the first lane's (no
     * index is 0xffffffff) */
    *ta = t.s0;
    uint8 o = select(t, (uint8)(0xffffffffu), t == (uint8)(*ta));
    uint4 o4 = min(o.lo, o.hi);
    uint2 o2 = min(o4.lo, o4.hi);
    uint m = min(o2.x, o2.y);
    *tb = m == 0xffffffffu ? *ta : m;
    *on_b = t == (uint8)(*tb);
    return !sluice_mask8((t != (uint8)(*ta)) & ~*on_b);
}

/* rt_area_light_point for 8 samples side by side (the shaders' light
 * samples): lane l picks with (u0, u1) lane l and gets the same triangle,
 * point and normal, the point's and normal's coordinates in q[0..2] and
 * lc[0..2]. The triangles go to *lt. */
inline void rt_area_light_point8(float8 u0, float8 u1, uint count, global const uint *area_tris,
                                 global const float *area_cdf, global const float *tv, float8 *q,
                                 float8 *lc, uint8 *lt)
{
    uint8 lo = (uint8)(0u), hi = (uint8)(count - 1u);
    for (int8 more = lo < hi; sluice_mask8(more); more = lo < hi) {
        uint8 mid = (lo + hi) / 2u;
        /* the lanes' first step reads one place (and with two triangles,
         * the only step) */
#ifndef RT_LIGHT_GATHER
        int8 ge = !sluice_mask8(mid != (uint8)(mid.s0)) ? (float8)(area_cdf[mid.s0]) >= u0
                                                        : RT_GATHER8_(float8, area_cdf, mid) >= u0;
#else
        int8 ge = RT_GATHER8_(float8, area_cdf, mid) >= u0;
#endif
        hi = select(hi, mid, more & ge);
        lo = select(lo, mid + 1u, more & ~ge);
    }
    float8 below, width;
    uint8 t;
#ifndef RT_LIGHT_GATHER
    uint la, lb;
    int8 on_lb;
    if (rt_two_of8(lo, &la, &lb, &on_lb)) { /* one or two places: each read once */
        float pa = la ? area_cdf[la - 1u] : 0.0f, pb = lb ? area_cdf[lb - 1u] : 0.0f;
        below = select((float8)(pa), (float8)(pb), on_lb);
        width = select((float8)(area_cdf[la] - pa), (float8)(area_cdf[lb] - pb), on_lb);
        t = select((uint8)(area_tris[la]), (uint8)(area_tris[lb]), as_uint8(on_lb));
    } else
#endif
    {
        uint8 before = select(lo - 1u, (uint8)(0u), lo == 0u);
        below = select(RT_GATHER8_(float8, area_cdf, before), (float8)(0.0f), lo == 0u);
        width = RT_GATHER8_(float8, area_cdf, lo) - below;
        t = RT_GATHER8_(uint8, area_tris, lo);
    }
    float8 ur = select((float8)(0.5f), clamp((u0 - below) / width, 0.0f, 1.0f), width > 0.0f);
    uint8 at = t * 9u;
    float8 v[9];
#ifndef RT_LIGHT_GATHER
    uint ta, tb;
    int8 on_b;
    if (rt_two_of8(t, &ta, &tb, &on_b)) {
        for (uint j = 0; j < 9u; ++j)
            v[j] = select((float8)(tv[ta * 9u + j]), (float8)(tv[tb * 9u + j]), on_b);
    } else
#endif
        for (uint j = 0; j < 9u; ++j)
            v[j] = RT_GATHER8_(float8, tv + j, at);
#ifdef RT_WATERTIGHT
    for (int a = 0; a < 3; ++a) {
        v[3 + a] -= v[a];
        v[6 + a] -= v[a];
    }
#endif
    float8 su = sqrt(ur);
    float8 s1 = su * (1.0f - u1), s2 = su * u1;
    for (int a = 0; a < 3; ++a)
        q[a] = v[a] + v[3 + a] * s1 + v[6 + a] * s2;
    lc[0] = v[4] * v[8] - v[5] * v[7];
    lc[1] = v[5] * v[6] - v[3] * v[8];
    lc[2] = v[3] * v[7] - v[4] * v[6];
    *lt = t;
}

/* rt_area_light_point with the unit normal in `*ln`. */
inline uint rt_area_light_sample(float u0, float u1, uint count, global const uint *area_tris,
                                 global const float *area_cdf, global const float *tv, float3 *q,
                                 float3 *ln)
{
    float3 lc;
    uint lt = rt_area_light_point(u0, u1, count, area_tris, area_cdf, tv, q, &lc);
    *ln = normalize(lc);
    return lt;
}

/* A uniform direction on the unit sphere (pdf 1 / (4 pi)). */
inline float3 rt_uniform_sphere(float u1, float u2)
{
    float z = 1.0f - 2.0f * u1;
    float r = sqrt(fmax(0.0f, 1.0f - z * z));
    return (float3)(r * cospi(2.0f * u2), r * sinpi(2.0f * u2), z); /* turns: rt_about */
}

/* A uniform direction in the cone about the unit axis `n` whose solid angle
 * is 2 pi omc (omc = 1 - the cosine of its half-angle, passed as is so that
 * narrow cones keep their precision): pdf 1 / (2 pi omc). */
inline float3 rt_cone_dir(float3 n, float omc, float u1, float u2)
{
    float t = u1 * omc; /* 1 - cos theta */
    return rt_about(n, u2, sqrt(fmax(0.0f, t * (2.0f - t))), 1.0f - t);
}

#endif
