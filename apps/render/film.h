/*
 * The film: a per-pixel accumulation buffer on the device that every
 * renderer's kernels add to (kernels/render/film.cl: 64-bit fixed point with
 * atomic adds, so the sum does not depend on the order of the adds: same
 * seed, same image, bit for bit), and the image made from it.
 *
 * The film holds two halves: sample s adds to half s & 1 (slot
 * p + (s & 1) * pixels). Their sum is the image; the odd half alone is an
 * independent estimate of it from half the samples, which is how a render
 * estimates its own noise (sr_adaptive) without keeping a second image.
 * Samples per pixel may differ by tile (adaptive sampling): the image is
 * resolved with a sample count per SR_FILM_TILE x SR_FILM_TILE tile.
 */
#ifndef SR_FILM_H
#define SR_FILM_H

#include "image.h"
#include "sluice/sluice.h"

#include <stddef.h>
#include <stdint.h>

typedef struct sr_film sr_film;

/** Creates a film of width x height pixels, all zero. On failure `*out` is
 *  NULL and `err` says why. */
sluice_status sr_film_create(sluice_context *ctx, unsigned width, unsigned height, sr_film **out,
                             char *err, size_t err_size);

/** Frees it (NULL is fine). */
void sr_film_destroy(sr_film *f);

/** Edge of the square tiles that share a sample count (and of the eye
 *  rays' tiles, kernels/render/camera.cl). */
#define SR_FILM_TILE 8u

/** The accumulation stream the kernels add to: 3 int64 per slot, 2 * pixels
 *  slots, slot p + half * pixels for pixel p = y * width + x and half 0 (even
 *  samples) or 1 (odd samples) (rt_add in film.cl). */
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

/** Tiles across and down: ceil(width / SR_FILM_TILE), ceil(height / ...). */
void sr_film_tiles(const sr_film *f, unsigned *across, unsigned *down);

/**
 * Resolves a film whose tiles took different numbers of samples:
 * `tile_samples[t]` for tile t = ty * across + tx (sr_film_tiles); a tile
 * with none is black. Writes the mean of all samples into `img`, and when
 * `odd` is not NULL the mean of the odd half alone into it (a tile with
 * n samples has n / 2 odd ones; black with none). `extra`, when not NULL, is
 * a film of the same size whose values are added to `f`'s first (a preview
 * layer, e.g. the photon mapper's intermediate estimates). Non-finite pixels
 * are written as 0 and counted in `*bad_pixels` (may be NULL).
 */
sluice_status sr_film_resolve_tiles(sr_film *f, sr_film *extra, const uint32_t *tile_samples,
                                    sr_image *img, sr_image *odd, size_t *bad_pixels);

/**
 * sr_film_resolve_tiles into the film's own image, then writes it to `path`
 * (the extension picks the format: .png, .exr, .hdr; NULL: resolved, with
 * its non-finite pixels counted, but not written). On failure `err` says
 * why.
 */
sluice_status sr_film_write(sr_film *f, const uint32_t *tile_samples, const char *path,
                            size_t *bad_pixels, char *err, size_t err_size);

#endif /* SR_FILM_H */
