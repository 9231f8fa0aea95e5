/*
 * Photon tracing as streams (Purcell 6.2.1): photons leave the lights, go
 * through the scene's tracer as rays of kind RT_KIND_PHOTON, and each bounce
 * is a pass over the photon stream with conditional outputs (stored,
 * bounced; the rest dropped), the loop stopping on an empty stream. Batches
 * of photons are emitted until the stored count reaches the target; stored
 * powers are then divided by the number emitted (flux per photon, Phi / N).
 *
 * Conventions are those of <sluice/sluice.h>: functions return a
 * sluice_status, never abort or print; messages go to `err`.
 */
#ifndef PM_PHOTONS_H
#define PM_PHOTONS_H

#include "tracer.h"

#include "../../kernels/photonmap/pm_types.h"

#include <stddef.h>
#include <stdint.h>

/** What to trace. */
typedef struct pm_photon_options {
    uint32_t target;    /**< photons to store (at least; the last batch may add a few) */
    unsigned max_depth; /**< most bounces of a photon (0: stored nowhere) */
    uint32_t seed;
    int no_projection; /**< 1: every photon leaves as its light emits, none
                            sent toward the mirrors and glass (Jensen's
                            projection map off; for tests and comparisons) */
} pm_photon_options;

/** What tracing did (the statistics of Purcell's "trace photons" phase). */
typedef struct pm_photon_stats {
    uint64_t emitted;     /**< photons that left the lights */
    uint64_t stored;      /**< photons stored (the map's size) */
    uint64_t caustic;     /**< of those, after mirrors and glass only */
    uint64_t bounced;     /**< bounces traced after the first flight */
    uint64_t left_scene;  /**< flights that hit nothing (dropped at once) */
    uint64_t absorbed;    /**< ended by Russian roulette or a black surface */
    uint64_t depth_limit; /**< ended by the depth limit */
    uint64_t nonfinite;   /**< dropped for a non-finite power */
    unsigned passes;      /**< bounce passes over all batches */
    unsigned batches;     /**< emission batches */
    double seconds;       /**< host wall time, waited for */
    char skipped[256];    /**< what was not traced and why (sr_skipped_add) */
} pm_photon_stats;

typedef struct pm_photons pm_photons;

/** Creates photon tracing over `tracer` (which must outlive it): its
 *  program and kernels, built for the tracer's scene. */
sluice_status pm_photons_create(rt_tracer *tracer, pm_photons **out, char *err, size_t err_size);

/** Frees it and its streams (NULL is fine). */
void pm_photons_destroy(pm_photons *p);

/**
 * Traces photons until `opt->target` are stored (or, when the scene stores
 * too few, until 256 times the target plus 2^20 have been emitted: the
 * statistics say so). Powers are Phi / N. `*photons` receives the
 * pm_photon stream (owned by `p`, valid until the next call) and `*count`
 * its length. A scene without lights stores nothing (the statistics say
 * so). Errors are the context's (sluice_context_error).
 */
sluice_status pm_photons_trace(pm_photons *p, const pm_photon_options *opt, sluice_stream **photons,
                               size_t *count, pm_photon_stats *stats);

#endif /* PM_PHOTONS_H */
