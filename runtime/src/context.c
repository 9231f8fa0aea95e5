/* Device selection, the context, its variable pool and scratch. */
#include "internal.h"

#include "program_cache.h"

#include <ctype.h>
#include <stdlib.h>
#include <string.h>

static void fill_info(cl_platform_id p, cl_device_id d, sluice_device_info *info)
{
    memset(info, 0, sizeof *info);
    clGetPlatformInfo(p, CL_PLATFORM_NAME, sizeof info->platform - 1, info->platform, NULL);
    clGetDeviceInfo(d, CL_DEVICE_NAME, sizeof info->name - 1, info->name, NULL);
    clGetDeviceInfo(d, CL_DEVICE_OPENCL_C_VERSION, sizeof info->version - 1, info->version, NULL);
    cl_device_type type = 0;
    clGetDeviceInfo(d, CL_DEVICE_TYPE, sizeof type, &type, NULL);
    info->is_cpu = (type & CL_DEVICE_TYPE_CPU) != 0;
    cl_uint cu = 0;
    clGetDeviceInfo(d, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof cu, &cu, NULL);
    info->compute_units = cu;
    clGetDeviceInfo(d, CL_DEVICE_MAX_WORK_GROUP_SIZE, sizeof info->max_work_group_size,
                    &info->max_work_group_size, NULL);
    cl_ulong v = 0;
    clGetDeviceInfo(d, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof v, &v, NULL);
    info->global_mem_bytes = v;
    clGetDeviceInfo(d, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof v, &v, NULL);
    info->max_alloc_bytes = v;
    clGetDeviceInfo(d, CL_DEVICE_LOCAL_MEM_SIZE, sizeof v, &v, NULL);
    info->local_mem_bytes = v;
    v = 0;
    clGetDeviceInfo(d, CL_DEVICE_GLOBAL_MEM_CACHE_SIZE, sizeof v, &v, NULL);
    info->cache_bytes = v;
}

/* Calls `visit` for every device of every platform; stops when it returns
 * non-zero. Returns SLUICE_ERROR_NO_DEVICE when no platform exists. */
typedef int (*device_visit)(void *user, cl_platform_id p, cl_device_id d);
static sluice_status for_each_device(device_visit visit, void *user)
{
    cl_uint np = 0;
    if (clGetPlatformIDs(0, NULL, &np) != CL_SUCCESS || np == 0)
        return SLUICE_ERROR_NO_DEVICE;
    cl_platform_id *ps = calloc(np, sizeof *ps);
    if (!ps)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    clGetPlatformIDs(np, ps, NULL);
    sluice_status st = SLUICE_OK;
    for (cl_uint i = 0; i < np; ++i) {
        cl_uint nd = 0;
        if (clGetDeviceIDs(ps[i], CL_DEVICE_TYPE_ALL, 0, NULL, &nd) != CL_SUCCESS || nd == 0)
            continue;
        cl_device_id *ds = calloc(nd, sizeof *ds);
        if (!ds) {
            st = SLUICE_ERROR_OUT_OF_MEMORY;
            break;
        }
        clGetDeviceIDs(ps[i], CL_DEVICE_TYPE_ALL, nd, ds, NULL);
        int stop = 0;
        for (cl_uint j = 0; j < nd && !stop; ++j)
            stop = visit(user, ps[i], ds[j]);
        free(ds);
        if (stop)
            break;
    }
    free(ps);
    return st;
}

typedef struct list_state {
    sluice_device_info *out;
    size_t max, count;
} list_state;

static int list_visit(void *user, cl_platform_id p, cl_device_id d)
{
    list_state *s = user;
    if (s->count < s->max)
        fill_info(p, d, &s->out[s->count]);
    s->count++;
    return 0;
}

sluice_status sluice_devices_list(sluice_device_info *out, size_t max, size_t *count)
{
    if (!count || (max && !out))
        return SLUICE_ERROR_INVALID_ARGUMENT;
    list_state s = {out, max, 0};
    sluice_status st = for_each_device(list_visit, &s);
    *count = s.count;
    return st;
}

