/* The uniform grid built on the device with the stream algorithms (grid.h,
 * kernels/render/grid.cl). Purcell (3.2) builds the grid offline; his
 * photon map (6.2.2) shows the streaming way to bin items into a grid: sort
 * them by cell, then index the cells. Here the items are (voxel, triangle)
 * pairs:
 *
 *   1. rt_grid_count: voxels overlapped per triangle (exact test)
 *   2. sluice_scan (exclusive): each triangle's first pair
 *   3. rt_grid_write: the pairs, triangle by triangle, at those offsets
 *   4. sluice_sort_radix by voxel: stable, so each voxel's triangles stay
 *      in ascending order, as in the C build
 *   5. sluice_cell_index_count: cell_start from the sorted voxel keys
 *
 * The sorted values are cell_tris. The host waits after step 1 (for the
 * count of triangles that could not be loaded) and step 2 (for the pair
 * count, which is checked against the limit (RT_GRID_MAX_PAIRS or the
 * caller's) before anything of that size is allocated). Step 1 also keeps
 * the voxel of each triangle that overlaps just one, so that step 3 writes
 * those (most triangles of a fine mesh) without loading them again. */
#include "grid.h"

#include "kernels.h"
#include "sluice/streams.h"

#include "../../kernels/render/tri_box.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Kernel argument numbers (after SLUICE_PARAMS), shared by both kernels up
 * to ARG_FOUND. */
enum {
    ARG_IDX,
    ARG_POS,
    ARG_NVERTS,
    ARG_GRID,
    ARG_COUNTS,
    ARG_FOUND,
    ARG_OFFSETS,
    ARG_KEYS,
    ARG_VALUES
};

static sluice_status fail(rt_grid_device *out, sluice_status st, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Writes the message of a failure of the build's own into out->message. */
static sluice_status fail(rt_grid_device *out, sluice_status st, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(out->message, sizeof out->message, fmt, ap);
    va_end(ap);
    return st;
}

/* Everything one build holds until it returns. */
typedef struct build {
    sluice_program *prog;
    sluice_kernel *k_count, *k_write;
    sluice_counters *bad;
    sluice_stream *counts, *found, *offsets, *keys, *values, *start;
} build;

static void build_release(build *b)
{
    sluice_kernel_destroy(b->k_count);
    sluice_kernel_destroy(b->k_write);
    sluice_program_destroy(b->prog);
    sluice_counters_destroy(b->bad);
    sluice_stream_destroy(b->counts);
    sluice_stream_destroy(b->found);
    sluice_stream_destroy(b->offsets);
    sluice_stream_destroy(b->keys);
    sluice_stream_destroy(b->values);
    sluice_stream_destroy(b->start);
    memset(b, 0, sizeof *b);
}

/* Binds the arguments both kernels share. */
static sluice_status bind_common(sluice_kernel *k, sluice_stream *indices, sluice_stream *positions,
                                 uint32_t nverts, const rt_grid_params *g, sluice_stream *counts,
                                 sluice_stream *found)
{
    sluice_status st = sluice_kernel_set_stream(k, ARG_IDX, indices, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, ARG_POS, positions, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, ARG_NVERTS, sizeof nverts, &nverts);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, ARG_GRID, sizeof *g, g);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, ARG_COUNTS, counts, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, ARG_FOUND, found, 0);
    return st;
}

/* The exact number of pairs: the scan's total wraps modulo 2^32, which can
 * only matter when triangles * (largest count) reaches 2^32; then the counts
 * are summed on the host in 64 bits. */
