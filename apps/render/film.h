/*
 * The film: a per-pixel accumulation buffer on the device that every
 * renderer's kernels add to (kernels/render/film.cl: 64-bit fixed point with
 * atomic adds, so the sum does not depend on the order of the adds: same
 * seed, same image, bit for bit), and the image made from it.
 */
#ifndef SR_FILM_H
#define SR_FILM_H

#include "image.h"
#include "sluice/sluice.h"

#include <stddef.h>

typedef struct sr_film sr_film;

/** Creates a film of width x height pixels, all zero. On failure `*out` is
 *  NULL and `err` says why. */
sluice_status sr_film_create(sluice_context *ctx, unsigned width, unsigned height, sr_film **out,
                             char *err, size_t err_size);

/** Frees it (NULL is fine). */
void sr_film_destroy(sr_film *f);

/** The accumulation stream the kernels add to: 3 int64 per pixel, pixel
 *  p = y * width + x (rt_add in film.cl). */
sluice_stream *sr_film_accum(sr_film *f);

/** Sets every pixel back to zero. */
sluice_status sr_film_clear(sr_film *f);

/** Device bytes the film holds. */
size_t sr_film_bytes(const sr_film *f);

/**
 * Writes the accumulated values times `scale` (e.g. 1 / samples) into `img`
 * (RGB, the film's size). Pixels that would not be finite (none should be)
 * are written as 0 and counted in `*bad_pixels` (may be NULL).
 */
sluice_status sr_film_resolve(sr_film *f, double scale, sr_image *img, size_t *bad_pixels);

/** sr_film_resolve of the sum of two films of the same size (a film and a
 *  preview layer over it, e.g. the photon mapper's intermediate estimates). */
sluice_status sr_film_resolve_sum(sr_film *f, sr_film *extra, double scale, sr_image *img,
                                  size_t *bad_pixels);

/**
 * sr_film_resolve into the film's own image, then writes it to `path` (the
 * extension picks the format: .png, .exr, .hdr). On failure `err` says why.
 */
sluice_status sr_film_write(sr_film *f, double scale, const char *path, size_t *bad_pixels,
                            char *err, size_t err_size);

#endif /* SR_FILM_H */
