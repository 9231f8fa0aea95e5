/* Test kernels that add to a film (apps/render/film.h): a program made of
 * the render layer's rt_types.h and film.cl (rt_add) plus the test's own
 * source, built. */
#ifndef SLUICE_TESTS_FILM_PROGRAM_H
#define SLUICE_TESTS_FILM_PROGRAM_H

#include "kernels.h"
#include "sluice/sluice.h"

#include <stdlib.h>
#include <string.h>

/* Creates and builds the program `name` from film.cl and `body`. Errors are
 * the context's (or SLUICE_ERROR_OUT_OF_MEMORY); `*out` is then NULL. */
static inline sluice_status film_program_create(sluice_context *ctx, const char *name,
                                                const char *body, sluice_program **out)
{
    static const char head[] = "#include \"sluice.cl\"\n";
    const char *parts[] = {"rt_types.h", "film.cl"};
    size_t len = sizeof head + strlen(body) + 1;
    for (int i = 0; i < 2; ++i)
        len += strlen(sr_kernel_text(parts[i])) + 1;
    *out = NULL;
    char *src = malloc(len);
    if (!src)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    strcpy(src, head);
    for (int i = 0; i < 2; ++i) {
        strcat(src, sr_kernel_text(parts[i]));
        strcat(src, "\n");
    }
    strcat(src, body);
    sluice_status st = sluice_program_create_source(ctx, name, src, NULL, out);
    free(src);
    if (st == SLUICE_OK && (st = sluice_program_build(*out)) != SLUICE_OK) {
        sluice_program_destroy(*out);
        *out = NULL;
    }
    return st;
}

#endif
