/*
 * The scene on the device: what every renderer reads of a scene (Purcell
 * 3.1 and 6.2 keep it in textures; here, read-only streams): vertices,
 * triangles, vertex normals, materials, point lights and the area-light
 * sampling table. One object per scene and context, created once and read
 * by the tracer (intersection), the ray tracer's shading and the photon
 * mapper's photon emission and shading alike.
 *
 * Conventions are those of <sluice/sluice.h>: functions return a
 * sluice_status, never abort or print; messages go to `err`.
 */
#ifndef SR_DEVICE_SCENE_H
#define SR_DEVICE_SCENE_H

#include "../../kernels/render/rt_types.h"
#include "scene.h"
#include "sluice/sluice.h"

#include <stddef.h>

/** How the per-triangle records (sr_device_scene.tri_records) hold a
 *  triangle: the intersector that reads them decides (kernels/render/
 *  rt_trace.cl, rt_tri_edges reads either). */
typedef enum sr_tri_layout {
    SR_TRI_EDGES = 0,   /**< v0, v1 - v0, v2 - v0 (Moller-Trumbore's edges, rounded once) */
    SR_TRI_VERTICES = 1 /**< v0, v1, v2 (the watertight test needs the exact vertices) */
} sr_tri_layout;

/** The scene's streams on the device. Every stream has at least one record
 *  (a zero record where the scene has none), so that kernels can always be
 *  given a buffer. Read-only for the renderers. */
typedef struct sr_device_scene {
    sluice_context *ctx;
    const sr_scene *scene; /**< the host scene it was made from (outlives it) */
    sr_tri_layout layout;
    sluice_stream *positions;    /**< float x3 per vertex */
    sluice_stream *indices;      /**< uint x3 per triangle */
    sluice_stream *tri_records;  /**< float x9 per triangle, in `layout` */
    sluice_stream *normals;      /**< float x3 per vertex (one zero record when none) */
    sluice_stream *tri_mat;      /**< uint per triangle: its material */
    sluice_stream *materials;    /**< rt_material */
    sluice_stream *point_lights; /**< rt_point_light */
    sluice_stream *area_tris;    /**< uint: the emissive triangles */
    sluice_stream *area_cdf;     /**< float: their cumulative area, normalised to 1 */
    size_t triangles, point_light_count, area_light_count;
    double area_total; /**< total area of the emissive triangles */
    float scene_eps;   /**< ray-origin offset for this scene's size (sr_scene_epsilon) */
    size_t bytes;      /**< device memory the streams take */
} sr_device_scene;

/**
 * Uploads `scene` (which must outlive the result) with triangle records in
 * `layout`. On failure `*out` is NULL, nothing is kept and `err` says why.
 */
sluice_status sr_device_scene_create(sluice_context *ctx, const sr_scene *scene,
                                     sr_tri_layout layout, sr_device_scene **out, char *err,
                                     size_t err_size);

/** Frees the streams and the object (NULL is fine). */
void sr_device_scene_destroy(sr_device_scene *ds);

/**
 * How far secondary rays (shadow rays, bounces, photons) start off the
 * surface they leave: relative to the scene's size, and at least some 32
 * ulps of its largest coordinate, so that it survives rounding far from the
 * origin.
 */
float sr_scene_epsilon(const sr_scene *scene);

#endif /* SR_DEVICE_SCENE_H */
