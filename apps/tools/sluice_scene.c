/* sluice-scene: loads a scene (a built-in name, a JSON scene file or a mesh
 * file) and prints what it holds: triangles, vertices, bounds, materials and
 * lights by kind, camera, render settings and warnings, as text or JSON.
 * Exits 0 on success, 1 when the scene cannot be loaded (the message, naming
 * the file and field, goes to stderr), 2 on a usage error. */
#include "scene.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static void usage(FILE *f)
{
    fprintf(f, "usage: sluice-scene NAME|FILE [--json] [--allow-no-light] [--export-mitsuba DIR]\n"
               "       sluice-scene --list | --help\n"
               "Loads a scene and prints its statistics: triangles, vertices, bounds,\n"
               "materials and lights by kind, camera, render settings, warnings.\n"
               "NAME is a built-in scene (see --list); FILE is a JSON scene file (.json,\n"
               "see docs/scenes.md) or a mesh file assimp reads (OBJ+MTL, PLY, glTF 2, ...),\n"
               "which gets a default camera and, without emissive materials, a default light.\n"
               "  --list            name the built-in scenes, one line each\n"
               "  --json            print the statistics as JSON\n"
               "  --allow-no-light  accept a scene without any light\n"
               "  --export-mitsuba DIR\n"
               "                    also write the scene for Mitsuba 3: DIR/scene.xml and\n"
               "                    DIR/meshes/*.ply (binary, one per material and shading:\n"
               "                    flat or with vertex normals), two-sided BSDFs, one-sided\n"
               "                    area emitters, point lights, the camera (vfov), a box\n"
               "                    filter and a path integrator with max_depth = the\n"
               "                    scene's max depth + 2; spp, max_depth, width, height and\n"
               "                    seed are <default>s to override when loading\n"
               "  --help            this text\n"
               "examples:\n"
               "  sluice-scene cornell\n"
               "  sluice-scene spheres:100 --json\n"
               "  sluice-scene scenes/example.json\n"
               "  sluice-scene cornell --export-mitsuba /tmp/cornell-mitsuba\n"
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

/* ------------------------------------------------------------------ */
/* Export for Mitsuba 3 (bench/references.py compares the renderers)   */
/* ------------------------------------------------------------------ */

/* Little-endian binary output, whatever the host's byte order. */
static void put_u32(FILE *f, uint32_t v)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    fwrite(b, 1, 4, f);
}

static void put_f32(FILE *f, float x)
{
    uint32_t v;
    memcpy(&v, &x, sizeof v);
    put_u32(f, v);
}

/* Non-zero when all three vertex normals of triangle `t` are non-zero: the
 * renderers then interpolate them (kernels/render/surface.cl), otherwise they
 * use the geometric normal. */
static int tri_smooth(const sr_scene *s, size_t t)
{
    const float *n = sr_scene_normals(s);
    if (!n)
        return 0;
    const uint32_t *idx = sr_scene_indices(s) + 3 * t;
    for (int k = 0; k < 3; ++k) {
        const float *v = n + 3 * (size_t)idx[k];
        if (v[0] == 0.0f && v[1] == 0.0f && v[2] == 0.0f)
            return 0;
    }
    return 1;
}

/* Writes the triangles of material `mat` whose shading is `smooth` to a
 * binary PLY at `path`, with vertex normals when `smooth`. `map` has one
 * entry per scene vertex, all UINT32_MAX on entry and on return. Returns the
 * number of triangles written (0: no file), or -1 on an I/O error. */
static long write_ply(const sr_scene *s, uint32_t mat, int smooth, uint32_t *map, const char *path)
{
    size_t nt = sr_scene_triangle_count(s);
    const uint32_t *tm = sr_scene_triangle_materials(s), *idx = sr_scene_indices(s);
    const float *p = sr_scene_positions(s), *n = sr_scene_normals(s);
    size_t tris = 0, verts = 0;
    uint32_t *order = NULL; /* the scene vertices used, in PLY order */
    for (size_t t = 0; t < nt; ++t)
        if (tm[t] == mat && tri_smooth(s, t) == smooth)
            tris++;
    if (!tris)
        return 0;
    order = malloc(3 * tris * sizeof *order);
    if (!order)
        return -1;
    for (size_t t = 0; t < nt; ++t) {
        if (tm[t] != mat || tri_smooth(s, t) != smooth)
            continue;
        for (int k = 0; k < 3; ++k) {
            uint32_t v = idx[3 * t + k];
            if (map[v] == UINT32_MAX) {
                map[v] = (uint32_t)verts;
                order[verts++] = v;
            }
        }
    }
    FILE *f = fopen(path, "wb");
    long rc = -1;
    if (f) {
        fprintf(f,
                "ply\nformat binary_little_endian 1.0\ncomment sluice-scene %s\n"
                "element vertex %zu\nproperty float x\nproperty float y\nproperty float z\n",
                sr_scene_source(s), verts);
        if (smooth)
            fprintf(f, "property float nx\nproperty float ny\nproperty float nz\n");
        fprintf(f, "element face %zu\nproperty list uchar int vertex_indices\nend_header\n", tris);
        for (size_t i = 0; i < verts; ++i) {
            for (int k = 0; k < 3; ++k)
                put_f32(f, p[3 * (size_t)order[i] + k]);
            for (int k = 0; smooth && k < 3; ++k)
                put_f32(f, n[3 * (size_t)order[i] + k]);
        }
        for (size_t t = 0; t < nt; ++t) {
            if (tm[t] != mat || tri_smooth(s, t) != smooth)
                continue;
            fputc(3, f);
            for (int k = 0; k < 3; ++k)
                put_u32(f, map[idx[3 * t + k]]);
        }
        rc = (fflush(f) == 0 && !ferror(f)) ? (long)tris : -1;
        if (fclose(f) != 0)
            rc = -1;
    }
    for (size_t i = 0; i < verts; ++i)
        map[order[i]] = UINT32_MAX;
    free(order);
    return rc;
}

static void xml_rgb(FILE *f, const char *name, const float *c)
{
    fprintf(f, "<rgb name=\"%s\" value=\"%.9g, %.9g, %.9g\"/>", name, c[0], c[1], c[2]);
}

static void xml_point(FILE *f, const char *name, const float *v)
{
    fprintf(f, "%s=\"%.9g, %.9g, %.9g\"", name, v[0], v[1], v[2]);
}

/* The BSDF of material `m` as Mitsuba 3 XML (one line). Sluice's surfaces
 * reflect on both sides (surface.cl turns the normals towards the ray), so
 * everything but glass is wrapped in "twosided". */
static void xml_bsdf(FILE *f, const sr_material *m, size_t i)
{
    fprintf(f, "    <!-- material %zu \"%s\": %s -->\n", i, m->name,
            sr_material_kind_name(m->kind));
    if (m->kind == SR_MATERIAL_GLASS) {
        /* outside is vacuum in Sluice (Mitsuba's default ext_ior is air) */
        fprintf(f,
                "    <bsdf type=\"dielectric\" id=\"mat%zu\"><float name=\"int_ior\" "
                "value=\"%.9g\"/><float name=\"ext_ior\" value=\"1\"/>",
                i, m->ior);
        xml_rgb(f, "specular_reflectance", m->specular);
        xml_rgb(f, "specular_transmittance", m->specular);
        fprintf(f, "</bsdf>\n");
        return;
    }
    fprintf(f, "    <bsdf type=\"twosided\" id=\"mat%zu\">", i);
    if (m->kind == SR_MATERIAL_MIRROR) {
        fprintf(f, "<bsdf type=\"conductor\"><string name=\"material\" value=\"none\"/>");
        xml_rgb(f, "specular_reflectance", m->specular);
    } else {
        /* DIFFUSE, EMISSIVE, and GLOSSY approximated by its diffuse part
         * (Mitsuba 3 has no modified Blinn-Phong) */
        if (m->kind == SR_MATERIAL_GLOSSY)
            fprintf(f, "<!-- APPROXIMATE: glossy exported as its diffuse part -->");
        fprintf(f, "<bsdf type=\"diffuse\">");
        xml_rgb(f, "reflectance", m->albedo);
    }
    fprintf(f, "</bsdf></bsdf>\n");
}

/* Writes DIR/scene.xml and the PLY files in DIR/meshes; returns 0, or 1 with a message
 * on stderr. */
static int export_mitsuba(const sr_scene *s, const char *dir)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/meshes", dir);
    if ((mkdir(dir, 0777) != 0 && errno != EEXIST) || (mkdir(path, 0777) != 0 && errno != EEXIST)) {
        fprintf(stderr, "sluice-scene: cannot create %s: %s\n", path, strerror(errno));
        return 1;
    }
    snprintf(path, sizeof path, "%s/scene.xml", dir);
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "sluice-scene: cannot write %s: %s\n", path, strerror(errno));
        return 1;
    }
    const sr_camera *c = sr_scene_camera(s);
    const sr_render_settings *r = sr_scene_render_settings(s);
    const sr_material *m = sr_scene_materials(s);
    size_t nm = sr_scene_material_count(s), nv = sr_scene_vertex_count(s);
    /* XML comments may not hold "--" (nor end in "-"): the scene's name is
     * written with a space after every '-' that a '-' or the end follows. */
    fprintf(f, "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
               "<!-- Written by sluice-scene (Mitsuba export) from ");
    for (const char *c = sr_scene_source(s); *c; ++c) {
        fputc(*c, f);
        if (*c == '-' && (c[1] == '-' || c[1] == '\0'))
            fputc(' ', f);
    }
    fprintf(f, ". Units and conventions\n"
               "     as in Sluice: linear RGB, radiance; area lights emit from the front\n"
               "     (counter-clockwise) side only; a Sluice path of max depth D has at most\n"
               "     D + 1 scattering vertices, D + 2 segments: Mitsuba's max_depth. -->\n");
    fprintf(f, "<scene version=\"3.0.0\">\n");
    fprintf(f, "    <default name=\"spp\" value=\"%u\"/>\n", r->samples_per_pixel);
    fprintf(f, "    <default name=\"max_depth\" value=\"%u\"/>\n", r->max_depth + 2u);
    fprintf(f, "    <default name=\"width\" value=\"%u\"/>\n", c->width);
    fprintf(f, "    <default name=\"height\" value=\"%u\"/>\n", c->height);
    fprintf(f, "    <default name=\"seed\" value=\"0\"/>\n");
    fprintf(f, "    <integrator type=\"path\"><integer name=\"max_depth\" "
               "value=\"$max_depth\"/></integrator>\n");
    fprintf(f, "    <sensor type=\"perspective\">\n"
               "        <string name=\"fov_axis\" value=\"y\"/>\n");
    fprintf(f, "        <float name=\"fov\" value=\"%.9g\"/>\n", c->vfov);
    fprintf(f, "        <transform name=\"to_world\"><lookat ");
    xml_point(f, "origin", c->eye);
    fputc(' ', f);
    xml_point(f, "target", c->look_at);
    fputc(' ', f);
    xml_point(f, "up", c->up);
    fprintf(f, "/></transform>\n"
               "        <sampler type=\"independent\"><integer name=\"sample_count\" "
               "value=\"$spp\"/><integer name=\"seed\" value=\"$seed\"/></sampler>\n"
               "        <film type=\"hdrfilm\"><integer name=\"width\" value=\"$width\"/>"
               "<integer name=\"height\" value=\"$height\"/>"
               "<string name=\"pixel_format\" value=\"rgb\"/>"
               "<string name=\"component_format\" value=\"float32\"/>"
               "<rfilter type=\"box\"/></film>\n"
               "    </sensor>\n");
    for (size_t i = 0; i < nm; ++i) {
        if (m[i].kind == SR_MATERIAL_GLOSSY)
            fprintf(stderr,
                    "sluice-scene: warning: material \"%s\" is glossy: exported as its "
                    "diffuse part\n",
                    m[i].name);
        xml_bsdf(f, &m[i], i);
    }
    uint32_t *map = malloc((nv ? nv : 1) * sizeof *map);
    int rc = map ? 0 : 1;
    for (size_t i = 0; map && i < nv; ++i)
        map[i] = UINT32_MAX;
    for (size_t i = 0; rc == 0 && i < nm; ++i) {
        for (int smooth = 0; rc == 0 && smooth < 2; ++smooth) {
            char name[64], ply[4096];
            snprintf(name, sizeof name, "meshes/mat%zu-%s.ply", i, smooth ? "smooth" : "flat");
            snprintf(ply, sizeof ply, "%s/%s", dir, name);
            long n = write_ply(s, (uint32_t)i, smooth, map, ply);
            if (n < 0) {
                fprintf(stderr, "sluice-scene: cannot write %s\n", ply);
                rc = 1;
            } else if (n > 0) {
                fprintf(f, "    <shape type=\"ply\"><!-- %ld triangles -->", n);
                fprintf(f, "<string name=\"filename\" value=\"%s\"/>", name);
                /* without normals in the file Mitsuba would make smooth ones */
                fprintf(f, "<boolean name=\"face_normals\" value=\"%s\"/>",
                        smooth ? "false" : "true");
                fprintf(f, "<ref id=\"mat%zu\"/>", i);
                if (sr_material_is_emissive(&m[i])) {
                    fprintf(f, "<emitter type=\"area\">");
                    xml_rgb(f, "radiance", m[i].emission);
                    fprintf(f, "</emitter>");
                }
                fprintf(f, "</shape>\n");
            }
        }
    }
    free(map);
    const sr_point_light *pl = sr_scene_point_lights(s);
    for (size_t i = 0; i < sr_scene_point_light_count(s); ++i) {
        fprintf(f,
                "    <emitter type=\"point\"><point name=\"position\" x=\"%.9g\" y=\"%.9g\" "
                "z=\"%.9g\"/>",
                pl[i].position[0], pl[i].position[1], pl[i].position[2]);
        xml_rgb(f, "intensity", pl[i].intensity);
        fprintf(f, "</emitter>\n");
    }
    fprintf(f, "</scene>\n");
    if (fclose(f) != 0 && rc == 0) {
        fprintf(stderr, "sluice-scene: cannot write %s\n", path);
        rc = 1;
    }
    return rc;
}

int main(int argc, char **argv)
{
    const char *input = NULL;
    int json = 0;
    const char *export_dir = NULL;
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
        } else if (strcmp(argv[i], "--export-mitsuba") == 0) {
            if (i + 1 >= argc) {
                fprintf(stderr, "sluice-scene: --export-mitsuba needs a directory\n");
                return 2;
            }
            export_dir = argv[++i];
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
    if (rc == 0 && export_dir)
        rc = export_mitsuba(s, export_dir);
    sr_scene_destroy(s);
    return rc;
}
