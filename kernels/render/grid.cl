/* The uniform grid build on the device (apps/render/grid_device.c; Purcell
 * 3.2 and 5.2.1). sr_program_create prepends tri_box.h, which holds the
 * overlap test shared with the C build: the two builds make the same
 * decisions bit for bit.
 *
 * Two passes over the triangles, one work-item per chunk of triangles (the
 * runtime's SLUICE_FOR_EACH, launched over a count): rt_grid_count counts
 * the voxels each triangle overlaps, the host scans the counts into offsets,
 * and rt_grid_write writes the (voxel, triangle) pairs at those offsets, in
 * the order of the triangles. Writing at scanned offsets instead of emitting
 * to an ordered conditional output keeps the pair count known on the host
 * before the pair streams are allocated, so an oversized grid fails cleanly,
 * and it is faster: an ordered output runs the whole body (every overlap
 * test) twice, where rt_grid_write repeats the tests only for triangles
 * that overlap more than one voxel (measured on the million-triangle scene:
 * 230 ms for the emitting kernel, 160 ms for count and write). */
#include "sluice.cl"

/* Gathers triangle t into `tri`. Returns 0 (and leaves tri invalid) when an
 * index is past the `nverts` vertices or a corner is not finite. */
static inline int rt_load_tri(global const uint *idx, global const float *pos, uint nverts, uint t,
                              rt_tri *tri)
{
    ulong base = 3ul * t;
    uint i0 = idx[base], i1 = idx[base + 1], i2 = idx[base + 2];
    if (i0 >= nverts || i1 >= nverts || i2 >= nverts) {
        tri->valid = 0;
        return 0;
    }
    float p[9];
    for (int a = 0; a < 3; ++a) {
        p[a] = pos[3ul * i0 + a];
        p[3 + a] = pos[3ul * i1 + a];
        p[6 + a] = pos[3ul * i2 + a];
    }
    rt_tri_setup(tri, p, p + 3, p + 6);
    return tri->valid;
}

/* counts[t] = number of voxels triangle t overlaps, and found[t] the last
 * of them (the only one when counts[t] is 1: most triangles of a fine mesh,
 * which rt_grid_write then writes without loading them again). Counter 0
 * counts the triangles that cannot be loaded (bad index, non-finite
 * corner). */
__kernel void rt_grid_count(SLUICE_PARAMS, global const uint *idx, global const float *pos,
                            uint nverts, rt_grid_params g, global uint *counts, global uint *found)
{
    SLUICE_FOR_EACH (t) {
        rt_tri tri;
        uint first[3], last[3], n = 0, cell = 0;
        if (!rt_load_tri(idx, pos, nverts, t, &tri)) {
            SLUICE_COUNT(0, 1u);
            counts[t] = 0;
            continue;
        }
        if (rt_tri_voxel_range(&tri, &g, first, last)) {
            int alone = first[0] == last[0] && first[1] == last[1] && first[2] == last[2];
            float c[3], h[3];
            for (int a = 0; a < 3; ++a)
                h[a] = rt_voxel_half(g.cell[a]);
            for (uint z = first[2]; z <= last[2]; ++z) {
                c[2] = rt_voxel_center(g.lo[2], g.cell[2], z);
                for (uint y = first[1]; y <= last[1]; ++y) {
                    c[1] = rt_voxel_center(g.lo[1], g.cell[1], y);
                    uint row = g.dims[0] * (y + g.dims[1] * z);
                    for (uint x = first[0]; x <= last[0]; ++x) {
                        c[0] = rt_voxel_center(g.lo[0], g.cell[0], x);
                        if (rt_tri_voxel_overlap(&tri, c, h, alone)) {
                            ++n;
                            cell = row + x;
                        }
                    }
                }
            }
        }
        counts[t] = n;
        found[t] = cell;
    }
}

/* Writes triangle t's pairs (voxel index into keys, t into values) at
 * offsets[t], voxels in x-fastest order. A triangle in one voxel is written
 * from found[t]; when every voxel of the range overlaps, the tests are
 * skipped. */
__kernel void rt_grid_write(SLUICE_PARAMS, global const uint *idx, global const float *pos,
                            uint nverts, rt_grid_params g, global const uint *counts,
                            global const uint *found, global const uint *offsets, global uint *keys,
                            global uint *values)
{
    SLUICE_FOR_EACH (t) {
        uint n = counts[t];
        if (n == 0u)
            continue;
        if (n == 1u) {
            keys[offsets[t]] = found[t];
            values[offsets[t]] = t;
            continue;
        }
        rt_tri tri;
        uint first[3], last[3];
        rt_load_tri(idx, pos, nverts, t, &tri);
        rt_tri_voxel_range(&tri, &g, first, last);
        uint range =
            (last[0] - first[0] + 1u) * (last[1] - first[1] + 1u) * (last[2] - first[2] + 1u);
        int all = range == n;
        uint at = offsets[t];
        float c[3], h[3];
        for (int a = 0; a < 3; ++a)
            h[a] = rt_voxel_half(g.cell[a]);
        for (uint z = first[2]; z <= last[2]; ++z) {
            c[2] = rt_voxel_center(g.lo[2], g.cell[2], z);
            for (uint y = first[1]; y <= last[1]; ++y) {
                c[1] = rt_voxel_center(g.lo[1], g.cell[1], y);
                uint row = g.dims[0] * (y + g.dims[1] * z);
                for (uint x = first[0]; x <= last[0]; ++x) {
                    c[0] = rt_voxel_center(g.lo[0], g.cell[0], x);
                    if (all || rt_tri_box_overlap(&tri, c, h)) {
                        keys[at] = row + x;
                        values[at] = t;
                        ++at;
                    }
                }
            }
        }
    }
}
