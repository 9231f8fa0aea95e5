/*
 * Sluice stream algorithms: scan, reduce, compaction and split, sorting, cell
 * indexing and bounded routing, over streams made with <sluice/sluice.h>.
 *
 * All functions queue their work on the context's queue and return once it
 * is queued, except where a result comes back to the host (reduce), which
 * waits. Inputs are read from position 0 up to the stream's length. Outputs
 * are overwritten (not appended) and their lengths set, unless said
 * otherwise. Scratch memory is allocated per call and released before return
 * (OpenCL keeps it alive until the queued work is done).
 *
 * An input that overflowed (its length past its capacity) is never read as
 * truncated: a function that reads the length on the host returns
 * SLUICE_ERROR_OVERFLOW naming where the overflow happened; one that only
 * queues work (compaction, split, partition, scan without a total) makes its
 * outputs void, so reading them reports the same overflow. An output too
 * small for the result is SLUICE_ERROR_OVERFLOW as well.
 */
#ifndef SLUICE_STREAMS_H
#define SLUICE_STREAMS_H

#include "sluice/sluice.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Element type of scalar streams (record size 4). */
typedef enum sluice_scalar_type {
    SLUICE_U32 = 0, /**< uint32_t, wrapping arithmetic */
    SLUICE_F32 = 1  /**< float */
} sluice_scalar_type;

/** Reduction operators. */
typedef enum sluice_reduce_op { SLUICE_SUM = 0, SLUICE_MIN = 1, SLUICE_MAX = 2 } sluice_reduce_op;

/** The stream algorithms, as bits of sluice_streams_prepare()'s mask. */
typedef enum sluice_algorithm {
    SLUICE_ALG_SCAN = 1u << 0,         /**< sluice_scan */
    SLUICE_ALG_REDUCE = 1u << 1,       /**< sluice_reduce */
    SLUICE_ALG_COMPACT = 1u << 2,      /**< sluice_compact, sluice_split, sluice_partition */
    SLUICE_ALG_SORT_BITONIC = 1u << 3, /**< sluice_sort_bitonic */
    SLUICE_ALG_SORT_RADIX = 1u << 4,   /**< sluice_sort_radix */
    SLUICE_ALG_CELL_INDEX = 1u << 5,   /**< sluice_cell_index_search and _count */
    SLUICE_ALG_ROUTE = 1u << 6,        /**< sluice_route_bounded */
    SLUICE_ALG_ALL = (1u << 7) - 1u    /**< every one */
} sluice_algorithm;

/** Builds the kernels of the algorithms in `algorithms` (a mask of
 *  sluice_algorithm bits) now, as the first call of each would have; later
 *  calls find them built. For setup code: a renderer's first frame, or a
 *  benchmark's first run, then does not pay for the builds (tens of
 *  milliseconds each from PoCL's kernel cache, seconds cold). On CPU
 *  devices the algorithms share one program, with the runtime's own kernels
 *  (the ordered outputs' scan), so preparing any of them builds them all at
 *  once. Optional: without it each algorithm builds its kernels on first
 *  use. Unknown bits are SLUICE_ERROR_INVALID_ARGUMENT. */
sluice_status sluice_streams_prepare(sluice_context *ctx, unsigned algorithms);

/** Prefix sum of a scalar stream into `out` (capacity >= input length; may
 *  not be `in`). Exclusive: out[i] = in[0] + ... + in[i-1], out[0] = 0.
 *  Inclusive: out[i] = in[0] + ... + in[i]. If `total` is not NULL it
 *  receives the sum of all records (waits for the result). */
sluice_status sluice_scan(sluice_context *ctx, sluice_stream *in, sluice_stream *out,
                          sluice_scalar_type type, int inclusive, void *total);

/** Reduces a scalar stream to one value written to `*result` (a uint32_t or
 *  a float). Waits for the result. An empty stream gives the identity: 0 for
 *  SUM, the largest value for MIN, the smallest for MAX. */
sluice_status sluice_reduce(sluice_context *ctx, sluice_stream *in, sluice_scalar_type type,
                            sluice_reduce_op op, void *result);

