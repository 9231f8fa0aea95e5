/* Profiling: per-kernel launches, records, bytes and OpenCL event time. */
#include "internal.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

int sluice_profile_enabled(const sluice_context *ctx)
{
    return ctx ? ctx->profile : 0;
}

/* Most raw launches whose record count, read from the device, waits to be
 * added up (a fixed array: the reads land in it). */
#define SL_PENDING_RECORDS 256

size_t sl_profile_entry(sluice_context *ctx, const char *name)
{
    for (size_t i = 0; i < ctx->prof_count; ++i)
        if (strncmp(ctx->prof[i].e.name, name, sizeof ctx->prof[i].e.name - 1) == 0)
            return i;
    if (ctx->prof_count == ctx->prof_cap) {
        size_t cap = ctx->prof_cap ? ctx->prof_cap * 2 : 16;
        sl_profile_slot *p = realloc(ctx->prof, cap * sizeof *p);
        if (!p)
            return SL_NO_ENTRY; /* the launch goes uncounted rather than failing */
        ctx->prof = p;
        ctx->prof_cap = cap;
    }
    sl_profile_slot *s = &ctx->prof[ctx->prof_count];
    memset(s, 0, sizeof *s);
    snprintf(s->e.name, sizeof s->e.name, "%s", name);
    return ctx->prof_count++;
}

size_t sl_profile_kernel_entry(sluice_kernel *k)
{
    sluice_context *ctx = k->ctx;
    if (k->prof_epoch != ctx->prof_epoch) {
        size_t entry = sl_profile_entry(ctx, k->name);
        if (entry == SL_NO_ENTRY)
            return entry;
        k->prof_entry = entry;
        k->prof_epoch = ctx->prof_epoch;
    }
    return k->prof_entry;
}

/* Adds the pending device-side record counts to their entries; the queue
 * must have finished. */
static void add_pending_records(sluice_context *ctx)
{
    for (size_t i = 0; i < ctx->pending_records_count; ++i) {
        const sl_pending_records *r = &ctx->pending_records[i];
        cl_uint n = r->value <= r->cap ? r->value : 0u;
        ctx->prof[r->entry].e.records_in += n;
        ctx->prof[r->entry].e.bytes += (uint64_t)n * r->record_bytes;
    }
    ctx->pending_records_count = 0;
}

static void add_records(sluice_context *ctx, size_t entry, const sl_raw_io *io)
{
    if (!io)
        return;
    sl_profile_slot *s = &ctx->prof[entry];
    if (io->n != SL_NONE) {
        s->e.records_in += io->n;
        s->e.bytes += (uint64_t)io->n * io->record_bytes;
        return;
    }
    /* The length as the launch reads it: a read queued behind it. */
    if (!ctx->pending_records) {
        ctx->pending_records = malloc(SL_PENDING_RECORDS * sizeof *ctx->pending_records);
        if (!ctx->pending_records)
            return; /* uncounted rather than failing the launch */
    }
    if (ctx->pending_records_count == SL_PENDING_RECORDS) {
        if (clFinish(ctx->queue) != CL_SUCCESS)
            return;
        add_pending_records(ctx);
    }
    sl_pending_records *r = &ctx->pending_records[ctx->pending_records_count];
    r->entry = entry;
    r->value = 0;
    r->cap = io->cap;
    r->record_bytes = io->record_bytes;
    if (clEnqueueReadBuffer(ctx->queue, ctx->vars, CL_FALSE, io->var * sizeof(cl_uint),
                            sizeof(cl_uint), &r->value, 0, NULL, NULL) == CL_SUCCESS)
        ctx->pending_records_count++;
}

