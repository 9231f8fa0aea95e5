/* Helpers shared by the stream algorithms in streams/ (internal). */
#ifndef SLUICE_STREAMS_COMMON_H
#define SLUICE_STREAMS_COMMON_H

#include "internal.h"

/* Checks a uint32 stream argument of `fn`: `s` must belong to `ctx` and hold
 * 4-byte records; `what` names the argument in the error message. When `n`
 * is not NULL, also returns the stream's length in *n; a stream that
 * overflowed (its length past its capacity) is SLUICE_ERROR_OVERFLOW. */
sluice_status sl_check_u32_stream(sluice_context *ctx, sluice_stream *s, const char *fn,
                                  const char *what, size_t *n);

/* Reads the 4-byte `value` at index `at` of `buf` and the overflow flag
 * after it in one read (scan.cl and reduce.cl write both). A set flag means
 * that the input `in` overflowed: SLUICE_ERROR_OVERFLOW, its message starting
 * with `fn`, and `value` is not written. `what` names the value read. */
sluice_status sl_read_flagged(sluice_context *ctx, cl_mem buf, size_t at, void *value,
                              sluice_stream *in, const char *fn, const char *what);

/* Sets arguments 0 .. count-1 of kernel `k` (named `name` in the error
 * message) from `sizes` and `values`; stops at the first failure. */
sluice_status sl_set_args(sluice_context *ctx, cl_kernel k, const char *name, unsigned count,
                          const size_t *sizes, const void *const *values);

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
