/* Kernels over streams: argument binding and launches with conditional
 * outputs (see kernels/sluice.cl for the device side). */
#include "internal.h"

#include <stdlib.h>
#include <string.h>

/* Hidden parameters before the user's: variable pool, scratch, launch info,
 * local memory for group emission (kernels/sluice.cl). */
#define SL_HIDDEN_ARGS 4u
/* The chunk a chained launch aims at (launch, below). */
#define SL_CHAIN_CHUNK 1024u
#define SL_LDS_WORDS (3u * SLUICE_MAX_OUTPUTS) /* SLUICE_LDS_WORDS_ */

sluice_status sluice_kernel_create(sluice_program *program, const char *name, sluice_kernel **out)
{
    sl_clear_error(program ? program->ctx : NULL);
    if (out)
        *out = NULL;
    if (!program || !name || !out)
        return sl_fail(program ? program->ctx : NULL, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_kernel_create: NULL program, name or out");
    sluice_context *ctx = program->ctx;
    sluice_status st = sluice_program_build(program);
    if (st != SLUICE_OK)
        return st;
    cl_int err;
    cl_kernel k = clCreateKernel(program->cl, name, &err);
    if (!k)
        return sl_fail(ctx, SLUICE_ERROR_NOT_FOUND, "no kernel named %s in %s (%s)", name,
                       program->name, sl_cl_error_string(err));
    cl_uint nargs = 0;
    clGetKernelInfo(k, CL_KERNEL_NUM_ARGS, sizeof nargs, &nargs, NULL);
    if (nargs < SL_HIDDEN_ARGS) {
        clReleaseKernel(k);
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "kernel %s in %s does not start with SLUICE_PARAMS", name, program->name);
    }
    sluice_kernel *kn = calloc(1, sizeof *kn);
    if (!kn) {
        clReleaseKernel(k);
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
    }
    kn->ctx = ctx;
    kn->program = program;
    kn->cl = k;
    snprintf(kn->name, sizeof kn->name, "%s", name);
    kn->n_args = nargs - SL_HIDDEN_ARGS;
    kn->group = sl_kernel_group(ctx, k, ctx->group);
    kn->prof_var = SL_NONE;
    size_t n = kn->n_args ? kn->n_args : 1;
    kn->arg_kind = calloc(n, sizeof *kn->arg_kind);
    kn->arg_stream = calloc(n, sizeof *kn->arg_stream);
    kn->arg_map = calloc(n, 1);
    if (!kn->arg_kind || !kn->arg_stream || !kn->arg_map) {
        sluice_kernel_destroy(kn);
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
    }
    if (ctx->profile) {
        st = sl_vars_alloc(ctx, 1 + SLUICE_MAX_OUTPUTS, &kn->prof_var);
        if (st != SLUICE_OK) {
            sluice_kernel_destroy(kn);
            return st;
        }
    }
    kn->next_live = ctx->kernels;
    ctx->kernels = kn;
    *out = kn;
    return SLUICE_OK;
}

void sluice_kernel_destroy(sluice_kernel *k)
{
    if (!k)
        return;
    sluice_context *ctx = k->ctx;
    if (k->prof_var != SL_NONE) {
        sl_profile_sync(ctx); /* fold this kernel's record counts in first */
        sl_vars_free(ctx, k->prof_var, 1 + SLUICE_MAX_OUTPUTS);
    }
    for (sluice_kernel **p = &ctx->kernels; *p; p = &(*p)->next_live) {
        if (*p == k) {
            *p = k->next_live;
            break;
        }
    }
    if (k->cl)
        clReleaseKernel(k->cl);
    free(k->arg_kind);
    free(k->arg_stream);
    free(k->arg_map);
    free(k);
}

const char *sluice_kernel_name(const sluice_kernel *k)
{
    return k ? k->name : "";
}

static sluice_status check_arg(sluice_kernel *k, unsigned arg)
{
    if (arg >= k->n_args)
        return sl_fail(k->ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "kernel %s has %u arguments; argument %u does not exist", k->name, k->n_args,
                       arg);
    return SLUICE_OK;
}

/* Forgets any stream role previously held by argument `arg`. */
static void unbind_roles(sluice_kernel *k, unsigned arg)
{
    if (k->input && k->input_arg == arg)
        k->input = NULL;
    for (unsigned s = 0; s < SLUICE_MAX_OUTPUTS; ++s)
        if (k->out[s] && k->out_arg[s] == arg)
            k->out[s] = NULL;
    k->arg_map[arg] = 0;
}

