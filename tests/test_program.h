/* Test kernels built on the render layer's kernel sources: a program made of
 * sluice.cl, the named parts of the embedded kernel text (apps/render/kernels.h)
 * and the test's own source. */
#ifndef SLUICE_TESTS_TEST_PROGRAM_H
#define SLUICE_TESTS_TEST_PROGRAM_H

#include "kernels.h"
#include "sluice/sluice.h"

#include <stdlib.h>
#include <string.h>

/* Creates and builds the program `name` from the `n` embedded kernel files
 * `parts` (in order) and `body`. Errors are the context's (or
 * SLUICE_ERROR_OUT_OF_MEMORY); `*out` is then NULL. */
static inline sluice_status test_program_create(sluice_context *ctx, const char *name,
                                                const char *const *parts, size_t n,
                                                const char *body, sluice_program **out)
{
    static const char head[] = "#include \"sluice.cl\"\n";
    size_t len = sizeof head + strlen(body) + 1;
    for (size_t i = 0; i < n; ++i)
        len += strlen(sr_kernel_text(parts[i])) + 1;
    *out = NULL;
    char *src = malloc(len);
    if (!src)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    strcpy(src, head);
    for (size_t i = 0; i < n; ++i) {
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

/* A test program that adds to a film (apps/render/film.h): rt_types.h and
 * film.cl (rt_add) before `body`. */
static inline sluice_status film_program_create(sluice_context *ctx, const char *name,
                                                const char *body, sluice_program **out)
{
    static const char *const parts[] = {"rt_types.h", "film.cl"};
    return test_program_create(ctx, name, parts, 2, body, out);
}

#endif
