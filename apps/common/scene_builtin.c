/* Built-in scenes, the test scenes of Purcell's thesis (ch. 5 and 6) and a
 * few synthetic ones, and sr_scene_load(), which resolves a name to a
 * built-in scene, a JSON file or a mesh file. Every scene here is fully
 * deterministic: its triangle count and bounds are fixed (docs/scenes.md
 * lists them and tests/test_scene.c checks them). */
#include "scene.h"
#include "app_error.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The Stanford bunny as Debian's glmark2-data ships it (69,666 triangles). */
#define BUNNY_PATH "/usr/share/glmark2/models/bunny.obj"

/* spheres:N: each sphere is a frequency-4 geodesic sphere (320 triangles);
 * the cap keeps a scene at 32 million triangles (about 1.3 GB of arrays). */
#define SPHERE_FREQUENCY 4u
#define SPHERES_MAX 100000u
/* "million": 3125 spheres of 320 triangles, exactly 1,000,000 triangles. */
#define MILLION_SPHERES 3125u

static const double PI = 3.14159265358979323846;

/* The names, in listing order, and their descriptions (same order). */
static const char *const builtin_names[] = {"cornell",   "cornell-point", "glassball",
                                            "ring",      "teapotahedron", "bunny",
                                            "spheres:N", "million",       NULL};
static const char *const builtin_descriptions[] = {
    "Cornell box (Cornell's measured geometry, mm) lit by its 130 x 105 mm emissive ceiling "
    "light; 38 triangles (Purcell ch. 6)",
    "the same Cornell box with a point light just below the light's centre; 30 triangles "
    "(Purcell ch. 5)",
    "a glass ball (ior 1.5) over a diffuse floor under an area light; 5,124 triangles (Purcell "
    "fig. 6.7, GLASS BALL)",
    "a mirror ring on a diffuse floor lit by a low point light: a caustic inside the ring; "
    "2,050 triangles (Purcell fig. 6.7, RING)",
    "six Utah teapots (mirror, glossy gold, copper) on the faces of a cube around a mirror "
    "ball, over a floor; 29,314 triangles (Purcell fig. 5.9)",
    "the Stanford bunny from glmark2-data (" BUNNY_PATH "), diffuse, one point light; 69,666 "
    "triangles",
    "N geodesic spheres (320 triangles each, 1 <= N <= 100000) on a jittered grid, seven "
    "materials; 320 N triangles",
    "spheres:3125: exactly 1,000,000 triangles",
};
#define BUILTIN_COUNT (sizeof builtin_descriptions / sizeof builtin_descriptions[0])
#define SPHERES_INDEX 6

const char *const *sr_scene_builtin_names(void)
{
    return builtin_names;
}

int sr_scene_is_builtin(const char *name)
{
    if (!name)
        return 0;
    if (strncmp(name, "spheres:", 8) == 0)
        return 1;
    for (size_t i = 0; i < BUILTIN_COUNT; ++i) {
        if (i != SPHERES_INDEX && strcmp(builtin_names[i], name) == 0)
            return 1;
    }
    return 0;
}

const char *sr_scene_builtin_description(const char *name)
{
    if (!name)
        return NULL;
    if (strncmp(name, "spheres:", 8) == 0)
        return builtin_descriptions[SPHERES_INDEX];
    for (size_t i = 0; i < BUILTIN_COUNT; ++i) {
        if (strcmp(builtin_names[i], name) == 0)
            return builtin_descriptions[i];
    }
    return NULL;
}

/* ------------------------------------------------------------------ */
/* Helpers                                                             */
/* ------------------------------------------------------------------ */

static sr_material diffuse(const char *name, float r, float g, float b)
{
    sr_material m = sr_material_make(SR_MATERIAL_DIFFUSE, name);
    m.albedo[0] = r;
    m.albedo[1] = g;
    m.albedo[2] = b;
    return m;
}

static sr_material mirror(const char *name, float r, float g, float b)
{
    sr_material m = sr_material_make(SR_MATERIAL_MIRROR, name);
    m.specular[0] = r;
    m.specular[1] = g;
    m.specular[2] = b;
    return m;
}

/* Adds a planar polygon given by 4 corners in order (counter-clockwise seen
 * from its front) as 2 triangles. */
