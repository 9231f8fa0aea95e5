/* See film.h. */
#include "film.h"
#include "app_error.h"

#include "../../kernels/render/rt_types.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

struct sr_film {
    sluice_context *ctx;
    unsigned width, height;
    sluice_stream *accum;
    sr_image *img; /* for sr_film_write, made when first needed */
};

sluice_status sr_film_create(sluice_context *ctx, unsigned width, unsigned height, sr_film **out,
                             char *err, size_t err_size)
{
    if (out)
        *out = NULL;
    if (!ctx || !out || width == 0 || height == 0 || (uint64_t)width * height > (1u << 26)) {
        sr_set_error(err, err_size, "film: bad size %ux%u", width, height);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sr_film *f = calloc(1, sizeof *f);
    if (!f) {
        sr_set_error(err, err_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    f->ctx = ctx;
    f->width = width;
    f->height = height;
    sluice_status st =
        sluice_stream_create(ctx, 3 * sizeof(int64_t), 2 * (size_t)width * height, &f->accum);
    if (st == SLUICE_OK)
        st = sr_film_clear(f);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "film: %s", sluice_context_error(ctx));
        sr_film_destroy(f);
        return st;
    }
    *out = f;
    return SLUICE_OK;
}

void sr_film_destroy(sr_film *f)
{
    if (!f)
        return;
    sluice_stream_destroy(f->accum);
    sr_image_destroy(f->img);
    free(f);
}

sluice_stream *sr_film_accum(sr_film *f)
{
    return f ? f->accum : NULL;
}

sluice_status sr_film_clear(sr_film *f)
{
    if (!f)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    size_t slots = 2 * (size_t)f->width * f->height;
    void *zero = calloc(slots, 3 * sizeof(int64_t));
    if (!zero)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    sluice_status st = sluice_stream_upload(f->accum, zero, slots);
    free(zero);
    return st;
}

size_t sr_film_bytes(const sr_film *f)
{
    return f ? 2 * (size_t)f->width * f->height * 3 * sizeof(int64_t) : 0;
}

void sr_film_tiles(const sr_film *f, unsigned *across, unsigned *down)
{
    *across = f ? (f->width + SR_FILM_TILE - 1) / SR_FILM_TILE : 0;
    *down = f ? (f->height + SR_FILM_TILE - 1) / SR_FILM_TILE : 0;
}

/* Writes pixel i of `img` (3 floats) from the fixed-point sums `a` times
 * `s`; returns 1 (and writes black) when a value would not be finite. */
static int put_pixel(float *px, const double a[3], double s)
{
    float v[3];
    int ok = 1;
    for (int k = 0; k < 3; ++k) {
        v[k] = (float)(a[k] * s);
        ok &= isfinite(v[k]) != 0;
    }
    if (!ok)
        v[0] = v[1] = v[2] = 0.0f;
    memcpy(px, v, sizeof v);
    return !ok;
}

static int image_fits(const sr_film *f, const sr_image *img)
{
    return !img || (sr_image_width(img) == f->width && sr_image_height(img) == f->height &&
                    sr_image_channels(img) == 3);
}

/* Resolves f (plus `extra`, a film of the same size, when not NULL): every
 * pixel times `scale`, or, with `tiles`, times 1 / its tile's samples (and
 * the odd half into `odd`, when not NULL). */
static sluice_status resolve(sr_film *f, sr_film *extra, double scale, const uint32_t *tiles,
                             sr_image *img, sr_image *odd, size_t *bad_pixels)
{
    if (bad_pixels)
        *bad_pixels = 0;
    if (!f || !img || !image_fits(f, img) || !image_fits(f, odd) || !isfinite(scale) ||
        (extra && (extra->width != f->width || extra->height != f->height)))
        return SLUICE_ERROR_INVALID_ARGUMENT;
    size_t pixels = (size_t)f->width * f->height;
    int64_t *acc = malloc(2 * pixels * 3 * sizeof *acc);
    int64_t *more = extra ? malloc(2 * pixels * 3 * sizeof *more) : NULL;
    if (!acc || (extra && !more)) {
        free(acc);
        free(more);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    sluice_status st = sluice_stream_download(f->accum, acc, 2 * pixels, NULL);
    if (st == SLUICE_OK && extra)
        st = sluice_stream_download(extra->accum, more, 2 * pixels, NULL);
    if (st == SLUICE_OK) {
        float *px = sr_image_pixels(img);
        float *po = odd ? sr_image_pixels(odd) : NULL;
        unsigned across = (f->width + SR_FILM_TILE - 1) / SR_FILM_TILE;
        double unit = 1.0 / (double)RT_FIXED_SCALE;
        size_t bad = 0;
        for (size_t i = 0; i < pixels; ++i) {
            double s = scale * unit, so = 0.0;
            if (tiles) {
                size_t x = i % f->width, y = i / f->width;
                uint32_t n = tiles[(y / SR_FILM_TILE) * across + x / SR_FILM_TILE];
                s = n ? unit / n : 0.0;
                so = n / 2 ? unit / (n / 2) : 0.0;
            }
            /* in double: the int64 sums could wrap where the images' sum
             * would not */
            double all[3], half[3];
            for (int k = 0; k < 3; ++k) {
                half[k] = (double)acc[3 * (pixels + i) + k];
                all[k] = (double)acc[3 * i + k] + half[k];
                if (more) {
                    double m = (double)more[3 * (pixels + i) + k];
                    half[k] += m;
                    all[k] += (double)more[3 * i + k] + m;
                }
            }
            bad += (size_t)put_pixel(px + 3 * i, all, s);
            if (po)
                put_pixel(po + 3 * i, half, so);
        }
        if (bad_pixels)
            *bad_pixels = bad;
    }
    free(acc);
    free(more);
    return st;
}

sluice_status sr_film_resolve(sr_film *f, double scale, sr_image *img, size_t *bad_pixels)
{
    return resolve(f, NULL, scale, NULL, img, NULL, bad_pixels);
}

sluice_status sr_film_resolve_tiles(sr_film *f, sr_film *extra, const uint32_t *tile_samples,
                                    sr_image *img, sr_image *odd, size_t *bad_pixels)
{
    return tile_samples ? resolve(f, extra, 1.0, tile_samples, img, odd, bad_pixels)
                        : SLUICE_ERROR_INVALID_ARGUMENT;
}

sluice_status sr_film_write(sr_film *f, const uint32_t *tile_samples, const char *path,
                            size_t *bad_pixels, char *err, size_t err_size)
{
    if (!f || !tile_samples) {
        sr_set_error(err, err_size, "sr_film_write: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sluice_status st = SLUICE_OK;
    if (!f->img)
        st = sr_image_create(f->width, f->height, 3, &f->img, err, err_size);
    if (st == SLUICE_OK) {
        st = sr_film_resolve_tiles(f, NULL, tile_samples, f->img, NULL, bad_pixels);
        if (st != SLUICE_OK)
            sr_set_error(err, err_size, "%s",
                         st == SLUICE_ERROR_OUT_OF_MEMORY ? "out of host memory"
                                                          : sluice_context_error(f->ctx));
    }
    if (st == SLUICE_OK && path)
        st = sr_image_write(f->img, path, err, err_size);
    return st;
}