static sluice_status bind_stream(sluice_kernel *k, unsigned arg, sluice_stream *stream)
{
    sluice_status st = check_arg(k, arg);
    if (st != SLUICE_OK)
        return st;
    if (!stream || stream->ctx != k->ctx)
        return sl_fail(k->ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "kernel %s argument %u: NULL stream or a stream of another context", k->name,
                       arg);
    unbind_roles(k, arg);
    k->arg_kind[arg] = SL_ARG_STREAM;
    k->arg_stream[arg] = stream;
    return SLUICE_OK;
}

sluice_status sluice_kernel_set_input(sluice_kernel *k, unsigned arg, sluice_stream *stream)
{
    if (!k)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(k->ctx);
    if (k->input) /* one input stream per kernel (Purcell 3.1.1) */
        k->input = NULL;
    sluice_status st = bind_stream(k, arg, stream);
    if (st != SLUICE_OK)
        return st;
    k->input = stream;
    k->input_arg = arg;
    return SLUICE_OK;
}

sluice_status sluice_kernel_set_output(sluice_kernel *k, unsigned arg, unsigned slot,
                                       sluice_stream *stream, sluice_output_mode mode)
{
    if (!k)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(k->ctx);
    if (slot >= SLUICE_MAX_OUTPUTS)
        return sl_fail(k->ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "kernel %s: output slot %u is out of range (0..%u)", k->name, slot,
                       SLUICE_MAX_OUTPUTS - 1);
    if (mode != SLUICE_ORDERED && mode != SLUICE_UNORDERED)
        return sl_fail(k->ctx, SLUICE_ERROR_INVALID_ARGUMENT, "kernel %s: bad output mode %d",
                       k->name, (int)mode);
    /* an ordered output's launches need the runtime's scan of the counts:
     * built now, at setup, and before anything is bound, so that a failed
     * build leaves the kernel as it was */
    sluice_status st = mode == SLUICE_ORDERED ? sl_ordered_ready(k->ctx) : SLUICE_OK;
    if (st == SLUICE_OK)
        st = bind_stream(k, arg, stream);
    if (st != SLUICE_OK)
        return st;
    if (k->out[slot]) /* the slot moves to this argument */
        k->arg_kind[k->out_arg[slot]] = k->out_arg[slot] == arg ? SL_ARG_STREAM : SL_ARG_UNSET;
    k->out[slot] = stream;
    k->out_arg[slot] = arg;
    k->out_mode[slot] = mode;
    return SLUICE_OK;
}

sluice_status sluice_kernel_set_stream(sluice_kernel *k, unsigned arg, sluice_stream *stream,
                                       int map_output)
{
    if (!k)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(k->ctx);
    sluice_status st = bind_stream(k, arg, stream);
    if (st == SLUICE_OK)
        k->arg_map[arg] = map_output ? 1 : 0;
    return st;
}

sluice_status sluice_kernel_set_arg(sluice_kernel *k, unsigned arg, size_t size, const void *value)
{
    if (!k)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(k->ctx);
    sluice_status st = check_arg(k, arg);
    if (st != SLUICE_OK)
        return st;
    if (!value || !size)
        return sl_fail(k->ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "kernel %s argument %u: NULL value or size 0", k->name, arg);
    cl_int err = clSetKernelArg(k->cl, SL_HIDDEN_ARGS + arg, size, value);
    if (err != CL_SUCCESS)
        return sl_fail(k->ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "kernel %s argument %u: %s (a value of %zu bytes does not fit its type)",
                       k->name, arg, sl_cl_error_string(err), size);
    unbind_roles(k, arg);
    k->arg_kind[arg] = SL_ARG_VALUE;
    k->arg_stream[arg] = NULL;
    return SLUICE_OK;
}

sluice_status sluice_kernel_set_counters(sluice_kernel *k, sluice_counters *counters)
{
    if (!k)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(k->ctx);
    if (counters && counters->ctx != k->ctx)
        return sl_fail(k->ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "kernel %s: counters belong to another context", k->name);
    k->counters = counters;
    return SLUICE_OK;
}

sluice_status sluice_kernel_set_uneven(sluice_kernel *k, int uneven)
{
    if (!k)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(k->ctx);
    k->uneven = uneven != 0;
    return SLUICE_OK;
}

