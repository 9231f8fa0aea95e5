/* Stable LSD radix sort of uint32 keys (optionally carrying uint32 values),
 * 8-bit digits, four passes at most (streams/sort_radix.c drives it).
 *
 * Tuned for CPU devices: the input is cut into a few large contiguous chunks
 * and one work-item (work-group of one) walks a whole chunk serially, so the
 * inner loops are the same tight loops as a single-threaded C radix sort and
 * the cores share the chunks. Per pass: a per-chunk histogram of the digit,
 * an exclusive scan of the chunk x digit table in digit-major order, and a
 * per-chunk scatter in input order. Chunk c's records of digit d land after
 * all records of smaller digits and after digit d's records of chunks < c, so
 * the sort is stable. */

#include "sluice.cl"

#define RADIX 256u

/* Records [*b, *e) of chunk c when n records are cut into `chunks` chunks. */
inline void radix_chunk(uint n, uint chunks, uint c, uint *b, uint *e)
{
    ulong size = ((ulong)n + chunks - 1u) / chunks;
    *b = (uint)min((ulong)c * size, (ulong)n);
    *e = (uint)min((ulong)(c + 1u) * size, (ulong)n);
}

/* First pass: each chunk counts all four digits in one read of its keys. The
 * table holds four digit-major tables of RADIX x chunks counts:
 * table[(p * RADIX + d) * chunks + c]. The host sums them to find passes in
 * which every key has the same digit (those are skipped), and the first pass
 * that runs uses its table directly, since no key has moved yet. */
__kernel void radix_hist_all(global const uint *keys, uint n, uint chunks, global uint *table)
{
    uint c = (uint)get_global_id(0);
    if (c >= chunks)
        return;
    uint h0[RADIX], h1[RADIX], h2[RADIX], h3[RADIX];
    for (uint d = 0; d < RADIX; ++d) {
        h0[d] = 0u;
        h1[d] = 0u;
        h2[d] = 0u;
        h3[d] = 0u;
    }
    uint b, e;
    radix_chunk(n, chunks, c, &b, &e);
    for (uint i = b; i < e; ++i) {
        uint k = keys[i];
        h0[k & 0xffu]++;
        h1[(k >> 8) & 0xffu]++;
        h2[(k >> 16) & 0xffu]++;
        h3[k >> 24]++;
    }
    for (uint d = 0; d < RADIX; ++d) {
        table[(0u * RADIX + d) * chunks + c] = h0[d];
        table[(1u * RADIX + d) * chunks + c] = h1[d];
        table[(2u * RADIX + d) * chunks + c] = h2[d];
        table[(3u * RADIX + d) * chunks + c] = h3[d];
    }
}

/* Later passes: the histogram of one digit of the (already permuted) keys,
 * into the digit-major table at table + offset. */
__kernel void radix_hist(global const uint *keys, uint n, uint chunks, uint shift,
                         global uint *table, uint offset)
{
    uint c = (uint)get_global_id(0);
    if (c >= chunks)
        return;
    uint h[RADIX], h2[RADIX];
    for (uint d = 0; d < RADIX; ++d)
        h[d] = h2[d] = 0u;
    uint b, e;
    radix_chunk(n, chunks, c, &b, &e);
    /* Four keys a step, alternate ones counted in a second table so that
     * neighbouring keys with one digit do not wait on each other's count
     * (measured in bench/README.md). */
    uint i = b;
    for (; i + 4u <= e; i += 4u) {
        uint4 k = vload4(0, keys + i) >> shift;
        h[k.x & 0xffu]++;
        h2[k.y & 0xffu]++;
        h[k.z & 0xffu]++;
        h2[k.w & 0xffu]++;
    }
    for (; i < e; ++i)
        h[(keys[i] >> shift) & 0xffu]++;
    global uint *t = table + offset;
    for (uint d = 0; d < RADIX; ++d)
        t[d * chunks + c] = h[d] + h2[d];
}

/* Exclusive scan, in place, of the RADIX x chunks table at table + offset
 * (digit-major, so the result is each chunk's first output position for each
 * digit). One work-item: the table is a few thousand entries. */
__kernel void radix_scan(global uint *table, uint offset, uint count)
{
    if (get_global_id(0) != 0)
        return;
    global uint *t = table + offset;
    uint sum = 0u;
    for (uint i = 0; i < count; ++i) {
        uint x = t[i];
        t[i] = sum;
        sum += x;
    }
}

