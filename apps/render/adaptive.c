/* See adaptive.h. */
#include "adaptive.h"
#include "app_error.h"
#include "clock.h"
#include "image.h"
#include "image_metrics.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct sr_adaptive {
    sluice_context *ctx;
    sr_adaptive_options opt;
    unsigned width, height, across, down;
    uint32_t *samples; /* per tile */
    uint32_t *list;    /* active tiles, host copy */
    uint8_t *active;   /* per tile */
    double *tile_error;
    size_t active_count, active_pixels;
    unsigned next_check;
    sluice_stream *list_dev;
    sr_image *all, *odd; /* made at the first check */
    sr_adaptive_stats stats;
};

void sr_adaptive_destroy(sr_adaptive *a)
{
    if (!a)
        return;
    free(a->samples);
    free(a->list);
    free(a->active);
    free(a->tile_error);
    sluice_stream_destroy(a->list_dev);
    sr_image_destroy(a->all);
    sr_image_destroy(a->odd);
    free(a);
}

static size_t tile_pixels(const sr_adaptive *a, uint32_t t)
{
    unsigned tx = t % a->across, ty = t / a->across;
    unsigned w = a->width - tx * SR_FILM_TILE, h = a->height - ty * SR_FILM_TILE;
    return (size_t)(w < SR_FILM_TILE ? w : SR_FILM_TILE) * (h < SR_FILM_TILE ? h : SR_FILM_TILE);
}

/* Rebuilds the list of active tiles and uploads it. */
static sluice_status update_list(sr_adaptive *a)
{
    size_t n = 0, px = 0;
    unsigned tiles = a->across * a->down;
    for (uint32_t t = 0; t < tiles; ++t)
        if (a->active[t]) {
            a->list[n++] = t;
            px += tile_pixels(a, t);
        }
    a->active_count = n;
    a->active_pixels = px;
    a->stats.tiles_active = (unsigned)n;
    return n ? sluice_stream_upload(a->list_dev, a->list, n) : SLUICE_OK;
}

