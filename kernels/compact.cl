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

/* 4-byte records, the common case, go 16 at a time (SLUICE_EMIT16) where
 * that is fast. Elsewhere (GPUs) they go 4 at a time as one vector
 * (SLUICE_FOR_EACH_BLOCK_OF, SLUICE_EMIT4), whose blocks a GPU's work-items
 * read side by side (interleaved), where a range would give each its own
 * stretch; one record at a time kept one 4-byte load in flight per
 * work-item (bench/README.md, the H100).
 *
 * COMPACT_AHEAD: the block kernels below take two blocks of 16 per step and
 * load both before emitting either. The compiler cannot move a load above
 * an emission's store itself (input and output could alias, as far as it
 * knows), so without this each block's loads wait behind the previous
 * block's stores. It matters with AVX2 kernels (measured in
 * bench/README.md, bench_streams). */
/* COMPACT_BLOCK: a GPU work-item's block per step, four such vectors.
 * Group order (ordered outputs) scans the group's counts once a step, so
 * blocks of 16 scan a quarter as often as blocks of 4; on the H100 longer
 * ones lost their reads' coalescing (bench/README.md). -DCOMPACT_BLOCK=4 in
 * SLUICE_BUILD_OPTIONS measures the trade (bench/lent_machine.sh
 * gpu-block-ab). A multiple of 4. */
#ifndef COMPACT_BLOCK
#define COMPACT_BLOCK 16u
#endif

/* COMPACT_NEXT: a chunk is counted, then written, so while a chunk is
 * written (its records already in the cache) the memory bus would idle; the
 * block kernels ask for the two lines at the same place of the next chunk
 * that the same thread runs (SLUICE_AHEAD: on a CPU the next work-item of
 * the group, which PoCL runs next, or in a chained launch the chunk of the
 * ticket taken for it), and its count pass finds them in the cache
 * (bench/README.md, bench_streams). */
#define COMPACT_NEXT_(p, i)                                                                        \
    do {                                                                                           \
        if (SLUICE_WRITING) {                                                                      \
            SLUICE_PREFETCH((p) + (i) + SLUICE_AHEAD);                                             \
            SLUICE_PREFETCH((p) + (i) + 16u + SLUICE_AHEAD);                                       \
        }                                                                                          \
    } while (0)

#if SLUICE_EMIT16_FAST
__kernel void compact_w1(SLUICE_PARAMS, global const uint *in, global const uint *flags,
                         global uint *out)
{
    SLUICE_FOR_EACH_RANGE (b, e) {
        uint i = b;
        for (; SLUICE_EMIT16_FAST && i + 32u <= e; i += 32u) {
            /* two blocks, loaded before either is emitted (COMPACT_AHEAD);
             * the records only in the pass that writes them */
            uint16 x = (uint16)0u, y = (uint16)0u;
            if (SLUICE_WRITING) {
                x = SLUICE_LOAD16(in + i);
                y = SLUICE_LOAD16(in + i + 16u);
            }
            COMPACT_NEXT_(flags, i);
            ushort mx = sluice_mask16(as_int16(SLUICE_LOAD16(flags + i) != (uint16)0u));
            ushort my = sluice_mask16(as_int16(SLUICE_LOAD16(flags + i + 16u) != (uint16)0u));
            SLUICE_EMIT16(0, out, x, mx);
            SLUICE_EMIT16(0, out, y, my);
        }
        for (; SLUICE_EMIT16_FAST && i + 16u <= e; i += 16u)
            SLUICE_EMIT16(0, out, SLUICE_LOAD16(in + i),
                          sluice_mask16(as_int16(SLUICE_LOAD16(flags + i) != (uint16)0u)));
        for (; i < e; ++i)
            SLUICE_EMIT_IF(0, out, in[i], flags[i] != 0u);
    }
}
#else
__kernel void compact_w1(SLUICE_PARAMS, global const uint *in, global const uint *flags,
                         global uint *out)
{
    SLUICE_FOR_EACH_BLOCK_OF(b, e, COMPACT_BLOCK)
    {
        uint i = b;
        for (; i + 4u <= e && (i & 3u) == 0u; i += 4u) {
            uint4 f = *(global const uint4 *)(flags + i);
            uint m = sluice_mask4(f != (uint4)0u);
            uint4 x = (uint4)0u; /* read where some are kept, in the pass that writes */
            if (m && SLUICE_WRITING)
                x = *(global const uint4 *)(in + i);
            SLUICE_EMIT4(0, out, x, m);
        }
        for (; i < e; ++i)
            SLUICE_EMIT_IF(0, out, in[i], flags[i] != 0u);
    }
}
#endif
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

/* 4-byte records go 16 at a time where that is fast (as compact_w1): one
 * mask per bound output. */