static sluice_status add_quad4(sr_scene_builder *b, const char *source, const float p[12],
                               uint32_t material, char *err, size_t err_size)
{
    static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    sr_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.source = source;
    d.positions = p;
    d.vertex_count = 4;
    d.indices = idx;
    d.triangle_count = 2;
    d.material = material;
    return sr_scene_builder_add_mesh(b, &d, err, err_size);
}

static sr_camera camera(float ex, float ey, float ez, float lx, float ly, float lz, float vfov,
                        uint32_t w, uint32_t h)
{
    sr_camera c = {{ex, ey, ez}, {lx, ly, lz}, {0.0f, 1.0f, 0.0f}, vfov, w, h};
    return c;
}

/* The chain of calls below stops at the first failure; `st` keeps it. */
#define TRY(call)                                                                                  \
    do {                                                                                           \
        if (st == SLUICE_OK)                                                                       \
            st = (call);                                                                           \
    } while (0)

/* ------------------------------------------------------------------ */
/* Cornell box                                                         */
/* ------------------------------------------------------------------ */

/* The Cornell box as measured by the Cornell Program of Computer Graphics
 * ("Cornell Box Data", https://www.graphics.cornell.edu/online/box/data.html),
 * in millimetres; each polygon's corners in the published order, which is
 * counter-clockwise seen from the inside of the room and from outside the
 * blocks. The walls are not quite rectangular (the floor's far edge is 549.6
 * wide, the ceiling 556.0): kept as measured. */
static const float cornell_floor[12] = {552.8f, 0, 0, 0, 0, 0, 0, 0, 559.2f, 549.6f, 0, 559.2f};
static const float cornell_ceiling[12] = {556.0f, 548.8f, 0,      556.0f, 548.8f, 559.2f,
                                          0,      548.8f, 559.2f, 0,      548.8f, 0};
static const float cornell_back[12] = {549.6f, 0,      559.2f, 0,      0,      559.2f,
                                       0,      548.8f, 559.2f, 556.0f, 548.8f, 559.2f};
/* x = 0 is on the camera's right: the green wall */
static const float cornell_right[12] = {0, 0, 559.2f, 0, 0, 0, 0, 548.8f, 0, 0, 548.8f, 559.2f};
static const float cornell_left[12] = {552.8f, 0,      0,      549.6f, 0,      559.2f,
                                       556.0f, 548.8f, 559.2f, 556.0f, 548.8f, 0};
static const float cornell_light[12] = {343.0f, 548.8f, 227.0f, 343.0f, 548.8f, 332.0f,
                                        213.0f, 548.8f, 332.0f, 213.0f, 548.8f, 227.0f};
static const float cornell_short[5][12] = {
    {130, 165, 65, 82, 165, 225, 240, 165, 272, 290, 165, 114},
    {290, 0, 114, 290, 165, 114, 240, 165, 272, 240, 0, 272},
    {130, 0, 65, 130, 165, 65, 290, 165, 114, 290, 0, 114},
    {82, 0, 225, 82, 165, 225, 130, 165, 65, 130, 0, 65},
    {240, 0, 272, 240, 165, 272, 82, 165, 225, 82, 0, 225},
};
static const float cornell_tall[5][12] = {
    {423, 330, 247, 265, 330, 296, 314, 330, 456, 472, 330, 406},
    {423, 0, 247, 423, 330, 247, 472, 330, 406, 472, 0, 406},
    {472, 0, 406, 472, 330, 406, 314, 330, 456, 314, 0, 456},
    {314, 0, 456, 314, 330, 456, 265, 330, 296, 265, 0, 296},
    {265, 0, 296, 265, 330, 296, 423, 330, 247, 423, 0, 247},
};

