/* Helpers shared by the stream algorithms in streams/ (internal). */
#ifndef SLUICE_STREAMS_COMMON_H
#define SLUICE_STREAMS_COMMON_H

#include "internal.h"

/* Checks a uint32 stream argument of `fn`: `s` must belong to `ctx` and hold
 * 4-byte records; `what` names the argument in the error message. When `n`
 * is not NULL, also returns the stream's length in *n, capped at its
 * capacity (an overflowed output: only the stored records count). */
sluice_status sl_check_u32_stream(sluice_context *ctx, sluice_stream *s, const char *fn,
                                  const char *what, size_t *n);

/* Sets arguments 0 .. count-1 of kernel `k` (named `name` in the error
 * message) from `sizes` and `values`; stops at the first failure. */
sluice_status sl_set_args(sluice_context *ctx, cl_kernel k, const char *name, unsigned count,
                          const size_t *sizes, const void *const *values);

/* Sets argument `i` of `k` unless `*err` already holds an error, and keeps
 * the first error in `*err`. */
void sl_set_arg(cl_kernel k, cl_uint i, size_t size, const void *value, cl_int *err);

/* Argument lists for sl_set_args: sizes, then pointers to the values. */
#define SIZES(...)                                                                                 \
    (const size_t[])                                                                               \
    {                                                                                              \
        __VA_ARGS__                                                                                \
    }
#define VALUES(...)                                                                                \
    (const void *const[])                                                                          \
    {                                                                                              \
        __VA_ARGS__                                                                                \
    }

#endif
