/* The uniform point grid built on the device (apps/render/point_grid.c;
 * Purcell 6.2.2). sr_program_create prepends rt_types.h and pg_types.h, so
 * pg_cell and pg_hash_point are the host reference's arithmetic, bit for
 * bit.
 *
 * All kernels are generators (sluice_kernel_launch_count) over points or
 * cells (buckets, in the hashed layout of Purcell 6.4.4), except pg_place,
 * which runs over the stream of overfull points. */
#include "sluice.cl"

/* keys[i] = the cell of point i (g.cells for a non-finite one, counted in
 * counter 0), values[i] = i. */
__kernel void pg_key(SLUICE_PARAMS, global const float *pts, pg_params g, global uint *keys,
                     global uint *values)
{
    SLUICE_FOR_EACH (i) {
        ulong b = (ulong)i * g.stride;
        uint c = pg_cell(pts[b], pts[b + 1], pts[b + 2], &g);
        keys[i] = c;
        values[i] = i;
        SLUICE_COUNT(0, c == g.cells);
    }
}

/* buf[i] = value. */
__kernel void pg_fill(SLUICE_PARAMS, global uint *buf, uint value)
{
    SLUICE_FOR_EACH (i) {
        buf[i] = value;
    }
}

/* The counting build's scatter: point i goes to its cell's next free place.
 * The atomic makes the order within a cell depend on timing; pg_finish
 * sorts each cell afterwards, so the result does not. */
__kernel void pg_scatter(SLUICE_PARAMS, global const uint *keys, global const uint *start,
                         global uint *cursor, global uint *order, uint cells)
{
    SLUICE_FOR_EACH (i) {
        uint c = keys[i];
        if (c < cells)
            order[start[c] + atomic_inc(&cursor[c])] = i;
    }
}

/* Restores the max-heap property of a[0 .. size) below `root`. */
static inline void pg_sift(global uint *a, uint root, uint size)
{
    for (;;) {
        uint c = 2u * root + 1u;
        if (c >= size)
            break;
        if (c + 1u < size && a[c + 1u] > a[c])
            ++c;
        if (a[root] >= a[c])
            break;
        uint t = a[root];
        a[root] = a[c];
        a[c] = t;
        root = c;
    }
}

/* Sorts a[0 .. n) ascending in place: insertion sort for the usual short
 * cells, heapsort (in place, n log n, no scratch) for the long ones a
 * dense or adversarial input makes (a million points in one cell). */
static inline void pg_sort(global uint *a, uint n)
{
    if (n <= 32u) {
        for (uint i = 1; i < n; ++i) {
            uint v = a[i], j = i;
            for (; j > 0u && a[j - 1u] > v; --j)
                a[j] = a[j - 1u];
            a[j] = v;
        }
        return;
    }
    for (uint i = n / 2u; i-- > 0u;)
        pg_sift(a, i, n);
    for (uint end = n - 1u; end > 0u; --end) {
        uint t = a[0];
        a[0] = a[end];
        a[end] = t;
        pg_sift(a, 0u, end);
    }
}

/* The compact builds' last step, per cell: counts from the starts, and the
 * cell's indices in ascending order (the bitonic sort is not stable and the
 * counting scatter races), so all builds give the same order. Counter 0:
 * occupied cells. */
__kernel void pg_finish(SLUICE_PARAMS, global const uint *start, global uint *order,
                        global uint *count, global uint *arrived)
{
    SLUICE_FOR_EACH (c) {
        uint s = start[c], n = start[c + 1u] - s;
        count[c] = n;
        arrived[c] = n;
        pg_sort(order + s, n);
        SLUICE_COUNT(0, n > 0u);
    }
}

/* The stencil build's last step, per cell: fill (already in count) and
 * overflow (in arrived) from sluice_route_bounded become stored and arrived
 * counts, starts are the fixed footprints, and a cell that did not overflow
 * holds all its points, sorted here. An overfull cell is refilled by
 * pg_place. Counters: 0 occupied cells, 1 overfull cells, 2 points not
 * stored. */
__kernel void pg_finish_stencil(SLUICE_PARAMS, global uint *order, global uint *start,
                                global const uint *count, global uint *arrived, uint slots,
                                uint cells)
{
    SLUICE_FOR_EACH (c) {
        uint f = count[c], over = arrived[c];
        start[c] = c * slots;
        if (c + 1u == cells)
            start[cells] = cells * slots;
        arrived[c] = f + over;
        if (over == 0u)
            pg_sort(order + (ulong)c * slots, f);
        SLUICE_COUNT(0, f > 0u);
        SLUICE_COUNT(1, over > 0u);
        SLUICE_COUNT(2, over);
    }
}

/* The points of overfull cells, in ascending index order (ordered outputs):
 * their cells to output 0, their indices to output 1. */
__kernel void pg_pick(SLUICE_PARAMS, global const uint *keys, global const uint *count,
                      global const uint *arrived, uint cells, global uint *sub_keys,
                      global uint *sub_values)
{
    SLUICE_FOR_EACH (i) {
        uint c = keys[i];
        int over = c < cells && arrived[c] > count[c];
        SLUICE_EMIT_IF(0, sub_keys, c, over);
        SLUICE_EMIT_IF(1, sub_values, i, over);
    }
}

/* Over the overfull points stably sorted by cell: the first `slots` of each
 * cell (its lowest indices) take the cell's footprint, in order. */
__kernel void pg_place(SLUICE_PARAMS, global const uint *sub_keys, global const uint *sub_values,
                       global const uint *sub_start, uint slots, global uint *order)
{
    SLUICE_FOR_EACH (i) {
        uint c = sub_keys[i], rank = i - sub_start[c];
        if (rank < slots)
            order[(ulong)c * slots + rank] = sub_values[i];
    }
}

/* The hashed layout's pg_key (pg_types.h: pg_hash_point): keys[i] = the
 * bucket of point i (h.buckets for a non-finite one, counted in counter 0),
 * values[i] = i. */
__kernel void pg_hash_key(SLUICE_PARAMS, global const float *pts, pg_hash_params h,
                          global uint *keys, global uint *values)
{
    SLUICE_FOR_EACH (i) {
        ulong b = (ulong)i * h.stride;
        uint c = pg_hash_point(pts[b], pts[b + 1], pts[b + 2], &h);
        keys[i] = c;
        values[i] = i;
        SLUICE_COUNT(0, c == h.buckets);
    }
}
