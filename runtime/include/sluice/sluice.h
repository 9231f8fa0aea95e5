/*
 * Sluice: stream programming on OpenCL, in the model of Purcell's thesis
 * ("Ray Tracing on a Stream Processor", 2004, ch. 3 and 4.1.2).
 *
 * The whole host-side runtime API is in this header. The stream algorithms
 * (scan, split, sort, ...) have their own header, <sluice/streams.h>.
 *
 * Vocabulary
 *   context   one OpenCL device, one in-order queue, the profiler and a pool of
 *             small device-side variables (stream lengths and counters).
 *   stream    a device buffer of fixed-size records with a capacity and a
 *             length. The length lives on the device, so a kernel with
 *             conditional outputs can set it and the next pass can read it
 *             without a round trip to the host.
 *   program   OpenCL C source (a user's file or string, or one of the kernels
 *             embedded in the library), built lazily the first time one of its
 *             kernels is needed, and only once.
 *   kernel    one __kernel of a program whose parameters start with
 *             SLUICE_PARAMS and whose body is a SLUICE_FOR_EACH loop (see the
 *             kernel-side header sluice.cl). A launch runs the loop body once
 *             per record of its single input stream.
 *   output    a conditional output stream of a kernel: each input record emits
 *             zero or more records into it with SLUICE_EMIT / SLUICE_EMIT_IF.
 *             ORDERED outputs keep input order (stable); UNORDERED outputs
 *             append whole chunks in any order (one global atomic per chunk).
 *   counters  named uint32 counters that kernels bump with SLUICE_COUNT: the
 *             occlusion query of this world (Purcell 4.1.2).
 *   loop      runs a pass (a few launches) again and again while a counter or a
 *             stream length is non-zero, optionally asking an oracle which pass
 *             to run next from the current counts.
 *
 * Overflow
 *   An output stream that receives more records than its capacity keeps the
 *   ones that fit and a length past its capacity: it has overflowed, and that
 *   is always an error, never a silent truncation. Wherever the length is
 *   read (sluice_stream_length, sluice_stream_download, the watched values of
 *   a loop, the stream algorithms) the result is SLUICE_ERROR_OVERFLOW, and
 *   the message names the kernel, the output slot, the stream's capacity and
 *   the records emitted. A launch refuses an input whose length is known to
 *   be past its capacity; when the length is only on the device, the launch
 *   reads no records and makes its outputs (and the counters it counts into)
 *   *void*, so the overflow is reported wherever they are read next, with the
 *   same message. None of this costs a round trip: the checks ride on the
 *   reads that happen anyway.
 *
 * Conventions
 *   Every function that can fail returns a sluice_status; SLUICE_OK is 0.
 *   On failure the context keeps a readable message, sluice_context_error(),
 *   until the next call (which empties it first).
 *   Nothing in the library aborts or exits. Handles are opaque and come in
 *   create/destroy pairs; destroy functions accept NULL. Objects are not
 *   thread-safe: use one context per thread, or lock around it.
 */
#ifndef SLUICE_SLUICE_H
#define SLUICE_SLUICE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Status codes returned by every fallible function. */
typedef enum sluice_status {
    SLUICE_OK = 0,
    SLUICE_ERROR_INVALID_ARGUMENT = 1, /**< a NULL handle, a bad index or size */
    SLUICE_ERROR_NO_DEVICE = 2,        /**< no OpenCL device matched */
    SLUICE_ERROR_OUT_OF_MEMORY = 3,    /**< host or device allocation failed */
    SLUICE_ERROR_BUILD = 4,            /**< OpenCL C compile error; see the log */
    SLUICE_ERROR_NOT_FOUND = 5,        /**< no such kernel, file or name */
    SLUICE_ERROR_IO = 6,               /**< a file could not be read or written */
    SLUICE_ERROR_OVERFLOW = 7,         /**< an output stream ran out of capacity */
    SLUICE_ERROR_OPENCL = 8,           /**< an OpenCL call failed */
    SLUICE_ERROR_LIMIT = 9             /**< a fixed limit (pass limit, pool size) was hit */
} sluice_status;

/** A short English name for a status code ("invalid argument", ...). */
const char *sluice_status_string(sluice_status status);

/* ------------------------------------------------------------------ */
/* Devices and contexts                                                */
/* ------------------------------------------------------------------ */

