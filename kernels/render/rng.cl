/*
 * rng.cl: counter-based random numbers for every renderer. A number is a hash
 * of (key, dimension): no state, no atomics, so the same seed gives the same
 * number whatever order work-items run in, and a path's numbers are its key
 * (seed, pixel or photon, sample, bounce) plus a dimension per decision.
 */
#ifndef SR_RNG_CL
#define SR_RNG_CL

/* A 32-bit integer hash with good avalanche (the "lowbias32" constants),
 * and the key of a sub-path: `a` (a parent key or a seed) combined with `b`.
 * Defined for uint and, for eye rays made 16 at a time (camera.cl), uint16:
 * the same operations lane by lane. */
#define RT_HASH_(T, hash, key)                                                                     \
    inline T hash(T x)                                                                             \
    {                                                                                              \
        x ^= x >> 16;                                                                              \
        x *= 0x7feb352du;                                                                          \
        x ^= x >> 15;                                                                              \
        x *= 0x846ca68bu;                                                                          \
        x ^= x >> 16;                                                                              \
        return x;                                                                                  \
    }                                                                                              \
    inline T key(T a, T b)                                                                         \
    {                                                                                              \
        return hash(a ^ hash(b + 0x9e3779b9u));                                                    \
    }
RT_HASH_(uint, rt_hash, rt_key)
RT_HASH_(uint16, rt_hash16, rt_key16)

/* A uniform number in [0, 1) for dimension `dim` of the path keyed `key`. */
inline float rt_rand(uint key, uint dim)
{
    return (float)(rt_key(key, dim) >> 8) * (1.0f / 16777216.0f);
}

/* rt_rand on 16 lanes. */
inline float16 rt_rand16(uint16 key, uint dim)
{
    return convert_float16(rt_key16(key, (uint16)(dim)) >> 8) * (1.0f / 16777216.0f);
}

/* The bits of x in reverse order; the hash of rt_owen on bits already
 * reversed (returns the reversed bits of the scrambled value: each bit of
 * the hash depends only on the bits below it, an add and multiplies by even
 * constants). Defined for uint and, for the shaders' light samples taken 8
 * side by side, uint8: the same operations lane by lane. */
#define RT_RNG_BITS_(T, reverse, owen_reversed)                                                    \
    inline T reverse(T x)                                                                          \
    {                                                                                              \
        x = (x << 16) | (x >> 16);                                                                 \
        x = ((x & 0x00ff00ffu) << 8) | ((x & 0xff00ff00u) >> 8);                                   \
        x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);                                   \
        x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);                                   \
        return ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);                                \
    }                                                                                              \
    inline T owen_reversed(T r, uint seed)                                                         \
    {                                                                                              \
        r += seed;                                                                                 \
        r ^= r * 0x6c50b47cu;                                                                      \
        r ^= r * 0xb82f1e52u;                                                                      \
        r ^= r * 0xc7afe638u;                                                                      \
        r ^= r * 0x8d22f6e6u;                                                                      \
        return reverse(r);                                                                         \
    }
RT_RNG_BITS_(uint, rt_reverse_bits, rt_owen_reversed_)
RT_RNG_BITS_(uint8, rt_reverse_bits8, rt_owen_reversed8_)
RT_RNG_BITS_(uint16, rt_reverse_bits16, rt_owen_reversed16_)

/* A nested uniform (Owen) scramble of x read as a binary fraction, keyed by
 * `seed`: each bit is flipped or not by a hash of the bits above it, so an
 * interval [a 2^-m, (a+1) 2^-m) goes to another of the same size, and a
 * random seed makes every point uniform while a stratified set stays
 * stratified. Burley 2020 ("Practical hash-based Owen scrambling", JCGT
 * 9(4)): on the reversed bits, a hash in which each bit depends only on the
 * bits below it. */
inline uint rt_owen(uint x, uint seed)
{
    return rt_owen_reversed_(rt_reverse_bits(x), seed);
}

/* rt_owen on 16 lanes (the same numbers lane by lane). */
inline uint16 rt_owen16(uint16 x, uint seed)
{
    return rt_owen_reversed16_(rt_reverse_bits16(x), seed);
}

/* The second dimension's bit 31 - j is the XOR of the bits i of k with C(i,
 * j) odd, that is (Lucas) with j's bits a subset of i's: a sum over
 * supersets, five shift-and-mask rounds on the reversed bits instead of a
 * loop over k's. Both coordinates stay reversed into the scramble, which
 * reverses them first. Integers (uint or uint8) x and y from k and seed. */
#define RT_SOBOL2_BITS_(T, owen_reversed, k, seed, x, y)                                           \
    T z = (k);                                                                                     \
    z ^= (z >> 1) & 0x55555555u;                                                                   \
    z ^= (z >> 2) & 0x33333333u;                                                                   \
    z ^= (z >> 4) & 0x0f0f0f0fu;                                                                   \
    z ^= (z >> 8) & 0x00ff00ffu;                                                                   \
    z ^= (z >> 16) & 0x0000ffffu;                                                                  \
    T x = owen_reversed((k), rt_hash((seed) ^ 0x2545f491u));                                       \
    T y = owen_reversed(z, rt_hash((seed) ^ 0x9e3779b9u))

/* Point k of an Owen-scrambled Sobol (0,2)-sequence keyed by `seed`, in
 * [0,1)^2: the first two dimensions of Sobol's sequence (van der Corput's
 * bits of k reversed; then the matrix of Pascal's triangle mod 2), each
 * scrambled by its own key. Points 0 .. 2^m - 1 put one point in every
 * elementary interval of area 2^-m; every point alone is uniform, so
 * averages over them are unbiased (Kollig and Keller 2002). Shuffle k with
 * rt_owen to draw several independent 2D sequences over the same indices
 * (Burley 2020, section 4): points whose indices differ below 2^m stay in
 * different strata. */
inline float2 rt_sobol2(uint k, uint seed)
{
    RT_SOBOL2_BITS_(uint, rt_owen_reversed_, k, seed, x, y);
    return (float2)((float)(x >> 8), (float)(y >> 8)) * (1.0f / 16777216.0f);
}

/* rt_sobol2 for the 8 or 16 points k (lane by lane the same numbers): the
 * first coordinates in *u0, the second in *u1. */
#define RT_SOBOL2_N_(N)                                                                            \
    inline void rt_sobol2_##N(uint##N k, uint seed, float##N *u0, float##N *u1)                    \
    {                                                                                              \
        RT_SOBOL2_BITS_(uint##N, rt_owen_reversed##N##_, k, seed, x, y);                           \
        *u0 = convert_float##N(x >> 8) * (1.0f / 16777216.0f);                                     \
        *u1 = convert_float##N(y >> 8) * (1.0f / 16777216.0f);                                     \
    }
RT_SOBOL2_N_(8)
RT_SOBOL2_N_(16)

#endif