static sluice_status build_cornell(sr_scene_builder *b, int area_light, char *err, size_t err_size)
{
    /* Cornell's measured reflectances are spectra; these are the usual RGB
     * approximations. The light's emission (17, 12, 4) approximates its
     * published warm spectrum as RGB radiance. */
    sr_material white = diffuse("white", 0.73f, 0.73f, 0.73f);
    sr_material red = diffuse("red", 0.63f, 0.065f, 0.05f);
    sr_material green = diffuse("green", 0.14f, 0.45f, 0.09f);
    sr_material light = sr_material_make(SR_MATERIAL_EMISSIVE, "light");
    light.albedo[0] = light.albedo[1] = light.albedo[2] = 0.78f;
    light.emission[0] = 17.0f;
    light.emission[1] = 12.0f;
    light.emission[2] = 4.0f;
    uint32_t mw = 0, mr = 0, mg = 0, ml = 0;
    sluice_status st = SLUICE_OK;
    TRY(sr_scene_builder_add_material(b, &white, &mw, err, err_size));
    TRY(sr_scene_builder_add_material(b, &red, &mr, err, err_size));
    TRY(sr_scene_builder_add_material(b, &green, &mg, err, err_size));
    if (area_light)
        TRY(sr_scene_builder_add_material(b, &light, &ml, err, err_size));
    TRY(add_quad4(b, "floor", cornell_floor, mw, err, err_size));
    if (area_light) {
        /* The light sits in a hole in the ceiling, in the ceiling's plane, so
         * the two never overlap: four strips around the 130 x 105 hole,
         * facing down (u x v = -y). */
        const float y = 548.8f;
        const float strips[4][4] = {/* x0, z0, dx, dz */
                                    {0.0f, 0.0f, 556.0f, 227.0f},
                                    {0.0f, 332.0f, 556.0f, 227.2f},
                                    {0.0f, 227.0f, 213.0f, 105.0f},
                                    {343.0f, 227.0f, 213.0f, 105.0f}};
        for (int i = 0; i < 4; ++i) {
            float c[3] = {strips[i][0], y, strips[i][1]}, u[3] = {strips[i][2], 0, 0},
                  v[3] = {0, 0, strips[i][3]};
            TRY(sr_scene_builder_add_quad(b, c, u, v, mw, NULL, err, err_size));
        }
    } else {
        TRY(add_quad4(b, "ceiling", cornell_ceiling, mw, err, err_size));
    }
    TRY(add_quad4(b, "back wall", cornell_back, mw, err, err_size));
    TRY(add_quad4(b, "right wall", cornell_right, mg, err, err_size));
    TRY(add_quad4(b, "left wall", cornell_left, mr, err, err_size));
    for (int i = 0; i < 5; ++i) {
        TRY(add_quad4(b, "short block", cornell_short[i], mw, err, err_size));
        TRY(add_quad4(b, "tall block", cornell_tall[i], mw, err, err_size));
    }
    if (area_light) {
        TRY(add_quad4(b, "light", cornell_light, ml, err, err_size));
    } else {
        /* 10 mm below the light's centre, with the area light's radiant
         * intensity straight down (emission times area). */
        const float area = 130.0f * 105.0f;
        sr_point_light l = {{278.0f, 538.8f, 279.5f}, {17.0f * area, 12.0f * area, 4.0f * area}};
        TRY(sr_scene_builder_add_point_light(b, &l, err, err_size));
    }
    /* Cornell's camera: at (278, 273, -800) looking along +z, focal length
     * 35 mm, a 25 x 25 mm film: vfov = 2 atan(12.5 / 35) = 39.31 degrees. */
    const float vfov = (float)(2.0 * atan(0.0125 / 0.035) * 180.0 / PI);
    sr_camera cam = camera(278.0f, 273.0f, -800.0f, 278.0f, 273.0f, 0.0f, vfov, 512, 512);
    TRY(sr_scene_builder_set_camera(b, &cam, err, err_size));
    sr_render_settings r = sr_render_settings_default();
    /* Purcell ch. 6.4: 32 light samples per pixel, 65,000 photons stored,
     * 500 sought per radiance estimate */
    r.light_samples = area_light ? 32 : 1;
    r.photons = 65000;
    r.photon_lookup = 500;
    TRY(sr_scene_builder_set_render_settings(b, &r, err, err_size));
    return st;
}

/* ------------------------------------------------------------------ */
/* Purcell's photon-mapping scenes                                     */
/* ------------------------------------------------------------------ */