/** What sluice_devices_list() reports about one OpenCL device. */
typedef struct sluice_device_info {
    char platform[128];         /**< platform name */
    char name[128];             /**< device name */
    char version[128];          /**< OpenCL C version string */
    int is_cpu;                 /**< 1 for CL_DEVICE_TYPE_CPU */
    unsigned compute_units;     /**< CL_DEVICE_MAX_COMPUTE_UNITS */
    size_t max_work_group_size; /**< CL_DEVICE_MAX_WORK_GROUP_SIZE */
    uint64_t global_mem_bytes;  /**< CL_DEVICE_GLOBAL_MEM_SIZE */
    uint64_t max_alloc_bytes;   /**< CL_DEVICE_MAX_MEM_ALLOC_SIZE */
    uint64_t local_mem_bytes;   /**< CL_DEVICE_LOCAL_MEM_SIZE */
    uint64_t cache_bytes;       /**< CL_DEVICE_GLOBAL_MEM_CACHE_SIZE (0: none reported) */
} sluice_device_info;

/**
 * Lists the OpenCL devices of all platforms. Writes up to `max` entries into
 * `out` (which may be NULL when max is 0) and the total number found into
 * `*count`. Returns SLUICE_ERROR_NO_DEVICE when there is no platform at all.
 */
sluice_status sluice_devices_list(sluice_device_info *out, size_t max, size_t *count);

/** How the work-items of a stream launch share out its records. */
typedef enum sluice_layout {
    /** By device type: contiguous on CPUs, interleaved elsewhere. */
    SLUICE_LAYOUT_AUTO = 0,
    /** Each work-item takes a contiguous chunk of records (work-groups of 8):
     *  on a CPU one work-item then runs like a C loop over its chunk. */
    SLUICE_LAYOUT_CONTIGUOUS = 1,
    /** Work-groups of up to 256 work-items take contiguous tiles, and within
     *  a tile work-item l takes records l, l + G, l + 2G, ... (G the group
     *  size), so neighbouring work-items read neighbouring records, as a GPU
     *  wants (coalesced loads). The work-items of a group reserve room for
     *  their unordered outputs together and take each emitted record's
     *  place from a counter in local memory, so records emitted side by side
     *  land side by side (their order within a group is not the input's).
     *  Ordered outputs are placed by the group in input order: one count per
     *  group is scanned, and the group takes its records in steps, each
     *  counted, scanned across the group, then written.
     *  SLUICE_FOR_EACH_RANGE keeps contiguous chunks per work-item. */
    SLUICE_LAYOUT_INTERLEAVED = 2
} sluice_layout;

/** Options for sluice_context_create(); zero-initialise, then set fields. */
typedef struct sluice_context_options {
    /** Case-insensitive substring of "platform name / device name" that picks
     *  the device. NULL: the environment variable SLUICE_DEVICE, and if that
     *  is unset, the first CPU device, then the first device of any type. */
    const char *device;
    /** Non-zero: time every launch with OpenCL events and keep per-kernel
     *  statistics (sluice_profile_print). Also enabled by SLUICE_PROFILE=1. */
    int profile;
    /** Records each work-item handles in one launch (0: chosen per launch
     *  from the stream size). Larger chunks mean fewer atomics. Also set
     *  by SLUICE_CHUNK=N, for measuring. */
    unsigned chunk;
    /** Non-zero: build every program with SLUICE_NO_SIMD defined, so kernels
     *  use only portable OpenCL C and no device-specific fast paths (see
     *  SLUICE_EMIT16 in sluice.cl). Also enabled by SLUICE_NO_SIMD=1. */
    int no_simd;
    /** Non-zero: every program build prints its compiler log (warnings
     *  included) and the compiler's own output on stderr. Otherwise a build
     *  that succeeds prints nothing: its warnings stay in
     *  sluice_program_build_log(). Also enabled by SLUICE_VERBOSE=1. */
    int verbose;
    /** How launches share out records (sluice_layout; 0 is AUTO). Also set
     *  by SLUICE_LAYOUT=contiguous or SLUICE_LAYOUT=interleaved, e.g. to
     *  test the GPU layout on a CPU. */
    sluice_layout layout;
    /** Options appended to every program build (NULL: none), e.g.
     *  "-cl-nv-verbose", with which NVIDIA's build log (printed with
     *  `verbose`) gives each kernel's registers and spills. Also set by
     *  SLUICE_BUILD_OPTIONS. */
    const char *build_options;
    /** Non-zero: in the contiguous layout, work-group g takes the chunks of
     *  group g also in the launches of kernels marked uneven
     *  (sluice_kernel_set_uneven), e.g. to measure what the spread gives.
     *  Also set by SLUICE_NO_SPREAD=1. */
    int no_spread;
    /** Non-zero: ordered outputs always take a count launch, a scan and a
     *  write launch. Otherwise, on CPU devices in the contiguous layout,
     *  launches of kernels not marked uneven place them in one launch, each
     *  chunk taking its places from the chunks before it (SLUICE_ORDERED),
     *  which reads the input once instead of twice. For measuring; also set
     *  by SLUICE_NO_CHAIN=1. (SLUICE_GROUP_CHAIN=1 chains launches in the
     *  interleaved layout too, each work-group placing its tile: for
     *  measuring on GPUs.) */
    int no_chain;
} sluice_context_options;

