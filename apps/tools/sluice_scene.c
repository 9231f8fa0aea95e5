/* sluice-scene: loads a scene (a built-in name, a JSON scene file or a mesh
 * file) and prints what it holds: triangles, vertices, bounds, materials and
 * lights by kind, camera, render settings and warnings, as text or JSON.
 * Exits 0 on success, 1 when the scene cannot be loaded (the message, naming
 * the file and field, goes to stderr), 2 on a usage error. */
#include "scene.h"

#include <cjson/cJSON.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *f)
{
    fprintf(f, "usage: sluice-scene NAME|FILE [--json] [--allow-no-light]\n"
               "       sluice-scene --list | --help\n"
               "Loads a scene and prints its statistics: triangles, vertices, bounds,\n"
               "materials and lights by kind, camera, render settings, warnings.\n"
               "NAME is a built-in scene (see --list); FILE is a JSON scene file (.json,\n"
               "see docs/scenes.md) or a mesh file assimp reads (OBJ+MTL, PLY, glTF 2, ...),\n"
               "which gets a default camera and, without emissive materials, a default light.\n"
               "  --list            name the built-in scenes, one line each\n"
               "  --json            print the statistics as JSON\n"
               "  --allow-no-light  accept a scene without any light\n"
               "  --help            this text\n"
               "examples:\n"
               "  sluice-scene cornell\n"
               "  sluice-scene spheres:100 --json\n"
               "  sluice-scene scenes/example.json\n"
               "  sluice-scene /usr/share/glmark2/models/bunny.obj\n");
}

static void list(void)
{
    for (const char *const *n = sr_scene_builtin_names(); *n; ++n)
        printf("%-14s %s\n", *n, sr_scene_builtin_description(*n));
}

/* Triangles per material, counted from the per-triangle material array. */
static size_t *material_counts(const sr_scene *s)
{
    size_t nm = sr_scene_material_count(s), nt = sr_scene_triangle_count(s);
    size_t *c = calloc(nm ? nm : 1, sizeof *c);
    if (!c)
        return NULL;
    const uint32_t *tm = sr_scene_triangle_materials(s);
    for (size_t t = 0; t < nt; ++t)
        c[tm[t]]++;
    return c;
}

