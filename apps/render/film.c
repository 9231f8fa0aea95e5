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
        sluice_stream_create(ctx, 3 * sizeof(int64_t), (size_t)width * height, &f->accum);
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
    size_t pixels = (size_t)f->width * f->height;
    void *zero = calloc(pixels, 3 * sizeof(int64_t));
    if (!zero)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    sluice_status st = sluice_stream_upload(f->accum, zero, pixels);
    free(zero);
    return st;
}

size_t sr_film_bytes(const sr_film *f)
{
    return f ? (size_t)f->width * f->height * 3 * sizeof(int64_t) : 0;
}

/* Resolves f (plus `extra`, a film of the same size, when not NULL). */
static sluice_status resolve(sr_film *f, sr_film *extra, double scale, sr_image *img,
                             size_t *bad_pixels)
{
    if (bad_pixels)
        *bad_pixels = 0;
    if (!f || !img || sr_image_width(img) != f->width || sr_image_height(img) != f->height ||
        sr_image_channels(img) != 3 || !isfinite(scale) ||
        (extra && (extra->width != f->width || extra->height != f->height)))
        return SLUICE_ERROR_INVALID_ARGUMENT;
    size_t pixels = (size_t)f->width * f->height;
    int64_t *acc = malloc(pixels * 3 * sizeof *acc);
    int64_t *more = extra ? malloc(pixels * 3 * sizeof *more) : NULL;
    if (!acc || (extra && !more)) {
        free(acc);
        free(more);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    sluice_status st = sluice_stream_download(f->accum, acc, pixels, NULL);
    if (st == SLUICE_OK && extra)
        st = sluice_stream_download(extra->accum, more, pixels, NULL);
    if (st == SLUICE_OK) {
        float *px = sr_image_pixels(img);
        double s = scale / (double)RT_FIXED_SCALE;
        size_t bad = 0;
        for (size_t i = 0; i < pixels; ++i) {
            int ok = 1;
            float v[3];
            for (int k = 0; k < 3; ++k) {
                /* in double: the int64 sum could wrap where the images'
                 * sum would not */
                double a = (double)acc[3 * i + k] + (more ? (double)more[3 * i + k] : 0.0);
                v[k] = (float)(a * s);
                ok &= isfinite(v[k]) != 0;
            }
            if (!ok) {
                ++bad;
                v[0] = v[1] = v[2] = 0.0f;
            }
            memcpy(px + 3 * i, v, sizeof v);
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
    return resolve(f, NULL, scale, img, bad_pixels);
}

sluice_status sr_film_resolve_sum(sr_film *f, sr_film *extra, double scale, sr_image *img,
                                  size_t *bad_pixels)
{
    return extra ? resolve(f, extra, scale, img, bad_pixels) : SLUICE_ERROR_INVALID_ARGUMENT;
}

sluice_status sr_film_write(sr_film *f, double scale, const char *path, size_t *bad_pixels,
                            char *err, size_t err_size)
{
    if (!f || !path) {
        sr_set_error(err, err_size, "sr_film_write: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sluice_status st = SLUICE_OK;
    if (!f->img)
        st = sr_image_create(f->width, f->height, 3, &f->img, err, err_size);
    if (st == SLUICE_OK) {
        st = sr_film_resolve(f, scale, f->img, bad_pixels);
        if (st != SLUICE_OK)
            sr_set_error(err, err_size, "%s",
                         st == SLUICE_ERROR_OUT_OF_MEMORY ? "out of host memory"
                                                          : sluice_context_error(f->ctx));
    }
    if (st == SLUICE_OK)
        st = sr_image_write(f->img, path, err, err_size);
    return st;
}
