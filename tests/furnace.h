/* The white furnace of the stress and sampling tests: a scene whose every
 * pixel has a radiance known in closed form. Include after check.h. */
#ifndef SLUICE_TESTS_FURNACE_H
#define SLUICE_TESTS_FURNACE_H

#include "scene.h"

#define PI_D 3.14159265358979323846

/* A closed diffuse sphere of radius R and albedo a (a geodesic sphere of
 * 20 * 48^2 facets with radial normals: its facets lie within 0.02% of the
 * sphere) with a point light of intensity I at its centre and the camera
 * there too. The irradiance of every wall point is I / R^2 direct plus, as
 * each bounce spreads a times the light evenly over a sphere, I / R^2 *
 * a / (1 - a) indirect: the radiance seen is a / pi * I / R^2 / (1 - a). */
static const float furnace_R = 2.0f, furnace_a = 0.5f, furnace_I = 3.0f;

/* The scene (32x32 camera), or NULL after a failed check. */
static inline sr_scene *furnace_scene(void)
{
    char err[512] = "";
    sr_scene_builder *b = NULL;
    sr_scene *scene = NULL;
    sluice_status st = sr_scene_builder_create("furnace", &b);
    sr_material m = sr_material_make(SR_MATERIAL_DIFFUSE, "wall");
    m.albedo[0] = m.albedo[1] = m.albedo[2] = furnace_a;
    uint32_t mi = 0;
    const float c[3] = {0, 0, 0};
    sr_point_light l = {{0, 0, 0}, {furnace_I, furnace_I, furnace_I}};
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_material(b, &m, &mi, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_sphere(b, c, furnace_R, 48, mi, NULL, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_point_light(b, &l, err, sizeof err);
    sr_camera cam = {{0, 0, 0}, {0.3f, 0.2f, 1}, {0, 1, 0}, 90.0f, 32, 32};
    if (st == SLUICE_OK)
        st = sr_scene_builder_set_camera(b, &cam, err, sizeof err);
    if (st == SLUICE_OK)
        st = sr_scene_builder_finish(b, 0, &scene, err, sizeof err);
    sr_scene_builder_destroy(b);
    CHECK(st == SLUICE_OK, "furnace scene: %s", err);
    return scene;
}

/* The radiance every pixel sees. */
static inline double furnace_radiance(void)
{
    return furnace_a / PI_D * furnace_I / (furnace_R * furnace_R) / (1.0 - furnace_a);
}

#endif
