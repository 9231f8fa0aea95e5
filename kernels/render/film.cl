/*
 * film.cl: the accumulation buffer every renderer adds to. Pixels accumulate
 * in 64-bit fixed point (RT_FIXED_SCALE, rt_types.h) with atomic adds:
 * integer sums do not depend on the order in which work-items finish, so the
 * same seed gives the same image bit for bit. The host side is
 * apps/render/film.h.
 */
#ifndef SR_FILM_CL
#define SR_FILM_CL

#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable

/* Colour `c` (finite) in the film's fixed point, clamped to [0, 1e6]. */
inline long3 rt_fixed(float3 c)
{
    c = clamp(c, 0.0f, 1.0e6f);
    return (long3)((long)(c.x * RT_FIXED_SCALE), (long)(c.y * RT_FIXED_SCALE),
                   (long)(c.z * RT_FIXED_SCALE));
}

/* Adds fixed-point colour `v` to slot `p`: an atomic add per channel that
 * is not zero. */
inline void rt_add_fixed(global long *accum, uint p, long3 v)
{
    if (v.x)
        atom_add(&accum[3u * p + 0u], v.x);
    if (v.y)
        atom_add(&accum[3u * p + 1u], v.y);
    if (v.z)
        atom_add(&accum[3u * p + 2u], v.z);
}

/* Adds colour `c` to slot `p` (a pixel in one of the film's two halves:
 * rt_ray.pixel); non-finite values are dropped (the caller counts them:
 * returns 1), so no NaN or Inf ever reaches the image. */
inline int rt_add(global long *accum, uint p, float3 c)
{
    if (!(isfinite(c.x) && isfinite(c.y) && isfinite(c.z)))
        return 1;
    rt_add_fixed(accum, p, rt_fixed(c));
    return 0;
}

#endif