/** Copies into `out` the records of `in` whose uint32 flag in `flags` is
 *  non-zero. Records of any size that is a multiple of 4 bytes. ORDERED keeps
 *  input order. */
sluice_status sluice_compact(sluice_context *ctx, sluice_stream *in, sluice_stream *flags,
                             sluice_stream *out, sluice_output_mode mode);

/** Splits `in` into `count` (1 .. SLUICE_MAX_OUTPUTS) streams: record i goes
 *  to outs[bucket[i]]; records whose bucket is >= count are dropped. */
sluice_status sluice_split(sluice_context *ctx, sluice_stream *in, sluice_stream *buckets,
                           sluice_stream *const *outs, unsigned count, sluice_output_mode mode);

/** Partitions a scalar stream by a threshold: records < threshold go to
 *  `below`, the others to `above` (NaN goes to `above`). `threshold` points to
 *  a uint32_t or a float. */
sluice_status sluice_partition(sluice_context *ctx, sluice_stream *in, sluice_scalar_type type,
                               const void *threshold, sluice_stream *below, sluice_stream *above,
                               sluice_output_mode mode);

/** Sorts uint32 keys ascending in place with a bitonic merge sort (any length,
 *  not only powers of two; stages that fit in local memory run there). If
 *  `values` is not NULL its uint32 records are permuted along with the keys.
 *  Not stable. */
sluice_status sluice_sort_bitonic(sluice_context *ctx, sluice_stream *keys, sluice_stream *values);

/** Sorts uint32 keys ascending in place with an LSD radix sort, carrying
 *  uint32 `values` (may be NULL). Stable. Same interface as the bitonic sort. */
sluice_status sluice_sort_radix(sluice_context *ctx, sluice_stream *keys, sluice_stream *values);

/** Cell-start index of sorted keys (Purcell 6.2.2): for every cell c in
 *  0 .. cell_count, start[c] is the first position whose key is >= c, so the
 *  records of cell c are [start[c], start[c+1]). `start` gets cell_count + 1
 *  uint32 records. Found by one binary search per cell. Keys >= cell_count
 *  sort after the last cell. */
sluice_status sluice_cell_index_search(sluice_context *ctx, sluice_stream *sorted_keys,
                                       uint32_t cell_count, sluice_stream *start);

/** The same index built by counting: a histogram of the keys (which need not
 *  be sorted) and an exclusive scan. */
sluice_status sluice_cell_index_count(sluice_context *ctx, sluice_stream *keys, uint32_t cell_count,
                                      sluice_stream *start);

/** Bounded routing, the stencil-routing primitive of Purcell 6.2.2: each
 *  record of `values` (uint32 payloads) goes to bucket keys[i] (< bucket_count,
 *  others are dropped) which has `slots` places. `out` gets bucket_count *
 *  slots uint32 records: bucket b's payloads in out[b*slots ..], unused places
 *  0xffffffff. `fill[b]` is how many were stored (at most slots) and
 *  `overflow[b]` how many did not fit. Which records of an overfull bucket are
 *  kept is unspecified. */
sluice_status sluice_route_bounded(sluice_context *ctx, sluice_stream *keys, sluice_stream *values,
                                   uint32_t bucket_count, uint32_t slots, sluice_stream *out,
                                   sluice_stream *fill, sluice_stream *overflow);

/** sluice_route_bounded without the marks: only bucket b's first fill[b]
 *  places are written, the others keep what they held. Its cost is the
 *  places filled, not the footprint: a few occupied buckets of many (a
 *  photon map's cells, most of them empty) touch a few pages of `out`,
 *  where marking every place writes all of it. */
sluice_status sluice_route_bounded_sparse(sluice_context *ctx, sluice_stream *keys,
                                          sluice_stream *values, uint32_t bucket_count,
                                          uint32_t slots, sluice_stream *out, sluice_stream *fill,
                                          sluice_stream *overflow);

#ifdef __cplusplus
}
#endif

#endif /* SLUICE_STREAMS_H */
