/* The uniform grid built in plain C (grid.h): the reference the device build
 * is tested against, with the same overlap test (kernels/render/tri_box.h)
 * in the same float arithmetic. Purcell (3.2) leaves the build out of the
 * ray tracer's cost; here it is a counting sort of (voxel, triangle) pairs,
 * generated in triangle order so that every voxel's list comes out
 * ascending. */
#include "grid.h"

#include "app_error.h"

#include "../../kernels/render/tri_box.h"

#include <stdlib.h>
#include <string.h>

/* A growable array of the voxel of each (voxel, triangle) pair, in the order
 * generated: triangle by triangle. */
typedef struct pair_list {
    uint32_t *cell;
    size_t count, capacity;
} pair_list;

static int pair_push(pair_list *p, uint32_t cell)
{
    if (p->count == p->capacity) {
        size_t cap = p->capacity ? 2 * p->capacity : 4096;
        uint32_t *grown = realloc(p->cell, cap * sizeof *grown);
        if (!grown)
            return 0;
        p->cell = grown;
        p->capacity = cap;
    }
    p->cell[p->count++] = cell;
    return 1;
}

sluice_status rt_grid_build_host(const rt_grid_desc *desc, const float *positions,
                                 const uint32_t *indices, size_t triangles, rt_grid_host *out,
                                 char *err, size_t err_size)
{
    return rt_grid_build_host_limit(desc, positions, indices, triangles, 0, out, err, err_size);
}

sluice_status rt_grid_build_host_limit(const rt_grid_desc *desc, const float *positions,
                                       const uint32_t *indices, size_t triangles, size_t max_pairs,
                                       rt_grid_host *out, char *err, size_t err_size)
{
    if (!out) {
        sr_set_error(err, err_size, "rt_grid_build_host: NULL output");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    memset(out, 0, sizeof *out);
    if (!desc || (triangles && (!positions || !indices))) {
        sr_set_error(err, err_size, "rt_grid_build_host: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    size_t cells = 0;
    sluice_status st = rt_grid_desc_check(desc, &cells, err, err_size);
    if (st != SLUICE_OK)
        return st;
    if (triangles > UINT32_MAX) {
        sr_set_error(err, err_size, "grid: %zu triangles exceed the limit of %u", triangles,
                     (unsigned)UINT32_MAX);
        return SLUICE_ERROR_LIMIT;
    }

    if (max_pairs == 0 || max_pairs > RT_GRID_MAX_PAIRS)
        max_pairs = RT_GRID_MAX_PAIRS;

    rt_grid_params g;
    rt_grid_params_make(&g, desc->lo, desc->cell, desc->dims);
    const float half[3] = {rt_voxel_half(g.cell[0]), rt_voxel_half(g.cell[1]),
                           rt_voxel_half(g.cell[2])};
    const size_t nx = desc->dims[0], nxy = nx * desc->dims[1];

    /* start[c] counts voxel c's pairs first, then becomes its offset. */
    uint32_t *start = calloc(cells + 1, sizeof *start);
    uint32_t *tri_end = malloc((triangles ? triangles : 1) * sizeof *tri_end);
    uint32_t *tris = NULL;
    pair_list pairs = {0};
    if (!start || !tri_end) {
        sr_set_error(err, err_size, "grid: out of host memory for %zu voxels", cells);
        st = SLUICE_ERROR_OUT_OF_MEMORY;
        goto fail;
    }

    /* Pass 1: every triangle against the voxels of its bounding box. */
    for (size_t t = 0; t < triangles; ++t) {
        const uint32_t *ix = indices + 3 * t;
        rt_tri tri;
        rt_tri_setup(&tri, positions + 3 * (size_t)ix[0], positions + 3 * (size_t)ix[1],
                     positions + 3 * (size_t)ix[2]);
        if (!tri.valid) {
            sr_set_error(err, err_size, "grid: triangle %zu has a corner that is not finite", t);
            st = SLUICE_ERROR_INVALID_ARGUMENT;
            goto fail;
        }
        rt_u32 first[3], last[3];
        if (rt_tri_voxel_range(&tri, &g, first, last)) {
            int alone = first[0] == last[0] && first[1] == last[1] && first[2] == last[2];
            float c[3];
            for (rt_u32 z = first[2]; z <= last[2]; ++z) {
                c[2] = rt_voxel_center(g.lo[2], g.cell[2], z);
                for (rt_u32 y = first[1]; y <= last[1]; ++y) {
                    c[1] = rt_voxel_center(g.lo[1], g.cell[1], y);
                    for (rt_u32 x = first[0]; x <= last[0]; ++x) {
                        c[0] = rt_voxel_center(g.lo[0], g.cell[0], x);
                        if (!rt_tri_voxel_overlap(&tri, c, half, alone))
                            continue;
                        uint32_t cell = (uint32_t)(x + nx * y + nxy * z);
                        if (pairs.count >= max_pairs) {
                            sr_set_error(err, err_size,
                                         "grid: more than the limit of %zu (voxel, "
                                         "triangle) entries (at triangle %zu of %zu); use "
                                         "a coarser grid",
                                         max_pairs, t, triangles);
                            st = SLUICE_ERROR_LIMIT;
                            goto fail;
                        }
                        if (!pair_push(&pairs, cell)) {
                            sr_set_error(err, err_size, "grid: out of host memory for %zu entries",
                                         pairs.count);
                            st = SLUICE_ERROR_OUT_OF_MEMORY;
                            goto fail;
                        }
                        start[cell]++;
                    }
                }
            }
        }
        tri_end[t] = (uint32_t)pairs.count;
    }

    /* Counts to offsets (exclusive scan); start[cells] is the total. */
    uint32_t sum = 0;
    for (size_t c = 0; c <= cells; ++c) {
        uint32_t n = start[c];
        start[c] = sum;
        sum += n;
    }
    tris = malloc((pairs.count ? pairs.count : 1) * sizeof *tris);
    if (!tris) {
        sr_set_error(err, err_size, "grid: out of host memory for %zu entries", pairs.count);
        st = SLUICE_ERROR_OUT_OF_MEMORY;
        goto fail;
    }
    /* Pass 2: scatter in generation order, using start[] as the cursors;
     * triangles come in ascending order, so each list is ascending. Each
     * cursor ends at the next voxel's offset: shift them back by one. */
    size_t p = 0;
    for (size_t t = 0; t < triangles; ++t)
        for (; p < tri_end[t]; ++p)
            tris[start[pairs.cell[p]]++] = (uint32_t)t;
    memmove(start + 1, start, cells * sizeof *start);
    start[0] = 0;

    free(pairs.cell);
    free(tri_end);
    out->desc = *desc;
    out->cell_start = start;
    out->cell_tris = tris;
    return SLUICE_OK;

fail:
    free(start);
    free(tri_end);
    free(tris);
    free(pairs.cell);
    return st;
}
