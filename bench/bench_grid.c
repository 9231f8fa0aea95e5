/*
 * bench_grid: the ray tracer's uniform grid build (apps/render/grid.h),
 * on the device (kernels, scan, radix sort, cell index) against the plain C
 * build, measured in one run on the same scenes, with the grid's memory.
 * The device result is checked against the C one, element by element; the
 * exit status is 1 on any mismatch. Times are the best of --reps runs after
 * a warm-up (the warm-up also compiles the kernels; every build after it
 * still loads them from PoCL's cache, see "program_seconds").
 *
 *   bench_grid [--scene NAME]... [--min-dim N] [--reps R] [--out FILE]
 *
 * Default scenes: cornell, bunny (when its mesh is installed), million.
 */
#include "clock.h"
#include "bench_args.h"
#include "grid.h"
#include "kernels.h"
#include "scene.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define MAX_SCENES 16
#define BUNNY_PATH "/usr/share/glmark2/models/bunny.obj"

typedef struct result {
    const char *scene;
    size_t triangles, entries, bytes;
    uint32_t dims[3];
    double c_seconds, device_seconds;
    int match;
} result;

/* The time to create and build the grid program, which every device build
 * pays (PoCL serves the binary from its cache). */
static double program_seconds(sluice_context *ctx)
{
    double t0 = sr_clock_seconds();
    sluice_program *p = NULL;
    sluice_kernel *k = NULL;
    if (sr_program_create(ctx, (const char *[]){"tri_box.h", "grid.cl"}, 2, NULL, &p) == SLUICE_OK)
        sluice_kernel_create(p, "rt_grid_count", &k);
    double t = sr_clock_seconds() - t0;
    sluice_kernel_destroy(k);
    sluice_program_destroy(p);
    return t;
}

static int run_scene(sluice_context *ctx, const char *name, unsigned min_dim, unsigned reps,
                     result *r)
{
    char err[512];
    sr_scene_load_options o = {0};
    o.flags = SR_SCENE_ALLOW_NO_LIGHT;
    sr_scene *sc = NULL;
    if (sr_scene_load(name, &o, &sc, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "bench_grid: %s\n", err);
        return 0;
    }
    const sr_scene_stats *st = sr_scene_statistics(sc);
    rt_grid_desc d;
    if (rt_grid_choose(st->bounds_min, st->bounds_max, min_dim, &d, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "bench_grid: %s: %s\n", name, err);
        sr_scene_destroy(sc);
        return 0;
    }
    size_t nt = sr_scene_triangle_count(sc), nv = sr_scene_vertex_count(sc);
    size_t cells = (size_t)d.dims[0] * d.dims[1] * d.dims[2];
    const float *pos = sr_scene_positions(sc);
    const uint32_t *idx = sr_scene_indices(sc);
    memset(r, 0, sizeof *r);
    r->scene = name;
    r->triangles = nt;
    memcpy(r->dims, d.dims, sizeof r->dims);

    rt_grid_host h = {0};
    int ok = 1;
    for (unsigned i = 0; i <= reps && ok; ++i) {
        rt_grid_host_free(&h);
        double t0 = sr_clock_seconds();
        ok = rt_grid_build_host(&d, pos, idx, nt, &h, err, sizeof err) == SLUICE_OK;
        double t = sr_clock_seconds() - t0;
        if (i > 0 && (i == 1 || t < r->c_seconds))
            r->c_seconds = t;
    }
    if (!ok)
        fprintf(stderr, "bench_grid: %s: C build: %s\n", name, err);

    sluice_stream *sp = NULL, *si = NULL;
    rt_grid_device g = {0};
    if (ok)
        ok = sluice_stream_create(ctx, 12, nv, &sp) == SLUICE_OK &&
             sluice_stream_create(ctx, 12, nt, &si) == SLUICE_OK &&
             sluice_stream_upload(sp, pos, nv) == SLUICE_OK &&
             sluice_stream_upload(si, idx, nt) == SLUICE_OK &&
             sluice_context_finish(ctx) == SLUICE_OK;
    for (unsigned i = 0; i <= reps && ok; ++i) {
        rt_grid_device_free(&g);
        double t0 = sr_clock_seconds();
        ok = rt_grid_build_device(ctx, &d, sp, si, nt, &g) == SLUICE_OK &&
             sluice_context_finish(ctx) == SLUICE_OK;
        double t = sr_clock_seconds() - t0;
        if (!ok)
            fprintf(stderr, "bench_grid: %s: device build: %s\n", name, g.message);
        if (i > 0 && (i == 1 || t < r->device_seconds))
            r->device_seconds = t;
    }
    if (ok) {
        r->entries = g.cell_tri_count;
        r->bytes = g.bytes;
        uint32_t *start = malloc((cells + 1) * sizeof *start);
        uint32_t *tris = malloc((g.cell_tri_count + 1) * sizeof *tris);
        size_t n1 = 0, n2 = 0;
        r->match = start && tris &&
                   sluice_stream_download(g.cell_start, start, cells + 1, &n1) == SLUICE_OK &&
                   sluice_stream_download(g.cell_tris, tris, g.cell_tri_count, &n2) == SLUICE_OK &&
                   n1 == cells + 1 && n2 == h.cell_start[cells] &&
                   memcmp(start, h.cell_start, (cells + 1) * sizeof *start) == 0 &&
                   memcmp(tris, h.cell_tris, n2 * sizeof *tris) == 0;
        free(start);
        free(tris);
    }
    rt_grid_device_free(&g);
    rt_grid_host_free(&h);
    sluice_stream_destroy(sp);
    sluice_stream_destroy(si);
    sr_scene_destroy(sc);
    return ok;
}

