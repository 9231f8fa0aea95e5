/* See rt_kernels.h. */
#include "kernels.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

sluice_status sr_program_create(sluice_context *ctx, const char *const *names, size_t count,
                                const char *options, sluice_program **out)
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
    sluice_status st = sluice_program_create_source(ctx, names[count - 1], src, options, out);
    free(src);
    return st;
}
