/*
 * Whole images with the tracer: eye rays from the scene's pinhole camera,
 * waves of rays through tracing and shading (Purcell Fig. 3.1), samples that
 * accumulate per pixel (progressive rendering).
 *
 * One sample: eye rays -> trace -> shade; shading emits shadow rays (traced
 * and resolved at once) and secondary rays (reflection, refraction, path
 * bounces), which form the next wave, until none are left or the depth
 * limit is reached. Nothing recurses.
 *
 * Determinism: random numbers are a hash of (seed, pixel, sample, bounce,
 * dimension), and pixels accumulate in 64-bit fixed point with integer
 * atomics, so the same options give the same image bit for bit whatever
 * order rays finish in.
 */
#ifndef SLUICE_RT_RENDER_H
#define SLUICE_RT_RENDER_H

#include "adaptive.h"
#include "image.h"
#include "camera.h"
#include "film.h"
#include "tracer.h"

/** What to render. */
typedef struct rt_render_options {
    unsigned mode;          /**< RT_MODE_* */
    unsigned width, height; /**< image size */
    unsigned max_depth;     /**< bounces (whitted, path) */
    unsigned light_samples; /**< shadow rays per area light and hit */
    uint32_t seed;
    /** Whitted mode only, may be NULL: called once a sample, after its last
     *  wave, with the gather points (rt_gather records, device stream, `n` of
     *  them) of the diffuse and glossy hits of all its waves, so that a
     *  caller adds what the shading does not know (the photon mapper's
     *  radiance estimate) to the film before the sampling check reads it and
     *  the stream is reused. Returning an error stops the sample. */
    sluice_status (*gather)(void *user, sluice_stream *points, size_t n);
    void *gather_user;
    /** Adaptive sampling and the target error (adaptive.h); all zero:
     *  every pixel takes every sample. */
    sr_adaptive_options sampling;
} rt_render_options;

/** Per-kind ray counts and shading work (Purcell Table 5.2). */
typedef struct rt_render_stats {
    uint64_t rays[RT_KIND_COUNT]; /**< rays made, by RT_KIND_* */
    uint64_t shades;              /**< shading calculations (hits shaded) */
    uint64_t nonfinite;           /**< contributions dropped as NaN or Inf */
    unsigned samples;             /**< samples done (by the tiles that took most) */
    unsigned waves;               /**< ray waves traced (eye + secondary) */
    size_t stream_bytes;          /**< device bytes of the ray, hit and image streams */
} rt_render_stats;

typedef struct rt_renderer rt_renderer;

/** Creates a renderer over `tracer` (which must outlive it). */
sluice_status rt_renderer_create(rt_tracer *tracer, const rt_render_options *opt, rt_renderer **out,
                                 char *err, size_t err_size);

/** Frees it (NULL is fine). */
void rt_renderer_destroy(rt_renderer *r);

/** Renders one more sample per pixel of the tiles still taking samples
 * (all of them without adaptive sampling), then checks the estimate when
 * one is due (sr_adaptive_check). Does nothing once rt_renderer_done. Errors
 * are the context's. */
sluice_status rt_renderer_sample(rt_renderer *r);

/** Non-zero once the target error is reached (never without one). */
int rt_renderer_done(const rt_renderer *r);

/** Writes the mean of each pixel's samples so far into `img` (RGB, the
 *  renderer's size). Counts pixels that would not be finite (none should
 *  be) in `*bad_pixels` (may be NULL) and writes 0 there instead. */
sluice_status rt_renderer_image(rt_renderer *r, sr_image *img, size_t *bad_pixels);

/** rt_renderer_image written to `path` (.png, .exr, .hdr; NULL: only its
 *  non-finite pixels counted); `err` says why it failed. */
sluice_status rt_renderer_write(rt_renderer *r, const char *path, size_t *bad_pixels, char *err,
                                size_t err_size);

/** Writes where the samples went (sr_adaptive_sample_map) to `path` (.png,
 *  .exr, .hdr); `err` says why it failed. */
sluice_status rt_renderer_write_sample_map(rt_renderer *r, const char *path, char *err,
                                           size_t err_size);

/** Samples per tile so far (sr_film_resolve_tiles). */
const uint32_t *rt_renderer_tile_samples(const rt_renderer *r);

/** What adaptive sampling did (the estimates, the work skipped). */
const sr_adaptive_stats *rt_renderer_sampling(const rt_renderer *r);

/** The film the samples accumulate in (its scale is 1 / samples). */
sr_film *rt_renderer_film(rt_renderer *r);

/** What the renderer left out for this scene and mode (sr_skipped_add),
 *  e.g. "refraction code (no glass)"; the tracer's list is separate
 *  (rt_tracer_skipped). */
const char *rt_renderer_skipped(const rt_renderer *r);

/** Statistics so far. */
const rt_render_stats *rt_renderer_stats(const rt_renderer *r);

#endif