static void print_text(const sr_scene *s)
{
    const sr_scene_stats *st = sr_scene_statistics(s);
    const sr_camera *c = sr_scene_camera(s);
    const sr_render_settings *r = sr_scene_render_settings(s);
    const sr_material *m = sr_scene_materials(s);
    size_t *counts = material_counts(s);
    printf("scene       %s\n", sr_scene_source(s));
    printf("triangles   %zu\n", st->triangles);
    printf("vertices    %zu%s\n", st->vertices, st->has_normals ? " (with normals)" : "");
    printf("bounds      min (%g, %g, %g)  max (%g, %g, %g)\n", st->bounds_min[0], st->bounds_min[1],
           st->bounds_min[2], st->bounds_max[0], st->bounds_max[1], st->bounds_max[2]);
    printf("materials   %zu\n", st->materials);
    for (size_t i = 0; i < st->materials; ++i) {
        printf("  %-3zu %-16s %-8s albedo (%g, %g, %g)", i, m[i].name,
               sr_material_kind_name(m[i].kind), m[i].albedo[0], m[i].albedo[1], m[i].albedo[2]);
        if (m[i].kind != SR_MATERIAL_DIFFUSE && m[i].kind != SR_MATERIAL_EMISSIVE)
            printf(" specular (%g, %g, %g)", m[i].specular[0], m[i].specular[1], m[i].specular[2]);
        if (m[i].kind == SR_MATERIAL_GLOSSY)
            printf(" exponent %g", m[i].exponent);
        if (m[i].kind == SR_MATERIAL_GLASS)
            printf(" ior %g", m[i].ior);
        if (sr_material_is_emissive(&m[i]))
            printf(" emission (%g, %g, %g)", m[i].emission[0], m[i].emission[1], m[i].emission[2]);
        if (counts)
            printf(", %zu triangles", counts[i]);
        printf("\n");
    }
    printf("by kind    ");
    for (int k = 0; k < SR_MATERIAL_KIND_COUNT; ++k) {
        if (st->kinds_present & SR_KIND_BIT(k))
            printf(" %s %zu", sr_material_kind_name((sr_material_kind)k), st->triangles_by_kind[k]);
    }
    printf(" (triangles)\n");
    sr_area_lights al;
    sr_scene_area_lights(s, &al);
    printf("lights      %zu point, %zu emissive triangles", st->point_lights,
           st->emissive_triangles);
    if (al.count)
        printf(" (area %g, power (%g, %g, %g))", al.total_area, al.total_power[0],
               al.total_power[1], al.total_power[2]);
    printf("\n");
    const sr_point_light *pl = sr_scene_point_lights(s);
    for (size_t i = 0; i < st->point_lights; ++i)
        printf("  point     at (%g, %g, %g) intensity (%g, %g, %g)\n", pl[i].position[0],
               pl[i].position[1], pl[i].position[2], pl[i].intensity[0], pl[i].intensity[1],
               pl[i].intensity[2]);
    printf("camera      eye (%g, %g, %g) look_at (%g, %g, %g) up (%g, %g, %g) vfov %.2f, "
           "%ux%u\n",
           c->eye[0], c->eye[1], c->eye[2], c->look_at[0], c->look_at[1], c->look_at[2], c->up[0],
           c->up[1], c->up[2], c->vfov, c->width, c->height);
    printf("render      spp %u, max depth %u, light samples %u, photons %u, lookup %u, mode %s\n",
           r->samples_per_pixel, r->max_depth, r->light_samples, r->photons, r->photon_lookup,
           sr_render_mode_name(r->mode));
    printf("degenerate  %zu dropped\n", st->degenerate_dropped);
    printf("warnings    %zu\n", st->warnings);
    const char *w = sr_scene_warnings(s);
    while (*w) {
        const char *nl = strchr(w, '\n');
        size_t n = nl ? (size_t)(nl - w) : strlen(w);
        printf("  %.*s\n", (int)n, w);
        w += n + (nl != NULL);
    }
    free(counts);
}

static cJSON *vec3(const float *v)
{
    return cJSON_CreateFloatArray(v, 3);
}

