/* A copy of a scene for the tests, moved: every point p to scale * p +
 * offset (meshes, point lights, camera), with the same images (point
 * lights' intensities scale with the square). */
#ifndef SLUICE_TESTS_SCENE_COPY_H
#define SLUICE_TESTS_SCENE_COPY_H

#include "scene.h"

#include <stdio.h>

/* The copy, or NULL with the reason in err. `camera` replaces the moved
 * camera when not NULL. */
static inline sr_scene *scene_copy(const sr_scene *s, float scale, float offset,
                                   const sr_camera *camera, char *err, size_t err_size)
{
    char name[64];
    snprintf(name, sizeof name, "%s*%g+%g", sr_scene_source(s), (double)scale, (double)offset);
    sr_scene_builder *b = NULL;
    sluice_status st = sr_scene_builder_create(name, &b);
    for (size_t i = 0; st == SLUICE_OK && i < sr_scene_material_count(s); ++i)
        st = sr_scene_builder_add_material(b, &sr_scene_materials(s)[i], NULL, err, err_size);
    float m[16] = {scale, 0, 0, offset, 0, scale, 0, offset, 0, 0, scale, offset, 0, 0, 0, 1};
    sr_mesh_desc md = {0};
    md.positions = sr_scene_positions(s);
    md.vertex_count = sr_scene_vertex_count(s);
    md.indices = sr_scene_indices(s);
    md.triangle_count = sr_scene_triangle_count(s);
    md.materials = sr_scene_triangle_materials(s);
    md.transform = m;
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_mesh(b, &md, err, err_size);
    for (size_t i = 0; st == SLUICE_OK && i < sr_scene_point_light_count(s); ++i) {
        sr_point_light l = sr_scene_point_lights(s)[i];
        for (int k = 0; k < 3; ++k) {
            l.position[k] = scale * l.position[k] + offset;
            l.intensity[k] *= scale * scale;
        }
        st = sr_scene_builder_add_point_light(b, &l, err, err_size);
    }
    sr_camera cam = *sr_scene_camera(s);
    for (int k = 0; k < 3; ++k) {
        cam.eye[k] = scale * cam.eye[k] + offset;
        cam.look_at[k] = scale * cam.look_at[k] + offset;
    }
    if (st == SLUICE_OK)
        st = sr_scene_builder_set_camera(b, camera ? camera : &cam, err, err_size);
    sr_scene *out = NULL;
    if (st == SLUICE_OK)
        st = sr_scene_builder_finish(b, 0, &out, err, err_size);
    sr_scene_builder_destroy(b);
    return out;
}

#endif