static void resolve_events(sluice_context *ctx)
{
    for (size_t i = 0; i < ctx->pending_count; ++i) {
        cl_event ev = ctx->pending[i].event;
        cl_ulong t0 = 0, t1 = 0;
        if (clWaitForEvents(1, &ev) == CL_SUCCESS &&
            clGetEventProfilingInfo(ev, CL_PROFILING_COMMAND_START, sizeof t0, &t0, NULL) ==
                CL_SUCCESS &&
            clGetEventProfilingInfo(ev, CL_PROFILING_COMMAND_END, sizeof t1, &t1, NULL) ==
                CL_SUCCESS &&
            t1 >= t0 && ctx->pending[i].entry < ctx->prof_count)
            ctx->prof[ctx->pending[i].entry].e.device_seconds += (double)(t1 - t0) * 1e-9;
        clReleaseEvent(ev);
    }
    ctx->pending_count = 0;
}

/* Keeps `ev` to add its time to `entry` when the profile is settled. */
static void track_event(sluice_context *ctx, size_t entry, cl_event ev)
{
    if (ctx->pending_count == ctx->pending_cap) {
        size_t cap = ctx->pending_cap ? ctx->pending_cap * 2 : 256;
        sl_pending_event *p = cap <= 65536 ? realloc(ctx->pending, cap * sizeof *p) : NULL;
        if (!p) {
            resolve_events(ctx); /* bounded memory: settle what is queued */
        } else {
            ctx->pending = p;
            ctx->pending_cap = cap;
        }
    }
    if (ctx->pending_count < ctx->pending_cap) {
        ctx->pending[ctx->pending_count].event = ev;
        ctx->pending[ctx->pending_count].entry = entry;
        ctx->pending_count++;
    } else {
        clReleaseEvent(ev);
    }
}

void sl_profile_command(sluice_context *ctx, size_t entry, cl_event ev, int launch,
                        const sl_raw_io *io)
{
    if (entry == SL_NO_ENTRY) {
        clReleaseEvent(ev);
        return;
    }
    if (launch)
        ctx->prof[entry].e.launches++;
    track_event(ctx, entry, ev);
    add_records(ctx, entry, io);
}

sluice_status sl_profile_sync(sluice_context *ctx)
{
    if (!ctx->profile)
        return SLUICE_OK;
    cl_int err = clFinish(ctx->queue);
    if (err != CL_SUCCESS)
        return sl_cl_fail(ctx, err, "clFinish");
    resolve_events(ctx);
    add_pending_records(ctx);
    for (sluice_kernel *k = ctx->kernels; k; k = k->next_live) {
        if (k->prof_var == SL_NONE || k->prof_epoch != ctx->prof_epoch)
            continue; /* not launched since the last reset: nothing counted */
        cl_uint v[1 + SLUICE_MAX_OUTPUTS];
        sluice_status st = sl_vars_read(ctx, k->prof_var, 1 + SLUICE_MAX_OUTPUTS, v);
        if (st != SLUICE_OK)
            return st;
        sl_profile_slot *s = &ctx->prof[k->prof_entry];
        s->e.records_in += v[0];
        s->e.bytes += (uint64_t)v[0] * (s->in_record_size + s->mapped_record_size);
        for (unsigned o = 0; o < SLUICE_MAX_OUTPUTS; ++o) {
            s->e.records_out += v[1 + o];
            s->e.bytes += (uint64_t)v[1 + o] * s->out_record_size[o];
        }
        st = sl_vars_fill(ctx, k->prof_var, 1 + SLUICE_MAX_OUTPUTS, 0);
        if (st != SLUICE_OK)
            return st;
    }
    return SLUICE_OK;
}

void sl_profile_free(sluice_context *ctx)
{
    resolve_events(ctx);
    free(ctx->pending);
    free(ctx->prof);
    free(ctx->pending_records); /* the queue has finished: no read is landing */
    ctx->pending = NULL;
    ctx->prof = NULL;
    ctx->pending_records = NULL;
    ctx->pending_count = ctx->pending_cap = ctx->prof_count = ctx->prof_cap = 0;
    ctx->pending_records_count = 0;
}

size_t sluice_profile_count(sluice_context *ctx)
{
    if (!ctx || !ctx->profile)
        return 0;
    sl_profile_sync(ctx);
    return ctx->prof_count;
}

