/*
 * sluice.cl: the kernel-side half of Sluice. A kernel file starts with
 *
 *     #include "sluice.cl"
 *
 * (served from the copy embedded in the library), and writes stream kernels as
 * plain OpenCL kernels whose parameter list starts with SLUICE_PARAMS and whose
 * body is a SLUICE_FOR_EACH loop, run once per input record with the record's
 * index in the named variable:
 *
 *     __kernel void split_sign(SLUICE_PARAMS, global const float *in,
 *                              global float *neg, global float *pos)
 *     {
 *         SLUICE_FOR_EACH(i) {
 *             float x = in[i];
 *             SLUICE_EMIT_IF(0, neg, x, x < 0.0f);  // conditional output slot 0
 *             SLUICE_EMIT_IF(1, pos, x, x >= 0.0f); // conditional output slot 1
 *             SLUICE_COUNT(0, x == 0.0f);           // counter 0 counts zeros
 *         }
 *     }
 *
 * How it runs (and why). On a CPU the fastest way to write a variable number of
 * records is the way a C programmer would: each work-item walks a contiguous
 * chunk of records, first counting what it will emit (pass 0), then reserving
 * room for the whole chunk with one global atomic per output and writing the
 * records (pass 1). This is Purcell's conditional output stream (thesis 3.1.2)
 * without the per-record atomics that make it slow: at most one global atomic
 * per chunk and output. For ORDERED outputs the counts go to a scratch array
 * instead, the host scans it, and a second launch writes at the scanned
 * offsets, so records keep the order of the input.
 *
 * On a GPU (the runtime's interleaved layout, sluice_layout in sluice.h)
 * the work-items of a group take the records of their chunks together, one
 * in every G (the group size) each, so that neighbouring work-items read
 * neighbouring records; bodies written with SLUICE_FOR_EACH_RANGE keep a
 * contiguous chunk per work-item. There the work-group also reserves room
 * together (SLUICE_GROUP_EMIT_ below): one global atomic per group and
 * output, and each record's place taken from a counter in local memory, so
 * that the records a group's work-items emit side by side land side by
 * side. Ordered outputs are placed by the group too (group order, below):
 * the host scans one count per group, and the group walks its records in
 * steps, each counted, scanned across the group and then written.
 *
 * Rules for a body that emits:
 *   - It runs twice per record (count pass, write pass; three times in group
 *     order, below) and must emit the same records every time: it must be
 *     deterministic and must not depend on what it wrote itself. Put heavy
 *     work in a kernel without conditional outputs, or guard other writes
 *     with `if (SLUICE_WRITING)`.
 *   - Use `continue` to skip the rest of a record. Never `return` or `break`:
 *     they would skip the reservation and the counter flush. Nor `return`
 *     before SLUICE_FOR_EACH: group emission's barriers (below) need every
 *     work-item of the group.
 *   - Emit with constant slot numbers (0 .. SLUICE_MAX_OUTPUTS-1).
 */
#ifndef SLUICE_CL_INCLUDED
#define SLUICE_CL_INCLUDED

#define SLUICE_MAX_OUTPUTS 8
#define SLUICE_MAX_COUNTERS 8

/* Off CPUs (the runtime defines SLUICE_UNROLL_STATE_ for devices other
 * than CPUs) every helper below is inlined into the kernel and every loop
 * over the outputs or counters unrolled, so that the state of a work-item
 * (sluice_state_) lives in registers: a GPU compiler otherwise keeps it in
 * memory, indexed at run time (NVIDIA's OpenCL showed a 176-byte stack
 * frame, the state's size, in every stream kernel; clang for NVPTX shows
 * the same frame, and none with these: tests/test_gpu_state.sh). PoCL
 * inlines everything anyway; there the unrolled loops' branches between
 * group emission's barriers made its compile time explode, and forced
 * inlining alone made it 30% longer. For measuring, the build option
 * -DSLUICE_NO_UNROLL_STATE (SLUICE_BUILD_OPTIONS) turns it off. */
#if defined(SLUICE_UNROLL_STATE_) && !defined(SLUICE_NO_UNROLL_STATE)
#define SLUICE_INLINE_ static inline __attribute__((always_inline))
#define SLUICE_UNROLL_ _Pragma("unroll")
#else
#define SLUICE_INLINE_ inline
#define SLUICE_UNROLL_
#endif
#define SLUICE_EACH_OUTPUT_(k) SLUICE_UNROLL_ for (uint k = 0; k < SLUICE_MAX_OUTPUTS; ++k)
#define SLUICE_EACH_COUNTER_(c) SLUICE_UNROLL_ for (uint c = 0; c < SLUICE_MAX_COUNTERS; ++c)
#define SLUICE_NONE 0xffffffffu

/* Overflow is an error, never a truncation. A stream's length lives in
 * vars[var], and vars[var + 1] is its second variable. When a kernel emits
 * past an output's capacity, the records that fit are written and the length
 * goes on counting past the capacity: the host reports the overflow when it
 * reads that length. A launch whose input length (on the device) is past the
 * input's capacity reads no records and makes its outputs void: their length
 * becomes SLUICE_VOID_ and their second variable the length variable of the
 * stream that overflowed first, so an overflow is reported wherever the
 * stream it spoiled is read (runtime/src/stream.c), however far downstream.
 * The same holds for counters: their note (the variable after the last
 * counter) gets 1 + that variable. */
#define SLUICE_VOID_ 0xfffffffeu

/* The length of the stream whose length is vars[var] and capacity `cap`, as
 * a launch reads it: 0 when it overflowed (or is void). */
SLUICE_INLINE_ uint sluice_stream_length_(global const uint *vars, uint var, uint cap)
{
    uint n = vars[var];
    return n <= cap ? n : 0u;
}

/* Makes the stream whose length is vars[var] void, because it was written
 * from the overflowed stream whose length is vars[from]. */
SLUICE_INLINE_ void sluice_void_(global uint *vars, uint var, uint from)
{
    vars[var + 1u] = vars[from] == SLUICE_VOID_ ? vars[from + 1u] : from;
    vars[var] = SLUICE_VOID_;
}

/* Launch parameters filled in by the host runtime (runtime/src/kernel.c keeps
 * the same layout). All fields are uint so host and device agree on layout. */
typedef struct sluice_launch_ {
    uint n_fixed;      /* input length when the host knows it, else SLUICE_NONE */
    uint in_var;       /* index of the input length in the variable pool */
    uint chunk;        /* records per work-item */
    uint mode;         /* 0: one launch, 1: ordered count launch, 2: ordered write,
                          3: ordered in one launch (the chain, below) */
    uint first_pass;   /* 0 when the count pass runs, else 1 */
    uint ordered_mask; /* bit k: output k is ordered */
    uint out_mask;     /* bit k: output k is bound */
    uint counter_var;  /* first counter in the pool, or SLUICE_NONE */
    uint n_counters;   /* counters bound */
    uint prof_var;     /* profile variables (records in, out[8]) or SLUICE_NONE */
    uint stride;       /* chunks + 1: scratch row length per ordered output */
    uint in_cap;       /* input capacity: a device length past it (overflow) voids the launch */
    uint n_map;        /* mapped outputs whose length the launch sets (n_fixed is SLUICE_NONE) */
    uint interleave;   /* 1: SLUICE_FOR_EACH interleaves its records within a work-group */
    uint spread;       /* work-group g takes the chunks of group g * spread mod groups */
    uint epoch;        /* mode 3: this launch's tag in the chain's flags */
    uint chain_flags;  /* mode 3: words of the chain's flag region (at least stride) */
    uint out_var[SLUICE_MAX_OUTPUTS]; /* output lengths in the pool */
    uint out_cap[SLUICE_MAX_OUTPUTS]; /* output capacities (records) */
    uint map_var[SLUICE_MAX_OUTPUTS]; /* the lengths of those mapped outputs */
} sluice_launch_;

/* Group emission (contexts in the interleaved layout: the runtime builds
 * their programs with -DSLUICE_GROUP_EMIT_). In an interleaved launch the 32
 * work-items of a GPU warp emit their records at the same time, and a
 * chunk's own reserved range per work-item would scatter those 32 stores
 * over 32 ranges. So for unordered outputs the group reserves room for its
 * work-items together and hands out places one record at a time from a
 * counter in local memory (sluice_lds_): records emitted side by side land
 * side by side; ordered outputs are placed in group order (below). Local
 * memory per group: a cursor, the reserved start (in group order the next
 * place) and its end per output (SLUICE_LDS_WORDS_), then group order's scan
 * (8 (G + 16) words). The barriers are reached by every work-item of the
 * group (the body never returns or breaks), and only in launches with
 * outputs: their conditions are the same for the whole launch. Contexts in
 * the contiguous layout (CPUs) build without any of it. */
#define SLUICE_LDS_WORDS_ (3 * SLUICE_MAX_OUTPUTS)

/* Per-work-item state of one launch. */
typedef struct sluice_state_ {
    uint begin, end; /* the chunk: records begin, begin + step, ... before end */
    uint step;       /* 1 (contiguous), or the work-group size (interleaved) */
    uint blk;        /* records per step: 1, or the block form's width */
    uint uend;       /* the loop's end: `end`, or past it where the group steps together */
    uint pass;       /* 0: count, 1: write, 3: a step's count (group order, below) */
    uint omask;      /* ordered outputs placed by the group (group order), else 0 */
    uint stepped;    /* 1: their places come from a scan per step (not a range's) */
    uint chunk_id;
    uint ahead;      /* records from this chunk to the next this thread takes (SLUICE_AHEAD) */
    uint group;      /* 1: the group reserves room together (group emission) */
    local uint *lds; /* its cursors, starts and ends (SLUICE_LDS_WORDS_) */
    uint cnt[SLUICE_MAX_OUTPUTS]; /* records this chunk emits, per output */
    uint pos[SLUICE_MAX_OUTPUTS]; /* next slot to write; the group's start in group emission */
    uint lim[SLUICE_MAX_OUTPUTS]; /* end of the reserved range, clamped to capacity */
    uint ctr[SLUICE_MAX_COUNTERS];
} sluice_state_;

