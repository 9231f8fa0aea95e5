/* The scenes and eye rays of the ray-tracer benchmarks (bench_raytrace.c,
 * bench_raytrace_ab.c). */
#ifndef SLUICE_BENCH_RAYS_H
#define SLUICE_BENCH_RAYS_H

#include "camera.h"
#include "scene.h"
#include "tracer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A scene by name or file; "bunny-close" is the bunny filling most of the
 * frame (bench/scenes, BENCH_SCENES_DIR). Scenes without a light load too
 * (tracing needs none). NULL after printing "prog: why" on stderr. */
static inline sr_scene *bench_load_scene(const char *prog, const char *name)
{
    char err[512];
    sr_scene_load_options o = {0};
    o.flags = SR_SCENE_ALLOW_NO_LIGHT;
    sr_scene *sc = NULL;
    const char *path =
        strcmp(name, "bunny-close") == 0 ? BENCH_SCENES_DIR "/bunny-close.json" : name;
    if (sr_scene_load(path, &o, &sc, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return NULL;
    }
    return sc;
}

/* One ray per pixel through its centre, in 8x8 tiles of four 4x4 blocks as
 * the renderer's rt_raygen orders them (neighbouring rays are neighbours in the stream).
 * Returns w * h rays (free them), or NULL when out of memory. */
static inline rt_ray *bench_eye_rays(const sr_scene *sc, unsigned w, unsigned h)
{
    rt_frame f;
    memset(&f, 0, sizeof f);
    sr_camera_frame(sr_scene_camera(sc), w, h, &f);
    rt_ray *rays = malloc((size_t)w * h * sizeof *rays + 1);
    if (!rays)
        return NULL;
    size_t n = 0;
    for (unsigned ty = 0; ty < h; ty += 8)
        for (unsigned tx = 0; tx < w; tx += 8)
            for (unsigned j = 0; j < 64; ++j) {
                /* the 4x4 blocks of rt_raygen */
                unsigned x = tx + (j >> 4 & 1u) * 4 + (j & 3u);
                unsigned y = ty + (j >> 5) * 4 + (j >> 2 & 3u);
                if (x >= w || y >= h)
                    continue;
                float px = (float)x + 0.5f, py = (float)y + 0.5f, d[3];
                for (int k = 0; k < 3; ++k)
                    d[k] = f.corner[k] + f.du[k] * px + f.dv[k] * py;
                float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                rt_ray *r = &rays[n++];
                memset(r, 0, sizeof *r);
                r->ox = f.eye[0];
                r->oy = f.eye[1];
                r->oz = f.eye[2];
                r->dx = d[0] / len;
                r->dy = d[1] / len;
                r->dz = d[2] / len;
                r->tmin = 0.0f;
                r->tmax = INFINITY;
                r->wr = r->wg = r->wb = 1.0f;
                r->pixel = y * w + x;
                r->flags = RT_KIND_EYE;
            }
    return rays;
}

#endif /* SLUICE_BENCH_RAYS_H */