sluice_status sluice_profile_get(sluice_context *ctx, size_t index, sluice_profile_entry *entry)
{
    if (!ctx || !entry)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    sluice_status st = sl_profile_sync(ctx);
    if (st != SLUICE_OK)
        return st;
    if (index >= ctx->prof_count)
        return sl_fail(ctx, SLUICE_ERROR_INVALID_ARGUMENT, "profile entry %zu of %zu", index,
                       ctx->prof_count);
    *entry = ctx->prof[index].e;
    return SLUICE_OK;
}

sluice_status sluice_profile_print(sluice_context *ctx, FILE *out)
{
    if (!ctx || !out)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    if (!ctx->profile) {
        fprintf(out, "profiling is off (set SLUICE_PROFILE=1 or the profile option)\n");
        return SLUICE_OK;
    }
    sluice_status st = sl_profile_sync(ctx);
    if (st != SLUICE_OK)
        return st;
    fprintf(out, "%-32s %9s %12s %12s %12s %10s %8s\n", "kernel", "launches", "records in",
            "records out", "MB", "ms", "GB/s");
    double total = 0;
    for (size_t i = 0; i < ctx->prof_count; ++i) {
        const sluice_profile_entry *e = &ctx->prof[i].e;
        double ms = e->device_seconds * 1e3;
        total += ms;
        fprintf(out, "%-32s %9llu %12llu %12llu %12.2f %10.3f %8.2f\n", e->name,
                (unsigned long long)e->launches, (unsigned long long)e->records_in,
                (unsigned long long)e->records_out, (double)e->bytes / 1e6, ms,
                e->device_seconds > 0 ? (double)e->bytes / e->device_seconds / 1e9 : 0.0);
    }
    fprintf(out, "%-32s %9s %12s %12s %12s %10.3f\n", "total", "", "", "", "", total);
    return SLUICE_OK;
}

static void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; ++s) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(f, "\\%c", c);
        else if (c < 0x20)
            fprintf(f, "\\u%04x", c);
        else
            fputc(c, f);
    }
    fputc('"', f);
}

sluice_status sluice_profile_write_json(sluice_context *ctx, const char *path)
{
    if (!ctx || !path)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    sl_clear_error(ctx);
    sluice_status st = sl_profile_sync(ctx);
    if (st != SLUICE_OK)
        return st;
    FILE *f = fopen(path, "w");
    if (!f)
        return sl_fail(ctx, SLUICE_ERROR_IO, "cannot write %s: %s", path, strerror(errno));
    fprintf(f, "{\n  \"device\": ");
    json_string(f, ctx->info.name);
    fprintf(f, ",\n  \"profiling\": %s,\n  \"kernels\": [", ctx->profile ? "true" : "false");
    for (size_t i = 0; i < ctx->prof_count; ++i) {
        const sluice_profile_entry *e = &ctx->prof[i].e;
        fprintf(f, "%s\n    {\"name\": ", i ? "," : "");
        json_string(f, e->name);
        fprintf(f,
                ", \"launches\": %llu, \"records_in\": %llu, \"records_out\": %llu, "
                "\"bytes\": %llu, \"device_seconds\": %.9f}",
                (unsigned long long)e->launches, (unsigned long long)e->records_in,
                (unsigned long long)e->records_out, (unsigned long long)e->bytes,
                e->device_seconds);
    }
    fprintf(f, "\n  ]\n}\n");
    if (fclose(f) != 0)
        return sl_fail(ctx, SLUICE_ERROR_IO, "error writing %s", path);
    return SLUICE_OK;
}

void sluice_profile_reset(sluice_context *ctx)
{
    if (!ctx)
        return;
    sl_profile_sync(ctx); /* folds in what the device counted, and zeroes it */
    ctx->prof_count = 0;
    ctx->pending_records_count = 0;
    ctx->prof_epoch++; /* every kernel makes its entry again at its next launch */
}