sluice_status sr_adaptive_create(sluice_context *ctx, unsigned width, unsigned height,
                                 const sr_adaptive_options *opt, sr_adaptive **out, char *err,
                                 size_t err_size)
{
    if (out)
        *out = NULL;
    sr_adaptive_options o = opt ? *opt : (sr_adaptive_options){0};
    if (o.min_samples == 0)
        o.min_samples = 8;
    if (!ctx || !out || width == 0 || height == 0 || !(o.target >= 0 && o.target < INFINITY) ||
        o.min_samples < 2 || o.min_samples % 2) {
        sr_set_error(err, err_size, "adaptive sampling: bad options");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sr_adaptive *a = calloc(1, sizeof *a);
    if (!a) {
        sr_set_error(err, err_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    a->ctx = ctx;
    a->opt = o;
    a->width = width;
    a->height = height;
    a->across = (width + SR_FILM_TILE - 1) / SR_FILM_TILE;
    a->down = (height + SR_FILM_TILE - 1) / SR_FILM_TILE;
    size_t tiles = (size_t)a->across * a->down;
    a->samples = calloc(tiles, sizeof *a->samples);
    a->list = malloc(tiles * sizeof *a->list);
    a->active = malloc(tiles);
    a->tile_error = malloc(tiles * sizeof *a->tile_error);
    a->next_check = o.min_samples;
    a->stats.tiles = (unsigned)tiles;
    a->stats.target = o.target;
    a->stats.adaptive = o.adaptive;
    a->stats.error = a->stats.error_uniform = -1.0;
    sluice_status st = SLUICE_OK;
    if (!a->samples || !a->list || !a->active || !a->tile_error) {
        sr_set_error(err, err_size, "out of host memory");
        st = SLUICE_ERROR_OUT_OF_MEMORY;
    } else {
        memset(a->active, 1, tiles);
        st = sluice_stream_create(ctx, sizeof(uint32_t), tiles, &a->list_dev);
        if (st == SLUICE_OK)
            st = update_list(a);
        if (st != SLUICE_OK)
            sr_set_error(err, err_size, "adaptive sampling: %s", sluice_context_error(ctx));
    }
    if (st != SLUICE_OK) {
        sr_adaptive_destroy(a);
        return st;
    }
    *out = a;
    return SLUICE_OK;
}

unsigned sr_adaptive_begin_sample(sr_adaptive *a)
{
    unsigned s = a->stats.samples++;
    for (size_t i = 0; i < a->active_count; ++i)
        a->samples[a->list[i]]++;
    a->stats.pixel_samples += a->active_pixels;
    a->stats.pixel_uniform += (uint64_t)a->width * a->height;
    return s;
}

sluice_stream *sr_adaptive_tile_list(sr_adaptive *a)
{
    return a ? a->list_dev : NULL;
}

size_t sr_adaptive_active_tiles(const sr_adaptive *a)
{
    return a ? a->active_count : 0;
}

size_t sr_adaptive_active_pixels(const sr_adaptive *a)
{
    return a ? a->active_pixels : 0;
}

const uint32_t *sr_adaptive_tile_samples(const sr_adaptive *a)
{
    return a ? a->samples : NULL;
}

/* Every tile's relMSE estimate from the two images (see adaptive.h), and
 * the image's (the pixel-weighted mean), with and without scaling stopped
 * tiles to every sample. */
static void estimate(sr_adaptive *a)
{
    const float *all = sr_image_pixels(a->all), *odd = sr_image_pixels(a->odd);
    unsigned tiles = a->across * a->down;
    double sum = 0.0, sum_uniform = 0.0;
    for (uint32_t t = 0; t < tiles; ++t) {
        unsigned tx = t % a->across, ty = t / a->across;
        double e = 0.0;
        size_t values = 0;
        for (unsigned y = ty * SR_FILM_TILE; y < a->height && y < (ty + 1) * SR_FILM_TILE; ++y)
            for (unsigned x = tx * SR_FILM_TILE; x < a->width && x < (tx + 1) * SR_FILM_TILE; ++x) {
                size_t i = 3 * ((size_t)y * a->width + x);
                for (int k = 0; k < 3; ++k, ++values) {
                    double b = odd[i + k], d = (double)all[i + k] - b;
                    double even = 2.0 * all[i + k] - b, m = even < b ? even : b;
                    e += d * d / (m * m + SR_IMAGE_REL_MSE_EPSILON);
                }
            }
        e /= (double)values;
        a->tile_error[t] = e;
        sum += e * (double)(values / 3);
        sum_uniform += e * (double)(values / 3) * a->samples[t] / a->stats.samples;
    }
    double pixels = (double)a->width * a->height;
    a->stats.error = sum / pixels;
    a->stats.error_uniform = sum_uniform / pixels;
    a->stats.error_samples = a->stats.samples;
}

sluice_status sr_adaptive_check(sr_adaptive *a, sr_film *film, int *checked)
{
    if (checked)
        *checked = 0;
    if (!a || !film)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    unsigned s = a->stats.samples;
    if (!(a->opt.target > 0) || s < a->next_check || s % 2 || a->active_count == 0)
        return SLUICE_OK;
    double t0 = sr_clock_seconds();
    sluice_status st = SLUICE_OK;
    if (!a->all)
        st = sr_image_create(a->width, a->height, 3, &a->all, NULL, 0);
    if (st == SLUICE_OK && !a->odd)
        st = sr_image_create(a->width, a->height, 3, &a->odd, NULL, 0);
    if (st == SLUICE_OK)
        st = sr_film_resolve_tiles(film, NULL, a->samples, a->all, a->odd, NULL);
    if (st != SLUICE_OK)
        return st;
    estimate(a);
    if (a->opt.adaptive && a->stats.error > a->opt.target) {
        int changed = 0;
        for (size_t i = 0; i < a->active_count; ++i) {
            uint32_t t = a->list[i];
            if (a->tile_error[t] <= a->opt.target) {
                a->active[t] = 0;
                changed = 1;
            }
        }
        if (changed && (st = update_list(a)) != SLUICE_OK)
            return st;
    }
    /* a quarter of the samples done, rounded to even, at least 2 */
    unsigned step = (s / 4) & ~1u;
    a->next_check = s + (step > 2 ? step : 2);
    a->stats.checks++;
    a->stats.check_seconds += sr_clock_seconds() - t0;
    if (checked)
        *checked = 1;
    return SLUICE_OK;
}

int sr_adaptive_done(const sr_adaptive *a)
{
    return a && a->opt.target > 0 &&
           ((a->stats.error >= 0 && a->stats.error <= a->opt.target) || a->active_count == 0);
}

const sr_adaptive_stats *sr_adaptive_statistics(const sr_adaptive *a)
{
    return a ? &a->stats : NULL;
}

sluice_status sr_adaptive_sample_map(const sr_adaptive *a, sr_image *img)
{
    if (!a || !img || sr_image_width(img) != a->width || sr_image_height(img) != a->height ||
        sr_image_channels(img) != 3)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    uint32_t most = 1;
    for (size_t t = 0; t < (size_t)a->across * a->down; ++t)
        most = a->samples[t] > most ? a->samples[t] : most;
    float *px = sr_image_pixels(img);
    for (unsigned y = 0; y < a->height; ++y)
        for (unsigned x = 0; x < a->width; ++x) {
            float v = (float)a->samples[(y / SR_FILM_TILE) * a->across + x / SR_FILM_TILE] / most;
            float *p = px + 3 * ((size_t)y * a->width + x);
            p[0] = p[1] = p[2] = v;
        }
    return SLUICE_OK;
}

/* The share of pixel samples skipped, in [0, 1]. */
static double skipped_share(const sr_adaptive_stats *s)
{
    return s->pixel_uniform ? 1.0 - (double)s->pixel_samples / (double)s->pixel_uniform : 0.0;
}

void sr_adaptive_print(const sr_adaptive_stats *s, FILE *out)
{
    if (!s || !(s->target > 0))
        return;
    fprintf(out, "sampling: target relMSE %g, ", s->target);
    if (s->adaptive)
        fprintf(out,
                "adaptive (%ux%u tiles): %u of %u tiles stopped early, %.1f%% of pixel samples "
                "skipped (%.3g M of %.3g M)\n",
                SR_FILM_TILE, SR_FILM_TILE, s->tiles - s->tiles_active, s->tiles,
                100.0 * skipped_share(s), 1e-6 * (double)(s->pixel_uniform - s->pixel_samples),
                1e-6 * (double)s->pixel_uniform);
    else
        fprintf(out, "every pixel takes every sample (--no-adaptive)\n");
    if (s->error < 0)
        fprintf(out, "  no estimate yet (fewer samples than the first check needs)\n");
    else
        fprintf(out,
                "  estimated relMSE %.3g after %u samples (%.3g had every tile taken every "
                "sample); %u checks, %.3f s\n",
                s->error, s->error_samples, s->error_uniform, s->checks, s->check_seconds);
}

void sr_adaptive_write_json(const sr_adaptive_stats *s, FILE *out, int indent)
{
    fprintf(out,
            "%*s\"sampling\": {\"target\": %.6g, \"adaptive\": %s, \"tile\": %u, "
            "\"tiles\": %u, \"tiles_active\": %u, \"pixel_samples\": %llu, "
            "\"pixel_samples_uniform\": %llu, \"skipped_share\": %.6g, \"checks\": %u, "
            "\"check_seconds\": %.6g, \"error\": %.6g, \"error_uniform\": %.6g, "
            "\"error_samples\": %u}",
            indent, "", s->target, s->adaptive ? "true" : "false", SR_FILM_TILE, s->tiles,
            s->tiles_active, (unsigned long long)s->pixel_samples,
            (unsigned long long)s->pixel_uniform, skipped_share(s), s->checks, s->check_seconds,
            s->error, s->error_uniform, s->error_samples);
}