static sluice_status build_glassball(sr_scene_builder *b, char *err, size_t err_size)
{
    sr_material floor_m = diffuse("floor", 0.7f, 0.7f, 0.7f);
    sr_material glass = sr_material_make(SR_MATERIAL_GLASS, "glass");
    sr_material light = sr_material_make(SR_MATERIAL_EMISSIVE, "light");
    /* 0.36 m^2 at 3 m: about irradiance 1 on the floor below */
    light.emission[0] = light.emission[1] = light.emission[2] = 25.0f;
    uint32_t mf = 0, mg = 0, ml = 0;
    sluice_status st = SLUICE_OK;
    TRY(sr_scene_builder_add_material(b, &floor_m, &mf, err, err_size));
    TRY(sr_scene_builder_add_material(b, &glass, &mg, err, err_size));
    TRY(sr_scene_builder_add_material(b, &light, &ml, err, err_size));
    const float fc[3] = {-4, 0, -4}, fu[3] = {0, 0, 8}, fv[3] = {8, 0, 0};
    TRY(sr_scene_builder_add_quad(b, fc, fu, fv, mf, NULL, err, err_size));
    /* The ball floats 0.3 above the floor: a ball lens of index 1.5 focuses
     * 0.75 r below its centre, so the caustic under it is nearly sharp. */
    const float center[3] = {0.0f, 0.8f, 0.0f};
    TRY(sr_scene_builder_add_sphere(b, center, 0.5f, 16, mg, NULL, err, err_size));
    const float lc[3] = {-0.8f, 3.0f, 0.2f}, lu[3] = {0.6f, 0, 0}, lv[3] = {0, 0, 0.6f};
    TRY(sr_scene_builder_add_quad(b, lc, lu, lv, ml, NULL, err, err_size));
    sr_camera cam = camera(0.0f, 1.6f, -4.0f, 0.0f, 0.6f, 0.0f, 40.0f, 512, 384);
    TRY(sr_scene_builder_set_camera(b, &cam, err, err_size));
    /* Purcell ch. 6.4: 4 light samples per pixel, 5,000 photons, 32 sought */
    sr_render_settings r = sr_render_settings_default();
    r.light_samples = 4;
    r.photons = 5000;
    r.photon_lookup = 32;
    r.mode = SR_RENDER_PHOTON;
    TRY(sr_scene_builder_set_render_settings(b, &r, err, err_size));
    return st;
}

static sluice_status build_ring(sr_scene_builder *b, char *err, size_t err_size)
{
    sr_material floor_m = diffuse("floor", 0.7f, 0.7f, 0.7f);
    sr_material metal = mirror("metal", 0.95f, 0.93f, 0.88f);
    uint32_t mf = 0, mm = 0;
    sluice_status st = SLUICE_OK;
    TRY(sr_scene_builder_add_material(b, &floor_m, &mf, err, err_size));
    TRY(sr_scene_builder_add_material(b, &metal, &mm, err, err_size));
    const float fc[3] = {-3, 0, -3}, fu[3] = {0, 0, 6}, fv[3] = {6, 0, 0};
    TRY(sr_scene_builder_add_quad(b, fc, fu, fv, mf, NULL, err, err_size));
    const float center[3] = {0, 0, 0};
    TRY(sr_scene_builder_add_ring(b, center, 1.0f, 0.05f, 0.35f, 256, mm, NULL, err, err_size));
    /* Low and to the front: rays pass over the near rim and reflect off the
     * far inner wall onto the floor inside the ring, where the reflected
     * rays' envelope is the cardioid-like caustic of a coffee cup. */
    sr_point_light l = {{0.0f, 0.75f, -4.0f}, {20.0f, 20.0f, 20.0f}};
    TRY(sr_scene_builder_add_point_light(b, &l, err, err_size));
    sr_camera cam = camera(0.0f, 3.2f, -2.2f, 0.0f, 0.0f, 0.2f, 45.0f, 512, 384);
    TRY(sr_scene_builder_set_camera(b, &cam, err, err_size));
    /* Purcell ch. 6.4: 16,000 photons, 64 sought */
    sr_render_settings r = sr_render_settings_default();
    r.photons = 16000;
    r.photon_lookup = 64;
    r.mode = SR_RENDER_PHOTON;
    TRY(sr_scene_builder_set_render_settings(b, &r, err, err_size));
    return st;
}

/* ------------------------------------------------------------------ */
/* Teapotahedron                                                       */
/* ------------------------------------------------------------------ */