/* Builds the JSON document; NULL when out of memory. */
static cJSON *stats_json(const sr_scene *s)
{
    const sr_scene_stats *st = sr_scene_statistics(s);
    const sr_camera *c = sr_scene_camera(s);
    const sr_render_settings *r = sr_scene_render_settings(s);
    const sr_material *m = sr_scene_materials(s);
    size_t *counts = material_counts(s);
    cJSON *o = cJSON_CreateObject();
    if (!o || !counts) {
        cJSON_Delete(o);
        free(counts);
        return NULL;
    }
    cJSON_AddStringToObject(o, "scene", sr_scene_source(s));
    cJSON_AddNumberToObject(o, "triangles", (double)st->triangles);
    cJSON_AddNumberToObject(o, "vertices", (double)st->vertices);
    cJSON_AddBoolToObject(o, "normals", st->has_normals);
    cJSON *bounds = cJSON_AddObjectToObject(o, "bounds");
    if (bounds) {
        cJSON_AddItemToObject(bounds, "min", vec3(st->bounds_min));
        cJSON_AddItemToObject(bounds, "max", vec3(st->bounds_max));
    }
    cJSON *mats = cJSON_AddArrayToObject(o, "materials");
    for (size_t i = 0; mats && i < st->materials; ++i) {
        cJSON *e = cJSON_CreateObject();
        if (!e)
            break;
        cJSON_AddStringToObject(e, "name", m[i].name);
        cJSON_AddStringToObject(e, "kind", sr_material_kind_name(m[i].kind));
        cJSON_AddItemToObject(e, "albedo", vec3(m[i].albedo));
        cJSON_AddItemToObject(e, "specular", vec3(m[i].specular));
        cJSON_AddNumberToObject(e, "exponent", m[i].exponent);
        cJSON_AddNumberToObject(e, "ior", m[i].ior);
        cJSON_AddItemToObject(e, "emission", vec3(m[i].emission));
        cJSON_AddNumberToObject(e, "triangles", (double)counts[i]);
        cJSON_AddItemToArray(mats, e);
    }
    cJSON *kinds = cJSON_AddObjectToObject(o, "triangles_by_kind");
    for (int k = 0; kinds && k < SR_MATERIAL_KIND_COUNT; ++k)
        cJSON_AddNumberToObject(kinds, sr_material_kind_name((sr_material_kind)k),
                                (double)st->triangles_by_kind[k]);
    cJSON_AddNumberToObject(o, "kinds_present", st->kinds_present);
    cJSON *lights = cJSON_AddObjectToObject(o, "lights");
    if (lights) {
        sr_area_lights al;
        sr_scene_area_lights(s, &al);
        cJSON_AddNumberToObject(lights, "point", (double)st->point_lights);
        cJSON_AddNumberToObject(lights, "emissive_triangles", (double)st->emissive_triangles);
        cJSON_AddNumberToObject(lights, "emissive_area", al.total_area);
        cJSON_AddItemToObject(lights, "emissive_power", cJSON_CreateDoubleArray(al.total_power, 3));
    }
    cJSON *cam = cJSON_AddObjectToObject(o, "camera");
    if (cam) {
        cJSON_AddItemToObject(cam, "eye", vec3(c->eye));
        cJSON_AddItemToObject(cam, "look_at", vec3(c->look_at));
        cJSON_AddItemToObject(cam, "up", vec3(c->up));
        cJSON_AddNumberToObject(cam, "vfov", c->vfov);
        cJSON_AddNumberToObject(cam, "width", c->width);
        cJSON_AddNumberToObject(cam, "height", c->height);
    }
    cJSON *ren = cJSON_AddObjectToObject(o, "render");
    if (ren) {
        cJSON_AddNumberToObject(ren, "spp", r->samples_per_pixel);
        cJSON_AddNumberToObject(ren, "max_depth", r->max_depth);
        cJSON_AddNumberToObject(ren, "light_samples", r->light_samples);
        cJSON_AddNumberToObject(ren, "photons", r->photons);
        cJSON_AddNumberToObject(ren, "photon_lookup", r->photon_lookup);
        cJSON_AddStringToObject(ren, "mode", sr_render_mode_name(r->mode));
    }
    cJSON_AddNumberToObject(o, "degenerate_dropped", (double)st->degenerate_dropped);
    cJSON *warn = cJSON_AddArrayToObject(o, "warnings");
    const char *w = sr_scene_warnings(s);
    char line[1024];
    while (warn && *w) {
        const char *nl = strchr(w, '\n');
        size_t n = nl ? (size_t)(nl - w) : strlen(w);
        snprintf(line, sizeof line, "%.*s", (int)n, w);
        cJSON_AddItemToArray(warn, cJSON_CreateString(line));
        w += n + (nl != NULL);
    }
    free(counts);
    return o;
}

int main(int argc, char **argv)
{
    const char *input = NULL;
    int json = 0;
    sr_scene_load_options opts = {0};
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(argv[i], "--list") == 0) {
            list();
            return 0;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (strcmp(argv[i], "--allow-no-light") == 0) {
            opts.flags |= SR_SCENE_ALLOW_NO_LIGHT;
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            fprintf(stderr, "sluice-scene: unknown option %s\n", argv[i]);
            usage(stderr);
            return 2;
        } else if (input) {
            fprintf(stderr, "sluice-scene: one scene at a time (%s, then %s)\n", input, argv[i]);
            return 2;
        } else {
            input = argv[i];
        }
    }
    if (!input) {
        usage(stderr);
        return 2;
    }
    char err[1024];
    sr_scene *s = NULL;
    sluice_status st = sr_scene_load(input, &opts, &s, err, sizeof err);
    if (st != SLUICE_OK) {
        fprintf(stderr, "sluice-scene: %s\n", err);
        return 1;
    }
    int rc = 0;
    if (json) {
        cJSON *o = stats_json(s);
        char *text = o ? cJSON_Print(o) : NULL;
        if (text) {
            printf("%s\n", text);
            cJSON_free(text);
        } else {
            fprintf(stderr, "sluice-scene: out of memory\n");
            rc = 1;
        }
        cJSON_Delete(o);
    } else {
        print_text(s);
    }
    sr_scene_destroy(s);
    return rc;
}
