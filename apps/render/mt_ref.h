/*
 * mt_ref.h: the Moller-Trumbore ray-triangle test (Purcell, Fig. 3.2) in
 * plain C, for the references that check and race the kernels (the brute
 * force of tests/test_raytrace.c, the C grid tracer of bench/bench_raytrace.c).
 *
 * It rounds exactly as rt_intersect_tri (kernels/render/rt_trace.cl) and
 * rt_intersect16_core (rt_lanes.cl) do: the same operations in the same
 * order, with fused multiply-adds at the same places and nowhere else. So
 * a reference disagrees with the kernels only where the grid makes them test
 * different triangles, never by rounding. Build the code that includes this
 * without -ffast-math and with contraction off (GCC contracts only with
 * -ffp-contract=fast and hardware FMA; the default ISO C mode has it off).
 */
#ifndef SLUICE_RT_MT_REF_H
#define SLUICE_RT_MT_REF_H

#include <math.h>

/* fmaf is exact wherever it runs, but without hardware FMA in the target it
 * is a library call. RT_MT_REF_FAST on the function whose loop calls
 * rt_mt_ref gives it a second copy built for FMA hardware, picked at load
 * time (GCC's function multi-versioning); elsewhere it expands to nothing. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define RT_MT_REF_FAST __attribute__((target_clones("fma", "default")))
#endif
#endif
#ifndef RT_MT_REF_FAST
#define RT_MT_REF_FAST
#endif

/* a b - c d, rounded as the kernels' rt_cross component. */
static inline float rt_mt_ref_fms(float a, float b, float c, float d)
{
    return fmaf(a, b, -(c * d));
}

/* a . b, rounded as the kernels' rt_dot. */
static inline float rt_mt_ref_dot(const float a[3], const float b[3])
{
    return fmaf(a[2], b[2], fmaf(a[1], b[1], a[0] * b[0]));
}

/* a x b, rounded as the kernels' rt_cross. */
static inline void rt_mt_ref_cross(const float a[3], const float b[3], float out[3])
{
    out[0] = rt_mt_ref_fms(a[1], b[2], a[2], b[1]);
    out[1] = rt_mt_ref_fms(a[2], b[0], a[0], b[2]);
    out[2] = rt_mt_ref_fms(a[0], b[1], a[1], b[0]);
}

/* Tests the ray (o, d) against the triangle with vertex v0 and edges e1, e2
 * (two-sided). Returns 1 and writes t, u, v when the ray's line meets the
 * triangle (det != 0, u, v >= 0, u + v <= 1); the caller checks t against
 * its interval and its nearest hit so far. Returns 0 otherwise. */
static inline int rt_mt_ref(const float v0[3], const float e1[3], const float e2[3],
                            const float o[3], const float d[3], float *t, float *u, float *v)
{
    float pv[3];
    rt_mt_ref_cross(d, e2, pv);
    float det = rt_mt_ref_dot(e1, pv);
    if (det == 0.0f)
        return 0;
    float inv = 1.0f / det;
    float s[3] = {o[0] - v0[0], o[1] - v0[1], o[2] - v0[2]};
    float uu = rt_mt_ref_dot(s, pv) * inv;
    if (uu < 0.0f || uu > 1.0f)
        return 0;
    float q[3];
    rt_mt_ref_cross(s, e1, q);
    float vv = rt_mt_ref_dot(d, q) * inv;
    if (vv < 0.0f || uu + vv > 1.0f)
        return 0;
    *t = rt_mt_ref_dot(e2, q) * inv;
    *u = uu;
    *v = vv;
    return 1;
}

#endif