/* Scatter of one chunk, in input order, to the scanned positions, with
 * software write combining: each digit gathers WC records (64 bytes) in a
 * private buffer (L1-resident) and writes them out together, so the output
 * is written in whole cache lines instead of one record at a time into
 * RADIX (or 2 x RADIX with values) scattered lines. Order within a digit is
 * kept: stable. Two ways, by output size (the host's `nt`, measured in
 * bench/README.md):
 *
 * - Smaller outputs (radix_scatter_groups): a digit's buffer goes out when
 *   it holds WC records, wherever they land.
 * - Outputs too large to stay in the cache (radix_scatter_lines): a digit's
 *   buffer follows the output's own lines (a record's slot is its place mod
 *   WC), and every line the chunk fills alone goes out as one aligned
 *   64-byte non-temporal store: no read for ownership of a line that is
 *   about to be overwritten, no cache evictions. The first and last line of
 *   a digit, which the chunks before and after share, are written record by
 *   record.
 *
 * Either way a full buffer is written out when the digit's next record
 * arrives, not when its last record went in: the write-out reads the buffer
 * with vector loads, and right after the 16 single-word stores that filled
 * it those loads wait for the stores to reach the cache (no store
 * forwarding from several stores to one load): profiled and measured in
 * bench/README.md (bench_streams). */
#define WC 16u

/* Clang's non-temporal store (PoCL, and most OpenCL compilers); a plain
 * store where a compiler does not have it. */
#if defined(__has_builtin)
#if __has_builtin(__builtin_nontemporal_store)
#define RADIX_NT_STORE_(v, p) __builtin_nontemporal_store((v), (p))
#endif
#endif
#ifndef RADIX_NT_STORE_
#define RADIX_NT_STORE_(v, p) (*(p) = (v))
#endif
/* Non-temporal stores are weakly ordered on x86: a store fence makes them
 * visible before the work-item ends (and so before the next launch reads
 * them) whatever the runtime's own synchronisation orders. */
#if defined(__has_builtin) && (defined(__x86_64__) || defined(__i386__))
#if __has_builtin(__builtin_ia32_sfence)
#define RADIX_NT_FENCE_() __builtin_ia32_sfence()
#endif
#endif
#ifndef RADIX_NT_FENCE_
#define RADIX_NT_FENCE_() mem_fence(CLK_GLOBAL_MEM_FENCE)
#endif

__attribute__((always_inline)) inline void
radix_scatter_groups(global const uint *keys_in, global const uint *vals_in, global uint *keys_out,
                     global uint *vals_out, uint has_values, uint b, uint e, uint shift, uint *pos,
                     uint *bk, uint *bv)
{
    uint fill[RADIX];
    for (uint d = 0; d < RADIX; ++d)
        fill[d] = 0u;
    for (uint i = b; i < e; ++i) {
        uint k = keys_in[i];
        uint d = (k >> shift) & 0xffu;
        uint f = fill[d];
        if (f == WC) {
            for (uint q = 0; q < WC; ++q)
                keys_out[pos[d] + q] = bk[d * WC + q];
            if (has_values)
                for (uint q = 0; q < WC; ++q)
                    vals_out[pos[d] + q] = bv[d * WC + q];
            pos[d] += WC;
            f = 0u;
        }
        bk[d * WC + f] = k;
        if (has_values)
            bv[d * WC + f] = vals_in[i];
        fill[d] = f + 1u;
    }
    for (uint d = 0; d < RADIX; ++d)
        for (uint q = 0; q < fill[d]; ++q) {
            keys_out[pos[d] + q] = bk[d * WC + q];
            if (has_values)
                vals_out[pos[d] + q] = bv[d * WC + q];
        }
}

/* Writes out the line of WC records at out + line from buffer buf: the whole
 * line, non-temporal, when it holds no record before `first` (the chunk's
 * first place for the digit), else its records from `first` on. */
__attribute__((always_inline)) inline void radix_line_out(global uint *out, const uint *buf,
                                                          uint line, uint first)
{
    if (line >= first) {
        global uint8 *o = (global uint8 *)(out + line);
        const uint8 *v = (const uint8 *)buf; /* 32-byte aligned: see the buffers */
        RADIX_NT_STORE_(v[0], o);
        RADIX_NT_STORE_(v[1], o + 1);
    } else {
        for (uint q = first - line; q < WC; ++q)
            out[line + q] = buf[q];
    }
}

