/* Programs: OpenCL C source built lazily, once. */
#include "internal.h"

#include "build_log.h"
#include "program_cache.h"

#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

const char *sl_embedded_find(const char *name)
{
    for (size_t i = 0; i < sl_embedded_source_count; ++i)
        if (strcmp(sl_embedded_sources[i].name, name) == 0)
            return sl_embedded_sources[i].text;
    return NULL;
}

/* Is this line `#include "sluice.cl"` or `#include <sluice.cl>`? */
static int is_sluice_include(const char *line, size_t len)
{
    size_t i = 0;
    while (i < len && (line[i] == ' ' || line[i] == '\t'))
        ++i;
    if (i >= len || line[i] != '#')
        return 0;
    ++i;
    while (i < len && (line[i] == ' ' || line[i] == '\t'))
        ++i;
    if (len - i < 7 || strncmp(line + i, "include", 7) != 0)
        return 0;
    i += 7;
    while (i < len && (line[i] == ' ' || line[i] == '\t'))
        ++i;
    return (len - i >= 11) && (strncmp(line + i, "\"sluice.cl\"", 11) == 0 ||
                               strncmp(line + i, "<sluice.cl>", 11) == 0);
}

/* The text handed to the compiler: the embedded sluice.cl, then the user's
 * source with its include lines of sluice.cl blanked (line numbers stay
 * right). A #line directive before each names its file, so that messages say
 * sluice.cl:LINE or the user's file:LINE. */
static char *compose_source(const char *name, const char *source)
{
    const char *header = sl_embedded_find("sluice.cl");
    size_t hl = header ? strlen(header) : 0, sl = strlen(source), nl = strlen(name);
    char *out = malloc(hl + sl + nl + 96);
    if (!out)
        return NULL;
    char *p = out;
    if (header) {
        p += sprintf(p, "#line 1 \"sluice.cl\"\n");
        memcpy(p, header, hl);
        p += hl;
    }
    p += sprintf(p, "\n#line 1 \"");
    for (const char *c = name; *c; ++c) /* quotes and backslashes would end the string */
        *p++ = (*c == '"' || *c == '\\') ? '_' : *c;
    p += sprintf(p, "\"\n");
    const char *s = source;
    while (*s) {
        const char *e = strchr(s, '\n');
        size_t len = e ? (size_t)(e - s) : strlen(s);
        if (!is_sluice_include(s, len)) {
            memcpy(p, s, len);
            p += len;
        }
        if (e)
            *p++ = '\n';
        s += len + (e ? 1 : 0);
    }
    *p = 0;
    return out;
}

sluice_status sluice_program_create_source(sluice_context *ctx, const char *name,
                                           const char *source, const char *options,
                                           sluice_program **out)
{
    sl_clear_error(ctx);
    if (out)
        *out = NULL;
    if (!ctx || !source || !out)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_program_create_source: NULL context, source or out");
    if (!name)
        name = "<string>";
    sluice_program *p = calloc(1, sizeof *p);
    if (!p)
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
    p->ctx = ctx;
    p->name = sl_strdup(name);
    p->source = compose_source(name, source);
    p->options = sl_strdup(options ? options : "");
    p->log = sl_strdup("");
    if (!p->name || !p->source || !p->options || !p->log) {
        sluice_program_destroy(p);
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
    }
    *out = p;
    return SLUICE_OK;
}

sluice_status sluice_program_create_file(sluice_context *ctx, const char *path, const char *options,
                                         sluice_program **out)
{
    sl_clear_error(ctx);
    if (out)
        *out = NULL;
    if (!ctx || !path || !out)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT,
                       "sluice_program_create_file: NULL context, path or out");
    FILE *f = fopen(path, "rb");
    if (!f)
        return sl_fail(ctx, SLUICE_ERROR_IO, "cannot open kernel file %s: %s", path,
                       strerror(errno));
    char *text = NULL;
    size_t len = 0, cap = 0;
    for (;;) {
        if (len + 4096 + 1 > cap) {
            cap = cap ? cap * 2 : 8192;
            char *t = realloc(text, cap);
            if (!t) {
                free(text);
                fclose(f);
                return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
            }
            text = t;
        }
        size_t got = fread(text + len, 1, 4096, f);
        len += got;
        if (got < 4096)
            break;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(text);
        return sl_fail(ctx, SLUICE_ERROR_IO, "error reading kernel file %s", path);
    }
    text[len] = 0;
    if (strlen(text) != len) {
        free(text);
        return sl_fail(ctx, SLUICE_ERROR_IO, "kernel file %s contains a NUL byte: not OpenCL C",
                       path);
    }
    sluice_status st = sluice_program_create_source(ctx, path, text, options, out);
    free(text);
    return st;
}