/* Work-item 0 of a launch whose input length is on the device, in the last
 * launch (not the count launch of ordered outputs): sets the mapped outputs'
 * lengths to the input's `n`, or, when the input overflowed, makes the
 * outputs, the mapped outputs and the counters void. No other work-item
 * touches them: an overflowed input has no records to read. */
SLUICE_INLINE_ void sluice_set_lengths_(global uint *vars, const sluice_launch_ *L, uint n)
{
    if (vars[L->in_var] <= L->in_cap) {
        for (uint m = 0; m < L->n_map; ++m)
            vars[L->map_var[m]] = n;
        return;
    }
    SLUICE_EACH_OUTPUT_ (k)
        if ((L->out_mask >> k) & 1u)
            sluice_void_(vars, L->out_var[k], L->in_var);
    for (uint m = 0; m < L->n_map; ++m)
        sluice_void_(vars, L->map_var[m], L->in_var);
    if (L->counter_var != SLUICE_NONE)
        vars[L->counter_var + L->n_counters] =
            1u + (vars[L->in_var] == SLUICE_VOID_ ? vars[L->in_var + 1u] : L->in_var);
}

/* Group order: ordered outputs in the interleaved layout (GPUs). The
 * work-group owns its work-items' records together (a tile of G chunks):
 * the count launch adds the group's counts (sluice_group_reserve_), the
 * host scans one count per group, and the write launch places each record
 * in input order within the group's room. In SLUICE_FOR_EACH and _BLOCK,
 * whose work-items take the tile's records side by side, the group walks
 * the tile in steps (one record or block per work-item) and runs each step
 * twice: first counting what each work-item emits to the ordered outputs
 * (pass 3), then, after a scan of those counts across the group
 * (sluice_step_places_), writing them (pass 1). A range (SLUICE_FOR_EACH_
 * RANGE) keeps a contiguous chunk per work-item: its write launch counts
 * again and one scan across the group places each work-item's records. */

/* The places of a work-item's records in the group's room, for all
 * outputs at once (the lanes of a uint8: outputs 0-7, so that no barrier
 * sits under a condition on which outputs are ordered): the group's next
 * places (*at, 8 words of local memory) plus the exclusive scan of x across
 * the group; *at moves past them all. In two levels, with four barriers and
 * none in a loop (PoCL's compile time grows with barriers in loops): 16
 * work-items scan a 16th of the group each, then one scans their sums. `t`
 * is local memory for 8 (G + 16) words (G the group size). Every work-item
 * of the group must reach it. */