static int contains_nocase(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    for (; *hay; ++hay) {
        size_t i = 0;
        while (i < n && hay[i] &&
               tolower((unsigned char)hay[i]) == tolower((unsigned char)needle[i]))
            ++i;
        if (i == n)
            return 1;
    }
    return n == 0;
}

typedef struct pick_state {
    const char *filter;
    int want_cpu; /* pass 1: CPU only; pass 2: anything */
    cl_platform_id p;
    cl_device_id d;
    int found;
} pick_state;

static int pick_visit(void *user, cl_platform_id p, cl_device_id d)
{
    pick_state *s = user;
    sluice_device_info info;
    fill_info(p, d, &info);
    if (s->filter) {
        char both[300];
        snprintf(both, sizeof both, "%s / %s", info.platform, info.name);
        if (!contains_nocase(both, s->filter))
            return 0;
    } else if (s->want_cpu && !info.is_cpu) {
        return 0;
    }
    s->p = p;
    s->d = d;
    s->found = 1;
    return 1;
}

/* Is the environment variable `name` set to something other than "" or "0"? */
static int env_on(const char *name)
{
    const char *v = getenv(name);
    return v && *v && strcmp(v, "0") != 0;
}

static void set_msg(char *error, size_t size, const char *msg)
{
    if (error && size) {
        strncpy(error, msg, size - 1);
        error[size - 1] = 0;
    }
}