typedef struct sluice_context sluice_context;

/**
 * Creates a context on one device. `options` may be NULL. On failure `*out`
 * is NULL and, when `error` is not NULL, a message of at most `error_size`
 * bytes (NUL-terminated) says why.
 */
sluice_status sluice_context_create(const sluice_context_options *options, sluice_context **out,
                                    char *error, size_t error_size);

/** Waits for all queued work, then frees the context. Every stream, program,
 *  kernel, counter set and loop made from it must be destroyed first. */
void sluice_context_destroy(sluice_context *ctx);

/** The message of the last call that failed, and only until the next call:
 *  every function that can fail with a message empties it when it starts,
 *  so after a call that succeeded it is "". Read it right after the failing
 *  call (like errno, but cleared on success). */
const char *sluice_context_error(const sluice_context *ctx);

/** Describes the context's device. */
sluice_status sluice_context_device(const sluice_context *ctx, sluice_device_info *info);

/** Blocks until everything queued on the context has finished. */
sluice_status sluice_context_finish(sluice_context *ctx);

/** Bytes of device scratch the context holds for ordered outputs (the
 *  per-chunk counts, and on CPUs the chain's flags and counts); it grows to
 *  the largest launch and is kept. */
size_t sluice_context_scratch_bytes(const sluice_context *ctx);

/** Bytes of device scratch the context holds for the radix sort (records to
 *  ping-pong with: 4 bytes a key, 4 more a value); it grows to the largest
 *  sort and is kept, so that repeated sorts (a grid or photon map rebuilt
 *  every frame) neither allocate nor touch new memory. */
size_t sluice_context_sort_scratch_bytes(const sluice_context *ctx);

/** Frees the scratch the context keeps (both of the above) once the work
 *  queued before it is done; the next call that needs scratch allocates
 *  it again. For a program that sorted or split a large stream once. */
void sluice_context_release_scratch(sluice_context *ctx);

/** The underlying OpenCL objects, for interoperation (cl_context,
 *  cl_command_queue and cl_device_id, returned as void* so this header does
 *  not need the OpenCL headers). The context keeps ownership. */
void *sluice_context_cl_context(sluice_context *ctx);
void *sluice_context_cl_queue(sluice_context *ctx);
void *sluice_context_cl_device(sluice_context *ctx);

/* ------------------------------------------------------------------ */
/* Streams                                                             */
/* ------------------------------------------------------------------ */

typedef struct sluice_stream sluice_stream;

/**
 * Creates a stream of `capacity` records of `record_size` bytes, with length
 * 0. Capacity 0 is allowed (grow it later). A request larger than the device
 * can allocate fails with SLUICE_ERROR_OUT_OF_MEMORY.
 */
sluice_status sluice_stream_create(sluice_context *ctx, size_t record_size, size_t capacity,
                                   sluice_stream **out);

/** Frees the stream (NULL is fine). */
void sluice_stream_destroy(sluice_stream *stream);

/** Record size in bytes. */
size_t sluice_stream_record_size(const sluice_stream *stream);

/** Capacity in records. */
size_t sluice_stream_capacity(const sluice_stream *stream);

/** Reads the current length. When the length lives on the device this waits
 *  for the work queued before it (not for work queued after). A length past
 *  the capacity (an overflowed output) returns SLUICE_ERROR_OVERFLOW, with
 *  `*length` the number of records emitted into it; a void stream (written
 *  from an overflowed input) returns it with `*length` 0. The message names
 *  the kernel and output slot that overflowed, the capacity and the records
 *  emitted. Until it is cleared, set or grown, the stream stays overflowed. */
