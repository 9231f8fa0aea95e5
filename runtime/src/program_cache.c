/* Programs built in a context, kept for the next build (program_cache.h). */
#include "program_cache.h"

#include <stdlib.h>
#include <string.h>

/* FNV-1a over the options, a NUL and the source: finds the candidates; the
 * key itself is compared. */
static unsigned long long key_hash(const char *options, const char *source, size_t *len)
{
    unsigned long long h = 14695981039346656037ull;
    size_t n = 0;
    for (const char *parts[2] = {options, source}, **p = parts; p < parts + 2; ++p) {
        const char *c = *p;
        do {
            h = (h ^ (unsigned char)*c) * 1099511628211ull;
            ++n;
        } while (*c++);
    }
    *len = n;
    return h;
}

static int key_equal(const sl_kept_program *k, const char *options, const char *source)
{
    size_t ol = strlen(options) + 1;
    return memcmp(k->key, options, ol) == 0 && strcmp(k->key + ol, source) == 0;
}

cl_program sl_program_cache_find(sluice_context *ctx, const char *options, const char *source,
                                 char **log)
{
    *log = NULL;
    size_t len;
    unsigned long long h = key_hash(options, source, &len);
    for (size_t i = 0; i < ctx->kept_count; ++i) {
        sl_kept_program *k = &ctx->kept[i];
        if (k->hash != h || k->key_len != len || !key_equal(k, options, source))
            continue;
        *log = sl_strdup(k->log);
        if (!*log || clRetainProgram(k->cl) != CL_SUCCESS) {
            free(*log);
            *log = NULL;
            return NULL;
        }
        k->used = ++ctx->kept_clock;
        return k->cl;
    }
    return NULL;
}

static void kept_free(sl_kept_program *k)
{
    if (k->cl)
        clReleaseProgram(k->cl);
    free(k->key);
    free(k->log);
    memset(k, 0, sizeof *k);
}

void sl_program_cache_add(sluice_context *ctx, const char *options, const char *source,
                          cl_program prog, const char *log)
{
    size_t len;
    unsigned long long h = key_hash(options, source, &len);
    size_t ol = strlen(options) + 1;
    if (!ctx->kept && !(ctx->kept = calloc(SL_PROGRAM_CACHE_MAX, sizeof *ctx->kept)))
        return;
    char *key = malloc(len), *log_copy = sl_strdup(log ? log : "");
    if (!key || !log_copy || clRetainProgram(prog) != CL_SUCCESS) {
        free(key);
        free(log_copy);
        return;
    }
    memcpy(key, options, ol);
    memcpy(key + ol, source, len - ol);
    size_t slot = ctx->kept_count;
    if (slot == SL_PROGRAM_CACHE_MAX) { /* full: the least recently used goes */
        slot = 0;
        for (size_t i = 1; i < SL_PROGRAM_CACHE_MAX; ++i)
            if (ctx->kept[i].used < ctx->kept[slot].used)
                slot = i;
        kept_free(&ctx->kept[slot]);
    } else {
        ++ctx->kept_count;
    }
    ctx->kept[slot] = (sl_kept_program){key, len, h, prog, log_copy, ++ctx->kept_clock};
}

void sl_program_cache_clear(sluice_context *ctx)
{
    for (size_t i = 0; i < ctx->kept_count; ++i)
        kept_free(&ctx->kept[i]);
    free(ctx->kept);
    ctx->kept = NULL;
    ctx->kept_count = 0;
}
