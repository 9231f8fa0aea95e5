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

/* Adds colour `c` to slot `p` (a pixel in one of the film's two halves:
 * rt_ray.pixel); non-finite values are dropped (the caller counts them:
 * returns 1), so no NaN or Inf ever reaches the image. */
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

#endif