/* Records per work-item. On a CPU a work-item walking a long contiguous chunk
 * is as fast as plain C and needs few atomics; aim for about a thousand chunks
 * so both cores stay busy and the ordered scan stays small. Up to 16384
 * records (64 KiB of 4-byte records, well inside L2 for the second pass):
 * at 2^24 records that measured 61-62% of copy for split against 54-59% with
 * 4096 (bench_streams --reps 15, two runs each). In the interleaved layout
 * (GPUs) up to 64 records: a work-group's tile of 64 chunks, whose ordered
 * outputs' counts the host scans one per group (group order, sluice.cl).
 * On CPUs a multiple of 16 records, so that kernels taking 16 records at a
 * time leave a tail only in the input's last chunk (bench/README.md, "The
 * stream mode's 3x on Zen 4"). The interleaved layout on a CPU (the GPU's
 * code, run by the tests) aims for at most 32768 work-items: PoCL builds a
 * second work-group function for every kernel launched on a grid of 65535
 * work-items or more (its grid_width_specialization_limit), which doubled
 * the minutes that the suite's cold kernel cache takes to build those. */
static size_t choose_chunk(const sluice_context *ctx, size_t bound)
{
    if (ctx->chunk)
        return ctx->chunk;
    size_t lo = 16, hi = 16384, want = bound / 1024;
    if (ctx->layout == SLUICE_LAYOUT_INTERLEAVED) {
        lo = 1;
        hi = 64;
        want = ctx->info.is_cpu ? (bound + 32767) / 32768 : bound / 65536;
    } else {
        want = (want + 15) & ~(size_t)15;
    }
    return want < lo ? lo : want > hi ? hi : want;
}

static size_t gcd(size_t a, size_t b)
{
    while (b) {
        size_t t = a % b;
        a = b;
        b = t;
    }
    return a;
}

/* The contiguous layout's spread of chunks over the work-groups
 * (sluice_begin_ in sluice.cl): the integer nearest groups / phi, the golden
 * ratio, that is coprime to groups, so that consecutive groups take chunks
 * far apart and every chunk is taken once. */
static cl_uint spread_of(size_t groups)
{
    if (groups < 3)
        return 1;
    size_t s = (size_t)((double)groups * 0.6180339887498949 + 0.5);
    while (gcd(s, groups) != 1)
        ++s;
    return (cl_uint)s;
}

/* Queues one command of a launch. The profile counts an ordered launch's
 * count command apart, as "<kernel> count", so that its two passes over the
 * input can be told apart; the write command (or the only one) is the
 * kernel's own entry. */
static sluice_status enqueue(sluice_kernel *k, size_t global, int count_launch)
{
    size_t local = k->group;
    cl_event ev = NULL;
    cl_int err = clEnqueueNDRangeKernel(k->ctx->queue, k->cl, 1, NULL, &global, &local, 0, NULL,
                                        k->ctx->profile ? &ev : NULL);
    if (err != CL_SUCCESS) {
        char what[128];
        snprintf(what, sizeof what, "launching kernel %s", k->name);
        return sl_cl_fail(k->ctx, err, what);
    }
    if (ev && count_launch) {
        char name[sizeof k->name + 8];
        snprintf(name, sizeof name, "%s count", k->name);
        sl_profile_command(k->ctx, sl_profile_entry(k->ctx, name), ev, 1, NULL);
    } else if (ev) {
        sl_profile_command(k->ctx, sl_profile_kernel_entry(k), ev, 1, NULL);
    }
    return SLUICE_OK;
}

static sluice_status set_hidden(sluice_kernel *k, const sl_launch *L)
{
    sluice_context *ctx = k->ctx;
    cl_mem scratch = ctx->scratch ? ctx->scratch : ctx->vars; /* never read unless ordered */
    if (L->mode == 3)
        scratch = ctx->chain;
    cl_int err = clSetKernelArg(k->cl, 0, sizeof(cl_mem), &ctx->vars);
    if (err == CL_SUCCESS)
        err = clSetKernelArg(k->cl, 1, sizeof(cl_mem), &scratch);
    if (err == CL_SUCCESS)
        err = clSetKernelArg(k->cl, 2, sizeof *L, L);
    if (err == CL_SUCCESS)
        /* group order's scans take 8 words per work-item and 16 more after
         * them (kernels/sluice.cl, sluice_group_place_) */
        err = clSetKernelArg(
            k->cl, 3,
            (SL_LDS_WORDS + (ctx->layout == SLUICE_LAYOUT_INTERLEAVED ? 8 * (k->group + 16) : 0)) *
                sizeof(cl_uint),
            NULL);
    return err == CL_SUCCESS ? SLUICE_OK : sl_cl_fail(ctx, err, "setting launch arguments");
}

