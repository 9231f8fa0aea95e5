/*
 * Compaction, split and partition (streams/compact.c), written as stream
 * kernels with conditional outputs (sluice.cl): the runtime walks each
 * work-item's contiguous chunk of records, reserves room per chunk and keeps
 * input order for ORDERED outputs. Records are moved as 32-bit words, so any
 * record size that is a multiple of 4 bytes works: the _w1, _w2 and _w4
 * kernels move 4, 8 and 16-byte records as one uint, uint2 or uint4; the
 * _words kernels move `words` words per record.
 */
#include "sluice.cl"

/* Compaction: record i goes to `out` when flags[i] != 0. */
#define COMPACT_KERNEL(T, SUFFIX)                                                                  \
    __kernel void compact_##SUFFIX(SLUICE_PARAMS, global const T *in, global const uint *flags,    \
                                   global T *out)                                                  \
    {                                                                                              \
        SLUICE_FOR_EACH (i) {                                                                      \
            SLUICE_EMIT_IF(0, out, in[i], flags[i] != 0u);                                         \
        }                                                                                          \
    }

COMPACT_KERNEL(uint, w1)
COMPACT_KERNEL(uint2, w2)
COMPACT_KERNEL(uint4, w4)

__kernel void compact_words(SLUICE_PARAMS, global const uint *in, global const uint *flags,
                            global uint *out, uint words)
{
    SLUICE_FOR_EACH (i) {
        uint keep = flags[i] != 0u;
        uint at = SLUICE_EMIT_INDEX(0, keep);
        if (SLUICE_WRITING && keep) {
            global const uint *src = in + (size_t)i * words;
            global uint *dst = out + (size_t)at * words;
            for (uint w = 0; w < words; ++w)
                dst[w] = src[w];
        }
    }
}

/* Split: record i goes to output slot buckets[i] when that is below `count`.
 * Slots at or above `count` are unbound (their arguments are placeholders)
 * and never written: the record is written only to the slot it goes to. */
#define SPLIT_MOVE_W_(dst, at, src) ((dst)[at] = (src)[i])
#define SPLIT_SLOT_(K, OUT, MOVE)                                                                  \
    do {                                                                                           \
        uint at_ = SLUICE_EMIT_INDEX(K, b == K##u);                                                \
        if (SLUICE_WRITING && b == K##u)                                                           \
            MOVE(OUT, at_, in);                                                                    \
    } while (0)
#define SPLIT_SLOTS_(MOVE)                                                                         \
    SPLIT_SLOT_(0, o0, MOVE);                                                                      \
    SPLIT_SLOT_(1, o1, MOVE);                                                                      \
    SPLIT_SLOT_(2, o2, MOVE);                                                                      \
    SPLIT_SLOT_(3, o3, MOVE);                                                                      \
    SPLIT_SLOT_(4, o4, MOVE);                                                                      \
    SPLIT_SLOT_(5, o5, MOVE);                                                                      \
    SPLIT_SLOT_(6, o6, MOVE);                                                                      \
    SPLIT_SLOT_(7, o7, MOVE)

#define SPLIT_KERNEL(T, SUFFIX)                                                                    \
    __kernel void split_##SUFFIX(SLUICE_PARAMS, global const T *in, global const uint *buckets,    \
                                 uint count, global T *o0, global T *o1, global T *o2,             \
                                 global T *o3, global T *o4, global T *o5, global T *o6,           \
                                 global T *o7)                                                     \
    {                                                                                              \
        SLUICE_FOR_EACH (i) {                                                                      \
            uint b = buckets[i];                                                                   \
            b = b < count ? b : SLUICE_NONE;                                                       \
            SPLIT_SLOTS_(SPLIT_MOVE_W_);                                                           \
        }                                                                                          \
    }

SPLIT_KERNEL(uint, w1)
SPLIT_KERNEL(uint2, w2)
SPLIT_KERNEL(uint4, w4)

#define SPLIT_MOVE_WORDS_(dst, at, src)                                                            \
    do {                                                                                           \
        global const uint *s_ = (src) + (size_t)i * words;                                         \
        global uint *d_ = (dst) + (size_t)(at)*words;                                              \
        for (uint w = 0; w < words; ++w)                                                           \
            d_[w] = s_[w];                                                                         \
    } while (0)

__kernel void split_words(SLUICE_PARAMS, global const uint *in, global const uint *buckets,
                          uint count, global uint *o0, global uint *o1, global uint *o2,
                          global uint *o3, global uint *o4, global uint *o5, global uint *o6,
                          global uint *o7, uint words)
{
    SLUICE_FOR_EACH (i) {
        uint b = buckets[i];
        b = b < count ? b : SLUICE_NONE;
        SPLIT_SLOTS_(SPLIT_MOVE_WORDS_);
    }
}

/* Partition of scalars by a threshold: x < t goes to slot 0 (`below`), the
 * rest to slot 1 (`above`); for floats a NaN compares false and goes above.
 * Records are moved as their bit patterns. */
__kernel void partition_u32(SLUICE_PARAMS, global const uint *in, uint t, global uint *below,
                            global uint *above)
{
    SLUICE_FOR_EACH (i) {
        uint x = in[i];
        uint lo = x < t;
        SLUICE_EMIT_IF(0, below, x, lo);
        SLUICE_EMIT_IF(1, above, x, !lo);
    }
}

__kernel void partition_f32(SLUICE_PARAMS, global const uint *in, float t, global uint *below,
                            global uint *above)
{
    SLUICE_FOR_EACH (i) {
        uint x = in[i];
        uint lo = as_float(x) < t;
        SLUICE_EMIT_IF(0, below, x, lo);
        SLUICE_EMIT_IF(1, above, x, !lo);
    }
}
