/*
 * Prefix sums (streams/scan.c): reduce-then-scan over contiguous chunks.
 *
 *   pass 1  scan_sums_T   one work-item per chunk sums its records
 *   pass 2  scan_chunks_T one work-item (a work-group on GPUs) scans the
 *                         chunk sums in place (exclusive), stores the total
 *                         after them and sets the output stream's length
 *   pass 3  scan_apply_T  one work-item per chunk scans its records serially,
 *                         starting from the chunk's offset
 *
 * On GPUs (the runtime's interleaved layout) passes 1 and 3 run one
 * work-group per chunk instead (SCAN_GROUP_KERNELS below).
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

/* x (a T16) shifted up k lanes (k = 1, 2, 4, 8), zeros shifted in. With
 * AVX-512 as one valignd of x and zeros: Clang lowers the shuffle below to
 * vpexpandd there, which on AMD's Zen 4 made the scan's write pass 2.2x
 * slower than with the AVX2 kernels (bench/README.md). */
#if defined(SLUICE_AVX512_) && __has_builtin(__builtin_ia32_alignd512)
#define SCAN_SHIFT_(T16, x, k) as_##T16(__builtin_ia32_alignd512(as_int16(x), (int16)(0), 16 - (k)))
#else
#define SCAN_SHIFT_(T16, x, k) SCAN_SHIFT_##k##_((T16)(0), x)
#endif
#define SCAN_SHIFT_1_(z, x)                                                                        \
    SLUICE_SHUF16_(z, x, 0, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30)
#define SCAN_SHIFT_2_(z, x)                                                                        \
    SLUICE_SHUF16_(z, x, 0, 0, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29)
#define SCAN_SHIFT_4_(z, x)                                                                        \
    SLUICE_SHUF16_(z, x, 0, 0, 0, 0, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27)
#define SCAN_SHIFT_8_(z, x)                                                                        \
    SLUICE_SHUF16_(z, x, 0, 0, 0, 0, 0, 0, 0, 0, 16, 17, 18, 19, 20, 21, 22, 23)

/* p (16 lanes of type T16) becomes its inclusive prefix sum, in four
 * shifted adds (Hillis and Steele). */
