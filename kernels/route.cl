/* Bounded routing, the stencil-routing primitive of Purcell (thesis 6.2.2):
 * Purcell routes each photon to its grid cell in one pass, and the stencil
 * buffer admits at most `slots` photons per cell, one stencil value per
 * place. Here a per-bucket atomic counter plays the stencil: the counter's
 * old value is the record's place, and places >= slots are overflow. */

/* counts[] (the fill stream, zeroed by the host) counts every record sent to
 * a bucket, stored or not. */
__kernel void route_scatter(global const uint *keys, global const uint *vals, uint n,
                            uint bucket_count, uint slots, global uint *counts, global uint *out)
{
    uint i = (uint)get_global_id(0);
    if (i >= n)
        return;
    uint b = keys[i];
    if (b >= bucket_count)
        return; /* dropped */
    uint place = atomic_inc(&counts[b]);
    if (place < slots)
        out[(size_t)b * slots + place] = vals[i];
}

/* Splits each bucket's count into fill (stored) and overflow (not stored). */
__kernel void route_finish(global uint *fill, global uint *overflow, uint bucket_count, uint slots)
{
    uint b = (uint)get_global_id(0);
    if (b >= bucket_count)
        return;
    uint c = fill[b], f = min(c, slots);
    fill[b] = f;
    overflow[b] = c - f;
}
