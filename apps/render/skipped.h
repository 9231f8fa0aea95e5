/*
 * What a renderer skipped because the scene or the mode does not need it
 * (kernels not compiled, passes not run, photons not traced): a text list
 * such as "refraction code (no glass); shadow pass (no lights)" that the
 * statistics print, so a user sees what was left out and why.
 */
#ifndef SR_SKIPPED_H
#define SR_SKIPPED_H

#include <stddef.h>

/** Appends `what` to the list in `list` (a NUL-terminated text in a buffer
 *  of `size` bytes), separated by "; ", when `cond` is non-zero. An item
 *  that does not fit is left out whole. */
void sr_skipped_add(char *list, size_t size, int cond, const char *what);

#endif /* SR_SKIPPED_H */