sluice_status sluice_stream_length(sluice_stream *stream, size_t *length);

/** Queues setting the length to `length` (at most the capacity). The records
 *  are not touched. */
sluice_status sluice_stream_set_length(sluice_stream *stream, size_t length);

/** Queues setting the length to 0. */
sluice_status sluice_stream_clear(sluice_stream *stream);

/** Copies `count` records from host memory into the stream and sets its
 *  length to `count`. Fails with SLUICE_ERROR_OVERFLOW if count > capacity. */
sluice_status sluice_stream_upload(sluice_stream *stream, const void *records, size_t count);

/** Queues setting the first `count` records to copies of `record` (record
 *  size bytes, e.g. zeros) and the length to `count`, without a host buffer
 *  of the stream's size. `record` may be reused when the call returns.
 *  Fails with SLUICE_ERROR_OVERFLOW if count > capacity. */
sluice_status sluice_stream_fill(sluice_stream *stream, const void *record, size_t count);

/** Copies the stream's records (at most `max` of them) to host memory and
 *  writes their number to `*count` (may be NULL). Blocks until done. Returns
 *  SLUICE_ERROR_OVERFLOW, as sluice_stream_length does, if the stream
 *  overflowed; the first `capacity` records (none of a void stream) are
 *  still copied. */
sluice_status sluice_stream_download(sluice_stream *stream, void *records, size_t max,
                                     size_t *count);

/** Reallocates to at least `capacity` records, keeping records and length.
 *  Never shrinks. A stream that overflowed (or is void) holds only part of
 *  what was emitted into it: it is grown empty (length 0), ready for the
 *  kernel that fills it to run again. */
sluice_status sluice_stream_grow(sluice_stream *stream, size_t capacity);

/** Exchanges the contents (buffers, lengths, capacities) of two streams of the
 *  same record size: the ping-pong of a multipass loop. Kernels that bound
 *  either stream see the swap at their next launch. */
sluice_status sluice_stream_swap(sluice_stream *a, sluice_stream *b);

/** The cl_mem of the records (as void*). It holds capacity+1 records: the
 *  last one is scratch that branch-free emission may overwrite. */
void *sluice_stream_cl_mem(sluice_stream *stream);

/* ------------------------------------------------------------------ */
/* Programs                                                            */
/* ------------------------------------------------------------------ */

typedef struct sluice_program sluice_program;

/**
 * Creates a program from OpenCL C source text. `name` is used in compiler
 * messages ("name:LINE:COL: error ..."); `options` are extra build options
 * (e.g. "-DTILE=8"), may be NULL. A line `#include "sluice.cl"` (or
 * <sluice.cl>) is served from the library's embedded copy of the kernel-side
 * header; nothing is read from disk. The source is compiled lazily, on the
 * first sluice_kernel_create() or an explicit sluice_program_build().
 */
sluice_status sluice_program_create_source(sluice_context *ctx, const char *name,
                                           const char *source, const char *options,
                                           sluice_program **out);

/** Like sluice_program_create_source(), reading the source from `path`. A
 *  missing file gives SLUICE_ERROR_IO naming the path. */
sluice_status sluice_program_create_file(sluice_context *ctx, const char *path, const char *options,
                                         sluice_program **out);

/** Frees the program. Kernels made from it must be destroyed first. */
void sluice_program_destroy(sluice_program *program);