static sluice_status build_teapotahedron(sr_scene_builder *b, char *err, size_t err_size)
{
    /* A simplified take on the cover of Glassner's "An Introduction to Ray
     * Tracing" (1989), as Purcell's TEAPOTAHEDRON is (ch. 5.3, fig. 5.9):
     * reflective teapots that see each other. Here: six half-size teapots
     * standing on the faces of a cube of half-size 2, spouts turning round,
     * a mirror ball in the middle, a floor to catch the shadows. Opposite
     * teapots share a material. */
    sr_material silver = mirror("silver", 0.9f, 0.9f, 0.9f);
    sr_material copper = mirror("copper", 0.95f, 0.64f, 0.54f);
    sr_material gold = sr_material_make(SR_MATERIAL_GLOSSY, "gold");
    const float kd[3] = {0.35f, 0.25f, 0.05f}, ks[3] = {0.6f, 0.5f, 0.25f};
    memcpy(gold.albedo, kd, sizeof kd);
    memcpy(gold.specular, ks, sizeof ks);
    gold.exponent = 200.0f;
    sr_material ball = mirror("ball", 0.95f, 0.95f, 0.95f);
    sr_material floor_m = diffuse("floor", 0.6f, 0.6f, 0.65f);
    uint32_t ms = 0, mc = 0, mgold = 0, mb = 0, mf = 0;
    sluice_status st = SLUICE_OK;
    TRY(sr_scene_builder_add_material(b, &silver, &ms, err, err_size));
    TRY(sr_scene_builder_add_material(b, &gold, &mgold, err, err_size));
    TRY(sr_scene_builder_add_material(b, &copper, &mc, err, err_size));
    TRY(sr_scene_builder_add_material(b, &ball, &mb, err, err_size));
    TRY(sr_scene_builder_add_material(b, &floor_m, &mf, err, err_size));
    /* face normal d (the teapot's up) and tangent t (its spout) */
    const float faces[6][6] = {
        {1, 0, 0, 0, 0, -1}, {-1, 0, 0, 0, 0, 1}, {0, 1, 0, 1, 0, 0},
        {0, -1, 0, 1, 0, 0}, {0, 0, 1, 1, 0, 0},  {0, 0, -1, -1, 0, 0},
    };
    const uint32_t mats[6] = {ms, ms, mgold, mgold, mc, mc};
    const float scale = 0.5f, half = 2.0f;
    for (int f = 0; f < 6; ++f) {
        const float *d = faces[f], *t = faces[f] + 3;
        /* columns: teapot x (spout) -> t, y (up) -> d, z -> t x d */
        float w[3] = {t[1] * d[2] - t[2] * d[1], t[2] * d[0] - t[0] * d[2],
                      t[0] * d[1] - t[1] * d[0]};
        float m[16] = {0};
        for (int r = 0; r < 3; ++r) {
            m[4 * r + 0] = scale * t[r];
            m[4 * r + 1] = scale * d[r];
            m[4 * r + 2] = scale * w[r];
            m[4 * r + 3] = half * d[r];
        }
        m[15] = 1.0f;
        TRY(sr_scene_builder_add_teapot(b, 8, mats[f], m, err, err_size));
    }
    const float center[3] = {0, 0, 0};
    TRY(sr_scene_builder_add_sphere(b, center, 1.2f, 16, mb, NULL, err, err_size));
    const float fc[3] = {-8, -4, -8}, fu[3] = {0, 0, 16}, fv[3] = {16, 0, 0};
    TRY(sr_scene_builder_add_quad(b, fc, fu, fv, mf, NULL, err, err_size));
    sr_point_light l = {{5.0f, 9.0f, -7.0f}, {150.0f, 150.0f, 150.0f}};
    TRY(sr_scene_builder_add_point_light(b, &l, err, err_size));
    sr_camera cam = camera(7.0f, 5.0f, -9.0f, 0.0f, 0.0f, 0.0f, 40.0f, 512, 512);
    TRY(sr_scene_builder_set_camera(b, &cam, err, err_size));
    sr_render_settings r = sr_render_settings_default();
    r.mode = SR_RENDER_WHITTED;
    TRY(sr_scene_builder_set_render_settings(b, &r, err, err_size));
    return st;
}

