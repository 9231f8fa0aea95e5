/* See device_scene.h. */
#include "device_scene.h"
#include "app_error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Creates a stream of max(count, 1) records and uploads `count` of them. */
static sluice_status upload(sr_device_scene *t, size_t record, size_t count, const void *data,
                            sluice_stream **out)
{
    sluice_status st = sluice_stream_create(t->ctx, record, count ? count : 1, out);
    if (st == SLUICE_OK && count)
        st = sluice_stream_upload(*out, data, count);
    if (st == SLUICE_OK)
        t->bytes += record * (count ? count : 1);
    return st;
}

static sluice_status upload_scene(sr_device_scene *t)
{
    const sr_scene *s = t->scene;
    size_t nv = sr_scene_vertex_count(s), nt = sr_scene_triangle_count(s);
    const float *pos = sr_scene_positions(s);
    const uint32_t *idx = sr_scene_indices(s);
    sluice_status st = upload(t, 12, nv, pos, &t->positions);
    if (st == SLUICE_OK)
        st = upload(t, 12, nt, idx, &t->indices);
    if (st == SLUICE_OK)
        st = upload(t, 4, nt, sr_scene_triangle_materials(s), &t->tri_mat);
    if (st != SLUICE_OK)
        return st;

    /* Triangle records: the intersector reads one 36-byte record per
     * triangle instead of three indices and three gathers (Purcell 4.2
     * keeps vertices in a texture indexed by triangle, the same idea). For
     * Moller-Trumbore they hold (v0, v1 - v0, v2 - v0), the edges rounded as
     * the test would round them; for the watertight test the vertices
     * (kernels/render/rt_trace.cl). */
    float *tv = malloc((nt ? nt : 1) * 9 * sizeof *tv);
    if (!tv)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    int edges = t->layout == SR_TRI_EDGES;
    for (size_t i = 0; i < nt; ++i) {
        const float *v0 = pos + 3 * (size_t)idx[3 * i];
        for (int k = 0; k < 3; ++k) {
            const float *v = pos + 3 * (size_t)idx[3 * i + k];
            for (int a = 0; a < 3; ++a)
                tv[9 * i + 3 * k + a] = edges && k > 0 ? v[a] - v0[a] : v[a];
        }
    }
    st = upload(t, 36, nt, tv, &t->tri_records);
    free(tv);
    if (st != SLUICE_OK)
        return st;

    const float *normals = sr_scene_normals(s);
    static const float zero[3] = {0, 0, 0};
    st = normals ? upload(t, 12, nv, normals, &t->normals) : upload(t, 12, 1, zero, &t->normals);
    if (st != SLUICE_OK)
        return st;

    size_t nm = sr_scene_material_count(s);
    const sr_material *mats = sr_scene_materials(s);
    rt_material *rm = calloc(nm ? nm : 1, sizeof *rm);
    if (!rm)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    for (size_t i = 0; i < nm; ++i) {
        rm[i].kind = (rt_u32)mats[i].kind;
        rm[i].ar = mats[i].albedo[0];
        rm[i].ag = mats[i].albedo[1];
        rm[i].ab = mats[i].albedo[2];
        rm[i].sr = mats[i].specular[0];
        rm[i].sg = mats[i].specular[1];
        rm[i].sb = mats[i].specular[2];
        rm[i].exponent = mats[i].exponent;
        rm[i].ior = mats[i].ior;
        rm[i].er = mats[i].emission[0];
        rm[i].eg = mats[i].emission[1];
        rm[i].eb = mats[i].emission[2];
    }
    st = upload(t, sizeof *rm, nm, rm, &t->materials);
    free(rm);
    if (st != SLUICE_OK)
        return st;

    size_t np = sr_scene_point_light_count(s);
    const sr_point_light *pl = sr_scene_point_lights(s);
    rt_point_light *rp = calloc(np ? np : 1, sizeof *rp);
    if (!rp)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    for (size_t i = 0; i < np; ++i) {
        rp[i].px = pl[i].position[0];
        rp[i].py = pl[i].position[1];
        rp[i].pz = pl[i].position[2];
        rp[i].ir = pl[i].intensity[0];
        rp[i].ig = pl[i].intensity[1];
        rp[i].ib = pl[i].intensity[2];
    }
    st = upload(t, sizeof *rp, np, rp, &t->point_lights);
    free(rp);
    if (st != SLUICE_OK)
        return st;

    sr_area_lights al;
    sr_scene_area_lights(s, &al);
    st = upload(t, 4, al.count, al.triangles, &t->area_tris);
    if (st == SLUICE_OK)
        st = upload(t, 4, al.count, al.area_cdf, &t->area_cdf);
    return st;
}

float sr_scene_epsilon(const sr_scene *scene)
{
    const sr_scene_stats *ss = sr_scene_statistics(scene);
    float diag = 0, maxabs = 0;
    for (int k = 0; k < 3; ++k) {
        float e = ss->bounds_max[k] - ss->bounds_min[k];
        diag += e * e;
        maxabs = fmaxf(maxabs, fmaxf(fabsf(ss->bounds_max[k]), fabsf(ss->bounds_min[k])));
    }
    return 1e-4f * sqrtf(diag) + 4e-6f * maxabs;
}

sluice_status sr_device_scene_create(sluice_context *ctx, const sr_scene *scene,
                                     sr_tri_layout layout, sr_device_scene **out, char *err,
                                     size_t err_size)
{
    if (out)
        *out = NULL;
    if (!ctx || !scene || !out || (unsigned)layout > (unsigned)SR_TRI_VERTICES) {
        sr_set_error(err, err_size, "sr_device_scene_create: bad arguments");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sr_device_scene *ds = calloc(1, sizeof *ds);
    if (!ds) {
        sr_set_error(err, err_size, "out of host memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    ds->ctx = ctx;
    ds->scene = scene;
    ds->layout = layout;
    ds->triangles = sr_scene_triangle_count(scene);
    ds->point_light_count = sr_scene_point_light_count(scene);
    sr_area_lights al;
    sr_scene_area_lights(scene, &al);
    ds->area_light_count = al.count;
    ds->area_total = al.total_area;
    ds->scene_eps = sr_scene_epsilon(scene);
    sluice_status st = upload_scene(ds);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "scene upload: %s",
                     st == SLUICE_ERROR_OUT_OF_MEMORY ? "out of memory"
                                                      : sluice_context_error(ctx));
        sr_device_scene_destroy(ds);
        return st;
    }
    *out = ds;
    return SLUICE_OK;
}

void sr_device_scene_destroy(sr_device_scene *ds)
{
    if (!ds)
        return;
    sluice_stream *s[] = {ds->positions,    ds->indices,   ds->tri_records,
                          ds->normals,      ds->tri_mat,   ds->materials,
                          ds->point_lights, ds->area_tris, ds->area_cdf};
    for (size_t i = 0; i < sizeof s / sizeof *s; ++i)
        sluice_stream_destroy(s[i]);
    free(ds);
}
