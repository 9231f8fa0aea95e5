/* The uniform grid (grid.h): the choice of resolution (Purcell 5.2.1), the
 * check of a description, the upload of a host-built grid and the frees.
 * The builds are in grid_host.c and grid_device.c. */
#include "grid.h"

#include "app_error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

sluice_status rt_grid_choose(const float lo[3], const float hi[3], unsigned min_dim,
                             rt_grid_desc *out, char *err, size_t err_size)
{
    if (!lo || !hi || !out) {
        sr_set_error(err, err_size, "rt_grid_choose: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    memset(out, 0, sizeof *out);
    if (min_dim == 0) {
        sr_set_error(err, err_size, "grid: the minimum grid dimension must be at least 1");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    static const char axis_name[3] = {'x', 'y', 'z'};
    double ext[3], max_ext = 0.0, mag = 0.0;
    for (int a = 0; a < 3; ++a) {
        if (!isfinite(lo[a]) || !isfinite(hi[a])) {
            sr_set_error(err, err_size, "grid: the scene bounds are not finite on %c",
                         axis_name[a]);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
        if (lo[a] > hi[a]) {
            sr_set_error(err, err_size, "grid: the scene bounds are empty on %c (%g > %g)",
                         axis_name[a], (double)lo[a], (double)hi[a]);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
        ext[a] = (double)hi[a] - (double)lo[a];
        max_ext = fmax(max_ext, ext[a]);
        mag = fmax(mag, fmax(fabs((double)lo[a]), fabs((double)hi[a])));
    }
    /* The margin keeps triangles on the box's faces strictly inside (the
     * tracer starts rays at the box), and its second term keeps it above the
     * float spacing of the coordinates when the box is far from the origin. */
    double pad = max_ext * 0x1p-12 + mag * 0x1p-20;
    if (pad == 0.0)
        pad = 1.0; /* a single point at the origin: any box will do */
    double padded[3];
    for (int a = 0; a < 3; ++a)
        padded[a] = ext[a] + 2.0 * pad;

    /* Purcell 5.2.1: the shortest (non-flat) axis gets min_dim voxels and the
     * others as many cubes of that edge as cover them. d = padded / shortest
     * * min_dim is exactly min_dim on the shortest axis (x / x is 1); the
     * ceiling allows for the rounding of the other quotients. */
    double ref = 0.0, per_ref = (double)min_dim;
    for (int a = 0; a < 3; ++a)
        if (ext[a] > max_ext * RT_GRID_FLAT_RATIO && (ref == 0.0 || padded[a] < ref))
            ref = padded[a];
    if (ref == 0.0) {
        /* Every axis is flat (a point): one voxel covering the padded box. */
        ref = fmax(padded[0], fmax(padded[1], padded[2]));
        per_ref = 1.0;
    }
    double edge = ref / per_ref, cells = 1.0;
    for (int a = 0; a < 3; ++a) {
        double d = padded[a] / ref * per_ref;
        d = ceil(d - d * 1e-12);
        if (d < 1.0)
            d = 1.0;
        if (d > (double)RT_GRID_MAX_SIDE) {
            sr_set_error(err, err_size,
                         "grid: %.0f voxels along %c exceed the limit of %u (minimum "
                         "dimension %u on a box of %g x %g x %g); use a smaller minimum "
                         "dimension",
                         d, axis_name[a], RT_GRID_MAX_SIDE, min_dim, ext[0], ext[1], ext[2]);
            memset(out, 0, sizeof *out);
            return SLUICE_ERROR_LIMIT;
        }
        out->dims[a] = (uint32_t)d;
        cells *= d;
    }
    if (cells > (double)RT_GRID_MAX_CELLS) {
        sr_set_error(err, err_size,
                     "grid: %u x %u x %u voxels exceed the limit of %u (minimum dimension "
                     "%u); use a smaller minimum dimension",
                     out->dims[0], out->dims[1], out->dims[2], RT_GRID_MAX_CELLS, min_dim);
        memset(out, 0, sizeof *out);
        return SLUICE_ERROR_LIMIT;
    }
    /* Stretch the box about its centre to a whole number of cubes. */
    for (int a = 0; a < 3; ++a) {
        double centre = 0.5 * ((double)lo[a] + (double)hi[a]);
        double half = 0.5 * edge * (double)out->dims[a];
        out->lo[a] = (float)(centre - half);
        out->hi[a] = (float)(centre + half);
        out->cell[a] = (out->hi[a] - out->lo[a]) / (float)out->dims[a];
        if (!isfinite(out->lo[a]) || !isfinite(out->hi[a]) || !(out->cell[a] > 0.0f) ||
            !isfinite(out->cell[a])) {
            sr_set_error(err, err_size, "grid: the scene bounds on %c are too large for float",
                         axis_name[a]);
            memset(out, 0, sizeof *out);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
    }
    return SLUICE_OK;
}

unsigned rt_grid_auto_min_dim(const float lo[3], const float hi[3], size_t triangles)
{
    return rt_grid_auto_min_dim_edge(lo, hi, triangles, 0.0);
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double rt_grid_edge_quartile(const float *positions, const uint32_t *indices, size_t triangles)
{
    enum { SAMPLE = 4096 };
    if (!positions || !indices || triangles == 0)
        return 0.0;
    size_t stride = (triangles + SAMPLE - 1) / SAMPLE, n = 0;
    double *e = malloc(3 * SAMPLE * sizeof *e);
    if (!e)
        return 0.0;
    for (size_t t = 0; t < triangles; t += stride)
        for (int k = 0; k < 3; ++k) {
            const float *a = positions + 3 * (size_t)indices[3 * t + k];
            const float *b = positions + 3 * (size_t)indices[3 * t + (k + 1) % 3];
            double dx = (double)a[0] - b[0], dy = (double)a[1] - b[1], dz = (double)a[2] - b[2];
            double len = sqrt(dx * dx + dy * dy + dz * dz);
            if (isfinite(len))
                e[n++] = len;
        }
    double q = 0.0;
    if (n > 0) {
        qsort(e, n, sizeof *e, compare_double);
        q = e[n / 4];
    }
    free(e);
    return q;
}

unsigned rt_grid_auto_min_dim_edge(const float lo[3], const float hi[3], size_t triangles,
                                   double min_edge)
{
    return rt_grid_auto_min_dim_density(lo, hi, triangles, min_edge, RT_GRID_AUTO_DENSITY);
}

unsigned rt_grid_auto_min_dim_density(const float lo[3], const float hi[3], size_t triangles,
                                      double min_edge, double density)
{
    if (!(density > 0.0) || !isfinite(density))
        density = RT_GRID_AUTO_DENSITY;
    if (!lo || !hi || triangles == 0)
        return RT_GRID_DEFAULT_MIN_DIM;
    double ext[3], max_ext = 0.0;
    for (int a = 0; a < 3; ++a) {
        if (!isfinite(lo[a]) || !isfinite(hi[a]) || lo[a] > hi[a])
            return RT_GRID_DEFAULT_MIN_DIM;
        ext[a] = (double)hi[a] - (double)lo[a];
        max_ext = fmax(max_ext, ext[a]);
    }
    /* the measure of the box over its non-flat axes, as rt_grid_choose sees
     * them, and the shortest of those axes */
    double measure = 1.0, shortest = 0.0;
    int axes = 0;
    for (int a = 0; a < 3; ++a) {
        if (ext[a] > max_ext * RT_GRID_FLAT_RATIO) {
            measure *= ext[a];
            shortest = axes == 0 ? ext[a] : fmin(shortest, ext[a]);
            ++axes;
        }
    }
    if (axes == 0)
        return 1;
    double cells = density * (double)triangles;
    if (cells > (double)RT_GRID_AUTO_MAX_CELLS)
        cells = (double)RT_GRID_AUTO_MAX_CELLS;
    /* voxels of edge e: measure / e^axes = cells */
    double edge = pow(measure / cells, 1.0 / (double)axes);
    if (isfinite(min_edge) && min_edge > edge)
        edge = min_edge;
    double d = edge > 0.0 ? floor(shortest / edge + 0.5) : 1.0;
    if (!(d >= 1.0))
        d = 1.0;
    /* rounding up the other axes may overshoot: step down until it fits */
    while (d > 1.0) {
        double n = 1.0;
        for (int a = 0; a < 3; ++a)
            if (ext[a] > max_ext * RT_GRID_FLAT_RATIO)
                n *= ceil(ext[a] / shortest * d);
        if (n <= (double)RT_GRID_AUTO_MAX_CELLS && d <= 1024.0)
            break;
        d = floor(d * 0.9);
    }
    return (unsigned)d;
}

sluice_status rt_grid_desc_check(const rt_grid_desc *desc, size_t *cells, char *err,
                                 size_t err_size)
{
    if (cells)
        *cells = 0;
    if (!desc) {
        sr_set_error(err, err_size, "grid: NULL description");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    size_t n = 1;
    for (int a = 0; a < 3; ++a) {
        uint32_t d = desc->dims[a];
        if (d == 0 || !isfinite(desc->lo[a]) || !isfinite(desc->cell[a]) ||
            !(desc->cell[a] > 0.0f) || !isfinite(desc->lo[a] + (float)d * desc->cell[a])) {
            sr_set_error(err, err_size,
                         "grid: bad description on axis %d (dims %u, lo %g, cell %g)", a,
                         (unsigned)d, (double)desc->lo[a], (double)desc->cell[a]);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
        if (d > RT_GRID_MAX_SIDE) {
            sr_set_error(err, err_size, "grid: %u voxels on axis %d exceed the limit of %u",
                         (unsigned)d, a, RT_GRID_MAX_SIDE);
            return SLUICE_ERROR_LIMIT;
        }
        n *= d; /* at most 2^60: no overflow in a 64-bit size_t */
        if (n > RT_GRID_MAX_CELLS) {
            sr_set_error(err, err_size, "grid: %u x %u x %u voxels exceed the limit of %u",
                         (unsigned)desc->dims[0], (unsigned)desc->dims[1], (unsigned)desc->dims[2],
                         RT_GRID_MAX_CELLS);
            return SLUICE_ERROR_LIMIT;
        }
    }
    if (cells)
        *cells = n;
    return SLUICE_OK;
}

void rt_grid_host_free(rt_grid_host *g)
{
    if (!g)
        return;
    free(g->cell_start);
    free(g->cell_tris);
    memset(g, 0, sizeof *g);
}

/* Device memory of a stream: the runtime allocates one spare record past the
 * capacity (sluice_stream_cl_mem). */
static size_t stream_bytes(sluice_stream *s)
{
    return s ? (sluice_stream_capacity(s) + 1) * sluice_stream_record_size(s) : 0;
}

sluice_status rt_grid_upload(sluice_context *ctx, const rt_grid_host *host, rt_grid_device *out)
{
    if (!out)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!ctx || !host || !host->cell_start) {
        snprintf(out->message, sizeof out->message, "rt_grid_upload: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    size_t cells = 0;
    sluice_status st = rt_grid_desc_check(&host->desc, &cells, out->message, sizeof out->message);
    if (st != SLUICE_OK)
        return st;
    size_t count = host->cell_start[cells];
    if (count && !host->cell_tris) {
        snprintf(out->message, sizeof out->message, "rt_grid_upload: NULL cell_tris");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sluice_stream *start = NULL, *tris = NULL;
    st = sluice_stream_create(ctx, 4, cells + 1, &start);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, 4, count, &tris);
    if (st == SLUICE_OK)
        st = sluice_stream_upload(start, host->cell_start, cells + 1);
    if (st == SLUICE_OK)
        st = sluice_stream_upload(tris, host->cell_tris, count);
    if (st != SLUICE_OK) {
        snprintf(out->message, sizeof out->message, "grid upload: %s", sluice_context_error(ctx));
        sluice_stream_destroy(start);
        sluice_stream_destroy(tris);
        return st;
    }
    out->desc = host->desc;
    out->cell_start = start;
    out->cell_tris = tris;
    out->cell_tri_count = count;
    out->bytes = stream_bytes(start) + stream_bytes(tris);
    return SLUICE_OK;
}

void rt_grid_device_free(rt_grid_device *g)
{
    if (!g)
        return;
    sluice_stream_destroy(g->cell_start);
    sluice_stream_destroy(g->cell_tris);
    memset(g, 0, sizeof *g);
}