#define SCAN_PREFIX16_(T16, p)                                                                     \
    do {                                                                                           \
        p += SCAN_SHIFT_(T16, p, 1);                                                               \
        p += SCAN_SHIFT_(T16, p, 2);                                                               \
        p += SCAN_SHIFT_(T16, p, 4);                                                               \
        p += SCAN_SHIFT_(T16, p, 8);                                                               \
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
    /* sums[0..m) becomes its exclusive scan, sums[m] the total, sums[m + 1]                       \
     * is non-zero when the input overflowed. One work-group                                       \
     * (SLUICE_GROUP_SCAN_; `part`: one T per work-item and one more): the host                    \
     * launches one work-item on a CPU, a group on a GPU. */                                       \
    __kernel void scan_chunks_##SUFFIX(global uint *vars, uint in_var, uint n_fixed, uint limit,   \
                                       uint out_var, global T *sums, uint m, local T *part)        \
    {                                                                                              \
        if (get_group_id(0) != 0)                                                                  \
            return;                                                                                \
        SLUICE_GROUP_SCAN_(T, sums, m, (T)(0), part);                                              \
        if (get_local_id(0) != 0)                                                                  \
            return;                                                                                \
        sums[m] = part[get_local_size(0)];                                                         \
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
            T16 p = *(global const sluice_##T16##_unaligned_ *)(in + i);                           \
            SCAN_PREFIX16_(T16, p);                                                                \
            /* exclusive: the inclusive prefix shifted up one lane (p - v is                       \
             * not exact for floats, and inf - inf is NaN) */                                      \
            T16 e = inclusive ? p : SCAN_SHIFT_(T16, p, 1);                                        \
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

/* Passes 1 and 3 for GPUs (the runtime's interleaved layout): one work-group
 * per chunk, whose work-items read neighbouring records together (coalesced)
 * instead of one work-item walking the chunk. Pass 1 sums the chunk
 * (SLUICE_GROUP_REDUCE_). Pass 3 takes the chunk in rounds of 4 Q g records
 * (g the group size, a power of two): work-item l loads the Q 4-record
 * vectors at 4 (q g + l), q < Q, all before waiting on any (a GPU keeps that
 * many loads in flight per work-item, where one record at a time left an
 * H100 at half its bandwidth, bench/README.md), scans each vector in
 * registers, and the group scans the round's Q g vector sums in local
 * memory: each work-item its Q consecutive sums, then a Hillis-Steele scan
 * of the g work-items' totals. `part` holds Q g T (pass 3) or g T (pass 1).
 * The host's chunks are multiples of 1024 records, so every vector starts
 * on a 16-byte boundary; a round past the end reads and writes record by
 * record. */
#define SCAN_Q_ 4u

inline void scan_group_range_(uint n, uint chunk, uint *begin, uint *end)
{
    ulong b = (ulong)get_group_id(0) * chunk;
    *begin = (uint)min(b, (ulong)n);
    *end = (uint)min(b + chunk, (ulong)n);
}

#define SCAN_GROUP_KERNELS(T, SUFFIX)                                                              \
    __kernel void scan_sums_wg_##SUFFIX(global const uint *vars, uint in_var, uint n_fixed,        \
                                        uint limit, uint chunk, global const T *in,                \
                                        global T *sums, local T *part)                             \
    {                                                                                              \
        uint begin, end;                                                                           \
        scan_group_range_(scan_length_(vars, in_var, n_fixed, limit), chunk, &begin, &end);        \
        SLUICE_GROUP_REDUCE_(T, in, begin, end, 0, SLUICE_ADD_, part);                             \
        if (get_local_id(0) == 0)                                                                  \
            sums[get_group_id(0)] = part[0];                                                       \
    }                                                                                              \
                                                                                                   \
    __kernel void scan_apply_wg_##SUFFIX(                                                          \
        global const uint *vars, uint in_var, uint n_fixed, uint limit, uint chunk,                \
        global const T *in, global T *out, global const T *sums, uint inclusive, local T *part)    \
    {                                                                                              \
        uint l = (uint)get_local_id(0), g = (uint)get_local_size(0), begin, end;                   \
        scan_group_range_(scan_length_(vars, in_var, n_fixed, limit), chunk, &begin, &end);        \
        T carry = sums[get_group_id(0)];                                                           \
        for (uint base = begin; base < end; base += 4u * SCAN_Q_ * g) {                            \
            T##4 v[SCAN_Q_];                                                                       \
            for (uint q = 0; q < SCAN_Q_; ++q) {                                                   \
                uint i = base + 4u * (q * g + l);                                                  \
                if (i + 4u <= end) {                                                               \
                    v[q] = *(global const T##4 *)(in + i);                                         \
                } else {                                                                           \
                    v[q].s0 = i < end ? in[i] : (T)(0);                                            \
                    v[q].s1 = i + 1u < end ? in[i + 1u] : (T)(0);                                  \
                    v[q].s2 = i + 2u < end ? in[i + 2u] : (T)(0);                                  \
                    v[q].s3 = (T)(0);                                                              \
                }                                                                                  \
            }                                                                                      \
            /* each vector's inclusive scan; its sum to local memory */                            \
            for (uint q = 0; q < SCAN_Q_; ++q) {                                                   \
                v[q].s1 += v[q].s0;                                                                \
                v[q].s2 += v[q].s1;                                                                \
                v[q].s3 += v[q].s2;                                                                \
                part[q * g + l] = v[q].s3;                                                         \
            }                                                                                      \
            barrier(CLK_LOCAL_MEM_FENCE);                                                          \
            /* work-item l: the sums of vectors Q l .. Q l + Q - 1 in round order */               \
            T t[SCAN_Q_], s = (T)(0);                                                              \
            for (uint k = 0; k < SCAN_Q_; ++k) {                                                   \
                t[k] = part[SCAN_Q_ * l + k];                                                      \
                s += t[k];                                                                         \
            }                                                                                      \
            barrier(CLK_LOCAL_MEM_FENCE);                                                          \
            part[l] = s;                                                                           \
            barrier(CLK_LOCAL_MEM_FENCE);                                                          \
            for (uint off = 1u; off < g; off *= 2u) {                                              \
                T y = l >= off ? part[l - off] : (T)(0);                                           \
                barrier(CLK_LOCAL_MEM_FENCE);                                                      \
                part[l] += y;                                                                      \
                barrier(CLK_LOCAL_MEM_FENCE);                                                      \
            }                                                                                      \
            /* exclusive from the lane before (p - x is not exact for floats) */                   \
            T e = l ? part[l - 1u] : (T)(0), total = part[g - 1u];                                 \
            barrier(CLK_LOCAL_MEM_FENCE);                                                          \
            for (uint k = 0; k < SCAN_Q_; ++k) {                                                   \
                part[SCAN_Q_ * l + k] = e;                                                         \
                e += t[k];                                                                         \
            }                                                                                      \
            barrier(CLK_LOCAL_MEM_FENCE);                                                          \
            for (uint q = 0; q < SCAN_Q_; ++q) {                                                   \
                uint i = base + 4u * (q * g + l);                                                  \
                T o = carry + part[q * g + l];                                                     \
                T##4 r = inclusive ? v[q] : (T##4)((T)(0), v[q].s0, v[q].s1, v[q].s2);             \
                r += (T##4)(o);                                                                    \
                if (i + 4u <= end) {                                                               \
                    *(global T##4 *)(out + i) = r;                                                 \
                } else {                                                                           \
                    if (i < end)                                                                   \
                        out[i] = r.s0;                                                             \
                    if (i + 1u < end)                                                              \
                        out[i + 1u] = r.s1;                                                        \
                    if (i + 2u < end)                                                              \
                        out[i + 2u] = r.s2;                                                        \
                }                                                                                  \
            }                                                                                      \
            carry += total;                                                                        \
            barrier(CLK_LOCAL_MEM_FENCE);                                                          \
        }                                                                                          \
    }

SCAN_GROUP_KERNELS(uint, u32)
SCAN_GROUP_KERNELS(float, f32)
