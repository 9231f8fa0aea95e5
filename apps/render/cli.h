/*
 * Command-line parsing shared by the renderers: the options every renderer
 * takes (scene, size, output, statistics, seed, progress, checkpoints, time
 * budget, device, profiling) parsed one way, and the helpers each renderer
 * uses for its own options, so that every bad value gets the same kind of
 * message: "PROG: --opt VALUE: why (see --help)" and exit status 2.
 */
#ifndef SR_CLI_H
#define SR_CLI_H

#include "adaptive.h"
#include "scene.h"
#include "sluice/sluice.h"

#include <stdio.h>

/** The options common to the renderers. */
typedef struct sr_cli_common {
    const char *scene;      /**< --scene (default "cornell") */
    const char *out;        /**< --out (default "out.png"): .png, .exr or .hdr */
    const char *stats;      /**< --stats FILE (JSON), or NULL */
    const char *sample_map; /**< --sample-map FILE (image), or NULL */
    const char *device;     /**< --device substring, or NULL */
    unsigned width, height; /**< --size; 0: the scene camera's */
    unsigned seed;          /**< --seed (default 1) */
    unsigned checkpoint;    /**< --checkpoint N; 0: none */
    double time_limit;      /**< --time SECONDS; 0: none */
    double target_error;    /**< --target-error E (relMSE); 0: none */
    int adaptive;           /**< 0 after --no-adaptive (1 by default) */
    unsigned min_samples;   /**< --min-spp N before adaptive checks; 0: 8 */
    int progress;           /**< --progress */
    int profile;            /**< 1 unless --no-profile */
    int quiet;              /**< --quiet */
    int no_image;           /**< --no-image: render and report, write no image */
    int out_given;          /**< --out was given */
} sr_cli_common;

/** Fills the defaults. */
void sr_cli_common_init(sr_cli_common *c);

/**
 * Parses argv[*i] if it is a common option, taking its value from
 * argv[*i + 1] (and advancing *i past it). Returns 1 when it was one, 0 when
 * it is not a common option (the caller tries its own), 2 after printing a
 * message for a bad or missing value.
 */
int sr_cli_common_parse(const char *prog, int argc, char **argv, int *i, sr_cli_common *c);

/** Checks what can only be checked once all options are read (the output's
 *  extension; --no-image with an option that writes an image). 0 when fine,
 *  2 after printing a message. */
int sr_cli_common_finish(const char *prog, const sr_cli_common *c);

/** Checks, before any rendering, that a file can be written at `path`
 *  (given to option `opt`): its folder exists and is writable, and the path
 *  is not a folder or a read-only file. 0, or sr_cli_bad's exit status
 *  after saying why (the file itself is not created). */
int sr_cli_output_path(const char *prog, const char *opt, const char *path);

/** Checks that an image path given to option `opt` ends in .png, .exr or
 *  .hdr and can be written (sr_cli_output_path): 0, or sr_cli_bad's exit
 *  status after saying why. */
int sr_cli_image_path(const char *prog, const char *opt, const char *path);

/** Loads c->scene (a built-in name or a file; a default light is added to a
 *  scene without one). A bare file name that does not exist in the current
 *  folder is also looked up in the installed scenes folder
 *  (<datadir>/sluice/scenes, relative to the program) and then in the source
 *  tree's scenes/. 0 on success, else 1 after printing
 *  "PROG: --scene NAME: why". */
int sr_cli_load_scene(const char *prog, const sr_cli_common *c, sr_scene **out);

/** The sampling options of sr_adaptive (adaptive.h) that --target-error,
 *  --no-adaptive and --min-spp give. */
sr_adaptive_options sr_cli_sampling(const sr_cli_common *c);

/** Creates the OpenCL context for --device and --no-profile. 0 on success,
 *  else 1 after printing "PROG: OpenCL: why". */
int sr_cli_context(const char *prog, const sr_cli_common *c, sluice_context **out);

/** Loads the image module (image.h) now: 0, or 1 after printing
 *  "PROG: --out FILE: why", so that a program fails before rendering rather
 *  than lose its image. With --no-image it loads nothing and returns 0. */
int sr_cli_images_ready(const char *prog, const sr_cli_common *c);

/** Prints the common options' lines of --help. */
void sr_cli_common_usage(FILE *out);

/** Prints "PROG: OPT VALUE: WHY (see --help)" to stderr and returns 2. */
int sr_cli_bad(const char *prog, const char *opt, const char *value, const char *why);

/** Parses a whole decimal number in [lo, hi]; 1 on success. */
int sr_cli_uint(const char *s, unsigned lo, unsigned hi, unsigned *out);

/** Parses a finite number in [lo, hi]; 1 on success. */
int sr_cli_double(const char *s, double lo, double hi, double *out);

/** Parses "WxH" (1 .. 16384 per side, at most 2^26 pixels); 1 on success,
 *  0 with `*why` set otherwise. */
int sr_cli_size(const char *s, unsigned *w, unsigned *h, const char **why);

/** Parses a value among `names` (NULL-terminated); the index, or -1. */
int sr_cli_choice(const char *s, const char *const *names);

#endif /* SR_CLI_H */
