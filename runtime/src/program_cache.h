/* Programs built in a context, kept for the next build of the same text.
 *
 * Objects that are rebuilt often (a tracer made anew for each view, a photon
 * map for each pass) create their programs again each time, with the same
 * source and options. Building one costs the compiler's front end every
 * time, even where the driver caches what it compiled: PoCL preprocesses the
 * whole text to find its cache entry, tenths of a second for a renderer's
 * program. So a context keeps the programs it built, up to
 * SL_PROGRAM_CACHE_MAX of them (the least recently used goes first), each
 * with its build log, and a build of the same source with the same options
 * takes the kept cl_program (retained) instead: its kernels are created
 * afresh from it, so nothing a program's user holds is shared but the
 * compiled code. */
#ifndef SLUICE_PROGRAM_CACHE_H
#define SLUICE_PROGRAM_CACHE_H

#include "internal.h"

#define SL_PROGRAM_CACHE_MAX 32

/* One kept program: its key (the options, a NUL, the source), a hash of the
 * key, the program and its build log. */
typedef struct sl_kept_program {
    char *key;
    size_t key_len;
    unsigned long long hash;
    cl_program cl;
    char *log;
    unsigned long long used; /* the context's clock at the last use */
} sl_kept_program;

/* The kept program built from `source` with `options` (a new reference,
 * which the caller releases) and a copy of its log in *log (the caller
 * frees it), or NULL when none is kept (or out of memory). */
cl_program sl_program_cache_find(sluice_context *ctx, const char *options, const char *source,
                                 char **log);

/* Keeps `prog` (retained), built from `source` with `options`, and its log;
 * out of memory, it keeps nothing (a later build compiles again). */
void sl_program_cache_add(sluice_context *ctx, const char *options, const char *source,
                          cl_program prog, const char *log);

/* Releases every kept program and frees the list (the context's
 * destruction). */
void sl_program_cache_clear(sluice_context *ctx);

#endif
