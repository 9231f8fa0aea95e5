/* See rt_kernels.h. */
#include "kernels.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The program named `name` (build errors say "building NAME failed"). */
static sluice_status program_create(sluice_context *ctx, const char *name, const char *const *names,
                                    size_t count, const char *options, sluice_program **out)
{
    if (!ctx || !names || !count || !out)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    size_t total = 1;
    for (size_t i = 0; i < count; ++i) {
        const char *t = sr_kernel_text(names[i]);
        if (!t)
            return SLUICE_ERROR_NOT_FOUND;
        total += strlen(t) + strlen(names[i]) + 32;
    }
    char *src = malloc(total), *p = src;
    if (!src)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    for (size_t i = 0; i < count; ++i)
        p += sprintf(p, "#line 1 \"%s\"\n%s\n", names[i], sr_kernel_text(names[i]));
    sluice_status st = sluice_program_create_source(ctx, name, src, options, out);
    free(src);
    return st;
}

sluice_status sr_program_create(sluice_context *ctx, const char *const *names, size_t count,
                                const char *options, sluice_program **out)
{
    if (!names || !count)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    return program_create(ctx, names[count - 1], names, count, options, out);
}

sluice_status sr_shared_program_create(sluice_context *ctx, const char *const *names, size_t count,
                                       const char *options, sluice_program **out)
{
    sluice_device_info info;
    if (!ctx || sluice_context_device(ctx, &info) != SLUICE_OK || !info.is_cpu)
        return sr_program_create(ctx, names, count, options, out);
    /* The headers first; tri_box.h, whose FP_CONTRACT OFF holds to the end
     * of the text, with grid.cl last: every source keeps the contraction
     * it had in a program of its own (pg_types.h and triangle.cl turn it
     * off before the others' code, as they did there). */
    static const char *const shared[] = {
        "rt_types.h",   "pg_types.h",    "pm_types.h", "triangle.cl", "film.cl", "surface.cl",
        "pm_render.cl", "point_grid.cl", "pm_knn.cl",  "tri_box.h",   "grid.cl"};
    return program_create(ctx, "the shared render kernels", shared, sizeof shared / sizeof *shared,
                          options, out);
}
