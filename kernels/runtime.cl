/* Kernels the runtime itself queues. */
#include "sluice.cl"

/* Turns the per-chunk counts of one ordered output into write offsets:
 * counts[0..n) (at scratch + offset) becomes an exclusive scan that starts at
 * the output stream's current length, counts[n] receives the end, and the
 * length grows by the total. One work-group (`part` holds one uint per
 * work-item and one more): each work-item sums a contiguous share of the
 * counts, work-item 0 scans the sums, and each work-item scans its share
 * from its sum's offset. The host launches one work-item on a CPU (a few
 * thousand counts, far less work than the launch it serves) and a group of
 * them on a GPU. */
__kernel void sluice_scan_chunk_counts(global uint *vars, global uint *scratch, uint offset,
                                       uint var, uint n, local uint *part)
{
    uint l = (uint)get_local_id(0), g = (uint)get_local_size(0);
    if (get_group_id(0) != 0)
        return;
    global uint *counts = scratch + offset;
    uint share = (n + g - 1u) / g;
    uint b = min(l * share, n), e = min(b + share, n);
    if (vars[var] == SLUICE_VOID_) { /* a void output stays void: no room is given */
        for (uint i = b; i < e; ++i)
            counts[i] = 0u;
        if (l == 0u)
            counts[n] = 0u;
        return;
    }
    uint sum = 0u;
    for (uint i = b; i < e; ++i)
        sum += counts[i];
    part[l] = sum;
    barrier(CLK_LOCAL_MEM_FENCE);
    if (l == 0u) {
        uint acc = vars[var];
        for (uint k = 0; k < g; ++k) {
            uint c = part[k];
            part[k] = acc;
            acc += c;
        }
        part[g] = acc;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    sum = part[l];
    for (uint i = b; i < e; ++i) {
        uint c = counts[i];
        counts[i] = sum;
        sum += c;
    }
    if (l == 0u) {
        counts[n] = part[g];
        vars[var] = part[g];
    }
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
