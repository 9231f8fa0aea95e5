/*
 * Adaptive sampling: which tiles of the image still take samples, and how
 * good the image is, estimated from the render itself.
 *
 * The image is cut into SR_FILM_TILE x SR_FILM_TILE tiles, each with its
 * own sample count. The estimate comes from the film's two halves (film.h):
 * with I the mean of a tile's n samples and B the mean of its n / 2 odd
 * ones, I - B = (A - B) / 2 for A the even half's mean, and A and B are
 * independent with variance 2 s^2 / n each, so E[(I - B)^2] = s^2 / n, the
 * variance of I. A tile's relMSE estimate is therefore
 *     mean over its pixels and channels of (I - B)^2 / (min(A, B)^2 + 0.01)
 * (the 0.01 as in image_metrics.h's rel_mse), and the image's is the mean
 * over all pixels. The denominator stands for the true value, which the
 * relMSE divides by: the noisy mean I itself would hide fireflies (a rare
 * bright sample raises I as much as the difference, and the estimate of a
 * caustic under glass came out 40 times too low), while the smaller half
 * has it only when both halves do. It overestimates smooth noise slightly
 * (the smaller of two means is a little low). It counts noise, not bias: a
 * biased render (a photon map of fixed size) is judged by how much more
 * samples would still change it.
 *
 * With a target, a tile whose estimate is at or below it stops taking
 * samples once it has min_samples (the rest of the image goes on), and the
 * render is done when the image's estimate reaches the target. Checks
 * download the film, so they are spaced out: at min_samples, then every
 * quarter of the samples done (at least every 2), always at an even count
 * so that both halves hold the same number of samples.
 */
#ifndef SR_ADAPTIVE_H
#define SR_ADAPTIVE_H

#include "film.h"
#include "image.h"
#include "sluice/sluice.h"

#include <stddef.h>
#include <stdio.h>
#include <stdint.h>

/** How to sample. */
typedef struct sr_adaptive_options {
    /** relMSE at which a tile stops (adaptive) and the render is done;
     *  0: neither (every tile takes every sample, no estimates). */
    double target;
    /** Non-zero: converged tiles stop taking samples. Zero: every tile takes
     *  every sample and only the image's estimate is checked. */
    int adaptive;
    /** Samples every tile takes before the first check (even, >= 2; 0: 8). */
    unsigned min_samples;
} sr_adaptive_options;

/** What adaptive sampling did. */
typedef struct sr_adaptive_stats {
    double target;          /**< the options' target (0: none) */
    int adaptive;           /**< the options' adaptive flag */
    unsigned tiles;         /**< tiles of the image */
    unsigned tiles_active;  /**< tiles still taking samples */
    unsigned samples;       /**< samples started (the most any tile took) */
    uint64_t pixel_samples; /**< pixel samples taken */
    uint64_t pixel_uniform; /**< pixel samples had every tile taken all */
    unsigned checks;        /**< estimates taken */
    double check_seconds;   /**< time spent on them (film downloads) */
    double error;           /**< the image's last relMSE estimate; -1: none */
    double error_uniform;   /**< the estimate had every tile taken every
                                 sample (each stopped tile's scaled by its
                                 samples over all: variance ~ 1 / n);
                                 -1: none */
    unsigned error_samples; /**< samples started when `error` was taken */
} sr_adaptive_stats;

typedef struct sr_adaptive sr_adaptive;

/** Creates the state for a film of width x height with every tile active.
 *  Errors: a bad target or min_samples (SLUICE_ERROR_INVALID_ARGUMENT), or
 *  the context's; `err` says which. */
sluice_status sr_adaptive_create(sluice_context *ctx, unsigned width, unsigned height,
                                 const sr_adaptive_options *opt, sr_adaptive **out, char *err,
                                 size_t err_size);

/** Frees it (NULL is fine). */
void sr_adaptive_destroy(sr_adaptive *a);

/** Starts a sample: every active tile's count goes up by one. Returns the
 *  sample's index (the samples started before it). */
unsigned sr_adaptive_begin_sample(sr_adaptive *a);

/** The device list of the active tiles (uint32 tile indices, ty * across +
 *  tx, ascending), sr_adaptive_active_tiles of them. */
sluice_stream *sr_adaptive_tile_list(sr_adaptive *a);

/** Tiles in the list. */
size_t sr_adaptive_active_tiles(const sr_adaptive *a);

/** Pixels of the active tiles (edge tiles may be partial). */
size_t sr_adaptive_active_pixels(const sr_adaptive *a);

/** Samples per tile (sr_film_resolve_tiles), including a sample begun and
 *  not finished. */
const uint32_t *sr_adaptive_tile_samples(const sr_adaptive *a);

/**
 * After a sample: when a check is due (see above), resolves `film`, takes
 * the estimates, stops converged tiles (adaptive) and uploads the new list.
 * `*checked` (may be NULL) says whether it did. Errors are the context's or
 * SLUICE_ERROR_OUT_OF_MEMORY.
 */
sluice_status sr_adaptive_check(sr_adaptive *a, sr_film *film, int *checked);

/** Non-zero once the image's estimate reached the target, or no tile is
 *  left taking samples. */
int sr_adaptive_done(const sr_adaptive *a);

/** What it did so far. */
const sr_adaptive_stats *sr_adaptive_statistics(const sr_adaptive *a);

/** Fills `img` (RGB, the film's size) with each pixel's samples over the
 *  most any tile took, in [0, 1] (grey): a picture of where the samples
 *  went. SLUICE_ERROR_INVALID_ARGUMENT for an image of another size. */
sluice_status sr_adaptive_sample_map(const sr_adaptive *a, sr_image *img);

/** Prints a "sampling:" line (nothing without a target): the target, the
 *  tiles stopped and pixel samples skipped, the estimate and what it would
 *  have been had every tile taken every sample, the checks' cost. */
void sr_adaptive_print(const sr_adaptive_stats *s, FILE *out);

/** Writes the same as a JSON member, `"sampling": {...}` (no comma around
 *  it), at `indent` spaces. */
void sr_adaptive_write_json(const sr_adaptive_stats *s, FILE *out, int indent);

#endif /* SR_ADAPTIVE_H */