/* ------------------------------------------------------------------ */
/* Bunny                                                               */
/* ------------------------------------------------------------------ */

static sluice_status build_bunny(sr_scene_builder *b, char *err, size_t err_size)
{
    FILE *f = fopen(BUNNY_PATH, "rb");
    if (!f) {
        int e = errno;
        sr_set_error(err, err_size,
                     "bunny: cannot open " BUNNY_PATH ": %s (the bunny comes with glmark2's data: "
                     "apt install glmark2-data)",
                     e == ENOENT ? "no such file" : strerror(e));
        return e == ENOENT ? SLUICE_ERROR_NOT_FOUND : SLUICE_ERROR_IO;
    }
    fclose(f);
    sr_material m = diffuse("bunny", 0.75f, 0.75f, 0.75f);
    uint32_t mi = 0;
    sluice_status st = SLUICE_OK;
    TRY(sr_scene_builder_add_material(b, &m, &mi, err, err_size));
    TRY(sr_scene_builder_add_mesh_file(b, BUNNY_PATH, NULL, &mi, BUNNY_PATH, err, err_size));
    /* The file's bunny fits [-1, 1]^3 with y up: light from above, right
     * and front (about irradiance 1 at the centre); the default camera frames
     * it from +z. */
    sr_point_light l = {{2.0f, 3.0f, 3.0f}, {22.0f, 22.0f, 22.0f}};
    TRY(sr_scene_builder_add_point_light(b, &l, err, err_size));
    return st;
}

/* ------------------------------------------------------------------ */
/* Spheres                                                             */
/* ------------------------------------------------------------------ */

