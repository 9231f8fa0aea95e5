/* The renderers' OpenCL sources (kernels/render/, kernels/raytrace/,
 * kernels/photonmap/), embedded once into the render layer at build time
 * (tools/embed_kernels.py --function), and programs built from them. */
#ifndef SLUICE_RT_KERNELS_H
#define SLUICE_RT_KERNELS_H

#include "sluice/sluice.h"

#include <stddef.h>

/** The text of the embedded source with base name `name` ("grid.cl"), or
 *  NULL when there is none. Generated. */
const char *sr_kernel_text(const char *name);

/**
 * Creates a program from embedded sources concatenated in the order given
 * (e.g. a header shared with the C code first, then the kernels), each
 * preceded by a #line directive so that compile errors name the right file
 * and line. `options` are OpenCL build options (may be NULL); the program is
 * built lazily by the runtime, when its first kernel is created.
 */
sluice_status sr_program_create(sluice_context *ctx, const char *const *names, size_t count,
                                const char *options, sluice_program **out);

/**
 * Creates the program of a module without build options of its own (the
 * device grid build, the point grid, the kNN search, the photon mapper's
 * gather): on CPU devices the program they all share, their sources as one
 * text, the same for every module; elsewhere the module's own sources
 * (`names`, `count`, as sr_program_create takes them). PoCL runs its front
 * end over its OpenCL headers for every program it builds, warm cache or not
 * (about 25 ms a program), so one program for four modules costs one such
 * run, and since the text is the same, the context's kept programs
 * (sluice_program_build) give every module after the first the program
 * already built. GPU drivers compile every kernel of a program when they
 * build it, so there each module keeps its own. `options` (may be NULL) are
 * the scene's layout defines where a module needs them (-DRT_WATERTIGHT);
 * modules that do not pass NULL.
 */
sluice_status sr_shared_program_create(sluice_context *ctx, const char *const *names, size_t count,
                                       const char *options, sluice_program **out);

#endif /* SLUICE_RT_KERNELS_H */