#define SPLIT16_SLOT_(K, OUT)                                                                      \
    do {                                                                                           \
        if (K##u < count)                                                                          \
            SLUICE_EMIT16(K, OUT, x, sluice_mask16(as_int16(bv == (uint16)K##u)));                 \
    } while (0)

#if SLUICE_EMIT16_FAST
__kernel void split_w1(SLUICE_PARAMS, global const uint *in, global const uint *buckets, uint count,
                       global uint *o0, global uint *o1, global uint *o2, global uint *o3,
                       global uint *o4, global uint *o5, global uint *o6, global uint *o7)
{
    SLUICE_FOR_EACH_RANGE (lo, hi) {
        uint i = lo;
        for (; SLUICE_EMIT16_FAST && i + 16u <= hi; i += 16u) {
            uint16 bv = SLUICE_LOAD16(buckets + i), x = (uint16)0u;
            if (SLUICE_WRITING) /* the records only in the pass that writes them */
                x = SLUICE_LOAD16(in + i);
            COMPACT_NEXT_(buckets, i);
            SPLIT16_SLOT_(0, o0);
            SPLIT16_SLOT_(1, o1);
            SPLIT16_SLOT_(2, o2);
            SPLIT16_SLOT_(3, o3);
            SPLIT16_SLOT_(4, o4);
            SPLIT16_SLOT_(5, o5);
            SPLIT16_SLOT_(6, o6);
            SPLIT16_SLOT_(7, o7);
        }
        for (; i < hi; ++i) {
            uint b = buckets[i];
            b = b < count ? b : SLUICE_NONE;
            SPLIT_SLOTS_(SPLIT_MOVE_W_);
        }
    }
}
#else
SPLIT_KERNEL(uint, w1)
#endif
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
 * Records are moved as their bit patterns, 16 at a time where that is fast
 * (as compact_w1), else one at a time. */
#define PARTITION_ONE_(AS1)                                                                        \
    do {                                                                                           \
        uint x = in[i];                                                                            \
        uint lo = AS1(x) < t;                                                                      \
        SLUICE_EMIT_IF(0, below, x, lo);                                                           \
        SLUICE_EMIT_IF(1, above, x, !lo);                                                          \
    } while (0)
#if SLUICE_EMIT16_FAST
#define PARTITION_KERNEL(SUFFIX, T, T16, AS1, AS16, AS4)                                           \
    __kernel void partition_##SUFFIX(SLUICE_PARAMS, global const uint *in, T t,                    \
                                     global uint *below, global uint *above)                       \
    {                                                                                              \
        SLUICE_FOR_EACH_RANGE (b, e) {                                                             \
            uint i = b;                                                                            \
            for (; SLUICE_EMIT16_FAST && i + 32u <= e; i += 32u) { /* COMPACT_AHEAD */             \
                uint16 x = SLUICE_LOAD16(in + i), y = SLUICE_LOAD16(in + i + 16u);                 \
                COMPACT_NEXT_(in, i);                                                              \
                ushort mx = sluice_mask16(as_int16(AS16(x) < (T16)t));                             \
                ushort my = sluice_mask16(as_int16(AS16(y) < (T16)t));                             \
                SLUICE_EMIT16(0, below, x, mx);                                                    \
                SLUICE_EMIT16(1, above, x, (ushort)~mx);                                           \
                SLUICE_EMIT16(0, below, y, my);                                                    \
                SLUICE_EMIT16(1, above, y, (ushort)~my);                                           \
            }                                                                                      \
            for (; SLUICE_EMIT16_FAST && i + 16u <= e; i += 16u) {                                 \
                uint16 x = SLUICE_LOAD16(in + i);                                                  \
                ushort m = sluice_mask16(as_int16(AS16(x) < (T16)t));                              \
                SLUICE_EMIT16(0, below, x, m);                                                     \
                SLUICE_EMIT16(1, above, x, (ushort)~m);                                            \
            }                                                                                      \
            for (; i < e; ++i)                                                                     \
                PARTITION_ONE_(AS1);                                                               \
        }                                                                                          \
    }
#else
/* 4 records at a time as one vector (compact_w1's comment) */
#define PARTITION_KERNEL(SUFFIX, T, T16, AS1, AS16, AS4)                                           \
    __kernel void partition_##SUFFIX(SLUICE_PARAMS, global const uint *in, T t,                    \
                                     global uint *below, global uint *above)                       \
    {                                                                                              \
        SLUICE_FOR_EACH_BLOCK_OF(b, e, COMPACT_BLOCK)                                              \
        {                                                                                          \
            uint i = b;                                                                            \
            for (; i + 4u <= e && (i & 3u) == 0u; i += 4u) {                                       \
                uint4 x = *(global const uint4 *)(in + i);                                         \
                uint m = sluice_mask4(AS4(x) < (T##4)t);                                           \
                SLUICE_EMIT4(0, below, x, m);                                                      \
                SLUICE_EMIT4(1, above, x, ~m);                                                     \
            }                                                                                      \
            for (; i < e; ++i)                                                                     \
                PARTITION_ONE_(AS1);                                                               \
        }                                                                                          \
    }
#endif

PARTITION_KERNEL(u32, uint, uint16, , , )
PARTITION_KERNEL(f32, float, float16, as_float, as_float16, as_float4)
