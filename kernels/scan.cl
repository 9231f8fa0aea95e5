/*
 * Prefix sums (streams/scan.c): reduce-then-scan over contiguous chunks.
 *
 *   pass 1  scan_sums_T   one work-item per chunk sums its records
 *   pass 2  scan_chunks_T one work-item scans the chunk sums in place
 *                         (exclusive), stores the total after them and sets
 *                         the output stream's length
 *   pass 3  scan_apply_T  one work-item per chunk scans its records serially,
 *                         starting from the chunk's offset
 *
 * On a CPU a work-item walking a contiguous chunk runs like a C loop. Both
 * record passes go 16 records per step (sluice.cl's SLUICE_REDUCE16_ and
 * SCAN_PREFIX16_ below): pass 1 with two 16-lane accumulators, pass 3 with a
 * prefix sum of the 16 lanes in four shifted adds; both measured faster
 * than four records per step with AVX-512 and AVX2 kernels (bench/README.md,
 * bench_streams). Float sums are associated in a different order than a
 * serial loop's, in shorter chains.
 *
 * The input length is `n_fixed` when the host knows it, otherwise the
 * device-side variable vars[in_var]; past `limit` (the capacity) the input
 * overflowed: nothing is read, the output is made void (sluice.cl) and the
 * flag after the total is set, so the overflow is reported, not truncated.
 */
#include "sluice.cl"

#define SCAN_NONE 0xffffffffu

inline uint scan_length_(global const uint *vars, uint in_var, uint n_fixed, uint limit)
{
    return n_fixed != SCAN_NONE ? n_fixed : sluice_stream_length_(vars, in_var, limit);
}

/* The records [*begin, *end) of chunk `id`. */
inline void scan_range_(uint n, uint chunk, uint *begin, uint *end)
{
    ulong b = (ulong)get_global_id(0) * chunk;
    *begin = (uint)min(b, (ulong)n);
    *end = (uint)min(b + chunk, (ulong)n);
}

/* x shifted up k lanes (k = 1, 2, 4, 8), zeros (z) shifted in. */
#define SCAN_SHIFT_(z, x, k) SCAN_SHIFT_##k##_(z, x)
#define SCAN_SHIFT_1_(z, x)                                                                        \
    SLUICE_SHUF16_(z, x, 0, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30)
#define SCAN_SHIFT_2_(z, x)                                                                        \
    SLUICE_SHUF16_(z, x, 0, 0, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29)
#define SCAN_SHIFT_4_(z, x)                                                                        \
    SLUICE_SHUF16_(z, x, 0, 0, 0, 0, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27)
#define SCAN_SHIFT_8_(z, x)                                                                        \
    SLUICE_SHUF16_(z, x, 0, 0, 0, 0, 0, 0, 0, 0, 16, 17, 18, 19, 20, 21, 22, 23)

/* p (16 lanes) becomes its inclusive prefix sum, in four shifted adds
 * (Hillis and Steele); z is a zero vector of p's type. */
#define SCAN_PREFIX16_(z, p)                                                                       \
    do {                                                                                           \
        p += SCAN_SHIFT_(z, p, 1);                                                                 \
        p += SCAN_SHIFT_(z, p, 2);                                                                 \
        p += SCAN_SHIFT_(z, p, 4);                                                                 \
        p += SCAN_SHIFT_(z, p, 8);                                                                 \
    } while (0)

#define SCAN_KERNELS(T, T16, SUFFIX)                                                               \
    __kernel void scan_sums_##SUFFIX(global const uint *vars, uint in_var, uint n_fixed,           \
                                     uint limit, uint chunk, global const T *in, global T *sums)   \
    {                                                                                              \
        uint begin, end;                                                                           \
        scan_range_(scan_length_(vars, in_var, n_fixed, limit), chunk, &begin, &end);              \
        T s;                                                                                       \
        SLUICE_REDUCE16_(T, T16, in, begin, end, (T)(0), SLUICE_ADD_, s);                          \
        sums[get_global_id(0)] = s;                                                                \
    }                                                                                              \
                                                                                                   \
    /* One work-item: sums[0..m) becomes its exclusive scan, sums[m] the total,                    \
     * sums[m + 1] is non-zero when the input overflowed. */                                       \
    __kernel void scan_chunks_##SUFFIX(global uint *vars, uint in_var, uint n_fixed, uint limit,   \
                                       uint out_var, global T *sums, uint m)                       \
    {                                                                                              \
        if (get_global_id(0) != 0)                                                                 \
            return;                                                                                \
        T s = (T)(0);                                                                              \
        for (uint i = 0; i < m; ++i) {                                                             \
            T c = sums[i];                                                                         \
            sums[i] = s;                                                                           \
            s += c;                                                                                \
        }                                                                                          \
        sums[m] = s;                                                                               \
        int overflowed = n_fixed == SCAN_NONE && vars[in_var] > limit;                             \
        sums[m + 1u] = (T)(overflowed);                                                            \
        if (overflowed)                                                                            \
            sluice_void_(vars, out_var, in_var);                                                   \
        else                                                                                       \
            vars[out_var] = scan_length_(vars, in_var, n_fixed, limit);                            \
    }                                                                                              \
                                                                                                   \
    __kernel void scan_apply_##SUFFIX(global const uint *vars, uint in_var, uint n_fixed,          \
                                      uint limit, uint chunk, global const T *in, global T *out,   \
                                      global const T *sums, uint inclusive)                        \
    {                                                                                              \
        uint begin, end;                                                                           \
        scan_range_(scan_length_(vars, in_var, n_fixed, limit), chunk, &begin, &end);              \
        T carry = sums[get_global_id(0)];                                                          \
        uint i = begin;                                                                            \
        for (; i + 16u <= end; i += 16u) {                                                         \
            T16 z = (T16)(0), p = *(global const sluice_##T16##_unaligned_ *)(in + i);             \
            SCAN_PREFIX16_(z, p);                                                                  \
            /* exclusive: the inclusive prefix shifted up one lane (p - v is                       \
             * not exact for floats, and inf - inf is NaN) */                                      \
            T16 e = inclusive ? p : SCAN_SHIFT_(z, p, 1);                                          \
            *(global sluice_##T16##_unaligned_ *)(out + i) = e + carry;                            \
            carry += p.sf;                                                                         \
        }                                                                                          \
        if (inclusive) {                                                                           \
            for (; i < end; ++i) {                                                                 \
                carry += in[i];                                                                    \
                out[i] = carry;                                                                    \
            }                                                                                      \
        } else {                                                                                   \
            for (; i < end; ++i) {                                                                 \
                T x = in[i];                                                                       \
                out[i] = carry;                                                                    \
                carry += x;                                                                        \
            }                                                                                      \
        }                                                                                          \
    }

SCAN_KERNELS(uint, uint16, u32)
SCAN_KERNELS(float, float16, f32)