/**
 * Compiles now if not yet compiled. A compile error returns
 * SLUICE_ERROR_BUILD. The context's error message then leads with the
 * errors in one shape, whichever OpenCL implementation compiled them:
 *
 *     my.cl:12:5: error: use of undeclared identifier 'x'
 *
 * one line per error, the first error first, with the file names given to
 * sluice_program_create_file() or _source() (also where the vendor's log
 * names the source `<kernel>` or the like); warnings only in verbose mode.
 * A line "building my.cl failed ..." follows, then the compiler's own log
 * when it holds more (source excerpts, notes) or in verbose mode. That log,
 * as the compiler wrote it, is in sluice_program_build_log(), except that
 * locations a compiler gives in its own name for the source, counting the
 * lines of the whole text it was handed (NVIDIA's `<kernel>:533:2:`), are
 * rewritten to the file and line they are in (`my.cl:2:2:`).
 *
 * A build that succeeds prints nothing, warnings or not: they are in the
 * build log. (With the verbose option or SLUICE_VERBOSE=1 the log is printed
 * on stderr after every build.) PoCL's compiler writes a count of its
 * diagnostics ("2 warnings generated.") straight to the process's stderr,
 * so while it runs, file descriptor 2 goes to a temporary file; afterwards
 * everything written there meanwhile, by any thread, is passed on to stderr
 * except that count, which is passed on too when the build failed. Builds
 * on several threads (several contexts) take turns at that redirection,
 * under one process-wide lock, so fresh builds do not run in parallel.
 *
 * A context keeps the last 32 programs it built, and a build of the same
 * text with the same options (a renderer's tracer made again, for another
 * view or pass) takes the kept one at once, with the same log, instead of
 * compiling again: the driver's own cache still runs the compiler's front
 * end each time (PoCL preprocesses the whole text, tenths of a second for a
 * renderer). Kernels are created afresh from it. Verbose builds always
 * compile.
 */
sluice_status sluice_program_build(sluice_program *program);

/** The compiler log of the last build, warnings and errors with file and
 *  line ("" before a build, or when the compiler had nothing to say). Kept
 *  until the program is destroyed. */
const char *sluice_program_build_log(const sluice_program *program);

/* ------------------------------------------------------------------ */
/* Kernels over streams                                                */
/* ------------------------------------------------------------------ */

typedef struct sluice_kernel sluice_kernel;
typedef struct sluice_counters sluice_counters;

/** How a conditional output stream receives records. */
typedef enum sluice_output_mode {
    /** Records keep the order of the input records that emitted them. Costs a
     *  counting launch and a small scan before the writing launch; on CPUs
     *  (the contiguous layout), for kernels not marked uneven
     *  (sluice_kernel_set_uneven), one launch whose chunks take their places
     *  in turn, each from the ones before it (decoupled look-back: a chunk
     *  waits only for the counts of chunks already started). */
    SLUICE_ORDERED = 0,
    /** Each chunk of input appends its records with one global atomic; order
     *  within a chunk is kept, order between chunks is not. */
    SLUICE_UNORDERED = 1
} sluice_output_mode;

/** Most conditional outputs per kernel, and most counters per counter set. */
#define SLUICE_MAX_OUTPUTS 8
#define SLUICE_MAX_COUNTERS 8

/**
 * Makes a launchable kernel from a program (building it if needed). The
 * kernel's parameters must start with SLUICE_PARAMS (sluice.cl). Argument
 * indices below count the parameters written after SLUICE_PARAMS, from 0.
 */
sluice_status sluice_kernel_create(sluice_program *program, const char *name, sluice_kernel **out);

/** Frees the kernel (NULL is fine). */
void sluice_kernel_destroy(sluice_kernel *kernel);

/** Binds the single input stream to argument `arg`: the launch runs once per
 *  record of it (the SLUICE_FOR_EACH index runs 0 .. length-1). */
sluice_status sluice_kernel_set_input(sluice_kernel *kernel, unsigned arg, sluice_stream *stream);

/** Binds conditional output `slot` (0 .. SLUICE_MAX_OUTPUTS-1, the first
 *  argument of SLUICE_EMIT) to `stream` at argument `arg`. Records are
 *  appended after the stream's current length. */
sluice_status sluice_kernel_set_output(sluice_kernel *kernel, unsigned arg, unsigned slot,
                                       sluice_stream *stream, sluice_output_mode mode);

/** Binds a stream's records to argument `arg` with no stream role: a gather
 *  source or a buffer indexed by the record index. If `map_output` is non-zero the
 *  stream's length is set to the input length after each launch (output i
 *  comes from input i). */
sluice_status sluice_kernel_set_stream(sluice_kernel *kernel, unsigned arg, sluice_stream *stream,
                                       int map_output);

/** Tells the runtime that the kernel's records cost very different amounts,
 *  in runs along the stream (`uneven` non-zero; 0, the default, undoes it):
 *  rays of a frame, for instance, where those through the object cost many
 *  times those that miss it. In the contiguous layout (CPUs) each
 *  work-group then takes chunks spread over the whole stream (sluice.cl,
 *  sluice_begin_), so that no thread of the OpenCL implementation is handed
 *  the expensive run alone; chunks, their records and the order of ordered
 *  outputs stay as they are. Kernels whose records cost about the same
 *  (copies, splits) are better without it. SLUICE_NO_SPREAD=1 (or the
 *  context option no_spread) turns it off for every kernel, for measuring. */
