/*
 * The progressive loop every renderer runs: steps (samples per pixel for the
 * ray tracer, passes for the photon mapper) repeated until the count or the
 * time budget is reached, with a progress bar and ETA, checkpoint images
 * every N steps, and Ctrl-C (SIGINT) turned into a request to stop after the
 * current step, so that the image so far is written before the program
 * exits (with status 130, by the caller's hand).
 */
#ifndef SR_PROGRESSIVE_H
#define SR_PROGRESSIVE_H

#include "image.h"
#include "sluice/sluice.h"

#include <stdio.h>

/** One step of the render (a sample, a pass). */
typedef sluice_status (*sr_step_fn)(void *user);

/** Writes the image so far (a checkpoint). */
typedef sluice_status (*sr_checkpoint_fn)(void *user);

/** After a step, with a target error: writes the render's latest estimate of
 *  its relMSE (-1 while it has none) and returns non-zero once the target is
 *  reached (e.g. rt_renderer_done and sr_adaptive_stats.error). */
typedef int (*sr_estimate_fn)(void *user, double *error);

/** How to run the loop. */
typedef struct sr_progressive {
    const char *unit;    /**< what a step is, plural: "samples", "passes" */
    unsigned total;      /**< steps to do (at least 1) */
    double time_limit;   /**< seconds; 0: none. Stops after the step that
                              reaches it (at least one step runs). */
    unsigned checkpoint; /**< call `checkpoint` every this many steps; 0: never */
    int progress;        /**< report progress on `out` */
    FILE *out;           /**< where progress goes (stderr when NULL) */
    /** The target relMSE the render was given (0: none), for the report;
     *  with one, `estimate` (required then) is asked after every step
     *  whether it is reached (the render estimates its own error: see
     *  adaptive.h). */
    double target_error;
    sr_estimate_fn estimate;
} sr_progressive;

/** How the loop went. */
typedef struct sr_progressive_result {
    unsigned done;   /**< steps done */
    double seconds;  /**< wall time of the steps (and checkpoints) */
    int interrupted; /**< stopped by Ctrl-C */
    int out_of_time; /**< stopped by the time limit */
    int converged;   /**< stopped at the target error */
    double error;    /**< the last error estimate (-1: none taken) */
} sr_progressive_result;

/**
 * Runs `step` until p->total steps are done, the time limit is reached or
 * Ctrl-C is pressed, calling `checkpoint` (may be NULL) every p->checkpoint
 * steps except after the last. Returns the first status other than
 * SLUICE_OK that a callback returned (the loop stops there); `*res` is
 * filled in any case. Installs the SIGINT handler (sr_progress_install_sigint).
 */
sluice_status sr_progressive_run(const sr_progressive *p, sr_step_fn step,
                                 sr_checkpoint_fn checkpoint, void *user,
                                 sr_progressive_result *res);

/** With a target error, says on `out` where the render stopped: the last
 *  estimate, after how many steps, and whether it reached the target. */
void sr_progressive_report_target(const char *prog, const sr_progressive *p,
                                  const sr_progressive_result *res, FILE *out);

/** Installs the SIGINT handler (the first Ctrl-C asks to stop; a second one
 *  gets the default action and ends the program at once). The flag it sets
 *  is the one piece of process-wide state in the renderers: a signal handler
 *  has nowhere else to write. */
void sr_progress_install_sigint(void);

/** Non-zero once Ctrl-C was pressed. */
int sr_progress_interrupted(void);

/** Reports `done` of `total` `unit` after `seconds` to `out`: a redrawn bar
 *  when `out` is a terminal, else a plain line. With a time limit (> 0) the
 *  bar and ETA follow whichever of the two ends the run first. */
void sr_progress_report(FILE *out, const char *unit, unsigned done, unsigned total, double seconds,
                        double time_limit);

/** Ends the bar's line on a terminal. */
void sr_progress_finish(FILE *out);

#endif /* SR_PROGRESSIVE_H */