static sluice_status pair_total(sluice_context *ctx, build *b, size_t triangles,
                                uint32_t scan_total, uint64_t *total)
{
    uint32_t largest = 0;
    sluice_status st = sluice_reduce(ctx, b->counts, SLUICE_U32, SLUICE_MAX, &largest);
    if (st != SLUICE_OK)
        return st;
    if ((uint64_t)triangles * largest < (UINT64_C(1) << 32)) {
        *total = scan_total;
        return SLUICE_OK;
    }
    uint32_t *c = malloc(triangles * sizeof *c);
    if (!c)
        return SLUICE_ERROR_OUT_OF_MEMORY; /* reported by the caller */
    st = sluice_stream_download(b->counts, c, triangles, NULL);
    uint64_t sum = 0;
    for (size_t t = 0; st == SLUICE_OK && t < triangles; ++t)
        sum += c[t];
    free(c);
    *total = sum;
    return st;
}

sluice_status rt_grid_build_device(sluice_context *ctx, const rt_grid_desc *desc,
                                   sluice_stream *positions, sluice_stream *indices,
                                   size_t triangles, rt_grid_device *out)
{
    return rt_grid_build_device_limit(ctx, desc, positions, indices, triangles, 0, out);
}

sluice_status rt_grid_build_device_limit(sluice_context *ctx, const rt_grid_desc *desc,
                                         sluice_stream *positions, sluice_stream *indices,
                                         size_t triangles, size_t max_pairs, rt_grid_device *out)
{
    if (!out)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!ctx || !desc || !positions || !indices)
        return fail(out, SLUICE_ERROR_INVALID_ARGUMENT, "rt_grid_build_device: NULL argument");
    size_t cells = 0;
    sluice_status st = rt_grid_desc_check(desc, &cells, out->message, sizeof out->message);
    if (st != SLUICE_OK)
        return st;
    if (sluice_stream_record_size(positions) != 12 || sluice_stream_record_size(indices) != 12)
        return fail(out, SLUICE_ERROR_INVALID_ARGUMENT,
                    "grid: positions and indices need 12-byte records (3 floats, 3 uint32), "
                    "not %zu and %zu",
                    sluice_stream_record_size(positions), sluice_stream_record_size(indices));
    if (triangles > UINT32_MAX)
        return fail(out, SLUICE_ERROR_LIMIT, "grid: %zu triangles exceed the limit of %u",
                    triangles, (unsigned)UINT32_MAX);
    size_t nverts = 0, nidx = 0;
    st = sluice_stream_length(positions, &nverts);
    if (st == SLUICE_OK)
        st = sluice_stream_length(indices, &nidx);
    if (st != SLUICE_OK)
        return fail(out, st, "grid: reading stream lengths: %s", sluice_context_error(ctx));
    if (nverts > sluice_stream_capacity(positions))
        nverts = sluice_stream_capacity(positions);
    if (nverts > UINT32_MAX)
        nverts = UINT32_MAX; /* indices cannot reach further */
    if (nidx < triangles)
        return fail(out, SLUICE_ERROR_INVALID_ARGUMENT,
                    "grid: %zu triangles asked for, the index stream holds %zu", triangles, nidx);

    if (max_pairs == 0 || max_pairs > RT_GRID_MAX_PAIRS)
        max_pairs = RT_GRID_MAX_PAIRS;

    rt_grid_params g;
    rt_grid_params_make(&g, desc->lo, desc->cell, desc->dims);
    const uint32_t nv = (uint32_t)nverts, nt = (uint32_t)triangles;
    build b = {0};
    uint64_t total = 0;
    const char *step = "creating the kernels";
    st = sr_shared_program_create(ctx, (const char *[]){"tri_box.h", "grid.cl"}, 2, NULL, &b.prog);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(b.prog, "rt_grid_count", &b.k_count);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(b.prog, "rt_grid_write", &b.k_write);
    if (st != SLUICE_OK)
        goto runtime_fail;

    if (triangles) {
        /* 1. Count. */
        step = "counting voxels per triangle";
        st = sluice_counters_create(ctx, 1, NULL, &b.bad);
        if (st == SLUICE_OK)
            st = sluice_stream_create(ctx, 4, triangles, &b.counts);
        if (st == SLUICE_OK)
            st = sluice_stream_create(ctx, 4, triangles, &b.found);
        if (st == SLUICE_OK)
            st = bind_common(b.k_count, indices, positions, nv, &g, b.counts, b.found);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_counters(b.k_count, b.bad);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch_count(b.k_count, triangles);
        if (st == SLUICE_OK)
            st = sluice_stream_set_length(b.counts, triangles);
        uint32_t bad = 0;
        if (st == SLUICE_OK)
            st = sluice_counters_read(b.bad, &bad);
        if (st != SLUICE_OK)
            goto runtime_fail;
        if (bad) {
            build_release(&b);
            return fail(out, SLUICE_ERROR_INVALID_ARGUMENT,
                        "grid: %u of %zu triangles have an index past the %zu vertices or a "
                        "corner that is not finite",
                        (unsigned)bad, triangles, nverts);
        }
        /* 2. Offsets, and the total (the host waits for it). */
        step = "scanning the counts";
        uint32_t scan_total = 0;
        st = sluice_stream_create(ctx, 4, triangles, &b.offsets);
        if (st == SLUICE_OK)
            st = sluice_scan(ctx, b.counts, b.offsets, SLUICE_U32, 0, &scan_total);
        if (st == SLUICE_OK)
            st = pair_total(ctx, &b, triangles, scan_total, &total);
        if (st != SLUICE_OK)
            goto runtime_fail;
        if (total > max_pairs) {
            build_release(&b);
            return fail(out, SLUICE_ERROR_LIMIT,
                        "grid: %u x %u x %u voxels over %zu triangles make %llu (voxel, "
                        "triangle) entries, more than the limit of %zu; use a coarser grid",
                        desc->dims[0], desc->dims[1], desc->dims[2], triangles,
                        (unsigned long long)total, max_pairs);
        }
    }

    /* 3. Pairs. */
    step = "writing the (voxel, triangle) pairs";
    st = sluice_stream_create(ctx, 4, (size_t)total, &b.keys);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, 4, (size_t)total, &b.values);
    if (st == SLUICE_OK && total) {
        st = bind_common(b.k_write, indices, positions, nv, &g, b.counts, b.found);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(b.k_write, ARG_OFFSETS, b.offsets, 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(b.k_write, ARG_KEYS, b.keys, 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(b.k_write, ARG_VALUES, b.values, 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch_count(b.k_write, nt);
        if (st == SLUICE_OK)
            st = sluice_stream_set_length(b.keys, (size_t)total);
        if (st == SLUICE_OK)
            st = sluice_stream_set_length(b.values, (size_t)total);
        /* 4. Sort by voxel, stably. */
        if (st == SLUICE_OK) {
            step = "sorting the pairs by voxel";
            st = sluice_sort_radix(ctx, b.keys, b.values);
        }
    }
    /* 5. Cell starts. */
    if (st == SLUICE_OK) {
        step = "indexing the voxels";
        st = sluice_stream_create(ctx, 4, cells + 1, &b.start);
    }
    if (st == SLUICE_OK)
        st = sluice_cell_index_count(ctx, b.keys, (uint32_t)cells, b.start);
    if (st != SLUICE_OK)
        goto runtime_fail;

    out->desc = *desc;
    out->cell_start = b.start;
    out->cell_tris = b.values;
    out->cell_tri_count = (size_t)total;
    out->bytes =
        (sluice_stream_capacity(b.start) + 1) * 4 + (sluice_stream_capacity(b.values) + 1) * 4;
    b.start = NULL;
    b.values = NULL;
    build_release(&b);
    return SLUICE_OK;

runtime_fail:
    if (st == SLUICE_ERROR_OUT_OF_MEMORY && !*sluice_context_error(ctx))
        fail(out, st, "grid build: %s: out of host memory", step);
    else
        fail(out, st, "grid build: %s: %s", step, sluice_context_error(ctx));
    build_release(&b);
    return st;
}