sluice_status sluice_kernel_set_uneven(sluice_kernel *kernel, int uneven);

/** Sets a plain argument (a scalar, a vector or a struct) by value. */
sluice_status sluice_kernel_set_arg(sluice_kernel *kernel, unsigned arg, size_t size,
                                    const void *value);

/** Makes SLUICE_COUNT(i, ...) in this kernel add to counter i of `counters`
 *  (NULL unbinds). */
sluice_status sluice_kernel_set_counters(sluice_kernel *kernel, sluice_counters *counters);

/** Queues one launch over the input stream. Returns when queued, not when
 *  done. Fails if an argument is unset or an output is too small to ever
 *  hold the result of a mapped output, and with SLUICE_ERROR_OVERFLOW if the
 *  input's length is known to be past its capacity. An input whose length is
 *  only on the device and turns out past its capacity is read as empty and
 *  the launch's outputs and counters become void (see "Overflow" above). */
sluice_status sluice_kernel_launch(sluice_kernel *kernel);

/** Queues one launch over `count` records without an input stream (a
 *  generator such as eye-ray generation): the record index runs 0 .. count-1. */
sluice_status sluice_kernel_launch_count(sluice_kernel *kernel, size_t count);

/** The kernel's name. */
const char *sluice_kernel_name(const sluice_kernel *kernel);

/* ------------------------------------------------------------------ */
/* Counters                                                            */
/* ------------------------------------------------------------------ */

/** Creates `count` (1 .. SLUICE_MAX_COUNTERS) counters, all 0. `names` may be
 *  NULL (names "c0", "c1", ...) or hold `count` strings. */
sluice_status sluice_counters_create(sluice_context *ctx, size_t count, const char *const *names,
                                     sluice_counters **out);

/** Frees the counter set (NULL is fine). */
void sluice_counters_destroy(sluice_counters *counters);

/** Number of counters in the set. */
size_t sluice_counters_count(const sluice_counters *counters);

/** The index of the counter called `name`, or -1. */
int sluice_counters_index(const sluice_counters *counters, const char *name);

/** Queues setting every counter to 0 (and clears the overflow note). */
sluice_status sluice_counters_reset(sluice_counters *counters);

/** Reads all counters into `values` (sluice_counters_count() entries): the
 *  counts since the last reset or restart. Waits only for the work queued
 *  before the call. Returns SLUICE_ERROR_OVERFLOW when, since the last
 *  reset, a kernel counting into them read an overflowed input (so it
 *  counted nothing). */
sluice_status sluice_counters_read(sluice_counters *counters, uint32_t *values);

/** sluice_counters_read(), then restarts the counters: later reads give the
 *  counts of the work queued after this call. Unlike a reset before each
 *  round of work, it queues nothing: the counters keep counting on the
 *  device and the host remembers where they stood (a reset is a command of
 *  its own, and on many-thread CPU devices each command costs tens of
 *  microseconds). When it returns SLUICE_ERROR_OVERFLOW (the counts read
 *  are void) it also clears that note, so that the next round counts
 *  afresh. */
sluice_status sluice_counters_read_restart(sluice_counters *counters, uint32_t *values);

/* ------------------------------------------------------------------ */
/* Multipass loops (Purcell 4.1.2)                                     */
/* ------------------------------------------------------------------ */

/** Returned by an oracle to end the loop. */
#define SLUICE_LOOP_STOP 0xffffffffu

/** Queues one pass. `choice` is what the oracle picked (0 without one).
 *  Return SLUICE_OK to go on; any other status ends the loop with it. */
typedef sluice_status (*sluice_pass_fn)(void *user, unsigned pass, unsigned choice);

/** Picks the next pass from the watched values (stream lengths first, then
 *  counters, in the order given in the descriptor). Return a choice for the
 *  pass function, or SLUICE_LOOP_STOP. */
typedef unsigned (*sluice_oracle_fn)(void *user, unsigned pass, const uint32_t *values,
                                     size_t count);

