/* Bitonic merge sort of uint32 keys (optionally carrying uint32 values), for
 * any length n (streams/sort_bitonic.c drives it). This is the sort Purcell
 * uses to order photons by grid cell (thesis 6.2.2), run here as one launch
 * per merge step instead of one rendering pass per step.
 *
 * The network sorts P = next power of two >= n positions, all in ascending
 * direction: the first step of each merge of size k compares i with its
 * mirror image in the block (k - 1 - i), the later steps compare i with
 * i + j. Every comparator (i, p) has i < p and leaves the smaller key at i.
 * Positions >= n are taken to hold +infinity: a comparator with p >= n would
 * never swap, so it is skipped and no padding memory is needed (the padding
 * never moves, because every real key is smaller than it). */

/* Comparator t of step (k, j): the pair (*i, *p), i < p. j == k / 2 is the
 * mirrored first step of a merge. k and j are powers of two. */
inline void bitonic_pair(uint t, uint k, uint j, uint *i, uint *p)
{
    /* t / j by a shift: j is a power of two, and a division per
     * comparator slowed the local steps on a CPU (measured,
     * bench/README.md) */
    uint block = t >> (31u - clz(j));
    uint off = t & (j - 1u);
    if (j == k >> 1) {
        *i = block * k + off;
        *p = block * k + k - 1u - off;
    } else {
        *i = block * (j << 1) + off;
        *p = *i + j;
    }
}

/* One step in global memory: one work-item per comparator. */
__kernel void bitonic_step(global uint *keys, global uint *vals, uint has_vals, uint n, uint k,
                           uint j)
{
    uint i, p;
    bitonic_pair((uint)get_global_id(0), k, j, &i, &p);
    if (p >= n)
        return;
    uint a = keys[i], b = keys[p];
    if (b < a) {
        keys[i] = b;
        keys[p] = a;
        if (has_vals) {
            uint v = vals[i];
            vals[i] = vals[p];
            vals[p] = v;
        }
    }
}

/* The steps whose pairs fall inside one block of 2 * W positions (W = the
 * work-group size), in local memory: merges of sizes k_lo .. k_hi, each from
 * its stride min(k / 2, W) down to 1. With k_lo = 2 and k_hi = 2W this sorts
 * every block; with k_lo = k_hi = K > 2W it finishes the merge of size K
 * after the global steps with strides >= 2W. */
__kernel void bitonic_local(global uint *keys, global uint *vals, uint has_vals, uint n, uint k_lo,
                            uint k_hi, local uint *lk, local uint *lv)
{
    uint w = (uint)get_local_size(0), lid = (uint)get_local_id(0);
    uint base = (uint)get_group_id(0) * 2u * w;
    for (uint r = lid; r < 2u * w; r += w) {
        if (base + r < n) {
            lk[r] = keys[base + r];
            if (has_vals)
                lv[r] = vals[base + r];
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint k = k_lo; k <= k_hi; k <<= 1) {
        for (uint j = min(k >> 1, w); j > 0u; j >>= 1) {
            uint i, p;
            bitonic_pair(lid, k, j, &i, &p);
            if (base + p < n) {
                /* without a branch, so that a CPU's work-group loop is
                 * vectorised: the same swaps */
                uint a = lk[i], b = lk[p];
                uint sw = b < a;
                lk[i] = sw ? b : a;
                lk[p] = sw ? a : b;
                if (has_vals) {
                    uint va = lv[i], vb = lv[p];
                    lv[i] = sw ? vb : va;
                    lv[p] = sw ? va : vb;
                }
            }
            barrier(CLK_LOCAL_MEM_FENCE);
        }
    }
    for (uint r = lid; r < 2u * w; r += w) {
        if (base + r < n) {
            keys[base + r] = lk[r];
            if (has_vals)
                vals[base + r] = lv[r];
        }
    }
}