void sluice_program_destroy(sluice_program *p)
{
    if (!p || p->owned_by_context)
        return;
    if (p->cl)
        clReleaseProgram(p->cl);
    free(p->name);
    free(p->source);
    free(p->options);
    free(p->log);
    free(p);
}

/* Standard error (file descriptor 2) sent to a temporary file while the
 * compiler runs: clang writes its summary line there itself. File descriptor
 * 2 belongs to the whole process, so captures are serialised by the
 * library's one process-wide lock: two contexts building on two threads
 * would otherwise each save the other's temporary file as "the real
 * stderr" and could leave it redirected for good. */
static pthread_mutex_t capture_lock = PTHREAD_MUTEX_INITIALIZER;

typedef struct stderr_capture {
    FILE *file; /* NULL: nothing captured (stderr left alone) */
    int saved;  /* the real stderr */
} stderr_capture;

static void capture_begin(stderr_capture *c)
{
    c->file = NULL;
    c->saved = -1;
    pthread_mutex_lock(&capture_lock);
    fflush(stderr);
    FILE *f = tmpfile();
    if (!f)
        return; /* no temporary file: the compiler's chatter gets through */
    int saved = dup(STDERR_FILENO);
    if (saved >= 0 && dup2(fileno(f), STDERR_FILENO) >= 0) {
        c->file = f;
        c->saved = saved;
        return;
    }
    if (saved >= 0)
        close(saved);
    fclose(f);
}

/* Restores stderr and writes to it what was captured: all of it when
 * `everything`, else all but the compiler's summary lines (what other code,
 * or another thread, wrote meanwhile is passed on, not lost). */
static void capture_end(stderr_capture *c, bool everything)
{
    if (!c->file) {
        pthread_mutex_unlock(&capture_lock);
        return;
    }
    fflush(stderr);
    dup2(c->saved, STDERR_FILENO);
    close(c->saved);
    rewind(c->file);
    char *line = NULL;
    size_t cap = 0;
    ssize_t len;
    while ((len = getline(&line, &cap, c->file)) > 0)
        if (everything || !sl_build_log_is_count(line, (size_t)len))
            fwrite(line, 1, (size_t)len, stderr);
    free(line);
    fclose(c->file);
    c->file = NULL;
    pthread_mutex_unlock(&capture_lock);
}

/* The message of a failed build. Each vendor words its log its own way, so
 * the message leads with the errors in one shape, `file:line:col: error:
 * message`, the first error first (build_log.h; warnings too when verbose),
 * for editors and for people reading the first line. The raw log follows
 * when it holds more than that (source excerpts, carets, notes) or when
 * verbose; it stays in sluice_program_build_log() in any case. */
static sluice_status build_failure(sluice_program *p)
{
    sluice_context *ctx = p->ctx;
    const char *log = p->log && p->log[0] ? p->log : "(no log)\n";
    size_t n = strlen(log);
    const char *nl = log[n - 1] == '\n' ? "" : "\n";
    bool more = false;
    char *digest = sl_build_log_digest(log, p->name, ctx->verbose != 0, &more);
    sluice_status st;
    if (!digest || !digest[0])
        st = sl_fail(ctx, SLUICE_ERROR_BUILD, "building %s failed:\n%s%s", p->name, log, nl);
    else if (more || ctx->verbose)
        st = sl_fail(ctx, SLUICE_ERROR_BUILD, "%sbuilding %s failed; the compiler's log:\n%s%s",
                     digest, p->name, log, nl);
    else
        st = sl_fail(ctx, SLUICE_ERROR_BUILD,
                     "%sbuilding %s failed (the compiler's log: sluice_program_build_log())\n",
                     digest, p->name);
    free(digest);
    return st;
}

