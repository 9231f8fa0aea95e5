/* See stats.h. */
#include "stats.h"

#include "json.h"

#include <errno.h>
#include <string.h>

static const char *const kind_names[RT_KIND_COUNT] = {"eye", "shadow", "reflection", "refraction",
                                                      "path"};

static double per(uint64_t a, uint64_t b)
{
    return b ? (double)a / (double)b : 0.0;
}

static uint64_t total_rays(const rt_stats_report *r)
{
    uint64_t n = 0;
    for (unsigned k = 0; k < RT_KIND_COUNT; ++k)
        n += r->render->rays[k];
    return n;
}

void rt_stats_print(const rt_stats_report *r, sluice_context *ctx, FILE *out)
{
    const rt_trace_stats *t = r->trace;
    uint64_t rays = total_rays(r);
    fprintf(out, "\n== sluice-raytrace: %s, %s mode, %s exec, %s, %ux%u, %u spp%s ==\n", r->scene,
            r->mode, r->exec, r->intersector, r->width, r->height, r->spp,
            r->interrupted ? " (interrupted)" : "");
    fprintf(out, "rays:");
    for (unsigned k = 0; k < RT_KIND_COUNT; ++k)
        fprintf(out, " %s %llu%s", kind_names[k], (unsigned long long)r->render->rays[k],
                k + 1 < RT_KIND_COUNT ? "," : "\n");
    fprintf(out, "per ray (Purcell Table 5.2): v %.2f voxels, t %.2f tests, s %.3f shadings\n",
            per(t->voxels, t->rays), per(t->tests, t->rays), per(r->render->shades, rays));
    fprintf(out, "passes P %llu (traverse %llu, intersect %llu), waves %u, trace calls %llu\n",
            (unsigned long long)t->passes, (unsigned long long)t->traverse_passes,
            (unsigned long long)t->intersect_passes, r->render->waves,
            (unsigned long long)t->calls);
    if (t->traverse_passes + t->intersect_passes)
        fprintf(out, "live rays per pass: %.1f%% on average\n",
                100.0 * t->live_fraction_sum / (double)(t->traverse_passes + t->intersect_passes));
    fprintf(out, "per-ray maxima: %u voxels, %u triangle tests\n", t->max_steps, t->max_tests);
    fprintf(out, "time %.3f s (tracing %.3f s): %.2f M rays/s overall, %.2f M rays/s traced\n",
            r->seconds, t->seconds, r->seconds > 0 ? 1e-6 * (double)rays / r->seconds : 0.0,
            t->seconds > 0 ? 1e-6 * (double)t->rays / t->seconds : 0.0);
    const rt_grid_desc *g = &r->grid->desc;
    fprintf(out,
            "memory: grid %.2f MB (%ux%ux%u voxels, %zu references), scene %.2f MB, "
            "streams %.2f MB\n",
            r->grid->bytes / 1048576.0, g->dims[0], g->dims[1], g->dims[2], r->grid->cell_tri_count,
            r->scene_bytes / 1048576.0,
            (r->tracer_stream_bytes + r->render->stream_bytes) / 1048576.0);
    if (r->fused_path && r->fused_path[0])
        fprintf(out, "fused traversal: %s\n", r->fused_path);
    if (t->slices)
        fprintf(out,
                "coherent packets: %llu slices crossed, %.1f%% of them skipped at once through "
                "empty 4x4x4 voxel blocks\n",
                (unsigned long long)t->slices, 100.0 * per(t->slices_skipped, t->slices));
    fprintf(out, "skipped: %s\n", r->skipped && r->skipped[0] ? r->skipped : "nothing");
    if (r->sampling)
        sr_adaptive_print(r->sampling, out);
    fprintf(out, "non-finite contributions dropped: %llu, non-finite pixels: %zu\n",
            (unsigned long long)r->render->nonfinite, r->bad_pixels);
    if (ctx && sluice_profile_enabled(ctx))
        sluice_profile_print(ctx, out);
}

