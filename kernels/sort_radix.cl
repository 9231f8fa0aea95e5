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
    uint h[RADIX];
    for (uint d = 0; d < RADIX; ++d)
        h[d] = 0u;
    uint b, e;
    radix_chunk(n, chunks, c, &b, &e);
    for (uint i = b; i < e; ++i)
        h[(keys[i] >> shift) & 0xffu]++;
    global uint *t = table + offset;
    for (uint d = 0; d < RADIX; ++d)
        t[d * chunks + c] = h[d];
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
 * software write combining: each digit gathers WC records in a private buffer
 * (L1-resident) and writes them out together, so the output is written in
 * whole cache lines instead of one record at a time into RADIX (or 2 x RADIX
 * with values) scattered lines. On the 2-core Xeon this halved the scatter
 * time at 2^24 records. Order within a digit is kept: stable.
 *
 * A full buffer is written out when the digit's next record arrives, not
 * when its last record went in: the write-out reads the buffer with vector
 * loads, and right after the 16 single-word stores that filled it those
 * loads wait for the stores to reach the cache (no store forwarding from
 * several stores to one load): profiled and measured in bench/README.md
 * (bench_streams). */
#define WC 16u

/* Writes the WC buffered records of digit d (buffer buf) to out + pos[d]. */
#define RADIX_FLUSH_(out, buf, d, p)                                                               \
    do {                                                                                           \
        for (uint q_ = 0; q_ < WC; ++q_)                                                           \
            (out)[(p) + q_] = (buf)[(d)*WC + q_];                                                  \
    } while (0)

__kernel void radix_scatter_keys(global const uint *keys_in, global uint *keys_out, uint n,
                                 uint chunks, uint shift, global const uint *table, uint offset)
{
    uint c = (uint)get_global_id(0);
    if (c >= chunks)
        return;
    uint pos[RADIX], fill[RADIX];
    uint bk[RADIX * WC];
    global const uint *t = table + offset;
    for (uint d = 0; d < RADIX; ++d) {
        pos[d] = t[d * chunks + c];
        fill[d] = 0u;
    }
    uint b, e;
    radix_chunk(n, chunks, c, &b, &e);
    for (uint i = b; i < e; ++i) {
        uint k = keys_in[i];
        uint d = (k >> shift) & 0xffu;
        uint f = fill[d];
        if (f == WC) {
            RADIX_FLUSH_(keys_out, bk, d, pos[d]);
            pos[d] += WC;
            f = 0u;
        }
        bk[d * WC + f] = k;
        fill[d] = f + 1u;
    }
    for (uint d = 0; d < RADIX; ++d) {
        uint p = pos[d];
        for (uint q = 0; q < fill[d]; ++q)
            keys_out[p + q] = bk[d * WC + q];
    }
}

__kernel void radix_scatter_pairs(global const uint *keys_in, global const uint *vals_in,
                                  global uint *keys_out, global uint *vals_out, uint n, uint chunks,
                                  uint shift, global const uint *table, uint offset)
{
    uint c = (uint)get_global_id(0);
    if (c >= chunks)
        return;
    uint pos[RADIX], fill[RADIX];
    uint bk[RADIX * WC], bv[RADIX * WC];
    global const uint *t = table + offset;
    for (uint d = 0; d < RADIX; ++d) {
        pos[d] = t[d * chunks + c];
        fill[d] = 0u;
    }
    uint b, e;
    radix_chunk(n, chunks, c, &b, &e);
    for (uint i = b; i < e; ++i) {
        uint k = keys_in[i];
        uint d = (k >> shift) & 0xffu;
        uint f = fill[d];
        if (f == WC) {
            RADIX_FLUSH_(keys_out, bk, d, pos[d]);
            RADIX_FLUSH_(vals_out, bv, d, pos[d]);
            pos[d] += WC;
            f = 0u;
        }
        bk[d * WC + f] = k;
        bv[d * WC + f] = vals_in[i];
        fill[d] = f + 1u;
    }
    for (uint d = 0; d < RADIX; ++d) {
        uint p = pos[d];
        for (uint q = 0; q < fill[d]; ++q) {
            keys_out[p + q] = bk[d * WC + q];
            vals_out[p + q] = bv[d * WC + q];
        }
    }
}