#define SLUICE_SCAN_SEGMENTS_ 16u
SLUICE_INLINE_ uint8 sluice_group_place_(local uint *t, uint8 x, local uint *at)
{
    uint l = (uint)get_local_id(0), g = (uint)get_local_size(0);
    uint segs = min(g, SLUICE_SCAN_SEGMENTS_), seg = (g + segs - 1u) / segs;
    vstore8(x, l, t);
    barrier(CLK_LOCAL_MEM_FENCE);
    if (l < segs) { /* its segment's exclusive scan in place, its sum after the group's */
        uint8 acc = (uint8)(0u);
        for (uint i = l * seg; i < min(l * seg + seg, g); ++i) {
            uint8 v = vload8(i, t);
            vstore8(acc, i, t);
            acc += v;
        }
        vstore8(acc, g + l, t);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (l == 0u) { /* the segments' starts, from the group's next places */
        uint8 acc = vload8(0, at);
        for (uint j = 0; j < segs; ++j) {
            uint8 v = vload8(g + j, t);
            vstore8(acc, g + j, t);
            acc += v;
        }
        vstore8(acc, 0, at);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    uint8 r = vload8(l, t) + vload8(g + l / seg, t);
    barrier(CLK_LOCAL_MEM_FENCE); /* t is read before the next scan writes it */
    return r;
}

/* Off CPUs (where the runtime defines SLUICE_UNROLL_STATE_) the group's
 * scan of ordered outputs takes Kogge and Stone's rounds below: on an H100
 * they made the ordered compaction and split faster (bench/README.md, "The
 * group's scan in rounds on the GPU"). -DSLUICE_NO_KS_SCAN keeps the serial
 * segments there; on PoCL the rounds compile far slower (a barrier in a
 * loop), so CPUs keep the segments unless -DSLUICE_KS_SCAN. */
#if defined(SLUICE_UNROLL_STATE_) && !defined(SLUICE_NO_KS_SCAN) && !defined(SLUICE_KS_SCAN)
#define SLUICE_KS_SCAN
#endif

#ifdef SLUICE_KS_SCAN
/* sluice_group_place_ for ordered outputs in slots 0 to N - 1 only, N = 2 or
 * 4 (uint2, uint4): the group's scan in log2(G) rounds of all its
 * work-items (Kogge and Stone's), each a barrier, in two buffers of N G
 * words of t, instead of 16 work-items' serial segments. A GPU's work-group
 * then waits on 8 short rounds (G = 256) rather than on 32 dependent reads
 * of local memory by a few work-items; the narrower vectors also move a
 * quarter or half of the words (bench/lent_machine.sh gpu-scan-ab measures
 * it against the segments). */
#define SLUICE_KS_PLACE_(N)                                                                        \
    SLUICE_INLINE_ uint##N sluice_group_place##N##_(local uint *t, uint##N x, local uint *at)      \
    {                                                                                              \
        uint l = (uint)get_local_id(0), g = (uint)get_local_size(0);                               \
        local uint *src = t, *dst = t + N * g;                                                     \
        vstore##N(x, l, src);                                                                      \
        barrier(CLK_LOCAL_MEM_FENCE);                                                              \
        for (uint off = 1u; off < g; off <<= 1) {                                                  \
            uint##N v = vload##N(l, src);                                                          \
            if (l >= off)                                                                          \
                v += vload##N(l - off, src);                                                       \
            vstore##N(v, l, dst);                                                                  \
            barrier(CLK_LOCAL_MEM_FENCE);                                                          \
            local uint *sw = src;                                                                  \
            src = dst;                                                                             \
            dst = sw;                                                                              \
        }                                                                                          \
        uint##N base = vload##N(0, at), total = vload##N(g - 1u, src);                             \
        uint##N r = base + vload##N(l, src) - x; /* the inclusive scan, less its own */            \
        barrier(CLK_LOCAL_MEM_FENCE); /* t and at are read before they are written again */        \
        if (l == 0u)                                                                               \
            vstore##N(base + total, 0, at);                                                        \
        return r;                                                                                  \
    }
SLUICE_KS_PLACE_(2)
SLUICE_KS_PLACE_(4)
#endif

/* sluice_group_place_ for the ordered outputs the group places, of the
 * counts cnt - from (from NULL: cnt; none when `none`, which leaves the
 * group's next places as they are): their places. */
SLUICE_INLINE_ uint8 sluice_group_places_(sluice_state_ *s, const uint *from, uint none)
{
    uint8 x;
    uint *xs = (uint *)&x;
    SLUICE_EACH_OUTPUT_ (k)
        xs[k] = (s->omask >> k) & 1u && !none ? s->cnt[k] - (from ? from[k] : 0u) : 0u;
    local uint *t = s->lds + SLUICE_LDS_WORDS_, *at = s->lds + SLUICE_MAX_OUTPUTS;
#ifdef SLUICE_KS_SCAN
    /* the same branch for the whole group: omask is the launch's */
    if (s->omask < 4u)
        return (uint8)(sluice_group_place2_(t, x.s01, at), (uint2)(0u), (uint4)(0u));
    if (s->omask < 16u)
        return (uint8)(sluice_group_place4_(t, x.lo, at), (uint4)(0u));
#endif
    return sluice_group_place_(t, x, at);
}

/* Into the write pass: where the group steps, into a step's count first;
 * its counts start from the marks in pos (the count pass's are dropped). */
SLUICE_INLINE_ void sluice_enter_write_(sluice_state_ *s)
{
    s->pass = 1u;
    if (!s->stepped || s->begin >= s->uend)
        return;
    s->pass = 3u;
    SLUICE_EACH_OUTPUT_ (k)
        if ((s->omask >> k) & 1u)
            s->pos[k] = s->cnt[k] = 0u;
}

/* Between a step's count and its writing: each ordered output's places for
 * this step, after the group's earlier steps (sluice_group_place_). */
SLUICE_INLINE_ void sluice_step_places_(sluice_state_ *s)
{
    uint8 p = sluice_group_places_(s, s->pos, 0u);
    const uint *ps = (const uint *)&p;
    SLUICE_EACH_OUTPUT_ (k)
        if ((s->omask >> k) & 1u)
            s->pos[k] = ps[k];
}

/* A range's places in group order, after its count pass: each work-item's
 * records after those of the work-items before it in the group. A group
 * that steps takes part with nothing (its count pass counted for the
 * unordered outputs; its places come per step). */
SLUICE_INLINE_ void sluice_range_places_(sluice_state_ *s)
{
    uint8 p = sluice_group_places_(s, 0, s->stepped);
    const uint *ps = (const uint *)&p;
    SLUICE_EACH_OUTPUT_ (k) {
        if (!((s->omask >> k) & 1u) || s->stepped)
            continue;
        s->lim[k] = (uint)min((ulong)ps[k] + s->cnt[k], (ulong)s->lim[k]);
        s->pos[k] = ps[k];
    }
}

/* The chain: ordered outputs in one launch (mode 3), for the contiguous
 * layout on CPUs. The count launch, the scan and the write launch read the
 * whole input twice from memory; here each work-item counts its chunk, takes
 * its chunk's places from the chunks before it by decoupled look-back
 * (Merrill and Garland, "Single-pass Parallel Prefix Scan with Decoupled
 * Look-back", 2016) and writes the chunk while it is still in the cache.
 * Chunks are numbered in the order work-items take them (a ticket from an
 * atomic counter), not by work-item id: PoCL hands a thread a run of
 * consecutive work-groups, and a chunk that waited on the end of another
 * thread's run would wait for all of it. So a chunk waits only on chunks
 * already taken, by work-items that run on a thread of their own or on one
 * that gets to them without waiting on anything later: the lowest
 * unfinished chunk waits on nobody, and the chain moves. A work-item takes
 * the ticket of the next work-item of its group (local memory) after its
 * look-back and before its write pass: PoCL runs a group's work-items one
 * after another on one thread, so that is the chunk this thread takes next,
 * and the write pass can ask for its first lines ahead (SLUICE_AHEAD). (The
 * two threads take alternate chunks; without the ticket ahead, the write
 * pass's prefetch of the adjacent chunk fetched the other thread's, and
 * ordered splits ran 30% slower than unordered ones; bench/README.md. A
 * ticket per work-group, for runs of G chunks, was slower still: a group
 * publishes nothing before its last work-item has counted.)
 * Implementations that run a group's work-items side by side in SIMD lanes
 * would have a lane wait on the one before it, and the tickets handed on
 * need them in turn: the host chains launches on PoCL only (kernel.c).
 *
 * The scratch buffer is the context's chain buffer (the host's
 * sl_chain_reserve; zeroed when made): word 0 the ticket counter, which the
 * work-item drawing the launch's last ticket sets back to 0; then a flag per
 * chunk, in a region of chain_flags words (at least stride) that keeps its
 * place as long as the buffer does; then, per ordered output up to the
 * highest (rows), a row of each chunk's count (published first, so that the
 * next chunk need not wait for this one's look-back) and a row of each
 * chunk's inclusive end (its place plus its count), stride words each. A
 * flag is the launch's epoch (the host's, different in every mode-3 launch,
 * so flags of earlier launches never count) shifted by 2, or-ed with what is
 * published: 1 the count, 2 the end. Values are written before their flag
 * and read after it. The flags' region is not placed by the launch's own
 * stride: with it, a launch of more chunks than the one before found that
 * one's counts and ends where its flags are, and a count that equalled its
 * tag read as a chunk's flag, so that a chunk looking back before its
 * neighbour had published took a stale count (test_runtime's
 * test_chain_strides; bench/README.md). */
#define SLUICE_CHAIN_COUNT_ 1u
#define SLUICE_CHAIN_END_ 2u

/* A chunk number of a mode-3 launch whose chunks number `total`: the
 * order in which they are taken (a group's, in the interleaved layout). */
SLUICE_INLINE_ uint sluice_chain_ticket_(global uint *chain, uint total)
{
    uint t = atomic_inc(chain);
    if (t == total - 1u) /* every ticket is taken */
        atomic_xchg(chain, 0u);
    return t;
}

/* Chunk t of a mode-3 launch (of chunks 0 .. last), once counted (cnt, per
 * output): the places of its ordered outputs' records (pos, lim), from the
 * counts and ends of the chunks before it, and its own published. The last
 * chunk sets the outputs' lengths (the scan kernel's job in modes 1 and 2):
 * their length before the launch plus every chunk's count, past the
 * capacity when they overflowed. A void output gets no room and stays void.
 * In the interleaved layout a chunk is a work-group's tile, and its first
 * work-item runs this for the group (programs built with
 * -DSLUICE_GROUP_CHAIN_, which the host adds for SLUICE_GROUP_CHAIN=1: the
 * look-back between group emission's barriers made PoCL's compile of those
 * programs several times longer, so only the contexts that chain have it). */
SLUICE_INLINE_ void sluice_chain_place_(global uint *chain, global uint *vars,
                                        const sluice_launch_ *L, uint t, uint last, const uint *cnt,
                                        uint *pos, uint *lim)
{
    uint st = L->stride, rows = 32u - clz(L->ordered_mask);
    uint tag = L->epoch << 2;
    volatile global uint *flag = chain + 1u;
    volatile global uint *count = flag + L->chain_flags, *end = count + rows * st;
    uint acc[SLUICE_MAX_OUTPUTS], dead = 0u;
    SLUICE_EACH_OUTPUT_ (k) {
        acc[k] = 0u;
        if (!((L->ordered_mask >> k) & 1u))
            continue;
        uint v = vars[L->out_var[k]];
        if (v == SLUICE_VOID_)
            dead |= 1u << k;
        else if (t == 0u)
            acc[k] = v; /* the first chunk's place: the length before */
        else
            count[k * st + t] = cnt[k];
    }
    if (t != 0u) {
        mem_fence(CLK_GLOBAL_MEM_FENCE);
        atomic_xchg((global uint *)&flag[t], tag | SLUICE_CHAIN_COUNT_);
        for (uint j = t - 1u;; --j) {
            uint f;
            while (((f = flag[j]) & ~3u) != tag)
                ; /* chunk j's work-item has started and will publish */
            mem_fence(CLK_GLOBAL_MEM_FENCE);
            volatile global uint *v = (f & SLUICE_CHAIN_END_) ? end : count;
            SLUICE_EACH_OUTPUT_ (k)
                if ((L->ordered_mask >> k) & 1u)
                    acc[k] += v[k * st + j];
            if (f & SLUICE_CHAIN_END_)
                break;
        }
    }
    /* an overflowed input voids the outputs instead (sluice_set_lengths_) */
    uint fin = t == last && (L->n_fixed != SLUICE_NONE || vars[L->in_var] <= L->in_cap);
    SLUICE_EACH_OUTPUT_ (k) {
        if (!((L->ordered_mask >> k) & 1u))
            continue;
        uint e = acc[k] + cnt[k];
        end[k * st + t] = e;
        pos[k] = (dead >> k) & 1u ? 0u : acc[k];
        lim[k] = (dead >> k) & 1u ? 0u : min(e, L->out_cap[k]);
        if (fin && !((dead >> k) & 1u))
            vars[L->out_var[k]] = e;
    }
    mem_fence(CLK_GLOBAL_MEM_FENCE);
    atomic_xchg((global uint *)&flag[t], tag | SLUICE_CHAIN_END_);
}

#ifndef SLUICE_GROUP_EMIT_
/* The contiguous layout's chain, after a chunk's count pass: its places,
 * then the ticket of the next work-item of the group (which runs after this
 * one) and how far ahead its chunk lies. */
SLUICE_INLINE_ void sluice_chain_(sluice_state_ *s, global uint *vars, global uint *chain,
                                  const sluice_launch_ *L)
{
    uint t = s->chunk_id, total = (uint)get_global_size(0);
    sluice_chain_place_(chain, vars, L, t, total - 1u, s->cnt, s->pos, s->lim);
    uint l = (uint)get_local_id(0);
    if (l + 1u < min((uint)get_local_size(0), (uint)SLUICE_LDS_WORDS_)) {
        uint next = sluice_chain_ticket_(chain, total);
        s->lds[l + 1u] = next;
        s->ahead = (next - t) * L->chunk;
    } else {
        s->ahead = 0u; /* not known */
    }
}
#endif

/* The loop forms (sluice_begin_'s `form`): SLUICE_FOR_EACH, _RANGE, _BLOCK. */
#define SLUICE_FORM_RECORD_ 0
#define SLUICE_FORM_RANGE_ 1
#define SLUICE_FORM_BLOCK_ 2

/* Records per block of SLUICE_FOR_EACH_BLOCK in the interleaved layout:
 * the 4 of one uint4 load, which the README's kernels take as given.
 * SLUICE_FOR_EACH_BLOCK_OF names another multiple of 4. */
#define SLUICE_BLOCK 4u

/* The lane numbers 0 to 15 of a 16-wide vector: a block of 16 records' offsets
 * from its first. */
#define SLUICE_LANE16                                                                              \
    ((uint16)(0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u, 9u, 10u, 11u, 12u, 13u, 14u, 15u))

/* The records of the work-item whose chunk (or whose group's tile) is
 * that of work-item `id` (sluice_begin_, below). */
SLUICE_INLINE_ void sluice_records_(sluice_state_ *s, uint id, uint n, const sluice_launch_ *L,
                                    int form, uint width)
{
    s->chunk_id = id;
    const int inter = L->interleave && form != SLUICE_FORM_RANGE_;
    if (inter) {
        uint l = (uint)get_local_id(0), g = (uint)get_local_size(0);
        uint w = form == SLUICE_FORM_BLOCK_ ? width : 1u;
        ulong tile = (ulong)(id - l) * L->chunk;
        s->begin = (uint)min(tile + (ulong)w * l, (ulong)n);
        s->end = (uint)min(tile + (ulong)g * L->chunk, (ulong)n);
        s->step = w * g;
        s->blk = w;
    } else {
        ulong b = (ulong)id * L->chunk;
        s->begin = (uint)min(b, (ulong)n);
        s->end = (uint)min(b + L->chunk, (ulong)n);
        s->step = 1u;
        s->blk = 1u;
        if (form == SLUICE_FORM_BLOCK_) /* one block: the whole chunk */
            s->step = s->blk = max(s->end - s->begin, 1u);
    }
    s->uend = s->end;
    s->ahead = s->end - s->begin;
}

/* The records of this work-item. Contiguous chunks (the range form, or a
 * launch without `interleave`): work-item i takes [i chunk, (i + 1) chunk),
 * the layout for CPUs, where one work-item walking its chunk runs like a C
 * loop. Interleaved (the layout for GPUs, whose work-items run in lockstep
 * groups and read memory together): a work-group takes the same records as
 * its work-items' chunks together, and work-item l of it takes every G-th of
 * them from the l-th (G the work-group size), so neighbouring work-items
 * read neighbouring records; in the block form every G-th block of
 * `width` records from the l-th. Ordered outputs are then placed in
 * group order (above).
 *
 * In the contiguous layout, for kernels marked uneven
 * (sluice_kernel_set_uneven), work-group g takes the chunks of group
 * g * spread mod G' (G' the number of groups; spread is coprime to it, so
 * every group's chunks are taken once). PoCL hands its threads runs of
 * consecutive work-groups, each a share of what is left (guided
 * scheduling), so without the spread a thread's first run is a band of the
 * stream: of a frame's rays, a band of rows, and the band holding the
 * object costs several times the others. Spread by about the golden ratio,
 * each run takes chunks from all over the stream and costs about its share
 * (bench/README.md, "Uneven records spread over the threads"). A chunk's
 * records, and the order of ordered outputs (by chunk), are as before. */
SLUICE_INLINE_ void sluice_begin_(sluice_state_ *s, global uint *vars, global uint *scratch,
                                  local uint *lds, const sluice_launch_ *L, int form, uint width)
{
    uint n = L->n_fixed;
    if (n == SLUICE_NONE) {
        n = sluice_stream_length_(vars, L->in_var, L->in_cap);
        if (L->mode != 1u && get_global_id(0) == 0)
            sluice_set_lengths_(vars, L, n);
    }
    uint id = (uint)get_global_id(0);
#ifndef SLUICE_GROUP_EMIT_
    if (L->mode == 3u) /* the chain's tickets, below */
        id = get_local_id(0) == 0 || get_local_id(0) >= SLUICE_LDS_WORDS_
                 ? sluice_chain_ticket_(scratch, (uint)get_global_size(0))
                 : lds[get_local_id(0)];
#endif
    if (L->spread > 1u) /* the spread, above */
        id = (uint)((ulong)get_group_id(0) * L->spread % get_num_groups(0)) *
                 (uint)get_local_size(0) +
             (uint)get_local_id(0);
    sluice_records_(s, id, n, L, form, width);
    s->pass = L->first_pass;
    s->lds = lds;
    s->group = 0u;
    s->omask = 0u;
    s->stepped = 0u;
    /* the row of scanned counts this work-item reads: its chunk's, or in
     * group order its group's */
    uint row = id;
#ifdef SLUICE_GROUP_EMIT_
    /* The interleaved layout with outputs: the same for the whole launch,
     * so the whole group takes the barriers or none does. */
#ifdef SLUICE_GROUP_CHAIN_
    /* with the groups' chain (mode 3): the group's ticket first, and its
     * tile from it */
    if (L->interleave && L->out_mask != 0u) {
        s->group = 1u;
        row = (uint)get_group_id(0);
        if (L->mode >= 2u) {
            s->omask = L->ordered_mask;
            s->stepped = form != SLUICE_FORM_RANGE_;
        }
        if (get_local_id(0) == 0) {
            SLUICE_EACH_OUTPUT_ (k) {
                lds[k] = 0u;
                if (L->mode == 2u && ((s->omask >> k) & 1u)) /* the group's next place */
                    lds[SLUICE_MAX_OUTPUTS + k] = scratch[k * L->stride + row];
            }
            /* the group chain's ticket (the chain, above; in the scan's
             * words, read by all before any scan) */
            if (L->mode == 3u)
                lds[SLUICE_LDS_WORDS_] = sluice_chain_ticket_(scratch, (uint)get_num_groups(0));
        }
        barrier(CLK_LOCAL_MEM_FENCE);
        if (L->mode == 3u) { /* the tile of the ticket's number */
            row = lds[SLUICE_LDS_WORDS_];
            sluice_records_(s, row * (uint)get_local_size(0) + (uint)get_local_id(0), n, L, form,
                            width);
        }
        if (s->stepped) {
            /* every work-item of the group takes the same number of steps */
            uint steps = (L->chunk + s->blk - 1u) / s->blk;
            s->uend = (uint)min((ulong)s->begin + (ulong)steps * s->step, (ulong)0xffffffffu);
            /* nothing to reserve: no count pass (the chain counts first) */
            if (L->mode == 2u && !(L->out_mask & ~L->ordered_mask))
                s->pass = 1u;
        }
#else
    if (L->interleave && L->out_mask != 0u) {
        s->group = 1u;
        row = (uint)get_group_id(0);
        if (L->mode == 2u) {
            s->omask = L->ordered_mask;
            s->stepped = form != SLUICE_FORM_RANGE_;
        }
        if (s->stepped) {
            /* every work-item of the group takes the same number of steps */
            uint steps = (L->chunk + s->blk - 1u) / s->blk;
            s->uend = (uint)min((ulong)s->begin + (ulong)steps * s->step, (ulong)0xffffffffu);
            if (!(L->out_mask & ~L->ordered_mask)) /* nothing to reserve: no count pass */
                s->pass = 1u;
        }
        if (get_local_id(0) == 0)
            SLUICE_EACH_OUTPUT_ (k) {
                lds[k] = 0u;
                if ((s->omask >> k) & 1u) /* the group's next place */
                    lds[SLUICE_MAX_OUTPUTS + k] = scratch[k * L->stride + row];
            }
        barrier(CLK_LOCAL_MEM_FENCE);
#endif
    }
#endif
    SLUICE_EACH_OUTPUT_ (k) {
        s->cnt[k] = 0;
        s->pos[k] = 0;
        s->lim[k] = 0;
        if (L->mode == 2 && ((L->ordered_mask >> k) & 1u)) {
            /* Write launch of an ordered output: offsets were scanned. */
            uint a = scratch[k * L->stride + row], e = scratch[k * L->stride + row + 1];
            s->cnt[k] = L->first_pass ? e - a : 0u; /* else recounted in pass 0 */
            s->pos[k] = a;
            s->lim[k] = min(e, L->out_cap[k]);
        }
    }
    if (s->pass == 1u)
        sluice_enter_write_(s);
    SLUICE_EACH_COUNTER_ (c)
        s->ctr[c] = 0;
}

/* Reserves room for `count` records of unordered output k: returns where
 * it starts and sets *lim to its end, clamped to the capacity (records past
 * it are dropped; the length counts them, so the overflow is reported). A
 * void output stays void: nothing is appended to it. */
SLUICE_INLINE_ uint sluice_reserve_(global uint *vars, const sluice_launch_ *L, uint k, uint count,
                                    uint *lim)
{
    uint p = 0u;
    *lim = 0u;
    if (count && vars[L->out_var[k]] != SLUICE_VOID_) {
        p = atomic_add(&vars[L->out_var[k]], count);
        *lim = (uint)min((ulong)p + count, (ulong)L->out_cap[k]);
    }
    return p;
}

/* Group emission's reservation, between the passes: the group's counts,
 * one global atomic per unordered output for all of them, then every
 * work-item reads the group's start and end. In a count launch (group
 * order) the group's counts of its ordered outputs go to the scratch row
 * of the group instead, and in a range's write launch each work-item takes
 * its places of them (sluice_range_places_). */
SLUICE_INLINE_ void sluice_group_reserve_(sluice_state_ *s, global uint *vars, global uint *scratch,
                                          const sluice_launch_ *L)
{
#ifdef SLUICE_GROUP_EMIT_
    local uint *lds = s->lds;
    /* the counts this adds up: a count launch's ordered outputs, or the
     * unordered outputs room is reserved for */
#ifdef SLUICE_GROUP_CHAIN_
    const uint mine = L->mode == 1u   ? L->ordered_mask
                      : L->mode == 3u ? L->out_mask
                                      : L->out_mask & ~s->omask;
    const uint chained = L->mode == 3u ? L->ordered_mask : 0u; /* placed by the chain */
#else
    const uint mine = L->mode == 1u ? L->ordered_mask : L->out_mask & ~s->omask;
    const uint chained = 0u;
#endif
    SLUICE_EACH_OUTPUT_ (k)
        if (((mine >> k) & 1u) && s->cnt[k])
            atomic_add(&lds[k], s->cnt[k]);
    barrier(CLK_LOCAL_MEM_FENCE);
    if (get_local_id(0) == 0) {
#ifdef SLUICE_GROUP_CHAIN_
        if (L->mode == 3u) { /* the group's places of its ordered outputs: the chain */
            uint tot[SLUICE_MAX_OUTPUTS], pos[SLUICE_MAX_OUTPUTS], lim[SLUICE_MAX_OUTPUTS];
            SLUICE_EACH_OUTPUT_ (k)
                tot[k] = lds[k];
            sluice_chain_place_(scratch, vars, L, s->chunk_id / (uint)get_local_size(0),
                                (uint)get_num_groups(0) - 1u, tot, pos, lim);
            SLUICE_EACH_OUTPUT_ (k) {
                if (!((L->ordered_mask >> k) & 1u))
                    continue;
                lds[SLUICE_MAX_OUTPUTS + k] = pos[k];
                lds[2 * SLUICE_MAX_OUTPUTS + k] = lim[k];
                lds[k] = 0u;
            }
        }
#endif
        SLUICE_EACH_OUTPUT_ (k) {
            if (!(((mine & ~chained) >> k) & 1u))
                continue;
            if (L->mode == 1u) {
                scratch[k * L->stride + get_group_id(0)] = lds[k];
                continue;
            }
            uint lim = 0u;
            lds[SLUICE_MAX_OUTPUTS + k] = sluice_reserve_(vars, L, k, lds[k], &lim);
            lds[2 * SLUICE_MAX_OUTPUTS + k] = lim;
            lds[k] = 0u;
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (L->mode == 1u)
        return;
    SLUICE_EACH_OUTPUT_ (k) {
        if ((mine >> k) & 1u) {
            s->pos[k] = lds[SLUICE_MAX_OUTPUTS + k];
            s->lim[k] = lds[2 * SLUICE_MAX_OUTPUTS + k];
        }
    }
    /* taken by every work-item in a write launch (no barrier under a
     * condition on the form); a stepping group's places come per step */
#ifdef SLUICE_GROUP_CHAIN_
    if (L->mode >= 2u)
#else
    if (L->mode == 2u)
#endif
        sluice_range_places_(s);
#else
    (void)s;
    (void)vars;
    (void)scratch;
    (void)L;
#endif
}

/* Runs between the passes and after the last one. */
SLUICE_INLINE_ void sluice_next_(sluice_state_ *s, global uint *vars, global uint *scratch,
                                 const sluice_launch_ *L)
{
    if (s->pass == 0 && s->group) {
        sluice_group_reserve_(s, vars, scratch, L);
    } else if (s->pass == 0) {
#ifndef SLUICE_GROUP_EMIT_
        if (L->mode == 3u)
            sluice_chain_(s, vars, scratch, L);
#endif
        SLUICE_EACH_OUTPUT_ (k) {
            if (!((L->out_mask >> k) & 1u))
                continue;
            int ordered = (L->ordered_mask >> k) & 1u;
            if (L->mode == 1) {
                if (ordered)
                    scratch[k * L->stride + s->chunk_id] = s->cnt[k];
            } else if (!ordered) {
                /* One global atomic per chunk and output. */
                s->pos[k] = sluice_reserve_(vars, L, k, s->cnt[k], &s->lim[k]);
            }
        }
    } else {
        SLUICE_EACH_COUNTER_ (c)
            if (c < L->n_counters && s->ctr[c])
                atomic_add(&vars[L->counter_var + c], s->ctr[c]);
        if (L->prof_var != SLUICE_NONE) {
            if (s->end > s->begin) {
                /* steps of blk records each, the last one cut at the end */
                uint steps = (s->end - s->begin + s->step - 1u) / s->step;
                uint last = s->begin + (steps - 1u) * s->step;
                atomic_add(&vars[L->prof_var], (steps - 1u) * s->blk + min(s->blk, s->end - last));
            }
            SLUICE_EACH_OUTPUT_ (k)
                if (s->cnt[k])
                    atomic_add(&vars[L->prof_var + 1 + k], s->cnt[k]);
        }
    }
    if (L->mode == 1)
        s->pass = 2u;
    else if (s->pass == 0u)
        sluice_enter_write_(s);
    else
        s->pass = 2u;
}

/* The hidden parameters every stream kernel takes first. The host numbers the
 * kernel's own parameters from 0, starting after these. */
#define SLUICE_PARAMS                                                                              \
    global uint *sluice_vars_, global uint *sluice_scratch_, const sluice_launch_ sluice_L_,       \
        local uint *sluice_lds_

/* The passes of a loop form: the state, then the loop over the passes,
 * whose body is the loop over the work-item's records. */
#define SLUICE_PASSES_(form, width)                                                                \
    sluice_state_ sluice_s_;                                                                       \
    sluice_begin_(&sluice_s_, sluice_vars_, sluice_scratch_, sluice_lds_, &sluice_L_, form,        \
                  width);                                                                          \
    for (; sluice_s_.pass != 2u;                                                                   \
         sluice_next_(&sluice_s_, sluice_vars_, sluice_scratch_, &sluice_L_))

/* The next record (or block) of the loop, from `id`. In group order the
 * group walks its tile in steps, each taken twice: a step's count, the
 * scan (sluice_step_places_), then the same records again to write them. */
SLUICE_INLINE_ uint sluice_advance_(sluice_state_ *s, uint id)
{
#ifdef SLUICE_GROUP_EMIT_
    if (s->pass == 3u) {
        sluice_step_places_(s);
        s->pass = 1u;
        return id;
    }
    if (s->pass == 1u && s->stepped) {
        uint next = id + s->step;
        next = next < id ? 0xffffffffu : next;
        if (next < s->uend) {
            SLUICE_EACH_OUTPUT_ (k)
                if ((s->omask >> k) & 1u)
                    s->pos[k] = s->cnt[k]; /* the next step counts from here */
            s->pass = 3u;
        }
        return next;
    }
#endif
    return id + s->step;
}

/* Loops over this work-item's records, with the record index in `id`, in
 * increasing order. The statement (usually a block) that follows is the
 * body. Code before it runs once per work-item; code after it must not emit
 * or count. The records need not be contiguous (on GPUs they are
 * interleaved; see sluice_begin_): a body that needs a contiguous range uses
 * SLUICE_FOR_EACH_RANGE. */
#ifdef SLUICE_GROUP_EMIT_
/* The interleaved layout's loops run to `uend`, the same number of steps
 * for every work-item of a group in group order, and skip what lies past
 * `end`. */
#define SLUICE_FOR_EACH(id)                                                                        \
    SLUICE_PASSES_(SLUICE_FORM_RECORD_, 1u)                                                        \
    for (uint id = sluice_s_.begin; id < sluice_s_.uend; id = sluice_advance_(&sluice_s_, id))     \
        if (id < sluice_s_.end)
#else
#define SLUICE_FOR_EACH(id)                                                                        \
    SLUICE_PASSES_(SLUICE_FORM_RECORD_, 1u)                                                        \
    for (uint id = sluice_s_.begin; id < sluice_s_.end; id += sluice_s_.step)
#endif

/* The range form of SLUICE_FOR_EACH, for bodies that handle records in
 * blocks (vector loads, SLUICE_EMIT16): the body runs once per pass with this
 * work-item's records [b, e) in the named variables and loops over them
 * itself. The rules above hold per record: both passes must emit the same
 * records. The per-record macros (SLUICE_EMIT_IF, SLUICE_COUNT) work inside
 * it too, e.g. for a tail of fewer than 16 records. */
#define SLUICE_FOR_EACH_RANGE(b, e)                                                                \
    SLUICE_PASSES_(SLUICE_FORM_RANGE_, 1u)                                                         \
    for (uint b = sluice_s_.begin, e = sluice_s_.end, sluice_once_ = 1u; sluice_once_;             \
         sluice_once_ = 0u)

/* The block form of SLUICE_FOR_EACH, for bodies that take a few records at a
 * time as one vector on GPUs: the body runs on blocks of consecutive
 * records [b, e) of this work-item, in increasing order. In the interleaved
 * layout (GPUs) a block holds SLUICE_BLOCK (4) records, fewer at the end of
 * the input, and the blocks of a work-group's work-items lie side by side,
 * so that their vector loads are coalesced; b is then a multiple of 4 when
 * the work-group size is (a block of 4-byte records starts on a 16-byte
 * boundary). Elsewhere the body runs once per pass on the whole chunk, as
 * in SLUICE_FOR_EACH_RANGE. A body loops over [b, e) itself and handles any
 * length; SLUICE_EMIT4 emits 4 records from a vector. The rules above hold
 * per record. */
#define SLUICE_FOR_EACH_BLOCK(b, e) SLUICE_FOR_EACH_BLOCK_OF(b, e, SLUICE_BLOCK)

/* SLUICE_FOR_EACH_BLOCK with blocks of W records in the interleaved layout,
 * W a multiple of 4 (a constant). Ordered outputs there are placed in group
 * order, which counts and scans each step of the work-group (a block a
 * work-item) across the group, so longer blocks scan less often; the body
 * then loops over the block's 4-record vectors. The library's compaction
 * and partition take 16 (bench/README.md, the H100). */
#define SLUICE_FOR_EACH_BLOCK_OF(b, e, W)                                                          \
    SLUICE_PASSES_(SLUICE_FORM_BLOCK_, (W))                                                        \
    for (uint b = sluice_s_.begin, e = min(b + sluice_s_.blk, sluice_s_.end); b < sluice_s_.uend;  \
         b = sluice_advance_(&sluice_s_, b), e = min(b + sluice_s_.blk, sluice_s_.end))            \
        if (b < sluice_s_.end)

/* True in the pass that writes (always true for kernels without conditional
 * outputs). Guard mapped writes with it to avoid doing them twice. */
#define SLUICE_WRITING (sluice_s_.pass == 1u)

/* In the count passes counts c records of output `slot` and returns 1: in
 * pass 0 every output's, in a step's count (pass 3, group order) only
 * those of the ordered outputs the group places. */
SLUICE_INLINE_ int sluice_counting_(sluice_state_ *s, uint slot, uint c)
{
#ifdef SLUICE_GROUP_EMIT_
    if (s->pass == 1u)
        return 0;
    if (s->pass == 0u || ((s->omask >> slot) & 1u))
        s->cnt[slot] += c;
    return 1;
#else /* no group order: passes 0 and 1 only */
    if (s->pass != 0u)
        return 0;
    s->cnt[slot] += c;
    return 1;
#endif
}

/* Reserves the next record of conditional output `slot` when `cond` is true
 * and evaluates to the index to write it at. Write the record there only
 * `if (SLUICE_WRITING)`; the index is always safe to write: when cond is
 * false, or in the count pass, it is a slot that a later record of the same
 * chunk overwrites or the stream's spare record past its capacity. Use this
 * for records written field by field. */
SLUICE_INLINE_ uint sluice_emit_index_(sluice_state_ *s, uint slot, uint c, uint cap)
{
    if (sluice_counting_(s, slot, c))
        return cap;
#ifdef SLUICE_GROUP_EMIT_
    if (s->group) {
        /* nothing written is a place another work-item's record may take,
         * so an unemitted record goes to the spare one */
        if (!c)
            return cap;
        if (!((s->omask >> slot) & 1u)) { /* the next place of the group's room */
            uint p = s->pos[slot] + atomic_inc(&s->lds[slot]);
            return p < s->lim[slot] ? p : cap;
        }
        /* group order: this work-item's own next place, as below */
    }
#endif
    uint p = s->pos[slot];
    s->pos[slot] = p + c;
    return p < s->lim[slot] ? p : cap;
}
#define SLUICE_EMIT_INDEX(slot, cond)                                                              \
    sluice_emit_index_(&sluice_s_, (slot), (cond) ? 1u : 0u, sluice_L_.out_cap[slot])

/* Emits `value` to conditional output `slot`, whose records are in `buf`,
 * when `cond` is true. Branch-free: when cond is false the value is written
 * to a slot that a later record of the same chunk overwrites (or to the
 * stream's spare record past its capacity), and the position does not move. */
#define SLUICE_EMIT_IF(slot, buf, value, cond)                                                     \
    do {                                                                                           \
        uint sluice_at_ = SLUICE_EMIT_INDEX(slot, cond);                                           \
        if (SLUICE_WRITING)                                                                        \
            (buf)[sluice_at_] = (value);                                                           \
    } while (0)

/* Emits `value` to conditional output `slot` unconditionally. A body may emit
 * several records per input (a bounded number) by emitting several times. */
#define SLUICE_EMIT(slot, buf, value) SLUICE_EMIT_IF(slot, buf, value, 1)

/* Emits the lanes of `x` (a uint4) whose bit is set in `m` (bits 0-3) to
 * conditional output `slot` (records of 32-bit words in `buf`), in lane
 * order, taking their places at once: in group emission one local atomic
 * for the 4 records instead of one each. */
SLUICE_INLINE_ void sluice_emit4_(sluice_state_ *s, uint slot, global uint *buf, uint4 x, uint m)
{
    m &= 15u;
    uint k = popcount(m);
    if (sluice_counting_(s, slot, k) || !k)
        return;
    uint p = s->pos[slot], lim = s->lim[slot];
#ifdef SLUICE_GROUP_EMIT_
    if (s->group && !((s->omask >> slot) & 1u))
        p += atomic_add(&s->lds[slot], k);
    else
#endif
        s->pos[slot] = p + k;
    if (m & 1u) {
        if (p < lim)
            buf[p] = x.s0;
        ++p;
    }
    if (m & 2u) {
        if (p < lim)
            buf[p] = x.s1;
        ++p;
    }
    if (m & 4u) {
        if (p < lim)
            buf[p] = x.s2;
        ++p;
    }
    if ((m & 8u) && p < lim)
        buf[p] = x.s3;
}
#define SLUICE_EMIT4(slot, buf, x, m) sluice_emit4_(&sluice_s_, (slot), (buf), (x), (m))

/* The 4-bit mask of an int4 comparison's true lanes (-1), for SLUICE_EMIT4. */
SLUICE_INLINE_ uint sluice_mask4(int4 c)
{
    return ((uint)c.s0 & 1u) | ((uint)c.s1 & 2u) | ((uint)c.s2 & 4u) | ((uint)c.s3 & 8u);
}

/* Block emission: 16 records at a time, selected by a 16-bit mask.
 *
 * On x86 CPUs with AVX-512 (PoCL compiles kernels with the host's features)
 * a block is written with the compress instruction: the selected lanes are
 * packed and stored as one 64-byte store, which is what brings conditional
 * output near the copy bandwidth (bench/README.md). With AVX2 but no
 * AVX-512 (AMD before Zen 4, most Intel client CPUs), each half of 8 lanes
 * is packed by one lane permutation (vpermd) whose indices come from a
 * 256-entry table, and stored as one 32-byte store. Elsewhere, or when the
 * host asks for portable kernels (SLUICE_NO_SIMD), the same macros write the
 * lanes one by one: the same result, but slower than the per-record macros,
 * so fast kernels test SLUICE_EMIT16_FAST (below) before taking blocks. All
 * three paths are tested on the same inputs (tests/meson.build:
 * runtime_portable, compact_portable, runtime_avx2, compact_avx2). */
#if !defined(SLUICE_NO_SIMD) && defined(__AVX512F__) && defined(__clang__) && defined(__has_builtin)
#if __has_builtin(__builtin_ia32_compresssi512_mask) &&                                            \
    __has_builtin(__builtin_ia32_compressstoresi512_mask) &&                                       \
    __has_builtin(__builtin_ia32_storedqusi512_mask) && __has_builtin(__builtin_ia32_cmpd512_mask)
#define SLUICE_AVX512_ 1
#endif
#endif

#if !defined(SLUICE_NO_SIMD) && !defined(SLUICE_AVX512_) && defined(__AVX2__) &&                   \
    defined(__clang__) && defined(__has_builtin)
#if __has_builtin(__builtin_ia32_permvarsi256) && __has_builtin(__builtin_ia32_movmskps256)
#define SLUICE_AVX2_ 1
#endif
#endif

/* 1 when SLUICE_EMIT16 compiles to compress or permute instructions, else 0.
 * The lane-by-lane fallback is correct but slower than the per-record
 * macros, so a kernel can take 16-record blocks only when this is 1:
 *     for (; SLUICE_EMIT16_FAST && i + 16u <= e; i += 16u) ...  */
#if defined(SLUICE_AVX512_) || defined(SLUICE_AVX2_)
#define SLUICE_EMIT16_FAST 1
#else
#define SLUICE_EMIT16_FAST 0
#endif

#ifdef SLUICE_AVX2_
/* Entry m: the positions of the set bits of the 8-bit mask m, in increasing
 * order, one per nibble from the lowest (nibble k holds the k-th set bit's
 * position; the nibbles past popcount(m) are 0). A vpermd with these indices
 * packs the selected lanes of 8 to the front. */
constant uint sluice_pack8_[256] = {
    0x00000000u, 0x00000000u, 0x00000001u, 0x00000010u, 0x00000002u, 0x00000020u, 0x00000021u,
    0x00000210u, 0x00000003u, 0x00000030u, 0x00000031u, 0x00000310u, 0x00000032u, 0x00000320u,
    0x00000321u, 0x00003210u, 0x00000004u, 0x00000040u, 0x00000041u, 0x00000410u, 0x00000042u,
    0x00000420u, 0x00000421u, 0x00004210u, 0x00000043u, 0x00000430u, 0x00000431u, 0x00004310u,
    0x00000432u, 0x00004320u, 0x00004321u, 0x00043210u, 0x00000005u, 0x00000050u, 0x00000051u,
    0x00000510u, 0x00000052u, 0x00000520u, 0x00000521u, 0x00005210u, 0x00000053u, 0x00000530u,
    0x00000531u, 0x00005310u, 0x00000532u, 0x00005320u, 0x00005321u, 0x00053210u, 0x00000054u,
    0x00000540u, 0x00000541u, 0x00005410u, 0x00000542u, 0x00005420u, 0x00005421u, 0x00054210u,
    0x00000543u, 0x00005430u, 0x00005431u, 0x00054310u, 0x00005432u, 0x00054320u, 0x00054321u,
    0x00543210u, 0x00000006u, 0x00000060u, 0x00000061u, 0x00000610u, 0x00000062u, 0x00000620u,
    0x00000621u, 0x00006210u, 0x00000063u, 0x00000630u, 0x00000631u, 0x00006310u, 0x00000632u,
    0x00006320u, 0x00006321u, 0x00063210u, 0x00000064u, 0x00000640u, 0x00000641u, 0x00006410u,
    0x00000642u, 0x00006420u, 0x00006421u, 0x00064210u, 0x00000643u, 0x00006430u, 0x00006431u,
    0x00064310u, 0x00006432u, 0x00064320u, 0x00064321u, 0x00643210u, 0x00000065u, 0x00000650u,
    0x00000651u, 0x00006510u, 0x00000652u, 0x00006520u, 0x00006521u, 0x00065210u, 0x00000653u,
    0x00006530u, 0x00006531u, 0x00065310u, 0x00006532u, 0x00065320u, 0x00065321u, 0x00653210u,
    0x00000654u, 0x00006540u, 0x00006541u, 0x00065410u, 0x00006542u, 0x00065420u, 0x00065421u,
    0x00654210u, 0x00006543u, 0x00065430u, 0x00065431u, 0x00654310u, 0x00065432u, 0x00654320u,
    0x00654321u, 0x06543210u, 0x00000007u, 0x00000070u, 0x00000071u, 0x00000710u, 0x00000072u,
    0x00000720u, 0x00000721u, 0x00007210u, 0x00000073u, 0x00000730u, 0x00000731u, 0x00007310u,
    0x00000732u, 0x00007320u, 0x00007321u, 0x00073210u, 0x00000074u, 0x00000740u, 0x00000741u,
    0x00007410u, 0x00000742u, 0x00007420u, 0x00007421u, 0x00074210u, 0x00000743u, 0x00007430u,
    0x00007431u, 0x00074310u, 0x00007432u, 0x00074320u, 0x00074321u, 0x00743210u, 0x00000075u,
    0x00000750u, 0x00000751u, 0x00007510u, 0x00000752u, 0x00007520u, 0x00007521u, 0x00075210u,
    0x00000753u, 0x00007530u, 0x00007531u, 0x00075310u, 0x00007532u, 0x00075320u, 0x00075321u,
    0x00753210u, 0x00000754u, 0x00007540u, 0x00007541u, 0x00075410u, 0x00007542u, 0x00075420u,
    0x00075421u, 0x00754210u, 0x00007543u, 0x00075430u, 0x00075431u, 0x00754310u, 0x00075432u,
    0x00754320u, 0x00754321u, 0x07543210u, 0x00000076u, 0x00000760u, 0x00000761u, 0x00007610u,
    0x00000762u, 0x00007620u, 0x00007621u, 0x00076210u, 0x00000763u, 0x00007630u, 0x00007631u,
    0x00076310u, 0x00007632u, 0x00076320u, 0x00076321u, 0x00763210u, 0x00000764u, 0x00007640u,
    0x00007641u, 0x00076410u, 0x00007642u, 0x00076420u, 0x00076421u, 0x00764210u, 0x00007643u,
    0x00076430u, 0x00076431u, 0x00764310u, 0x00076432u, 0x00764320u, 0x00764321u, 0x07643210u,
    0x00000765u, 0x00007650u, 0x00007651u, 0x00076510u, 0x00007652u, 0x00076520u, 0x00076521u,
    0x00765210u, 0x00007653u, 0x00076530u, 0x00076531u, 0x00765310u, 0x00076532u, 0x00765320u,
    0x00765321u, 0x07653210u, 0x00007654u, 0x00076540u, 0x00076541u, 0x00765410u, 0x00076542u,
    0x00765420u, 0x00765421u, 0x07654210u, 0x00076543u, 0x00765430u, 0x00765431u, 0x07654310u,
    0x00765432u, 0x07654320u, 0x07654321u, 0x76543210u,
};

typedef uint8 sluice_uint8_unaligned_ __attribute__((aligned(4)));

/* Packs the lanes of `x` selected by the 8-bit mask `m` to the front. */
SLUICE_INLINE_ uint8 sluice_pack8_lanes_(uint8 x, uint m)
{
    uint8 idx = ((uint8)sluice_pack8_[m] >> (uint8)(0u, 4u, 8u, 12u, 16u, 20u, 24u, 28u)) & 7u;
    return as_uint8(__builtin_ia32_permvarsi256(as_int8(x), as_int8(idx)));
}
#endif

/* No 16-wide vector crosses a call here, so the helpers below build without
 * warnings on every x86 CPU: passing or returning one by value (a 512-bit
 * vector) changes the calling convention when AVX-512 is missing, and clang
 * warns at every such call, ours and the OpenCL builtins' (vload16,
 * vstore16) alike, even in code that SLUICE_EMIT16_FAST leaves dead. So the
 * helpers are macros that hand the vector to a function by pointer, and
 * SLUICE_LOAD16 reads 16 words without vload16. Once inlined, the pointer is
 * gone: the AVX-512 path compiles to the same instructions. */

/* The 16 32-bit words at `p` (a global pointer to 4-byte words, aligned to 4
 * bytes), as a uint16: vload16(0, p) without its 16-wide return value (see
 * above). Apply as_int16 or as_float16 for other 32-bit types. */
typedef uint16 sluice_uint16_unaligned_ __attribute__((aligned(4)));
typedef float16 sluice_float16_unaligned_ __attribute__((aligned(4)));
#define SLUICE_LOAD16(p) (*(global const sluice_uint16_unaligned_ *)(p))

/* Lanes of two 16-lane vectors picked by constant indices (0-15 from a,
 * 16-31 from b), as OpenCL's shuffle2 but without a call (see above).
 * Sixteen named index parameters, not `...`: OpenCL C 1.2 has no variadic
 * macros, and NVIDIA's compiler refuses them. */
#if defined(__clang__)
#define SLUICE_SHUF16_(a, b, i0, i1, i2, i3, i4, i5, i6, i7, i8, i9, i10, i11, i12, i13, i14, i15) \
    __builtin_shufflevector((a), (b), i0, i1, i2, i3, i4, i5, i6, i7, i8, i9, i10, i11, i12, i13,  \
                            i14, i15)
#else
#define SLUICE_SHUF16_(a, b, i0, i1, i2, i3, i4, i5, i6, i7, i8, i9, i10, i11, i12, i13, i14, i15) \
    shuffle2((a), (b),                                                                             \
             (uint16)(i0, i1, i2, i3, i4, i5, i6, i7, i8, i9, i10, i11, i12, i13, i14, i15))
#endif

/* Lanewise operators for SLUICE_REDUCE16_, on scalars and vectors alike:
 * operators, not calls (see above). SLUICE_FMIN_ and SLUICE_FMAX_ follow
 * fmin and fmax: a NaN operand gives the other one (x != x only for NaN). */
#define SLUICE_ADD_(a, b) ((a) + (b))
#define SLUICE_MIN_(a, b) ((b) < (a) ? (b) : (a))
#define SLUICE_MAX_(a, b) ((b) > (a) ? (b) : (a))
#define SLUICE_FMIN_(a, b) ((((b) < (a)) | ((a) != (a))) ? (b) : (a))
#define SLUICE_FMAX_(a, b) ((((b) > (a)) | ((a) != (a))) ? (b) : (a))

/* Reduces records [begin, end) of `in` (a global T pointer; T a 32-bit
 * scalar, T16 its 16-lane vector) with OP (one of the operators above)
 * into `result`, a T. Sixteen records per step into two accumulators: on a
 * CPU that keeps the loads ahead of the adds (measured against four records
 * per step in bench/README.md, bench_streams). The records are combined in
 * a tree, not in input order. */
#define SLUICE_REDUCE16_(T, T16, in, begin, end, identity, OP, result)                             \
    do {                                                                                           \
        T16 a_ = (T16)(identity), b_ = a_;                                                         \
        uint i_ = (begin), e_ = (end);                                                             \
        for (; i_ + 32u <= e_; i_ += 32u) {                                                        \
            T16 x_ = *(global const sluice_##T16##_unaligned_ *)((in) + i_);                       \
            T16 y_ = *(global const sluice_##T16##_unaligned_ *)((in) + i_ + 16u);                 \
            a_ = OP(a_, x_);                                                                       \
            b_ = OP(b_, y_);                                                                       \
        }                                                                                          \
        a_ = OP(a_, b_);                                                                           \
        b_ = SLUICE_SHUF16_(a_, a_, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7);         \
        a_ = OP(a_, b_);                                                                           \
        b_ = SLUICE_SHUF16_(a_, a_, 4, 5, 6, 7, 0, 1, 2, 3, 4, 5, 6, 7, 0, 1, 2, 3);               \
        a_ = OP(a_, b_);                                                                           \
        b_ = SLUICE_SHUF16_(a_, a_, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1);               \
        a_ = OP(a_, b_);                                                                           \
        b_ = SLUICE_SHUF16_(a_, a_, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0);               \
        a_ = OP(a_, b_);                                                                           \
        T r_ = a_.s0;                                                                              \
        for (; i_ < e_; ++i_) {                                                                    \
            T x_ = (in)[i_];                                                                       \
            r_ = OP(r_, x_);                                                                       \
        }                                                                                          \
        (result) = r_;                                                                             \
    } while (0)

/* Reduces in[begin..end) (a global T array, T uint or float) with OP
 * (SLUICE_ADD_ ...) by one work-group, the group's work-items reading
 * neighbouring records, then the group combines its g values (g the group
 * size, a power of two) in a tree in `part` (local memory for g T). The
 * result is in part[0]. Every work-item of the group must reach it (it has
 * barriers). Where `begin` is a multiple of 4 (16 bytes), work-item l reads
 * the 4 records at begin + 4 l, begin + 4 (l + g), ... as one vector, two
 * vectors per step: a GPU keeps a load in flight per outstanding vector of
 * a work-item, and one 4-byte load per work-item at a time moved about half
 * an H100's bandwidth (bench/README.md). The rest go one record per
 * work-item. */
#define SLUICE_GROUP_REDUCE_(T, in, begin, end, identity, OP, part)                                \
    do {                                                                                           \
        uint l_ = (uint)get_local_id(0), g_ = (uint)get_local_size(0);                             \
        uint b_ = (begin), e_ = (end);                                                             \
        T r_ = (T)(identity);                                                                      \
        if ((b_ & 3u) == 0u) {                                                                     \
            T##4 a_ = (T##4)(identity), c_ = a_;                                                   \
            uint v_ = b_ + ((e_ - b_) & ~3u), i_ = b_ + 4u * l_;                                   \
            for (; i_ + 4u * g_ < v_; i_ += 8u * g_) {                                             \
                T##4 x_ = *(global const T##4 *)((in) + i_);                                       \
                T##4 y_ = *(global const T##4 *)((in) + i_ + 4u * g_);                             \
                a_ = OP(a_, x_);                                                                   \
                c_ = OP(c_, y_);                                                                   \
            }                                                                                      \
            if (i_ < v_)                                                                           \
                a_ = OP(a_, *(global const T##4 *)((in) + i_));                                    \
            a_ = OP(a_, c_);                                                                       \
            r_ = OP(OP(a_.s0, a_.s1), OP(a_.s2, a_.s3));                                           \
            b_ = v_;                                                                               \
        }                                                                                          \
        for (uint i_ = b_ + l_; i_ < e_; i_ += g_) {                                               \
            T x_ = (in)[i_];                                                                       \
            r_ = OP(r_, x_);                                                                       \
        }                                                                                          \
        (part)[l_] = r_;                                                                           \
        barrier(CLK_LOCAL_MEM_FENCE);                                                              \
        for (uint h_ = g_ / 2u; h_ > 0u; h_ /= 2u) {                                               \
            if (l_ < h_) {                                                                         \
                T p_ = (part)[l_], q_ = (part)[l_ + h_];                                           \
                (part)[l_] = OP(p_, q_);                                                           \
            }                                                                                      \
            barrier(CLK_LOCAL_MEM_FENCE);                                                          \
        }                                                                                          \
    } while (0)

/* Exclusive scan, in place, of a[0..m) (a global T array) by one work-group,
 * starting at `start` (evaluated by work-item 0 only); `part` is local
 * memory for g + 1 T (g the group size), and part[g] receives the end
 * (start plus the sum). Each work-item sums a contiguous share, work-item 0
 * scans the shares' sums, and each work-item scans its share from there.
 * Every work-item of the group must reach it (it has barriers). */
#define SLUICE_GROUP_SCAN_(T, a, m, start, part)                                                   \
    do {                                                                                           \
        uint l_ = (uint)get_local_id(0), g_ = (uint)get_local_size(0);                             \
        uint sh_ = ((m) + g_ - 1u) / g_, b_ = min(l_ * sh_, (m)), e_ = min(b_ + sh_, (m));         \
        T s_ = (T)(0);                                                                             \
        for (uint i_ = b_; i_ < e_; ++i_)                                                          \
            s_ += (a)[i_];                                                                         \
        (part)[l_] = s_;                                                                           \
        barrier(CLK_LOCAL_MEM_FENCE);                                                              \
        if (l_ == 0u) {                                                                            \
            T acc_ = (start);                                                                      \
            for (uint k_ = 0; k_ < g_; ++k_) {                                                     \
                T c_ = (part)[k_];                                                                 \
                (part)[k_] = acc_;                                                                 \
                acc_ += c_;                                                                        \
            }                                                                                      \
            (part)[g_] = acc_;                                                                     \
        }                                                                                          \
        barrier(CLK_LOCAL_MEM_FENCE);                                                              \
        s_ = (part)[l_];                                                                           \
        for (uint i_ = b_; i_ < e_; ++i_) {                                                        \
            T c_ = (a)[i_];                                                                        \
            (a)[i_] = s_;                                                                          \
            s_ += c_;                                                                              \
        }                                                                                          \
    } while (0)

/* The mask of the non-zero lanes of `c` (an int16; bit k for lane k), e.g. of
 * a vector comparison such as `x < (float16)t`. */
#define sluice_mask16(c) sluice_mask16_((private int16[1]){(c)})

SLUICE_INLINE_ ushort sluice_mask16_(const int16 *c)
{
#if defined(SLUICE_AVX512_)
    return __builtin_ia32_cmpd512_mask(*c, (int16)0, 4 /* not equal */, (ushort)0xffff);
#elif defined(SLUICE_AVX2_)
    /* A non-zero lane becomes -1 (sign bit set); vmovmskps gathers 8 signs. */
    int16 nz = *c != (int16)0;
    return (ushort)(__builtin_ia32_movmskps256(as_float8(nz.lo)) |
                    (__builtin_ia32_movmskps256(as_float8(nz.hi)) << 8));
#else
    /* Lane k keeps bit k where it is non-zero; OR the halves together. */
    int16 b = (*c != (int16)0) & (int16)(0x1, 0x2, 0x4, 0x8, 0x10, 0x20, 0x40, 0x80, 0x100, 0x200,
                                         0x400, 0x800, 0x1000, 0x2000, 0x4000, 0x8000);
    int8 h8 = b.lo | b.hi;
    int4 h4 = h8.lo | h8.hi;
    int2 h2 = h4.lo | h4.hi;
    return (ushort)(h2.x | h2.y);
#endif
}

/* The mask of the non-zero lanes of `c` (an int8; bit k for lane k). */
#define sluice_mask8(c) sluice_mask8_((private int8[1]){(c)})

SLUICE_INLINE_ uchar sluice_mask8_(const int8 *c)
{
#if defined(SLUICE_AVX512_) || defined(SLUICE_AVX2_)
    /* a non-zero lane becomes -1 (sign bit set); vmovmskps gathers 8 signs */
    return (uchar)__builtin_ia32_movmskps256(as_float8(*c != (int8)0));
#else
    int8 b = (*c != (int8)0) & (int8)(0x1, 0x2, 0x4, 0x8, 0x10, 0x20, 0x40, 0x80);
    int4 h4 = b.lo | b.hi;
    int2 h2 = h4.lo | h4.hi;
    return (uchar)(h2.x | h2.y);
#endif
}

/* Writes the lanes of *x selected by m to buf[p], buf[p + 1], ..., those at
 * or past lim dropped (an overflowing output). The copy keeps the
 * lane-by-lane reads off the caller's vector. */
SLUICE_INLINE_ void sluice_emit_lanes_(global uint *buf, const uint16 *x, ushort m, uint p,
                                       uint lim)
{
    uint16 lanes = *x;
    const uint *v = (const uint *)&lanes;
    for (uint l = 0; l < 16u; ++l) {
        if ((m >> l) & 1u) {
            if (p < lim)
                buf[p] = v[l];
            ++p;
        }
    }
}

SLUICE_INLINE_ void sluice_emit16_(sluice_state_ *s, uint slot, global uint *buf, const uint16 *x,
                                   ushort m)
{
    uint k = popcount((uint)m);
    if (sluice_counting_(s, slot, k))
        return;
    uint p = s->pos[slot], lim = s->lim[slot];
#ifdef SLUICE_GROUP_EMIT_
    if (s->group) {
        /* k places of the group's room (or in group order this work-item's
         * own), lane by lane: a block store would reach places that other
         * work-items' records take */
        if ((s->omask >> slot) & 1u)
            s->pos[slot] = p + k;
        else if (k)
            p += atomic_add(&s->lds[slot], k);
        if (k)
            sluice_emit_lanes_(buf, x, m, p, lim);
        return;
    }
#endif
    s->pos[slot] = p + k;
    if (!k)
        return; /* nothing to write: most blocks of a rarely chosen output */
#ifdef SLUICE_AVX512_
    /* The kernels run on the host CPU, where every address space is plain
     * memory: the builtins take a generic pointer, so the global pointer goes
     * through an integer. A full 16-lane store is safe while it stays inside
     * this chunk's reserved room: the lanes past the k records written are
     * overwritten by the chunk's next records. */
    if (p + 16u <= lim) {
        __builtin_ia32_storedqusi512_mask(
            (int *)(size_t)(buf + p),
            __builtin_ia32_compresssi512_mask(as_int16(*x), as_int16(*x), m), (ushort)0xffff);
        return;
    }
    if (p + k <= lim) {
        /* packed in a register, then k lanes stored under a mask: the
         * compress instruction's own store form is far slower on AMD's
         * Zen 4 (measured, bench/README.md) */
        __builtin_ia32_storedqusi512_mask(
            (int *)(size_t)(buf + p),
            __builtin_ia32_compresssi512_mask(as_int16(*x), as_int16(*x), m),
            (ushort)((1u << k) - 1u));
        return;
    }
#elif defined(SLUICE_AVX2_)
    /* Two full 8-lane stores, the second where the first's records end;
     * safe while both stay inside this chunk's reserved room (as above). */
    if (p + 16u <= lim) {
        uint m0 = m & 0xffu;
        global sluice_uint8_unaligned_ *q = (global sluice_uint8_unaligned_ *)(buf + p);
        *q = sluice_pack8_lanes_(x->lo, m0);
        q = (global sluice_uint8_unaligned_ *)(buf + p + popcount(m0));
        *q = sluice_pack8_lanes_(x->hi, (uint)m >> 8);
        return;
    }
#endif
    /* Near an overflowing output's capacity, or without AVX-512. */
    sluice_emit_lanes_(buf, x, m, p, lim);
}

/* Emits the lanes of `x` (a uint16; use as_uint16 for other 32-bit types)
 * whose bit is set in `mask` (a ushort) to conditional output `slot`, whose
 * records are 32-bit words in `buf`, in lane order. */
#define SLUICE_EMIT16(slot, buf, x, mask)                                                          \
    sluice_emit16_(&sluice_s_, (slot), (buf), (private uint16[1]){(x)}, (mask))

/* Adds `amount` (a uint) to counter `i` of the bound counter set. Aggregated
 * per work-item chunk: one global atomic per chunk and counter. */
#define SLUICE_COUNT(i, amount)                                                                    \
    do {                                                                                           \
        if (sluice_s_.pass == 1u)                                                                  \
            sluice_s_.ctr[i] += (uint)(amount);                                                    \
    } while (0)

/* The number of input records of this launch. */
#define SLUICE_LENGTH                                                                              \
    (sluice_L_.n_fixed != SLUICE_NONE                                                              \
         ? sluice_L_.n_fixed                                                                       \
         : sluice_stream_length_(sluice_vars_, sluice_L_.in_var, sluice_L_.in_cap))

/* In the write pass of a range (SLUICE_FOR_EACH_RANGE), the records from
 * this work-item's first to the first of the chunk that its thread (on a
 * CPU) most likely takes next: a kernel that asks for that chunk's first
 * lines while it writes keeps the memory bus busy (COMPACT_NEXT_ in
 * compact.cl). Its own length, or in a chained launch (sluice_chain_) the
 * distance to the chunk whose ticket it took; 0 when not known. */
#define SLUICE_AHEAD (sluice_s_.ahead)

/* Asks for the cache line holding global address `p` ahead of its use. A
 * hint: nothing happens where the
 * compiler has no prefetch. On CPUs the hardware prefetcher misses gathers
 * and scattered records: a kernel that reads record i + 16 while it works
 * on record i no longer waits on memory for it (the ray tracer's packets,
 * bench/README.md). OpenCL's own prefetch() is a no-op in PoCL; Clang's
 * builtin takes a flat pointer, which a CPU's global address is. */
#if defined(__has_builtin) && (defined(__x86_64__) || defined(__aarch64__))
#if __has_builtin(__builtin_prefetch)
#define SLUICE_PREFETCH(p) __builtin_prefetch((const void *)(ulong)(p), 0)
#endif
#endif
#ifndef SLUICE_PREFETCH
#define SLUICE_PREFETCH(p) ((void)0)
#endif

#endif /* SLUICE_CL_INCLUDED */