/** What a loop runs and watches. Zero-initialise, then set fields. */
typedef struct sluice_loop_desc {
    sluice_pass_fn pass;           /**< required */
    sluice_oracle_fn oracle;       /**< optional */
    void *user;                    /**< handed to pass and oracle */
    sluice_stream *const *streams; /**< lengths to watch (may be NULL) */
    size_t stream_count;           /**< how many */
    sluice_counters *counters;     /**< counters to watch (may be NULL) */
    int reset_counters;            /**< non-zero: each pass counts from zero (they are
                                        restarted, sluice_counters_read_restart(), at no
                                        extra command) */
    unsigned max_passes;           /**< 0: 100000 */
} sluice_loop_desc;

/** Per-pass statistics kept by a loop. */
typedef struct sluice_pass_stats {
    unsigned choice;     /**< what the pass function was given */
    uint32_t values[16]; /**< watched values after the pass (first 16) */
    double seconds;      /**< host wall time from queueing to values read */
} sluice_pass_stats;

typedef struct sluice_loop sluice_loop;

/** Creates a loop from a descriptor (copied; the arrays it points to must
 *  outlive the loop). */
sluice_status sluice_loop_create(sluice_context *ctx, const sluice_loop_desc *desc,
                                 sluice_loop **out);

/** Frees the loop (NULL is fine). */
void sluice_loop_destroy(sluice_loop *loop);

/**
 * Runs the loop: before each pass, the oracle (if any) picks a choice from the
 * watched values of the previous pass (all values are read before the first
 * pass too); without an oracle the loop goes on while any watched value is
 * non-zero. Stops with SLUICE_ERROR_LIMIT after max_passes passes. Stops
 * with SLUICE_ERROR_OVERFLOW after the first pass that leaves a watched
 * stream overflowed or void, or the watched counters void, or whose pass
 * function returns it; the message starts with "loop pass N: " (or "loop,
 * before pass 0: ") and names the kernel, the output slot, the capacity and
 * the records emitted. Per-pass statistics of the last run are kept until
 * the next run.
 */
sluice_status sluice_loop_run(sluice_loop *loop);

/** Number of passes of the last run. */
unsigned sluice_loop_pass_count(const sluice_loop *loop);

/** Statistics of pass `index` of the last run (NULL if out of range). */
const sluice_pass_stats *sluice_loop_pass(const sluice_loop *loop, unsigned index);

/* ------------------------------------------------------------------ */
/* Profiling                                                           */
/* ------------------------------------------------------------------ */

/** Per-kernel totals kept when profiling is on. The stream algorithms'
 *  kernels (scan_sums_u32, radix_scatter_pairs, ...) are listed too. */
typedef struct sluice_profile_entry {
    char name[64];         /**< kernel name */
    uint64_t launches;     /**< launches queued (an ordered launch counts once) */
    uint64_t records_in;   /**< input records processed (of a stream algorithm's
                                kernel: the records, chunk sums or table entries
                                it works through) */
    uint64_t records_out;  /**< records emitted to conditional outputs */
    uint64_t bytes;        /**< bytes of the input records read, and of the
                                records emitted and written to mapped outputs
                                (a stream algorithm's kernel: what it reads and
                                writes per record) */
    double device_seconds; /**< summed OpenCL event time */
} sluice_profile_entry;

/** Non-zero if the context profiles launches. */
int sluice_profile_enabled(const sluice_context *ctx);

/** Number of kernels with statistics: those launched since the context was
 *  made or the profile reset (waits for queued work first). A kernel that
 *  never ran has no entry. */
size_t sluice_profile_count(sluice_context *ctx);

/** Entry `index` (0 .. count-1), in the order of the kernels' first launch. */
sluice_status sluice_profile_get(sluice_context *ctx, size_t index, sluice_profile_entry *entry);

/** Prints the table of the kernels that ran (launches, records, bytes, time,
 *  GB/s), one line per entry, then the total time. */
sluice_status sluice_profile_print(sluice_context *ctx, FILE *out);

/** Saves the same table as JSON: {"device": ..., "kernels": [{...}, ...]}. */
sluice_status sluice_profile_write_json(sluice_context *ctx, const char *path);

/** Forgets all statistics and entries: the next table lists only the kernels
 *  launched after this call. */
void sluice_profile_reset(sluice_context *ctx);

#ifdef __cplusplus
}
#endif

#endif /* SLUICE_SLUICE_H */