sluice_status sluice_context_create(const sluice_context_options *options, sluice_context **out,
                                    char *error, size_t error_size)
{
    if (!out) {
        set_msg(error, error_size, "sluice_context_create: out is NULL");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    *out = NULL;
    sluice_context_options opt = {0};
    if (options)
        opt = *options;
    if (!opt.device) {
        const char *env = getenv("SLUICE_DEVICE");
        if (env && *env)
            opt.device = env;
    }
    if (env_on("SLUICE_PROFILE"))
        opt.profile = 1;
    if (env_on("SLUICE_NO_SIMD"))
        opt.no_simd = 1;
    if (env_on("SLUICE_VERBOSE"))
        opt.verbose = 1;
    if (env_on("SLUICE_NO_SPREAD"))
        opt.no_spread = 1;
    if (env_on("SLUICE_NO_CHAIN"))
        opt.no_chain = 1;
    if (!opt.build_options)
        opt.build_options = getenv("SLUICE_BUILD_OPTIONS");
    const char *chunk_env = getenv("SLUICE_CHUNK");
    if (!opt.chunk && chunk_env && *chunk_env) {
        char *end;
        unsigned long c = strtoul(chunk_env, &end, 10);
        if (*end || c == 0 || c > (1ul << 24)) {
            set_msg(error, error_size, "SLUICE_CHUNK must be a number of records, 1 .. 16777216");
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
        opt.chunk = (unsigned)c;
    }
    const char *layout_env = getenv("SLUICE_LAYOUT");
    if (opt.layout == SLUICE_LAYOUT_AUTO && layout_env && *layout_env) {
        if (strcmp(layout_env, "contiguous") == 0)
            opt.layout = SLUICE_LAYOUT_CONTIGUOUS;
        else if (strcmp(layout_env, "interleaved") == 0)
            opt.layout = SLUICE_LAYOUT_INTERLEAVED;
        else if (strcmp(layout_env, "auto") != 0) {
            set_msg(error, error_size, "SLUICE_LAYOUT must be auto, contiguous or interleaved");
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
    }
    if ((unsigned)opt.layout > (unsigned)SLUICE_LAYOUT_INTERLEAVED) {
        set_msg(error, error_size, "sluice_context_create: bad layout");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }

    pick_state ps = {opt.device, 1, NULL, NULL, 0};
    sluice_status st = for_each_device(pick_visit, &ps);
    if (st == SLUICE_OK && !ps.found && !opt.device) {
        ps.want_cpu = 0;
        st = for_each_device(pick_visit, &ps);
    }
    if (st != SLUICE_OK || !ps.found) {
        char msg[512];
        if (opt.device)
            snprintf(msg, sizeof msg,
                     "no OpenCL device matches \"%s\" (run sluice-info to list devices)",
                     opt.device);
        else
            snprintf(msg, sizeof msg,
                     "no OpenCL device found: is an ICD installed (e.g. pocl-opencl-icd)?");
        set_msg(error, error_size, msg);
        return st == SLUICE_OK ? SLUICE_ERROR_NO_DEVICE : st;
    }

    sluice_context *ctx = calloc(1, sizeof *ctx);
    if (!ctx) {
        set_msg(error, error_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    ctx->platform = ps.p;
    ctx->device = ps.d;
    fill_info(ps.p, ps.d, &ctx->info);
    ctx->profile = opt.profile;
    ctx->prof_epoch = 1;
    ctx->no_simd = opt.no_simd;
    ctx->verbose = opt.verbose;
    ctx->build_options = sl_strdup(opt.build_options ? opt.build_options : "");
    if (!ctx->build_options) {
        free(ctx);
        set_msg(error, error_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    ctx->chunk = opt.chunk;
    ctx->no_spread = opt.no_spread;
    ctx->no_chain = opt.no_chain;
    ctx->group_chain = env_on("SLUICE_GROUP_CHAIN");
    ctx->chain_cpu =
        ctx->info.is_cpu && strstr(ctx->info.platform, "Portable Computing Language") != NULL;
    ctx->layout = opt.layout != SLUICE_LAYOUT_AUTO ? (int)opt.layout
                  : ctx->info.is_cpu               ? SLUICE_LAYOUT_CONTIGUOUS
                                                   : SLUICE_LAYOUT_INTERLEAVED;
    /* GPUs run work-items in lockstep groups of 32 or 64: a work-group of 8
     * would leave most lanes idle */
    ctx->group = 8;
    if (ctx->layout == SLUICE_LAYOUT_INTERLEAVED) /* a power of two (the scans' trees) */
        for (ctx->group = 256; ctx->group > 1 && ctx->group > ctx->info.max_work_group_size;)
            ctx->group /= 2;
    cl_int err;
    cl_context_properties props[] = {CL_CONTEXT_PLATFORM, (cl_context_properties)ps.p, 0};
    ctx->cl = clCreateContext(props, 1, &ps.d, NULL, NULL, &err);
    if (!ctx->cl)
        goto cl_error;
    ctx->queue =
        clCreateCommandQueue(ctx->cl, ps.d, opt.profile ? CL_QUEUE_PROFILING_ENABLE : 0, &err);
    if (!ctx->queue)
        goto cl_error;
    ctx->vars =
        clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, SL_VAR_POOL * sizeof(cl_uint), NULL, &err);
    if (!ctx->vars)
        goto cl_error;
    ctx->var_used = calloc(SL_VAR_POOL, 1);
    ctx->embedded = calloc(sl_embedded_source_count, sizeof *ctx->embedded);
    if (!ctx->var_used || !ctx->embedded) {
        sluice_context_destroy(ctx);
        set_msg(error, error_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    *out = ctx;
    return SLUICE_OK;

cl_error : {
    char msg[256];
    snprintf(msg, sizeof msg, "creating an OpenCL context on \"%s\" failed: %s", ctx->info.name,
             sl_cl_error_string(err));
    set_msg(error, error_size, msg);
    sluice_context_destroy(ctx);
    return SLUICE_ERROR_OPENCL;
}
}

void sluice_context_destroy(sluice_context *ctx)
{
    if (!ctx)
        return;
    if (ctx->queue)
        clFinish(ctx->queue);
    sl_profile_free(ctx);
    free(ctx->build_options);
    if (ctx->scan_kernel)
        clReleaseKernel(ctx->scan_kernel);
    if (ctx->map_length_kernel)
        clReleaseKernel(ctx->map_length_kernel);
    if (ctx->embedded) {
        for (size_t i = 0; i < sl_embedded_source_count; ++i) {
            if (ctx->embedded[i]) {
                ctx->embedded[i]->owned_by_context = false;
                sluice_program_destroy(ctx->embedded[i]);
            }
        }
        free(ctx->embedded);
    }
    if (ctx->algorithms) {
        ctx->algorithms->owned_by_context = false;
        sluice_program_destroy(ctx->algorithms);
    }
    sl_program_cache_clear(ctx);
    sluice_context_release_scratch(ctx);
    if (ctx->vars)
        clReleaseMemObject(ctx->vars);
    if (ctx->queue)
        clReleaseCommandQueue(ctx->queue);
    if (ctx->cl)
        clReleaseContext(ctx->cl);
    free(ctx->var_used);
    free(ctx);
}

const char *sluice_context_error(const sluice_context *ctx)
{
    return ctx ? ctx->error : "no context";
}

sluice_status sluice_context_device(const sluice_context *ctx, sluice_device_info *info)
{
    if (!ctx || !info)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    *info = ctx->info;
    return SLUICE_OK;
}

sluice_status sluice_context_finish(sluice_context *ctx)
{
    sl_clear_error(ctx);
    if (!ctx)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    cl_int err = clFinish(ctx->queue);
    return err == CL_SUCCESS ? SLUICE_OK : sl_cl_fail(ctx, err, "clFinish");
}

size_t sluice_context_scratch_bytes(const sluice_context *ctx)
{
    return ctx ? ctx->scratch_bytes + ctx->chain_bytes : 0;
}

size_t sluice_context_sort_scratch_bytes(const sluice_context *ctx)
{
    if (!ctx)
        return 0;
    return ctx->sort_scratch_bytes *
           ((ctx->sort_scratch[0] != NULL) + (ctx->sort_scratch[1] != NULL));
}

void sluice_context_release_scratch(sluice_context *ctx)
{
    if (!ctx)
        return;
    /* An in-order queue: work queued before keeps the buffers alive. */
    cl_mem *ms[] = {&ctx->scratch, &ctx->chain, &ctx->sort_scratch[0], &ctx->sort_scratch[1]};
    for (size_t i = 0; i < sizeof ms / sizeof *ms; ++i) {
        if (*ms[i])
            clReleaseMemObject(*ms[i]);
        *ms[i] = NULL;
    }
    ctx->scratch_bytes = 0;
    ctx->chain_bytes = 0;
    ctx->chain_flags = 0;
    ctx->sort_scratch_bytes = 0;
}

void *sluice_context_cl_context(sluice_context *ctx)
{
    return ctx ? (void *)ctx->cl : NULL;
}

void *sluice_context_cl_queue(sluice_context *ctx)
{
    return ctx ? (void *)ctx->queue : NULL;
}

void *sluice_context_cl_device(sluice_context *ctx)
{
    return ctx ? (void *)ctx->device : NULL;
}

/* ---- variable pool ---- */

sluice_status sl_vars_alloc(sluice_context *ctx, size_t count, cl_uint *first)
{
    size_t run = 0;
    for (size_t i = 0; i < SL_VAR_POOL; ++i) {
        run = ctx->var_used[i] ? 0 : run + 1;
        if (run == count) {
            size_t start = i + 1 - count;
            memset(ctx->var_used + start, 1, count);
            *first = (cl_uint)start;
            return sl_vars_fill(ctx, (cl_uint)start, count, 0);
        }
    }
    return sl_fail(ctx, SLUICE_ERROR_LIMIT,
                   "the context's pool of %u device variables (stream lengths and counters) is "
                   "full: destroy unused streams or counters",
                   SL_VAR_POOL);
}

void sl_vars_free(sluice_context *ctx, cl_uint first, size_t count)
{
    if (first == SL_NONE)
        return;
    memset(ctx->var_used + first, 0, count);
}

sluice_status sl_vars_read(sluice_context *ctx, cl_uint first, size_t count, cl_uint *values)
{
    cl_int err = clEnqueueReadBuffer(ctx->queue, ctx->vars, CL_TRUE, first * sizeof(cl_uint),
                                     count * sizeof(cl_uint), values, 0, NULL, NULL);
    return err == CL_SUCCESS ? SLUICE_OK : sl_cl_fail(ctx, err, "reading device variables");
}

sluice_status sl_vars_fill(sluice_context *ctx, cl_uint first, size_t count, cl_uint value)
{
    cl_int err =
        clEnqueueFillBuffer(ctx->queue, ctx->vars, &value, sizeof value, first * sizeof(cl_uint),
                            count * sizeof(cl_uint), 0, NULL, NULL);
    return err == CL_SUCCESS ? SLUICE_OK : sl_cl_fail(ctx, err, "setting device variables");
}

/* Grows *buf (of *have bytes) to hold at least `bytes`, a new buffer of at
 * least 4 KiB, zeroed when `zero`; `what` names it in errors. */
static sluice_status grow_buffer(sluice_context *ctx, cl_mem *buf, size_t *have, size_t bytes,
                                 int zero, const char *what)
{
    if (bytes <= *have)
        return SLUICE_OK;
    size_t want = bytes < 4096 ? 4096 : bytes;
    cl_int err;
    cl_mem m = clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, want, NULL, &err);
    if (m && zero) {
        cl_uint z = 0;
        err = clEnqueueFillBuffer(ctx->queue, m, &z, sizeof z, 0, want, 0, NULL, NULL);
        if (err != CL_SUCCESS) {
            clReleaseMemObject(m);
            m = NULL;
        }
    }
    if (!m) {
        char msg[128];
        snprintf(msg, sizeof msg, "allocating %s", what);
        return sl_cl_fail(ctx, err, msg);
    }
    if (*buf)
        clReleaseMemObject(*buf); /* in-order queue: pending users keep it alive */
    *buf = m;
    *have = want;
    return SLUICE_OK;
}

sluice_status sl_scratch_reserve(sluice_context *ctx, size_t bytes)
{
    return grow_buffer(ctx, &ctx->scratch, &ctx->scratch_bytes, bytes, 0,
                       "scratch for ordered outputs");
}

sluice_status sl_chain_reserve(sluice_context *ctx, size_t flags, size_t values)
{
    if (flags > ctx->chain_flags) {
        /* a wider flag region moves the values: a buffer anew, zeroed (an
         * in-order queue: work queued before keeps the old one alive) */
        if (ctx->chain)
            clReleaseMemObject(ctx->chain);
        ctx->chain = NULL;
        ctx->chain_bytes = 0;
        ctx->chain_flags = flags;
    }
    sluice_status st = grow_buffer(ctx, &ctx->chain, &ctx->chain_bytes,
                                   (1 + ctx->chain_flags + values) * sizeof(cl_uint), 1,
                                   "the ordered outputs' chain");
    if (st != SLUICE_OK && !ctx->chain)
        ctx->chain_flags = 0;
    return st;
}

sluice_status sl_sort_scratch(sluice_context *ctx, size_t bytes, int two, cl_mem out[2])
{
    if (bytes > ctx->sort_scratch_bytes) { /* both buffers anew, at the new size */
        for (int i = 0; i < 2; ++i) {
            if (ctx->sort_scratch[i])
                clReleaseMemObject(ctx->sort_scratch[i]); /* in-order queue, as above */
            ctx->sort_scratch[i] = NULL;
        }
        ctx->sort_scratch_bytes = bytes;
    }
    for (int i = 0; i < 1 + (two != 0); ++i) {
        if (!ctx->sort_scratch[i]) {
            cl_int err;
            ctx->sort_scratch[i] =
                clCreateBuffer(ctx->cl, CL_MEM_READ_WRITE, ctx->sort_scratch_bytes, NULL, &err);
            if (!ctx->sort_scratch[i])
                return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY,
                               "cannot allocate %zu bytes of sort scratch (%s)",
                               ctx->sort_scratch_bytes, sl_cl_error_string(err));
        }
        out[i] = ctx->sort_scratch[i];
    }
    return SLUICE_OK;
}