sluice_status sluice_program_build(sluice_program *p)
{
    if (!p)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(p->ctx);
    if (p->cl)
        return SLUICE_OK;
    sluice_context *ctx = p->ctx;
    cl_int err;
    size_t ol = strlen(p->options) + strlen(ctx->build_options) + 128;
    char *opts = malloc(ol);
    if (!opts)
        return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
    /* the interleaved layout's stream kernels reserve room per work-group
     * (group emission, kernels/sluice.cl), and with SLUICE_GROUP_CHAIN=1
     * place ordered outputs by the groups' chain; off CPUs the loops over a
     * work-item's outputs are unrolled, to keep its state in registers */
    snprintf(opts, ol, "-cl-std=CL1.2%s%s%s%s %s %s", ctx->no_simd ? " -DSLUICE_NO_SIMD" : "",
             ctx->layout == SLUICE_LAYOUT_INTERLEAVED ? " -DSLUICE_GROUP_EMIT_" : "",
             ctx->layout == SLUICE_LAYOUT_INTERLEAVED && ctx->group_chain ? " -DSLUICE_GROUP_CHAIN_"
                                                                          : "",
             ctx->info.is_cpu ? "" : " -DSLUICE_UNROLL_STATE_", p->options, ctx->build_options);
    /* built before in this context: taken as it is (verbose builds compile
     * again, so that the compiler's own output shows) */
    char *kept_log = NULL;
    cl_program kept = ctx->verbose ? NULL : sl_program_cache_find(ctx, opts, p->source, &kept_log);
    if (kept) {
        free(opts);
        free(p->log);
        p->log = kept_log;
        p->cl = kept;
        return SLUICE_OK;
    }
    const char *src = p->source;
    cl_program prog = clCreateProgramWithSource(ctx->cl, 1, &src, NULL, &err);
    if (!prog) {
        free(opts);
        return sl_cl_fail(ctx, err, "clCreateProgramWithSource");
    }
    stderr_capture capture;
    capture_begin(&capture);
    err = clBuildProgram(prog, 1, &ctx->device, opts, NULL, NULL);
    capture_end(&capture, err != CL_SUCCESS || ctx->verbose);
    size_t log_size = 0;
    clGetProgramBuildInfo(prog, ctx->device, CL_PROGRAM_BUILD_LOG, 0, NULL, &log_size);
    char *log = malloc(log_size + 1);
    if (log) {
        log[0] = 0;
        clGetProgramBuildInfo(prog, ctx->device, CL_PROGRAM_BUILD_LOG, log_size, log, NULL);
        log[log_size] = 0;
        /* Locations in NVIDIA's "<kernel>" become our file names and lines. */
        char *relocated = sl_build_log_relocate(log, p->source);
        if (relocated) {
            free(log);
            log = relocated;
        }
        free(p->log);
        p->log = log;
    }
    if (ctx->verbose && p->log && p->log[0]) {
        size_t n = strlen(p->log);
        fprintf(stderr, "sluice: build log of %s:\n%s%s", p->name, p->log,
                p->log[n - 1] == '\n' ? "" : "\n");
    }
    if (err != CL_SUCCESS) {
        free(opts);
        clReleaseProgram(prog);
        if (err == CL_BUILD_PROGRAM_FAILURE || err == CL_INVALID_BUILD_OPTIONS)
            return build_failure(p);
        return sl_cl_fail(ctx, err, "clBuildProgram");
    }
    sl_program_cache_add(ctx, opts, p->source, prog, p->log);
    free(opts);
    p->cl = prog;
    return SLUICE_OK;
}

const char *sluice_program_build_log(const sluice_program *p)
{
    return (p && p->log) ? p->log : "";
}

/* Does embedded source `name` go into the stream algorithms' program
 * (every embedded source but the prelude, sluice.cl)? The runtime's own
 * kernels (runtime.cl: the ordered outputs' scan, mapped lengths) go with
 * them: a process that binds an output almost always runs an algorithm too,
 * and one build costs less than two. */
static bool is_algorithm_source(const char *name)
{
    return strcmp(name, "sluice.cl") != 0;
}

/* The stream algorithms' sources as one program, for CPU devices. PoCL
 * preprocesses a program's text with some 900 KB of OpenCL headers before it
 * looks in its cache, a fixed cost of each build however warm the cache, and
 * compiles a kernel only at its first launch, so one program costs less than
 * the several a process asks for (bench/README.md has the figures). Each
 * source keeps its file name and lines in messages (#line). */
