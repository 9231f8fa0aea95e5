/* Kernels the runtime itself queues. */
#include "sluice.cl"

/* Turns the per-chunk counts of one ordered output into write offsets:
 * counts[0..n) (at scratch + offset) becomes an exclusive scan that starts at
 * the output stream's current length, counts[n] receives the end, and the
 * length grows by the total. One work-group (SLUICE_GROUP_SCAN_; `part`
 * holds one uint per work-item and one more). The host launches one
 * work-item on a CPU (a few thousand counts, far less work than the launch
 * it serves) and a group of them on a GPU. */
__kernel void sluice_scan_chunk_counts(global uint *vars, global uint *scratch, uint offset,
                                       uint var, uint n, local uint *part)
{
    if (get_group_id(0) != 0)
        return;
    global uint *counts = scratch + offset;
    uint l = (uint)get_local_id(0), g = (uint)get_local_size(0);
    if (vars[var] == SLUICE_VOID_) { /* a void output stays void: no room is given */
        for (uint i = l; i <= n; i += g)
            counts[i] = 0u;
        return;
    }
    SLUICE_GROUP_SCAN_(uint, counts, n, vars[var], part);
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
