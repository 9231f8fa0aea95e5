/*
 * Purcell's photon mapper (thesis ch. 6) on the render layer: photons traced
 * as streams through the scene's tracer (photons.h), a photon map that is a
 * uniform grid over the stored photons, built by bitonic sort, stencil
 * routing or counting sort (point_grid.h), and images from the ray tracer's
 * Whitted integrator (eye rays, mirrors and glass followed, direct light by
 * shadow rays) plus the kNN-grid radiance estimate at every diffuse hit
 * (knn.h) for indirect light and caustics (6.2.4).
 *
 * Same seed, same image, bit for bit: photon and eye-path random numbers are
 * hashes of (seed, index, dimension), every output whose order matters is
 * ordered, and pixels accumulate in fixed point.
 */
#ifndef PM_PHOTONMAP_H
#define PM_PHOTONMAP_H

#include "film.h"
#include "knn.h"
#include "photons.h"
#include "point_grid.h"
#include "render.h"
#include "tracer.h"

/**
 * Receives an intermediate image (Purcell 6.3.4): the film so far plus every
 * radiance estimate of the current gather step as it stands after one kNN
 * pass (queries still searching show the photons found so far). `index`
 * counts the images of the render from 0. A non-OK return stops the render
 * with that status; `err` then says why.
 */
typedef sluice_status (*pm_pass_image_fn)(void *user, const sr_image *img, unsigned index,
                                          char *err, size_t err_size);

/** What to render. */
typedef struct pm_options {
    unsigned width, height;
    uint32_t seed;
    unsigned light_samples;       /**< shadow rays per area light and hit */
    unsigned max_depth;           /**< mirror/glass chain of eye rays, photon bounces */
    uint32_t photons;             /**< photons to store */
    uint32_t k;                   /**< photons sought per estimate */
    float max_radius;             /**< 0: chosen from the photon density (pm_max_radius_auto) */
    sr_point_grid_build_kind map; /**< how the photon map is built */
    uint32_t slots;               /**< stencil: places per cell (m^2; Purcell's m = 16) */
    uint32_t grid_dims[3];        /**< photon-map grid; all 0: chosen from count and radius */
    pm_knn_mode knn;              /**< atleast (Purcell) or exact (Jensen) */
    uint32_t shells_per_pass;     /**< kNN shells per pass (pm_knn_options) */
    rt_tracer_options tracer;     /**< the tracer's options */
    pm_pass_image_fn pass_image;  /**< NULL, or called after every kNN pass */
    void *pass_image_user;        /**< passed to pass_image */
    /** Non-zero: progressive photon mapping (Hachisuka et al. 2009, in Knaus
     *  and Zwicker's 2011 form): every sample traces new photons, rebuilds the
     *  map and estimates with a radius search of radius r_i, where r_0 is
     *  max_radius when set, else the geometric mean of two radii of k
     *  photons: around the photons themselves (median) and spread evenly, and
     *  r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1); the image is the mean of the
     *  samples, and its bias and noise both vanish as samples grow. */
    int progressive;
    float alpha; /**< progressive radius reduction, 0 < alpha < 1 (2/3) */
    /** Adaptive sampling and the target error of the eye pass (adaptive.h):
     *  tiles that stopped take no eye rays and no radiance estimates. */
    sr_adaptive_options sampling;
    /** The photon map's layout (point_grid.h): SR_POINT_GRID_LAYOUT_AUTO (the
     *  default), SR_POINT_GRID_DENSE or SR_POINT_GRID_HASHED. Only the
     *  progressive radius search reads a hashed map (Purcell 6.4.4): auto
     *  takes the hash there (sr_point_grid_plan_auto), and the dense grid
     *  everywhere else, for the k-nearest searches, the stencil build and
     *  --grid dimensions. Asking for the hash
     *  where it cannot serve is an error of pm_renderer_create. */
    sr_point_grid_layout photon_grid;
} pm_options;

/** Defaults: 512x384, seed 1, 1 light sample, depth 5, 16,000 photons,
 *  k = 64, automatic radius and grid, count build, 256 slots, atleast, not
 *  progressive (alpha 2/3 when it is), automatic photon-map layout. */
pm_options pm_options_default(void);

/** Figures of a render (Purcell Table 6.1's phases and more). */
typedef struct pm_stats {
    pm_photon_stats photons;
    sr_point_grid_stats map;
    rt_grid_desc map_grid;            /**< the last map's grid (all zero when hashed) */
    sr_point_grid_layout map_layout;  /**< the layout of the last map the estimates used */
    sr_point_hash_desc map_hash;      /**< the last map's lattice and table (zero when dense) */
    unsigned maps_dense, maps_hashed; /**< maps the estimates used, per layout (progressive:
                                          one per sample) */
    char map_why[256];                /**< why the last map has its layout */
    float max_radius;                 /**< the maximum search radius used */
    double trace_photons_s;           /**< Table 6.1 phases, host wall time */
    double build_map_s;
    double trace_rays_s; /**< eye, specular and shadow rays and their shading */
    double estimate_s;   /**< the radiance estimates */
    uint64_t queries;    /**< radiance estimates */
    uint64_t found;      /**< photons used, summed over estimates */
    double radius_sum;   /**< radius summed over estimates with photons */
    uint64_t with_photons, hit_max_radius, nonfinite;
    unsigned knn_passes;                /**< kNN passes, all estimates */
    uint32_t live[PM_KNN_STATS_PASSES]; /**< live queries after kNN pass i (summed) */
    unsigned samples;
    float radius;         /**< progressive: the radius of the last sample's search */
    float radius0;        /**< progressive: the first sample's */
    unsigned pass_images; /**< intermediate images handed to pm_options.pass_image */
    double pass_images_s; /**< their cost, left out of the phases above */
} pm_stats;

typedef struct pm_renderer pm_renderer;

/** Creates the photon mapper for `scene` on `ctx` (both must outlive it):
 *  the tracer, photon tracing, map builder, search and the Whitted renderer.
 *  On failure `*out` is NULL and `err` says why. */
sluice_status pm_renderer_create(sluice_context *ctx, const sr_scene *scene, const pm_options *opt,
                                 pm_renderer **out, char *err, size_t err_size);

/** Frees it (NULL is fine). */
void pm_renderer_destroy(pm_renderer *r);

/** Traces the photons and builds the photon map (once per image; the first
 *  sample does it when not called before). */
sluice_status pm_renderer_prepare(pm_renderer *r, char *err, size_t err_size);

/** Renders one more sample per pixel (eye rays jittered after the first).
 *  Errors go to `err`. */
sluice_status pm_renderer_sample(pm_renderer *r, char *err, size_t err_size);

/** The film (scale 1 / samples). */
sr_film *pm_renderer_film(pm_renderer *r);

/** The tracer (its statistics count eye, shadow, specular and photon rays). */
rt_tracer *pm_renderer_tracer(pm_renderer *r);

/** The Whitted renderer underneath (its ray and shading statistics). */
rt_renderer *pm_renderer_whitted(pm_renderer *r);

/** Statistics so far. */
const pm_stats *pm_renderer_stats(const pm_renderer *r);

/** The photon map (for tests): the photon stream and its count, and the
 *  grid built over it. Valid after pm_renderer_prepare. */
sluice_stream *pm_renderer_photons(pm_renderer *r, size_t *count);
const sr_point_grid *pm_renderer_map(const pm_renderer *r);

/** What was skipped for this scene, as one list (sr_skipped_add). */
const char *pm_renderer_skipped(pm_renderer *r);

#endif /* PM_PHOTONMAP_H */
