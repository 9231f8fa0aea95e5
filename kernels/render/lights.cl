/*
 * lights.cl: sampling the scene's lights, for shadow rays (direct light) and
 * for emitting photons (Purcell 6.2.1). Area lights are the emissive
 * triangles, picked by area through their cumulative table (area_cdf) and
 * sampled uniformly; point lights emit the same intensity in every direction.
 */
#ifndef SR_LIGHTS_CL
#define SR_LIGHTS_CL

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
    float phi = 2.0f * RT_PI * u2;
    return (float3)(r * cos(phi), r * sin(phi), z);
}

/* A uniform direction in the cone about the unit axis `n` whose solid angle
 * is 2 pi omc (omc = 1 - the cosine of its half-angle, passed as is so that
 * narrow cones keep their precision): pdf 1 / (2 pi omc). */
inline float3 rt_cone_dir(float3 n, float omc, float u1, float u2)
{
    float t = u1 * omc; /* 1 - cos theta */
    return rt_about(n, 2.0f * RT_PI * u2, sqrt(fmax(0.0f, t * (2.0f - t))), 1.0f - t);
}

#endif
