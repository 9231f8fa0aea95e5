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
 * On a CPU a work-item walking a contiguous chunk runs like a C loop; four
 * records are handled per step with vector loads and stores (chunks are a
 * multiple of 4 records, so every chunk but the last is 16-byte aligned).
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

#define SCAN_KERNELS(T, T4, SUFFIX)                                                                \
    __kernel void scan_sums_##SUFFIX(global const uint *vars, uint in_var, uint n_fixed,           \
                                     uint limit, uint chunk, global const T *in, global T *sums)   \
    {                                                                                              \
        uint begin, end;                                                                           \
        scan_range_(scan_length_(vars, in_var, n_fixed, limit), chunk, &begin, &end);              \
        T4 acc = (T4)(0);                                                                          \
        uint i = begin;                                                                            \
        for (; i + 4u <= end; i += 4u)                                                             \
            acc += vload4(0, in + i);                                                              \
        T s = (acc.s0 + acc.s1) + (acc.s2 + acc.s3);                                               \
        for (; i < end; ++i)                                                                       \
            s += in[i];                                                                            \
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
        if (inclusive) {                                                                           \
            for (; i + 4u <= end; i += 4u) {                                                       \
                T4 v = vload4(0, in + i);                                                          \
                T4 p;                                                                              \
                p.s0 = v.s0;                                                                       \
                p.s1 = v.s0 + v.s1;                                                                \
                p.s2 = p.s1 + v.s2;                                                                \
                p.s3 = p.s2 + v.s3;                                                                \
                vstore4(p + carry, 0, out + i);                                                    \
                carry += p.s3;                                                                     \
            }                                                                                      \
            for (; i < end; ++i) {                                                                 \
                carry += in[i];                                                                    \
                out[i] = carry;                                                                    \
            }                                                                                      \
        } else {                                                                                   \
            for (; i + 4u <= end; i += 4u) {                                                       \
                T4 v = vload4(0, in + i);                                                          \
                T4 e;                                                                              \
                e.s0 = (T)(0);                                                                     \
                e.s1 = v.s0;                                                                       \
                e.s2 = v.s0 + v.s1;                                                                \
                e.s3 = e.s2 + v.s2;                                                                \
                vstore4(e + carry, 0, out + i);                                                    \
                carry += e.s3 + v.s3;                                                              \
            }                                                                                      \
            for (; i < end; ++i) {                                                                 \
                T x = in[i];                                                                       \
                out[i] = carry;                                                                    \
                carry += x;                                                                        \
            }                                                                                      \
        }                                                                                          \
    }

SCAN_KERNELS(uint, uint4, u32)
SCAN_KERNELS(float, float4, f32)
