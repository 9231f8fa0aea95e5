/* Kernels the runtime itself queues. */
#include "sluice.cl"

/* Turns the per-chunk counts of one ordered output into write offsets:
 * counts[0..n) (at scratch + offset) becomes an exclusive scan that starts at the output stream's
 * current length, counts[n] receives the end, and the length grows by the
 * total. One work-item: n is the number of chunks of one launch (a few
 * thousand at most), far less work than the launch it serves. */
__kernel void sluice_scan_chunk_counts(global uint *vars, global uint *scratch, uint offset,
                                       uint var, uint n)
{
    if (get_global_id(0) != 0)
        return;
    global uint *counts = scratch + offset;
    uint sum = vars[var];
    if (sum == SLUICE_VOID_) { /* a void output stays void: no room is given */
        for (uint i = 0; i <= n; ++i)
            counts[i] = 0u;
        return;
    }
    for (uint i = 0; i < n; ++i) {
        uint c = counts[i];
        counts[i] = sum;
        sum += c;
    }
    counts[n] = sum;
    vars[var] = sum;
}

/* The length of a mapped output (variable `dst`) becomes the input's
 * (variable `src`, capacity `cap`), or void when the input overflowed. */
__kernel void sluice_map_length(global uint *vars, uint src, uint cap, uint dst)
{
    if (get_global_id(0) != 0)
        return;
    if (vars[src] <= cap)
        vars[dst] = vars[src];
    else
        sluice_void_(vars, dst, src);
}