sluice_status rt_stats_write_json(const rt_stats_report *r, sluice_context *ctx, const char *path,
                                  char *err, size_t err_size)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        if (err && err_size)
            snprintf(err, err_size, "%s: %s", path, strerror(errno));
        return SLUICE_ERROR_IO;
    }
    const rt_trace_stats *t = r->trace;
    uint64_t rays = total_rays(r);
    fprintf(f, "{\n  \"scene\": ");
    sr_json_string(f, r->scene);
    fprintf(f, ",\n  \"mode\": \"%s\",\n  \"exec\": \"%s\",\n  \"intersector\": \"%s\",\n", r->mode,
            r->exec, r->intersector);
    fprintf(f, "  \"width\": %u,\n  \"height\": %u,\n  \"spp\": %u,\n  \"interrupted\": %s,\n",
            r->width, r->height, r->spp, r->interrupted ? "true" : "false");
    fprintf(f, "  \"rays\": {");
    for (unsigned k = 0; k < RT_KIND_COUNT; ++k)
        fprintf(f, "\"%s\": %llu, ", kind_names[k], (unsigned long long)r->render->rays[k]);
    fprintf(f, "\"total\": %llu, \"traced\": %llu},\n", (unsigned long long)rays,
            (unsigned long long)t->rays);
    fprintf(f, "  \"v\": %.6g,\n  \"t\": %.6g,\n  \"s\": %.6g,\n  \"P\": %llu,\n",
            per(t->voxels, t->rays), per(t->tests, t->rays), per(r->render->shades, rays),
            (unsigned long long)t->passes);
    fprintf(f, "  \"voxels\": %llu,\n  \"tests\": %llu,\n  \"shades\": %llu,\n",
            (unsigned long long)t->voxels, (unsigned long long)t->tests,
            (unsigned long long)r->render->shades);
    fprintf(f, "  \"traverse_passes\": %llu,\n  \"intersect_passes\": %llu,\n",
            (unsigned long long)t->traverse_passes, (unsigned long long)t->intersect_passes);
    uint64_t np = t->traverse_passes + t->intersect_passes;
    fprintf(f, "  \"live_percent_per_pass\": %.4g,\n",
            np ? 100.0 * t->live_fraction_sum / (double)np : 0.0);
    fprintf(f, "  \"max_steps_per_ray\": %u,\n  \"max_tests_per_ray\": %u,\n", t->max_steps,
            t->max_tests);
    fprintf(f, "  \"seconds\": %.6g,\n  \"trace_seconds\": %.6g,\n", r->seconds, t->seconds);
    fprintf(f, "  \"rays_per_second\": %.6g,\n  \"traced_rays_per_second\": %.6g,\n",
            r->seconds > 0 ? (double)rays / r->seconds : 0.0,
            t->seconds > 0 ? (double)t->rays / t->seconds : 0.0);
    const rt_grid_desc *g = &r->grid->desc;
    fprintf(f, "  \"grid\": {\"dims\": [%u, %u, %u], \"references\": %zu, \"bytes\": %zu},\n",
            g->dims[0], g->dims[1], g->dims[2], r->grid->cell_tri_count, r->grid->bytes);
    fprintf(f, "  \"memory\": {\"grid\": %zu, \"scene\": %zu, \"streams\": %zu},\n", r->grid->bytes,
            r->scene_bytes, r->tracer_stream_bytes + r->render->stream_bytes);
    fprintf(f, "  \"nonfinite_contributions\": %llu,\n  \"nonfinite_pixels\": %zu,\n",
            (unsigned long long)r->render->nonfinite, r->bad_pixels);
    fprintf(f, "  \"fused_traversal\": ");
    sr_json_string(f, r->fused_path ? r->fused_path : "");
    fprintf(f, ",\n  \"packet_slices\": %llu,\n  \"packet_slices_skipped\": %llu",
            (unsigned long long)t->slices, (unsigned long long)t->slices_skipped);
    fprintf(f, ",\n  \"skipped\": ");
    sr_json_string(f, r->skipped);
    fprintf(f, ",\n");
    if (r->sampling) {
        sr_adaptive_write_json(r->sampling, f, 2);
        fprintf(f, ",\n");
    }
    sr_json_kernels(f, ctx, 2);
    fprintf(f, "\n}\n");
    if (fclose(f) != 0) {
        if (err && err_size)
            snprintf(err, err_size, "%s: write failed", path);
        return SLUICE_ERROR_IO;
    }
    return SLUICE_OK;
}
