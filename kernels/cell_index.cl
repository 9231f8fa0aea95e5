/* Cell-start index of keys (Purcell, thesis 6.2.2): start[c] is the first
 * position of sorted keys whose key is >= c, for c in 0 .. cell_count.
 * streams/cell_index.c builds it either by binary search over sorted keys
 * (Purcell's method) or by counting and scanning. */

/* One work-item per cell: the lower bound of c in the sorted keys. Purcell
 * runs this search as a fragment program over the grid; here it is the same
 * search per work-item, log2(n) reads each. */
__kernel void cell_search(global const uint *keys, uint n, uint cells_plus_one, global uint *start)
{
    uint c = (uint)get_global_id(0);
    if (c >= cells_plus_one)
        return;
    uint lo = 0u, hi = n;
    while (lo < hi) {
        uint mid = lo + (hi - lo) / 2u;
        if (keys[mid] < c)
            lo = mid + 1u;
        else
            hi = mid;
    }
    start[c] = lo;
}

/* Histogram of the keys below cell_count into counts[0 .. cell_count)
 * (zeroed by the host). One global atomic per key: the cells are too many to
 * keep private copies per work-item, and the keys need not be sorted. */
__kernel void cell_hist(global const uint *keys, uint n, uint cell_count, global uint *counts)
{
    uint i = (uint)get_global_id(0);
    if (i >= n)
        return;
    uint k = keys[i];
    if (k < cell_count)
        atomic_inc(&counts[k]);
}

/* In-place exclusive scan of data[0 .. len) in three launches, shaped for a
 * CPU: `blocks` contiguous blocks, one work-item each, walked serially.
 * 1: each block's sum into sums[block]. */
inline void cell_block(uint len, uint blocks, uint b, uint *lo, uint *hi)
{
    ulong size = ((ulong)len + blocks - 1u) / blocks;
    *lo = (uint)min((ulong)b * size, (ulong)len);
    *hi = (uint)min((ulong)(b + 1u) * size, (ulong)len);
}

__kernel void cell_scan_sums(global const uint *data, uint len, uint blocks, global uint *sums)
{
    uint b = (uint)get_global_id(0);
    if (b >= blocks)
        return;
    uint lo, hi, s = 0u;
    cell_block(len, blocks, b, &lo, &hi);
    for (uint i = lo; i < hi; ++i)
        s += data[i];
    sums[b] = s;
}

/* 2: exclusive scan of the block sums (one work-item; a few hundred). */
__kernel void cell_scan_offsets(global uint *sums, uint blocks)
{
    if (get_global_id(0) != 0)
        return;
    uint s = 0u;
    for (uint b = 0; b < blocks; ++b) {
        uint x = sums[b];
        sums[b] = s;
        s += x;
    }
}

/* 3: each block scans itself, starting from its offset. */
__kernel void cell_scan_apply(global uint *data, uint len, uint blocks, global const uint *sums)
{
    uint b = (uint)get_global_id(0);
    if (b >= blocks)
        return;
    uint lo, hi, s = sums[b];
    cell_block(len, blocks, b, &lo, &hi);
    for (uint i = lo; i < hi; ++i) {
        uint x = data[i];
        data[i] = s;
        s += x;
    }
}