/* Needs 64-byte aligned outputs (see radix_scatter_chunk). */
__attribute__((always_inline)) inline void
radix_scatter_lines(global const uint *keys_in, global const uint *vals_in, global uint *keys_out,
                    global uint *vals_out, uint has_values, uint b, uint e, uint shift, uint *pos,
                    uint *bk, uint *bv)
{
    uint first[RADIX];
    for (uint d = 0; d < RADIX; ++d)
        first[d] = pos[d];
    for (uint i = b; i < e; ++i) {
        uint k = keys_in[i];
        uint d = (k >> shift) & 0xffu;
        uint p = pos[d], s = p & (WC - 1u);
        if (s == 0u && p != first[d]) { /* the line before p is complete */
            radix_line_out(keys_out, bk + d * WC, p - WC, first[d]);
            if (has_values)
                radix_line_out(vals_out, bv + d * WC, p - WC, first[d]);
        }
        bk[d * WC + s] = k;
        if (has_values)
            bv[d * WC + s] = vals_in[i];
        pos[d] = p + 1u;
    }
    for (uint d = 0; d < RADIX; ++d) /* the last line of each digit */
        for (uint q = max((pos[d] - 1u) & ~(WC - 1u), first[d]); q < pos[d]; ++q) {
            keys_out[q] = bk[d * WC + (q & (WC - 1u))];
            if (has_values)
                vals_out[q] = bv[d * WC + (q & (WC - 1u))];
        }
    RADIX_NT_FENCE_();
}

/* The scatter of chunk c, for keys alone or (has_values, a constant after
 * inlining) for keys and values. */
__attribute__((always_inline)) inline void
radix_scatter_chunk(global const uint *keys_in, global const uint *vals_in, global uint *keys_out,
                    global uint *vals_out, uint has_values, uint n, uint chunks, uint c, uint shift,
                    global const uint *t, uint nt)
{
    uint pos[RADIX];
    /* Aligned so that each digit's line is too (radix_line_out). */
    uint bk[RADIX * WC] __attribute__((aligned(64)));
    uint bv[RADIX * WC] __attribute__((aligned(64)));
    for (uint d = 0; d < RADIX; ++d)
        pos[d] = t[d * chunks + c];
    uint b, e;
    radix_chunk(n, chunks, c, &b, &e);
    /* Whole-line stores need 64-byte aligned outputs (OpenCL buffers are
     * aligned to CL_DEVICE_MEM_BASE_ADDR_ALIGN, 128 bytes on PoCL). */
    if (nt && (((ulong)keys_out | (ulong)vals_out) & 63u) == 0u)
        radix_scatter_lines(keys_in, vals_in, keys_out, vals_out, has_values, b, e, shift, pos, bk,
                            bv);
    else
        radix_scatter_groups(keys_in, vals_in, keys_out, vals_out, has_values, b, e, shift, pos, bk,
                             bv);
}

__kernel void radix_scatter_keys(global const uint *keys_in, global uint *keys_out, uint n,
                                 uint chunks, uint shift, global const uint *table, uint offset,
                                 uint nt)
{
    uint c = (uint)get_global_id(0);
    if (c < chunks)
        radix_scatter_chunk(keys_in, keys_in, keys_out, keys_out, 0u, n, chunks, c, shift,
                            table + offset, nt);
}

__kernel void radix_scatter_pairs(global const uint *keys_in, global const uint *vals_in,
                                  global uint *keys_out, global uint *vals_out, uint n, uint chunks,
                                  uint shift, global const uint *table, uint offset, uint nt)
{
    uint c = (uint)get_global_id(0);
    if (c < chunks)
        radix_scatter_chunk(keys_in, vals_in, keys_out, vals_out, 1u, n, chunks, c, shift,
                            table + offset, nt);
}

/* ------------------------------------------------------------------ */
/* The GPU layout (the runtime's interleaved layout, SLUICE_LAYOUT):   */
/* work-groups of G work-items (a power of two, at most 256) on tiles  */
/* of RG_ROUNDS x G keys, 4-bit digits                                 */
/* ------------------------------------------------------------------ */

