/*
 * rng.cl: counter-based random numbers for every renderer. A number is a hash
 * of (key, dimension): no state, no atomics, so the same seed gives the same
 * number whatever order work-items run in, and a path's numbers are its key
 * (seed, pixel or photon, sample, bounce) plus a dimension per decision.
 */
#ifndef SR_RNG_CL
#define SR_RNG_CL

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

/* The key of a sub-path: `a` (a parent key or a seed) combined with `b`. */
inline uint rt_key(uint a, uint b)
{
    return rt_hash(a ^ rt_hash(b + 0x9e3779b9u));
}

/* A uniform number in [0, 1) for dimension `dim` of the path keyed `key`. */
inline float rt_rand(uint key, uint dim)
{
    return (float)(rt_key(key, dim) >> 8) * (1.0f / 16777216.0f);
}

#endif