sluice_status sl_ordered_ready(sluice_context *ctx)
{
    if (ctx->scan_kernel)
        return SLUICE_OK;
    return sl_embedded_cl_kernel(ctx, "runtime.cl", "sluice_scan_chunk_counts", &ctx->scan_kernel);
}

/* Queues setting the length of the stream with variable `dst` to the
 * device-side length of the input (variable `src`, capacity `cap`), or
 * voiding it when the input overflowed (kernels/runtime.cl): for the mapped
 * outputs past the SLUICE_MAX_OUTPUTS that a launch sets itself. */
static sluice_status map_length(sluice_context *ctx, cl_uint src, cl_uint cap, cl_uint dst)
{
    sluice_status st = SLUICE_OK;
    if (!ctx->map_length_kernel)
        st = sl_embedded_cl_kernel(ctx, "runtime.cl", "sluice_map_length", &ctx->map_length_kernel);
    cl_kernel mk = ctx->map_length_kernel;
    cl_int err = CL_SUCCESS;
    if (st == SLUICE_OK) {
        sl_set_arg(mk, 0, sizeof(cl_mem), &ctx->vars, &err);
        sl_set_arg(mk, 1, sizeof src, &src, &err);
        sl_set_arg(mk, 2, sizeof cap, &cap, &err);
        sl_set_arg(mk, 3, sizeof dst, &dst, &err);
        if (err != CL_SUCCESS)
            st = sl_cl_fail(ctx, err, "setting the arguments of sluice_map_length");
    }
    if (st == SLUICE_OK)
        st = sl_enqueue_raw(ctx, mk, "sluice_map_length", 1, 1, NULL);
    return st;
}