/* Same stable LSD sort, laid out for GPUs: a work-group takes each tile and
 * its work-items read neighbouring keys (coalesced), G keys per round. Per
 * pass: a per-tile histogram in local memory (16 digits), an exclusive scan
 * of the digit-major table of digits x tiles by one work-group, and a
 * per-tile scatter in which each key's place among the keys of its digit in
 * its round is counted over the work-items before it, so the sort stays
 * stable. Digits of 4 bits keep the local tables small: eight passes at
 * most, and the passes in which every key has the same digit are skipped. */
#define RG_BINS 16u
#define RG_PASSES 8u

/* The keys [*b, *e) of this work-group's tile. */
inline void rg_tile(uint n, uint tile, uint *b, uint *e)
{
    ulong s = (ulong)get_group_id(0) * tile;
    *b = (uint)min(s, (ulong)n);
    *e = (uint)min(s + tile, (ulong)n);
}

/* totals[p * RG_BINS + d] += keys whose digit p (bits 4p .. 4p + 3) is d. */
__kernel void radix_wg_hist_all(global const uint *keys, uint n, uint tile, global uint *totals)
{
    local uint h[RG_PASSES * RG_BINS];
    uint l = (uint)get_local_id(0), g = (uint)get_local_size(0), b, e;
    for (uint i = l; i < RG_PASSES * RG_BINS; i += g)
        h[i] = 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    rg_tile(n, tile, &b, &e);
    for (uint i = b + l; i < e; i += g) {
        uint k = keys[i];
        for (uint p = 0; p < RG_PASSES; ++p)
            atomic_inc(&h[p * RG_BINS + ((k >> (4u * p)) & 15u)]);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint i = l; i < RG_PASSES * RG_BINS; i += g)
        if (h[i])
            atomic_add(&totals[i], h[i]);
}

/* table[d * tiles + tile] = this tile's keys of digit d (at `shift`). */
__kernel void radix_wg_hist(global const uint *keys, uint n, uint tile, uint shift,
                            global uint *table, uint tiles)
{
    local uint h[RG_BINS];
    uint l = (uint)get_local_id(0), g = (uint)get_local_size(0), b, e;
    if (l < RG_BINS)
        h[l] = 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    rg_tile(n, tile, &b, &e);
    for (uint i = b + l; i < e; i += g)
        atomic_inc(&h[(keys[i] >> shift) & 15u]);
    barrier(CLK_LOCAL_MEM_FENCE);
    if (l < RG_BINS)
        table[l * tiles + get_group_id(0)] = h[l];
}

/* Exclusive scan of the table in place, by one work-group. */
__kernel void radix_wg_scan(global uint *table, uint count, local uint *part)
{
    if (get_group_id(0) != 0)
        return;
    SLUICE_GROUP_SCAN_(uint, table, count, 0u, part);
}

/* The tile's keys (and values, when has_values) to their places: the
 * scanned table gives each digit's first place for the tile; each round of G
 * keys, a key goes after the keys of its digit in earlier rounds and after
 * those of the work-items before it in its round. */
__kernel void radix_wg_scatter(global const uint *keys_in, global const uint *vals_in,
                               global uint *keys_out, global uint *vals_out, uint has_values,
                               uint n, uint tile, uint shift, global const uint *table, uint tiles)
{
    local uint base[RG_BINS], count[RG_BINS], digs[256];
    uint l = (uint)get_local_id(0), g = (uint)get_local_size(0), b, e;
    if (l < RG_BINS)
        base[l] = table[l * tiles + get_group_id(0)];
    rg_tile(n, tile, &b, &e);
    for (uint r = b; r < e; r += g) {
        uint i = r + l, valid = i < e;
        uint k = valid ? keys_in[i] : 0u, d = valid ? (k >> shift) & 15u : RG_BINS;
        digs[l] = d;
        if (l < RG_BINS)
            count[l] = 0u;
        barrier(CLK_LOCAL_MEM_FENCE);
        uint rank = 0u;
        for (uint j = 0; j < l; ++j)
            rank += digs[j] == d;
        if (valid)
            atomic_inc(&count[d]);
        barrier(CLK_LOCAL_MEM_FENCE);
        if (valid) {
            uint at = base[d] + rank;
            keys_out[at] = k;
            if (has_values)
                vals_out[at] = vals_in[i];
        }
        barrier(CLK_LOCAL_MEM_FENCE);
        if (l < RG_BINS)
            base[l] += count[l];
    }
}