static sluice_status algorithms_program(sluice_context *ctx, sluice_program **out)
{
    if (!ctx->algorithms) {
        size_t n = 1;
        for (size_t i = 0; i < sl_embedded_source_count; ++i)
            if (is_algorithm_source(sl_embedded_sources[i].name))
                n += strlen(sl_embedded_sources[i].name) + strlen(sl_embedded_sources[i].text) + 16;
        char *text = malloc(n), *t = text;
        if (!text)
            return sl_fail(ctx, SLUICE_ERROR_OUT_OF_MEMORY, "out of host memory");
        for (size_t i = 0; i < sl_embedded_source_count; ++i)
            if (is_algorithm_source(sl_embedded_sources[i].name))
                t += sprintf(t, "#line 1 \"%s\"\n%s\n", sl_embedded_sources[i].name,
                             sl_embedded_sources[i].text);
        sluice_program *p;
        sluice_status st =
            sluice_program_create_source(ctx, "the stream algorithms", text, NULL, &p);
        free(text);
        if (st != SLUICE_OK)
            return st;
        p->owned_by_context = true;
        ctx->algorithms = p;
    }
    *out = ctx->algorithms;
    return sluice_program_build(*out);
}

sluice_status sl_embedded_program(sluice_context *ctx, const char *name, sluice_program **out)
{
    if (ctx->info.is_cpu && is_algorithm_source(name) && sl_embedded_find(name))
        return algorithms_program(ctx, out);
    for (size_t i = 0; i < sl_embedded_source_count; ++i) {
        if (strcmp(sl_embedded_sources[i].name, name) != 0)
            continue;
        if (!ctx->embedded[i]) {
            sluice_program *p;
            sluice_status st =
                sluice_program_create_source(ctx, name, sl_embedded_sources[i].text, NULL, &p);
            if (st != SLUICE_OK)
                return st;
            p->owned_by_context = true;
            ctx->embedded[i] = p;
        }
        *out = ctx->embedded[i];
        return sluice_program_build(*out);
    }
    return sl_fail(ctx, SLUICE_ERROR_NOT_FOUND, "no embedded kernel source named %s", name);
}

sluice_status sl_embedded_cl_kernel(sluice_context *ctx, const char *program, const char *kernel,
                                    cl_kernel *out)
{
    sluice_program *p;
    sluice_status st = sl_embedded_program(ctx, program, &p);
    if (st != SLUICE_OK)
        return st;
    cl_int err;
    *out = clCreateKernel(p->cl, kernel, &err);
    if (!*out)
        return sl_fail(ctx, SLUICE_ERROR_NOT_FOUND, "kernel %s not found in %s: %s", kernel,
                       program, sl_cl_error_string(err));
    return SLUICE_OK;
}

void sl_set_arg(cl_kernel k, cl_uint i, size_t size, const void *value, cl_int *err)
{
    if (*err == CL_SUCCESS)
        *err = clSetKernelArg(k, i, size, value);
}

size_t sl_kernel_group(sluice_context *ctx, cl_kernel k, size_t want)
{
    if (want <= 8)
        return want;
    size_t most = 0;
    if (clGetKernelWorkGroupInfo(k, ctx->device, CL_KERNEL_WORK_GROUP_SIZE, sizeof most, &most,
                                 NULL) != CL_SUCCESS ||
        most == 0)
        return want;
    while (want > 1 && want > most)
        want /= 2;
    return want;
}

sluice_status sl_enqueue_raw(sluice_context *ctx, cl_kernel k, const char *name, size_t global,
                             size_t local, const sl_raw_io *io)
{
    if (global == 0)
        return SLUICE_OK;
    if (local) {
        /* as many groups, each smaller where the kernel needs it (the
         * group kernels loop over their tile with the group's size) */
        size_t groups = (global + local - 1) / local;
        local = sl_kernel_group(ctx, k, local);
        global = groups * local;
    }
    cl_event ev = NULL;
    cl_int err = clEnqueueNDRangeKernel(ctx->queue, k, 1, NULL, &global, local ? &local : NULL, 0,
                                        NULL, ctx->profile ? &ev : NULL);
    if (err != CL_SUCCESS) {
        char what[128];
        snprintf(what, sizeof what, "launching %s", name);
        return sl_cl_fail(ctx, err, what);
    }
    if (ev)
        sl_profile_command(ctx, sl_profile_entry(ctx, name), ev, 1, io);
    return SLUICE_OK;
}