static sluice_status launch(sluice_kernel *k, int has_count, size_t count)
{
    if (!k)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(k->ctx);
    sluice_context *ctx = k->ctx;
    if (!has_count && !k->input)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "kernel %s has no input stream: bind one with sluice_kernel_set_input or "
                       "use sluice_kernel_launch_count",
                       k->name);
    for (unsigned a = 0; a < k->n_args; ++a)
        if (k->arg_kind[a] == SL_ARG_UNSET)
            return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "kernel %s: argument %u is not set",
                           k->name, a);
    if (has_count && count > 0xfffffff0u)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "kernel %s: count %zu is too large",
                       k->name, count);

    sl_launch L;
    memset(&L, 0, sizeof L);
    size_t bound;
    if (has_count) {
        L.n_fixed = (cl_uint)count;
        L.in_var = 0;
        bound = count;
    } else if (k->input->len_known) {
        /* An overflowed input is an error, never read as truncated. (One
         * whose length is only on the device is checked there: the launch
         * reads no records and voids its outputs, see sluice_begin_.) */
        if (k->input->len > k->input->capacity) {
            char prefix[128];
            snprintf(prefix, sizeof prefix, "kernel %s: its input (argument %u) ", k->name,
                     k->input_arg);
            return sl_stream_check_known(k->input, prefix);
        }
        L.n_fixed = (cl_uint)k->input->len;
        L.in_var = k->input->var;
        bound = L.n_fixed;
    } else {
        L.n_fixed = SL_NONE;
        L.in_var = k->input->var;
        L.in_cap = (cl_uint)k->input->capacity;
        bound = k->input->capacity;
    }
    /* A launch is queued when there may be records, and always when the
     * input's length is on the device: even an input of capacity 0 may have
     * overflowed, and the launch then voids what it writes. */
    const int queued = bound > 0 || L.n_fixed == SL_NONE;
    /* Mapped outputs must hold the whole input. When its length is on the
     * device, the launch sets theirs (up to SLUICE_MAX_OUTPUTS of them). */
    for (unsigned a = 0; a < k->n_args; ++a) {
        if (!k->arg_map[a])
            continue;
        if (k->arg_stream[a]->capacity < bound)
            return sl_fail(ctx, SLUICE_ERROR_OVERFLOW,
                           "kernel %s: mapped output (argument %u) holds %zu records but the "
                           "input may have %zu",
                           k->name, a, k->arg_stream[a]->capacity, bound);
        if (L.n_fixed == SL_NONE && L.n_map < SLUICE_MAX_OUTPUTS)
            L.map_var[L.n_map++] = k->arg_stream[a]->var;
    }

    int any_unordered = 0;
    for (unsigned s = 0; s < SLUICE_MAX_OUTPUTS; ++s) {
        sluice_stream *o = k->out[s];
        if (!o)
            continue;
        L.out_mask |= 1u << s;
        L.out_var[s] = o->var;
        L.out_cap[s] = (cl_uint)o->capacity;
        if (k->out_mode[s] == SLUICE_ORDERED)
            L.ordered_mask |= 1u << s;
        else
            any_unordered = 1;
    }
    /* Ordered outputs in one launch (the chain, kernels/sluice.cl), for
     * kernels whose chunks cost about the same (a chunk waits for the one
     * before it to be counted): on PoCL's CPU devices (which run a group's
     * work-items one after another, as the chain needs) in the contiguous
     * layout; in the interleaved layout (GPUs), where a group's first
     * work-item places the group's tile, only with SLUICE_GROUP_CHAIN=1 until
     * it is measured on a GPU. */
    const int contiguous = ctx->layout == SLUICE_LAYOUT_CONTIGUOUS;
    int chain = L.ordered_mask && !k->uneven && !ctx->no_chain &&
                (contiguous ? ctx->chain_cpu : ctx->group_chain);
    size_t chunk = choose_chunk(ctx, bound);
    if (chain && contiguous && !ctx->chunk) {
        /* A chained chunk costs a few cross-core reads and writes: at 16 to
         * 64 records the chain was slower than the three commands, from 256
         * on faster, so its chunks grow to 1024 records, as far as every
         * thread keeps 4 work-groups (PoCL's unit of work: with fewer, one
         * thread took most of a photon stream); a launch too small for
         * chunks of 256 so shared takes the three commands
         * (bench/README.md). SLUICE_CHUNK keeps its own. */
        size_t cu = ctx->info.compute_units ? ctx->info.compute_units : 1;
        size_t most = bound / (k->group * 4 * cu) & ~(size_t)15;
        size_t want = most < SL_CHAIN_CHUNK ? most : SL_CHAIN_CHUNK;
        if (want > chunk)
            chunk = want;
        if (chunk < SL_CHAIN_CHUNK / 4)
            chain = 0;
    }
    size_t chunks = (bound + chunk - 1) / chunk;
    size_t global = sl_round_up(chunks ? chunks : 1, k->group);
    L.chunk = (cl_uint)chunk;
    L.stride = (cl_uint)(global + 1);
    L.spread = k->uneven && ctx->layout == SLUICE_LAYOUT_CONTIGUOUS && !ctx->no_spread
                   ? spread_of(global / k->group)
                   : 1;
    L.counter_var = k->counters ? k->counters->var : SL_NONE;
    L.n_counters = k->counters ? (cl_uint)k->counters->count : 0;
    L.prof_var = k->prof_var;

    /* Stream arguments are set now, so swaps and grows since binding count. */
    for (unsigned a = 0; a < k->n_args; ++a) {
        if (k->arg_kind[a] != SL_ARG_STREAM)
            continue;
        cl_int err =
            clSetKernelArg(k->cl, SL_HIDDEN_ARGS + a, sizeof(cl_mem), &k->arg_stream[a]->mem);
        if (err != CL_SUCCESS)
            return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                           "kernel %s argument %u is not a global buffer: %s", k->name, a,
                           sl_cl_error_string(err));
    }

    sluice_status st = SLUICE_OK;
    L.interleave = ctx->layout == SLUICE_LAYOUT_INTERLEAVED;
    size_t rows = 0; /* ordered outputs' rows: up to the highest ordered slot */
    for (unsigned s = 0; s < SLUICE_MAX_OUTPUTS; ++s)
        if ((L.ordered_mask >> s) & 1u)
            rows = s + 1;
    if (queued && chain) {
        st = sl_chain_reserve(ctx, L.stride, 2 * rows * L.stride);
        if (st != SLUICE_OK)
            return st;
        L.chain_flags = (cl_uint)ctx->chain_flags;
        ctx->chain_epoch = ctx->chain_epoch + 1 < (1u << 30) ? ctx->chain_epoch + 1 : 1;
        L.epoch = ctx->chain_epoch;
        L.mode = 3;
        L.first_pass = 0;
        st = set_hidden(k, &L);
        if (st == SLUICE_OK)
            st = enqueue(k, global, 0);
        if (st != SLUICE_OK)
            return st;
    } else if (queued) {
        if (L.ordered_mask) {
            st = sl_scratch_reserve(ctx, rows * L.stride * sizeof(cl_uint));
            if (st != SLUICE_OK)
                return st;
            /* Count launch, scan of the chunk counts, write launch. In the
             * interleaved layout the work-groups place the records (group
             * order, sluice.cl): one count per group is scanned. */
            const int grouped = L.interleave;
            L.mode = 1;
            L.first_pass = 0;
            st = set_hidden(k, &L);
            if (st == SLUICE_OK)
                st = enqueue(k, global, 1);
            if (st == SLUICE_OK)
                st = sl_ordered_ready(ctx);
            for (unsigned s = 0; st == SLUICE_OK && s < SLUICE_MAX_OUTPUTS; ++s) {
                if (!((L.ordered_mask >> s) & 1u))
                    continue;
                cl_uint n = (cl_uint)(grouped ? global / k->group : global), var = L.out_var[s],
                        offset = s * L.stride;
                /* one work-item on a CPU (a few thousand counts); on a GPU,
                 * whose single work-item is slow and whose launches have
                 * many more chunks, one work-group */
                size_t scan_group = ctx->layout == SLUICE_LAYOUT_INTERLEAVED ? ctx->group : 1;
                clSetKernelArg(ctx->scan_kernel, 0, sizeof(cl_mem), &ctx->vars);
                clSetKernelArg(ctx->scan_kernel, 1, sizeof(cl_mem), &ctx->scratch);
                clSetKernelArg(ctx->scan_kernel, 2, sizeof offset, &offset);
                clSetKernelArg(ctx->scan_kernel, 3, sizeof var, &var);
                clSetKernelArg(ctx->scan_kernel, 4, sizeof n, &n);
                clSetKernelArg(ctx->scan_kernel, 5, (scan_group + 1) * sizeof(cl_uint), NULL);
                st = sl_enqueue_raw(ctx, ctx->scan_kernel, "sluice_scan_chunk_counts", scan_group,
                                    scan_group, SL_RAW_IO(n, 8)); /* each count read, written */
            }
            L.mode = 2;
            /* group order counts again where it needs to (sluice_begin_) */
            L.first_pass = any_unordered || grouped ? 0 : 1;
        } else {
            L.mode = 0;
            L.first_pass = L.out_mask ? 0 : 1;
        }
        if (st == SLUICE_OK)
            st = set_hidden(k, &L);
        if (st == SLUICE_OK)
            st = enqueue(k, global, 0);
        if (st != SLUICE_OK)
            return st;
    }

    /* Lengths: conditional outputs are now known only on the device; mapped
     * outputs take the input's length. */
    for (unsigned s = 0; s < SLUICE_MAX_OUTPUTS; ++s) {
        if (k->out[s] && queued) {
            k->out[s]->len_known = false;
            sl_stream_written(k->out[s], SL_WRITER_OUTPUT, s, k->name);
        }
    }
    unsigned mapped = 0;
    for (unsigned a = 0; a < k->n_args && st == SLUICE_OK; ++a) {
        if (!k->arg_map[a])
            continue;
        sluice_stream *m = k->arg_stream[a];
        if (L.n_fixed != SL_NONE) {
            st = sluice_stream_set_length(m, L.n_fixed);
            continue;
        }
        if (mapped++ >= L.n_map) /* not set by the launch */
            st = map_length(ctx, L.in_var, L.in_cap, m->var);
        m->len_known = false;
        sl_stream_written(m, SL_WRITER_MAPPED, a, k->name);
    }
    if (ctx->profile && st == SLUICE_OK && queued && k->prof_epoch == ctx->prof_epoch) {
        /* What the device counts is turned into bytes with these. */
        sl_profile_slot *slot = &ctx->prof[k->prof_entry];
        slot->in_record_size = k->input ? k->input->record_size : 0;
        for (unsigned s = 0; s < SLUICE_MAX_OUTPUTS; ++s)
            slot->out_record_size[s] = k->out[s] ? k->out[s]->record_size : 0;
        slot->mapped_record_size = 0;
        for (unsigned a = 0; a < k->n_args; ++a)
            if (k->arg_map[a])
                slot->mapped_record_size += k->arg_stream[a]->record_size;
    }
    return st;
}

sluice_status sluice_kernel_launch(sluice_kernel *k)
{
    return launch(k, 0, 0);
}

sluice_status sluice_kernel_launch_count(sluice_kernel *k, size_t count)
{
    return launch(k, 1, count);
}