/* Parses N of "spheres:N": decimal digits only, 1 .. SPHERES_MAX. */
static sluice_status parse_count(const char *name, const char *s, unsigned *out, char *err,
                                 size_t err_size)
{
    unsigned long long v = 0;
    size_t n = 0;
    for (; s[n] >= '0' && s[n] <= '9'; ++n) {
        if (v <= SPHERES_MAX)
            v = v * 10 + (unsigned)(s[n] - '0');
    }
    if (n == 0 || s[n] != '\0') {
        sr_set_error(err, err_size, "%s: expected spheres:N with N a whole number from 1 to %u",
                     name, SPHERES_MAX);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (v < 1 || v > SPHERES_MAX) {
        sr_set_error(err, err_size, "%s: N must be from 1 to %u (at most %u triangles)", name,
                     SPHERES_MAX, SPHERES_MAX * 20u * SPHERE_FREQUENCY * SPHERE_FREQUENCY);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    *out = (unsigned)v;
    return SLUICE_OK;
}

/* xorshift32: the jitter must be the same on every machine. */
static double next_unit(uint32_t *s)
{
    uint32_t x = *s;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *s = x;
    return (double)(x >> 8) / 16777216.0;
}

static sluice_status build_spheres(sr_scene_builder *b, unsigned count, char *err, size_t err_size)
{
    sr_material mats[7] = {
        diffuse("red", 0.7f, 0.15f, 0.1f),
        diffuse("green", 0.15f, 0.6f, 0.15f),
        diffuse("blue", 0.1f, 0.2f, 0.7f),
        diffuse("white", 0.75f, 0.75f, 0.75f),
        mirror("mirror", 0.9f, 0.9f, 0.9f),
        sr_material_make(SR_MATERIAL_GLASS, "glass"),
        sr_material_make(SR_MATERIAL_GLOSSY, "glossy"),
    };
    uint32_t ids[7] = {0};
    sluice_status st = SLUICE_OK;
    for (int i = 0; i < 7; ++i)
        TRY(sr_scene_builder_add_material(b, &mats[i], &ids[i], err, err_size));
    /* the smallest cube grid that holds them, one sphere per unit cell:
     * centres jittered by up to 0.15 and radii in [0.25, 0.35), so spheres
     * never touch */
    unsigned g = 1;
    while ((unsigned long long)g * g * g < count)
        g++;
    uint32_t seed = 0x9e3779b9u;
    for (unsigned i = 0; i < count && st == SLUICE_OK; ++i) {
        unsigned cx = i % g, cy = (i / g) % g, cz = i / (g * g);
        float c[3] = {(float)(cx + 0.5 + 0.3 * (next_unit(&seed) - 0.5)),
                      (float)(cy + 0.5 + 0.3 * (next_unit(&seed) - 0.5)),
                      (float)(cz + 0.5 + 0.3 * (next_unit(&seed) - 0.5))};
        float r = (float)(0.25 + 0.1 * next_unit(&seed));
        st =
            sr_scene_builder_add_sphere(b, c, r, SPHERE_FREQUENCY, ids[i % 7], NULL, err, err_size);
    }
    /* above, right and in front of the grid, irradiance about 1 at its
     * centre; the default camera frames the grid from the front */
    double h = 0.5 * g, d[3] = {0.5 * (g + 1), 1.2 * (g + 1), 1.0 * (g + 1)};
    double dist2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    sr_point_light l = {{(float)(h + d[0]), (float)(h + d[1]), (float)(h + d[2])},
                        {(float)dist2, (float)dist2, (float)dist2}};
    TRY(sr_scene_builder_add_point_light(b, &l, err, err_size));
    return st;
}

/* ------------------------------------------------------------------ */
/* Entry points                                                        */
/* ------------------------------------------------------------------ */

sluice_status sr_scene_load_builtin(const char *name, const sr_scene_load_options *opts,
                                    sr_scene **out, char *err, size_t err_size)
{
    if (!out || !name) {
        sr_set_error(err, err_size, "load_builtin: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    *out = NULL;
    unsigned count = 0;
    if (strncmp(name, "spheres:", 8) == 0) {
        sluice_status st = parse_count(name, name + 8, &count, err, err_size);
        if (st != SLUICE_OK)
            return st;
    } else if (!sr_scene_is_builtin(name)) {
        sr_set_error(err, err_size, "%s: no such built-in scene (sluice-scene --list names them)",
                     name);
        return SLUICE_ERROR_NOT_FOUND;
    }
    sr_scene_builder *b = NULL;
    if (sr_scene_builder_create(name, &b) != SLUICE_OK) {
        sr_set_error(err, err_size, "%s: out of memory", name);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    unsigned flags = 0;
    if (opts) {
        sr_scene_builder_set_warning_callback(b, opts->warning, opts->warning_user);
        flags = opts->flags;
    }
    sluice_status st;
    if (strcmp(name, "cornell") == 0)
        st = build_cornell(b, 1, err, err_size);
    else if (strcmp(name, "cornell-point") == 0)
        st = build_cornell(b, 0, err, err_size);
    else if (strcmp(name, "glassball") == 0)
        st = build_glassball(b, err, err_size);
    else if (strcmp(name, "ring") == 0)
        st = build_ring(b, err, err_size);
    else if (strcmp(name, "teapotahedron") == 0)
        st = build_teapotahedron(b, err, err_size);
    else if (strcmp(name, "bunny") == 0)
        st = build_bunny(b, err, err_size);
    else if (strcmp(name, "million") == 0)
        st = build_spheres(b, MILLION_SPHERES, err, err_size);
    else
        st = build_spheres(b, count, err, err_size);
    if (st == SLUICE_OK)
        st = sr_scene_builder_finish(b, flags, out, err, err_size);
    sr_scene_builder_destroy(b);
    return st;
}

static int ends_with_json(const char *s)
{
    size_t n = strlen(s);
    if (n < 5)
        return 0;
    const char *e = s + n - 5, *j = ".json";
    for (int i = 0; i < 5; ++i) {
        char c = e[i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != j[i])
            return 0;
    }
    return 1;
}

sluice_status sr_scene_load(const char *name_or_path, const sr_scene_load_options *opts,
                            sr_scene **out, char *err, size_t err_size)
{
    if (out)
        *out = NULL;
    if (!out || !name_or_path || !*name_or_path) {
        sr_set_error(err, err_size, "load: needs a scene name or a file");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (sr_scene_is_builtin(name_or_path))
        return sr_scene_load_builtin(name_or_path, opts, out, err, err_size);
    if (ends_with_json(name_or_path))
        return sr_scene_load_json(name_or_path, opts, out, err, err_size);
    return sr_scene_load_mesh(name_or_path, opts, out, err, err_size);
}