int main(int argc, char **argv)
{
    const char *scenes[MAX_SCENES], *out = NULL;
    size_t nscenes = 0;
    unsigned min_dim = RT_GRID_DEFAULT_MIN_DIM, reps = 5;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--scene") == 0 && i + 1 < argc && nscenes < MAX_SCENES)
            scenes[nscenes++] = argv[++i];
        else if (strcmp(argv[i], "--min-dim") == 0 && i + 1 < argc &&
                 bench_parse_uint(argv[i + 1], 1u << 20, &min_dim) && min_dim > 0)
            ++i;
        else if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc &&
                 bench_parse_uint(argv[i + 1], 1000, &reps) && reps > 0)
            ++i;
        else if (strcmp(argv[i], "--out") == 0 && i + 1 < argc)
            out = argv[++i];
        else {
            fprintf(stderr, "usage: bench_grid [--scene NAME]... [--min-dim N] [--reps R] "
                            "[--out FILE]\n");
            return 2;
        }
    }
    if (!nscenes) {
        scenes[nscenes++] = "cornell";
        if (access(BUNNY_PATH, R_OK) == 0)
            scenes[nscenes++] = "bunny";
        scenes[nscenes++] = "million";
    }
    char err[512];
    sluice_context *ctx = NULL;
    if (sluice_context_create(NULL, &ctx, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "bench_grid: %s\n", err);
        return 2;
    }
    program_seconds(ctx); /* the first build compiles */
    double prog = program_seconds(ctx);
    result res[MAX_SCENES];
    int status = 0;
    printf("grid program creation: %.3f s per device build\n", prog);
    printf("%-12s %9s %14s %10s %9s %10s %10s %8s %s\n", "scene", "triangles", "grid", "entries",
           "MB", "C s", "device s", "vs C", "match");
    for (size_t i = 0; i < nscenes; ++i) {
        if (!run_scene(ctx, scenes[i], min_dim, reps, &res[i])) {
            status = 1;
            res[i].scene = NULL;
            continue;
        }
        result *r = &res[i];
        char grid[48];
        snprintf(grid, sizeof grid, "%ux%ux%u", r->dims[0], r->dims[1], r->dims[2]);
        printf("%-12s %9zu %14s %10zu %9.1f %10.4f %10.4f %7.2fx %s\n", r->scene, r->triangles,
               grid, r->entries, r->bytes / 1e6, r->c_seconds, r->device_seconds,
               r->c_seconds / r->device_seconds, r->match ? "yes" : "NO");
        if (!r->match)
            status = 1;
    }
    if (out) {
        FILE *f = fopen(out, "w");
        if (!f) {
            fprintf(stderr, "bench_grid: cannot write %s\n", out);
            status = 1;
        } else {
            sluice_device_info info;
            sluice_context_device(ctx, &info);
            fprintf(f,
                    "{\"device\": \"%s / %s\", \"min_dim\": %u, \"program_seconds\": %.6f, "
                    "\"scenes\": [",
                    info.platform, info.name, min_dim, prog);
            int first = 1;
            for (size_t i = 0; i < nscenes; ++i) {
                result *r = &res[i];
                if (!r->scene)
                    continue;
                fprintf(f,
                        "%s\n  {\"scene\": \"%s\", \"triangles\": %zu, \"dims\": [%u, %u, %u], "
                        "\"entries\": %zu, \"bytes\": %zu, \"c_seconds\": %.6f, "
                        "\"device_seconds\": %.6f, \"speedup_vs_c\": %.4f, \"match\": %s}",
                        first ? "" : ",", r->scene, r->triangles, r->dims[0], r->dims[1],
                        r->dims[2], r->entries, r->bytes, r->c_seconds, r->device_seconds,
                        r->c_seconds / r->device_seconds, r->match ? "true" : "false");
                first = 0;
            }
            fprintf(f, "\n]}\n");
            fclose(f);
        }
    }
    sluice_context_destroy(ctx);
    return status;
}
