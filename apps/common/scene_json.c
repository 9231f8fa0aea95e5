/* JSON scene files (format: docs/scenes.md), parsed with cJSON into the
 * builder. Every object is checked for unknown and repeated fields, so a
 * typo is an error that names the field instead of a silently ignored
 * setting; every error names the file and the field's path, e.g.
 * "s.json: meshes[2].transform.scale: expected a number or an array of 3
 * numbers". */
#include "scene.h"
#include "app_error.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A scene file is a description, not data: anything larger is a mistake. */
#define MAX_JSON_BYTES (64u << 20)

static const double PI = 3.14159265358979323846;

typedef struct jctx {
    const char *file; /* as given, for messages */
    char *dir;        /* directory of the file, for relative mesh paths ("" = cwd) */
    sr_scene_builder *b;
    int have_default;
    uint32_t default_material;
    char *err;
    size_t err_size;
} jctx;

/* "file: path: message"; returns SLUICE_ERROR_INVALID_ARGUMENT. */
static sluice_status jfail(const jctx *c, const char *path, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    sr_set_error(c->err, c->err_size, "%s: %s: %s", c->file, path, msg);
    return SLUICE_ERROR_INVALID_ARGUMENT;
}

/* Child path "parent.key" (or "key" at the top). */
static void sub(char *out, size_t n, const char *parent, const char *key)
{
    /* a path that does not fit is cut short: it only ends up in a message */
    const char *parts[3] = {parent, *parent ? "." : "", key};
    size_t len = 0;
    for (int i = 0; i < 3; ++i) {
        for (const char *c = parts[i]; *c && len + 1 < n; ++c)
            out[len++] = *c;
    }
    out[len] = '\0';
}

static const char *type_name(const cJSON *v)
{
    if (cJSON_IsNumber(v))
        return "a number";
    if (cJSON_IsString(v))
        return "a string";
    if (cJSON_IsBool(v))
        return "a boolean";
    if (cJSON_IsNull(v))
        return "null";
    if (cJSON_IsArray(v))
        return "an array";
    return "an object";
}

/* Rejects fields not in `allowed` (NULL-terminated) and repeated fields. */
static sluice_status check_fields(const jctx *c, const cJSON *obj, const char *path,
                                  const char *const *allowed)
{
    for (const cJSON *it = obj->child; it; it = it->next) {
        int known = 0;
        for (const char *const *a = allowed; *a && !known; ++a)
            known = strcmp(it->string, *a) == 0;
        char p[256];
        sub(p, sizeof p, path, it->string);
        if (!known) {
            char list[256] = "";
            for (const char *const *a = allowed; *a; ++a) {
                size_t l = strlen(list);
                snprintf(list + l, sizeof list - l, "%s%s", l ? ", " : "", *a);
            }
            return jfail(c, p, "unknown field (expected one of: %s)", list);
        }
        for (const cJSON *o = obj->child; o != it; o = o->next) {
            if (strcmp(o->string, it->string) == 0)
                return jfail(c, p, "field given twice");
        }
    }
    return SLUICE_OK;
}

static sluice_status want_object(const jctx *c, const cJSON *v, const char *path)
{
    if (!cJSON_IsObject(v))
        return jfail(c, path, "expected an object, got %s", type_name(v));
    return SLUICE_OK;
}

/* The field `key` of `obj`, or NULL when it is absent; `*found` (may be
 * NULL) says whether it was there. */
static const cJSON *optional_field(const cJSON *obj, const char *key, int *found)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (found)
        *found = v != NULL;
    return v;
}

/* Reads an optional number field; `*found` (may be NULL) says whether it was
 * there. */
static sluice_status get_number(const jctx *c, const cJSON *obj, const char *key, const char *path,
                                double *out, int *found)
{
    const cJSON *v = optional_field(obj, key, found);
    if (!v)
        return SLUICE_OK;
    char p[256];
    sub(p, sizeof p, path, key);
    if (!cJSON_IsNumber(v))
        return jfail(c, p, "expected a number, got %s", type_name(v));
    if (!(fabs(v->valuedouble) <= FLT_MAX)) /* the scene stores floats */
        return jfail(c, p, "%g is out of range for a float", v->valuedouble);
    *out = v->valuedouble;
    return SLUICE_OK;
}

/* Reads an optional integer field in [lo, hi]. */
static sluice_status get_uint(const jctx *c, const cJSON *obj, const char *key, const char *path,
                              double lo, double hi, uint32_t *out)
{
    double d = 0.0;
    int found = 0;
    sluice_status st = get_number(c, obj, key, path, &d, &found);
    if (st != SLUICE_OK || !found)
        return st;
    char p[256];
    sub(p, sizeof p, path, key);
    if (d != floor(d))
        return jfail(c, p, "expected a whole number, got %g", d);
    if (d < lo || d > hi)
        return jfail(c, p, "%.0f is out of range (%.0f..%.0f)", d, lo, hi);
    *out = (uint32_t)d;
    return SLUICE_OK;
}

/* Reads an array of n numbers at `v` (already located) into out. */
static sluice_status read_array(const jctx *c, const cJSON *v, const char *path, int n, double *out)
{
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != n)
        return jfail(c, path, "expected an array of %d numbers", n);
    int i = 0;
    for (const cJSON *e = v->child; e; e = e->next, ++i) {
        if (!cJSON_IsNumber(e))
            return jfail(c, path, "element %d: expected a number, got %s", i, type_name(e));
        if (!(fabs(e->valuedouble) <= FLT_MAX))
            return jfail(c, path, "element %d: %g is out of range for a float", i, e->valuedouble);
        out[i] = e->valuedouble;
    }
    return SLUICE_OK;
}

/* Reads an optional [x, y, z] field into float[3]. */
static sluice_status get_vec3(const jctx *c, const cJSON *obj, const char *key, const char *path,
                              float *out, int *found)
{
    const cJSON *v = optional_field(obj, key, found);
    if (!v)
        return SLUICE_OK;
    char p[256];
    sub(p, sizeof p, path, key);
    double d[3];
    sluice_status st = read_array(c, v, p, 3, d);
    if (st != SLUICE_OK)
        return st;
    for (int k = 0; k < 3; ++k)
        out[k] = (float)d[k];
    return SLUICE_OK;
}

/* A colour: a number (grey) or [r, g, b]. */
static sluice_status get_color(const jctx *c, const cJSON *obj, const char *key, const char *path,
                               float *out)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!v)
        return SLUICE_OK;
    char p[256];
    sub(p, sizeof p, path, key);
    if (cJSON_IsNumber(v) && fabs(v->valuedouble) <= FLT_MAX) {
        out[0] = out[1] = out[2] = (float)v->valuedouble;
        return SLUICE_OK;
    }
    double d[3];
    if (!cJSON_IsArray(v) || read_array(c, v, p, 3, d) != SLUICE_OK)
        return jfail(c, p, "expected a number or an array of 3 numbers");
    for (int k = 0; k < 3; ++k)
        out[k] = (float)d[k];
    return SLUICE_OK;
}

static sluice_status require(const jctx *c, const cJSON *obj, const char *key, const char *path)
{
    if (cJSON_GetObjectItemCaseSensitive(obj, key))
        return SLUICE_OK;
    char p[256];
    sub(p, sizeof p, path, key);
    return jfail(c, p, "required field missing");
}

/* ------------------------------------------------------------------ */
/* Sections                                                            */
/* ------------------------------------------------------------------ */

static sluice_status parse_material(jctx *c, const cJSON *v, const char *path)
{
    static const char *const fields[] = {"kind", "albedo",   "specular", "exponent",
                                         "ior",  "emission", NULL};
    sluice_status st = want_object(c, v, path);
    if (st == SLUICE_OK)
        st = check_fields(c, v, path, fields);
    if (st == SLUICE_OK)
        st = require(c, v, "kind", path);
    if (st != SLUICE_OK)
        return st;
    if (strlen(v->string) >= SR_MATERIAL_NAME_SIZE)
        return jfail(c, path, "name longer than %d characters", SR_MATERIAL_NAME_SIZE - 1);
    if (sr_scene_builder_find_material(c->b, v->string, NULL) == SLUICE_OK)
        return jfail(c, path, "material defined twice");
    const cJSON *kind = cJSON_GetObjectItemCaseSensitive(v, "kind");
    char p[256];
    sub(p, sizeof p, path, "kind");
    sr_material_kind k;
    if (!cJSON_IsString(kind) || sr_material_kind_parse(kind->valuestring, &k) != SLUICE_OK)
        return jfail(c, p,
                     "expected one of \"diffuse\", \"mirror\", \"glass\", \"glossy\", "
                     "\"emissive\"");
    sr_material m = sr_material_make(k, v->string);
    double d;
    int found;
    if ((st = get_color(c, v, "albedo", path, m.albedo)) != SLUICE_OK ||
        (st = get_color(c, v, "specular", path, m.specular)) != SLUICE_OK ||
        (st = get_color(c, v, "emission", path, m.emission)) != SLUICE_OK)
        return st;
    if ((st = get_number(c, v, "exponent", path, &d, &found)) != SLUICE_OK)
        return st;
    if (found)
        m.exponent = (float)d;
    if ((st = get_number(c, v, "ior", path, &d, &found)) != SLUICE_OK)
        return st;
    if (found)
        m.ior = (float)d;
    char msg[512], prefix[256];
    st = sr_scene_builder_add_material(c->b, &m, NULL, msg, sizeof msg);
    if (st != SLUICE_OK) {
        /* the builder says "FILE: material 'NAME': what"; say "FILE: PATH: what" */
        snprintf(prefix, sizeof prefix, "%s: material '%s': ", c->file, m.name);
        size_t pl = strlen(prefix);
        jfail(c, path, "%s", strncmp(msg, prefix, pl) == 0 ? msg + pl : msg);
        return st;
    }
    return SLUICE_OK;
}

/* 4x4 row-major product c = a b. */
static void mul4(const double *a, const double *b, double *c)
{
    for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k)
            c[r * 4 + k] = a[r * 4] * b[k] + a[r * 4 + 1] * b[4 + k] + a[r * 4 + 2] * b[8 + k] +
                           a[r * 4 + 3] * b[12 + k];
}

static void identity4(double *m)
{
    for (int i = 0; i < 16; ++i)
        m[i] = i % 5 == 0 ? 1.0 : 0.0;
}

/* Rotation by `deg` degrees about the unit axis (x, y, z) (Rodrigues). */
static void rotation4(double x, double y, double z, double deg, double *m)
{
    double a = deg * PI / 180.0, c = cos(a), s = sin(a), t = 1.0 - c;
    identity4(m);
    m[0] = t * x * x + c;
    m[1] = t * x * y - s * z;
    m[2] = t * x * z + s * y;
    m[4] = t * x * y + s * z;
    m[5] = t * y * y + c;
    m[6] = t * y * z - s * x;
    m[8] = t * x * z - s * y;
    m[9] = t * y * z + s * x;
    m[10] = t * z * z + c;
}

/* transform: {"matrix": [16 numbers, row-major]} or any of "scale", "rotate",
 * "translate", applied in that order (M = T R S). */
static sluice_status parse_transform(jctx *c, const cJSON *v, const char *path, float *out)
{
    static const char *const fields[] = {"translate", "rotate", "scale", "matrix", NULL};
    sluice_status st = want_object(c, v, path);
    if (st == SLUICE_OK)
        st = check_fields(c, v, path, fields);
    if (st != SLUICE_OK)
        return st;
    double m[16];
    identity4(m);
    char p[256];
    const cJSON *mat = cJSON_GetObjectItemCaseSensitive(v, "matrix");
    if (mat) {
        sub(p, sizeof p, path, "matrix");
        if (cJSON_GetArraySize(v) != 1)
            return jfail(c, p, "\"matrix\" cannot be combined with translate, rotate or scale");
        if ((st = read_array(c, mat, p, 16, m)) != SLUICE_OK)
            return st;
        if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0)
            return jfail(c, p, "not an affine transform (the last row must be 0, 0, 0, 1)");
    }
    const cJSON *scale = cJSON_GetObjectItemCaseSensitive(v, "scale");
    if (scale) {
        sub(p, sizeof p, path, "scale");
        double s[3];
        if (cJSON_IsNumber(scale) && fabs(scale->valuedouble) <= FLT_MAX)
            s[0] = s[1] = s[2] = scale->valuedouble;
        else if (!cJSON_IsArray(scale) || read_array(c, scale, p, 3, s) != SLUICE_OK)
            return jfail(c, p, "expected a number or an array of 3 numbers");
        if (s[0] == 0.0 || s[1] == 0.0 || s[2] == 0.0)
            return jfail(c, p, "a scale of 0 flattens the mesh");
        double t[16], r[16];
        identity4(t);
        t[0] = s[0];
        t[5] = s[1];
        t[10] = s[2];
        mul4(t, m, r);
        memcpy(m, r, sizeof m);
    }
    const cJSON *rot = cJSON_GetObjectItemCaseSensitive(v, "rotate");
    if (rot) {
        sub(p, sizeof p, path, "rotate");
        double r[16], t[16];
        if (cJSON_IsArray(rot)) {
            /* Euler angles in degrees about x, then y, then z: R = Rz Ry Rx */
            double e[3], rx[16], ry[16], rz[16];
            if ((st = read_array(c, rot, p, 3, e)) != SLUICE_OK)
                return jfail(c, p,
                             "expected {\"axis\": [x, y, z], \"angle\": degrees} or an array of "
                             "3 Euler angles in degrees");
            rotation4(1, 0, 0, e[0], rx);
            rotation4(0, 1, 0, e[1], ry);
            rotation4(0, 0, 1, e[2], rz);
            mul4(ry, rx, t);
            mul4(rz, t, r);
        } else if (cJSON_IsObject(rot)) {
            static const char *const rf[] = {"axis", "angle", NULL};
            if ((st = check_fields(c, rot, p, rf)) != SLUICE_OK ||
                (st = require(c, rot, "axis", p)) != SLUICE_OK ||
                (st = require(c, rot, "angle", p)) != SLUICE_OK)
                return st;
            float axis[3] = {0, 0, 0};
            double angle = 0.0;
            if ((st = get_vec3(c, rot, "axis", p, axis, NULL)) != SLUICE_OK ||
                (st = get_number(c, rot, "angle", p, &angle, NULL)) != SLUICE_OK)
                return st;
            double l = sqrt((double)axis[0] * axis[0] + (double)axis[1] * axis[1] +
                            (double)axis[2] * axis[2]);
            if (!(l > 0.0)) {
                char pa[256];
                sub(pa, sizeof pa, p, "axis");
                return jfail(c, pa, "the axis is zero");
            }
            rotation4(axis[0] / l, axis[1] / l, axis[2] / l, angle, r);
        } else {
            return jfail(c, p,
                         "expected {\"axis\": [x, y, z], \"angle\": degrees} or an array of 3 "
                         "Euler angles in degrees");
        }
        mul4(r, m, t);
        memcpy(m, t, sizeof m);
    }
    float tr[3] = {0, 0, 0};
    int found = 0;
    if ((st = get_vec3(c, v, "translate", path, tr, &found)) != SLUICE_OK)
        return st;
    for (int k = 0; k < 3; ++k)
        m[4 * k + 3] += tr[k];
    for (int k = 0; k < 16; ++k) {
        if (!(fabs(m[k]) <= FLT_MAX))
            return jfail(c, path, "the combined transform is out of range for floats");
        out[k] = (float)m[k];
    }
    return SLUICE_OK;
}

static sluice_status default_material(jctx *c, uint32_t *out)
{
    if (!c->have_default &&
        sr_scene_builder_find_material(c->b, "default", &c->default_material) != SLUICE_OK) {
        sr_material m = sr_material_make(SR_MATERIAL_DIFFUSE, "default");
        sluice_status st =
            sr_scene_builder_add_material(c->b, &m, &c->default_material, c->err, c->err_size);
        if (st != SLUICE_OK)
            return st;
    }
    c->have_default = 1;
    *out = c->default_material;
    return SLUICE_OK;
}

/* Prefixes a builder or loader message with the JSON file and field (the
 * builder's own messages start with the file already: that goes). */
static sluice_status wrap(const jctx *c, const char *path, sluice_status st, const char *msg)
{
    size_t fl = strlen(c->file);
    if (strncmp(msg, c->file, fl) == 0 && msg[fl] == ':' && msg[fl + 1] == ' ')
        msg += fl + 2;
    sr_set_error(c->err, c->err_size, "%s: %s: %s", c->file, path, msg);
    return st;
}

static sluice_status parse_shape(jctx *c, const cJSON *v, const char *path, const char *shape,
                                 uint32_t material, const float *xf)
{
    char msg[512] = "";
    char p[256];
    sub(p, sizeof p, path, "shape");
    sluice_status st = SLUICE_OK;
    float center[3] = {0, 0, 0};
    if (strcmp(shape, "sphere") == 0) {
        static const char *const f[] = {"shape",    "center",    "radius", "subdiv",
                                        "material", "transform", "name",   NULL};
        double radius = 1.0;
        uint32_t subdiv = 8;
        if ((st = check_fields(c, v, path, f)) != SLUICE_OK ||
            (st = get_vec3(c, v, "center", path, center, NULL)) != SLUICE_OK ||
            (st = get_number(c, v, "radius", path, &radius, NULL)) != SLUICE_OK ||
            (st = get_uint(c, v, "subdiv", path, 1, 256, &subdiv)) != SLUICE_OK)
            return st;
        if (!(radius > 0.0)) {
            sub(p, sizeof p, path, "radius");
            return jfail(c, p, "must be > 0");
        }
        st = sr_scene_builder_add_sphere(c->b, center, (float)radius, subdiv, material, xf, msg,
                                         sizeof msg);
    } else if (strcmp(shape, "quad") == 0) {
        static const char *const f[] = {"shape",    "corner",    "u",    "v",
                                        "material", "transform", "name", NULL};
        float corner[3] = {0, 0, 0}, u[3] = {1, 0, 0}, w[3] = {0, 0, 1};
        if ((st = check_fields(c, v, path, f)) != SLUICE_OK ||
            (st = require(c, v, "u", path)) != SLUICE_OK ||
            (st = require(c, v, "v", path)) != SLUICE_OK ||
            (st = get_vec3(c, v, "corner", path, corner, NULL)) != SLUICE_OK ||
            (st = get_vec3(c, v, "u", path, u, NULL)) != SLUICE_OK ||
            (st = get_vec3(c, v, "v", path, w, NULL)) != SLUICE_OK)
            return st;
        st = sr_scene_builder_add_quad(c->b, corner, u, w, material, xf, msg, sizeof msg);
    } else if (strcmp(shape, "box") == 0) {
        static const char *const f[] = {"shape",     "min",  "max", "material",
                                        "transform", "name", NULL};
        float lo[3], hi[3];
        if ((st = check_fields(c, v, path, f)) != SLUICE_OK ||
            (st = require(c, v, "min", path)) != SLUICE_OK ||
            (st = require(c, v, "max", path)) != SLUICE_OK ||
            (st = get_vec3(c, v, "min", path, lo, NULL)) != SLUICE_OK ||
            (st = get_vec3(c, v, "max", path, hi, NULL)) != SLUICE_OK)
            return st;
        st = sr_scene_builder_add_box(c->b, lo, hi, material, xf, msg, sizeof msg);
    } else if (strcmp(shape, "ring") == 0) {
        static const char *const f[] = {"shape",    "center",   "radius",    "thickness", "height",
                                        "segments", "material", "transform", "name",      NULL};
        double radius = 1.0, thickness = 0.05, height = 0.3;
        uint32_t segments = 128;
        if ((st = check_fields(c, v, path, f)) != SLUICE_OK ||
            (st = get_vec3(c, v, "center", path, center, NULL)) != SLUICE_OK ||
            (st = get_number(c, v, "radius", path, &radius, NULL)) != SLUICE_OK ||
            (st = get_number(c, v, "thickness", path, &thickness, NULL)) != SLUICE_OK ||
            (st = get_number(c, v, "height", path, &height, NULL)) != SLUICE_OK ||
            (st = get_uint(c, v, "segments", path, 3, 65536, &segments)) != SLUICE_OK)
            return st;
        st = sr_scene_builder_add_ring(c->b, center, (float)radius, (float)thickness, (float)height,
                                       segments, material, xf, msg, sizeof msg);
    } else if (strcmp(shape, "teapot") == 0) {
        static const char *const f[] = {"shape", "subdiv", "material", "transform", "name", NULL};
        uint32_t subdiv = 8;
        if ((st = check_fields(c, v, path, f)) != SLUICE_OK ||
            (st = get_uint(c, v, "subdiv", path, 2, 64, &subdiv)) != SLUICE_OK)
            return st;
        st = sr_scene_builder_add_teapot(c->b, subdiv, material, xf, msg, sizeof msg);
    } else {
        return jfail(c, p,
                     "unknown shape '%s' (expected \"sphere\", \"quad\", \"box\", \"ring\" or "
                     "\"teapot\")",
                     shape);
    }
    return st == SLUICE_OK ? st : wrap(c, path, st, msg);
}

static sluice_status parse_mesh(jctx *c, const cJSON *v, const char *path)
{
    sluice_status st = want_object(c, v, path);
    if (st != SLUICE_OK)
        return st;
    const cJSON *file = cJSON_GetObjectItemCaseSensitive(v, "file");
    const cJSON *shape = cJSON_GetObjectItemCaseSensitive(v, "shape");
    if ((file != NULL) == (shape != NULL))
        return jfail(c, path, "needs exactly one of \"file\" and \"shape\"");
    char p[256];
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(v, "name");
    if (name && !cJSON_IsString(name)) {
        sub(p, sizeof p, path, "name");
        return jfail(c, p, "expected a string, got %s", type_name(name));
    }
    float xf[16];
    const float *xfp = NULL;
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(v, "transform");
    if (t) {
        sub(p, sizeof p, path, "transform");
        if ((st = parse_transform(c, t, p, xf)) != SLUICE_OK)
            return st;
        xfp = xf;
    }
    uint32_t material = 0;
    int have_material = 0;
    const cJSON *mat = cJSON_GetObjectItemCaseSensitive(v, "material");
    if (mat) {
        sub(p, sizeof p, path, "material");
        if (!cJSON_IsString(mat))
            return jfail(c, p, "expected a material name, got %s", type_name(mat));
        if (sr_scene_builder_find_material(c->b, mat->valuestring, &material) != SLUICE_OK)
            return jfail(c, p, "no material named '%s' in \"materials\"", mat->valuestring);
        have_material = 1;
    }
    if (shape) {
        sub(p, sizeof p, path, "shape");
        if (!cJSON_IsString(shape))
            return jfail(c, p, "expected a string, got %s", type_name(shape));
        if (!have_material && (st = default_material(c, &material)) != SLUICE_OK)
            return st;
        return parse_shape(c, v, path, shape->valuestring, material, xfp);
    }
    static const char *const f[] = {"file", "material", "transform", "name", NULL};
    if ((st = check_fields(c, v, path, f)) != SLUICE_OK)
        return st;
    sub(p, sizeof p, path, "file");
    if (!cJSON_IsString(file) || !file->valuestring[0])
        return jfail(c, p, "expected a file name");
    const char *fn = file->valuestring;
    size_t n = strlen(c->dir) + strlen(fn) + 2;
    char *full = malloc(n);
    if (!full) {
        sr_set_error(c->err, c->err_size, "%s: out of memory", c->file);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    if (fn[0] == '/' || !c->dir[0])
        snprintf(full, n, "%s", fn);
    else
        snprintf(full, n, "%s/%s", c->dir, fn);
    char msg[768];
    st = sr_scene_builder_add_mesh_file(c->b, full, xfp, have_material ? &material : NULL, full,
                                        msg, sizeof msg);
    free(full);
    return st == SLUICE_OK ? st : wrap(c, p, st, msg);
}

static sluice_status parse_light(jctx *c, const cJSON *v, const char *path)
{
    static const char *const f[] = {"type", "position", "intensity", NULL};
    sluice_status st = want_object(c, v, path);
    if (st == SLUICE_OK)
        st = check_fields(c, v, path, f);
    if (st == SLUICE_OK)
        st = require(c, v, "position", path);
    if (st == SLUICE_OK)
        st = require(c, v, "intensity", path);
    if (st != SLUICE_OK)
        return st;
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(v, "type");
    if (type && (!cJSON_IsString(type) || strcmp(type->valuestring, "point") != 0)) {
        char p[256];
        sub(p, sizeof p, path, "type");
        return jfail(c, p, "expected \"point\" (area lights are meshes with an emissive material)");
    }
    sr_point_light l;
    if ((st = get_vec3(c, v, "position", path, l.position, NULL)) != SLUICE_OK ||
        (st = get_color(c, v, "intensity", path, l.intensity)) != SLUICE_OK)
        return st;
    char msg[512];
    st = sr_scene_builder_add_point_light(c->b, &l, msg, sizeof msg);
    return st == SLUICE_OK ? st : wrap(c, path, st, msg);
}

static sluice_status parse_camera(jctx *c, const cJSON *v, const char *path)
{
    static const char *const f[] = {"eye", "look_at", "up", "vfov", "width", "height", NULL};
    sluice_status st = want_object(c, v, path);
    if (st == SLUICE_OK)
        st = check_fields(c, v, path, f);
    if (st == SLUICE_OK)
        st = require(c, v, "eye", path);
    if (st == SLUICE_OK)
        st = require(c, v, "look_at", path);
    if (st != SLUICE_OK)
        return st;
    sr_camera cam;
    memset(&cam, 0, sizeof cam);
    cam.up[1] = 1.0f;
    cam.width = cam.height = 512;
    double vfov = 40.0;
    if ((st = get_vec3(c, v, "eye", path, cam.eye, NULL)) != SLUICE_OK ||
        (st = get_vec3(c, v, "look_at", path, cam.look_at, NULL)) != SLUICE_OK ||
        (st = get_vec3(c, v, "up", path, cam.up, NULL)) != SLUICE_OK ||
        (st = get_number(c, v, "vfov", path, &vfov, NULL)) != SLUICE_OK ||
        (st = get_uint(c, v, "width", path, 1, SR_SCENE_MAX_IMAGE_SIDE, &cam.width)) != SLUICE_OK ||
        (st = get_uint(c, v, "height", path, 1, SR_SCENE_MAX_IMAGE_SIDE, &cam.height)) != SLUICE_OK)
        return st;
    if (!(vfov > 0.0 && vfov < 180.0)) {
        char p[256];
        sub(p, sizeof p, path, "vfov");
        return jfail(c, p, "%g is out of range (0..180 degrees, exclusive)", vfov);
    }
    cam.vfov = (float)vfov;
    char msg[512];
    st = sr_scene_builder_set_camera(c->b, &cam, msg, sizeof msg);
    return st == SLUICE_OK ? st : wrap(c, path, st, msg);
}

static sluice_status parse_render(jctx *c, const cJSON *v, const char *path)
{
    static const char *const f[] = {
        "spp", "max_depth", "light_samples", "photons", "photon_lookup", "mode", NULL};
    sluice_status st = want_object(c, v, path);
    if (st == SLUICE_OK)
        st = check_fields(c, v, path, f);
    if (st != SLUICE_OK)
        return st;
    sr_render_settings r = sr_render_settings_default();
    const double big = 4294967295.0;
    if ((st = get_uint(c, v, "spp", path, 1, 1 << 20, &r.samples_per_pixel)) != SLUICE_OK ||
        (st = get_uint(c, v, "max_depth", path, 0, 1024, &r.max_depth)) != SLUICE_OK ||
        (st = get_uint(c, v, "light_samples", path, 1, 1 << 20, &r.light_samples)) != SLUICE_OK ||
        (st = get_uint(c, v, "photons", path, 0, big, &r.photons)) != SLUICE_OK ||
        (st = get_uint(c, v, "photon_lookup", path, 0, big, &r.photon_lookup)) != SLUICE_OK)
        return st;
    const cJSON *mode = cJSON_GetObjectItemCaseSensitive(v, "mode");
    if (mode &&
        (!cJSON_IsString(mode) || sr_render_mode_parse(mode->valuestring, &r.mode) != SLUICE_OK)) {
        char p[256];
        sub(p, sizeof p, path, "mode");
        return jfail(c, p,
                     "expected one of \"auto\", \"cast\", \"shadow\", \"whitted\", \"path\", "
                     "\"photon\"");
    }
    char msg[512];
    st = sr_scene_builder_set_render_settings(c->b, &r, msg, sizeof msg);
    return st == SLUICE_OK ? st : wrap(c, path, st, msg);
}

static sluice_status parse_scene(jctx *c, const cJSON *root)
{
    static const char *const f[] = {"description", "materials", "meshes", "lights",
                                    "camera",      "render",    NULL};
    if (!cJSON_IsObject(root)) {
        sr_set_error(c->err, c->err_size, "%s: expected a JSON object at the top, got %s", c->file,
                     type_name(root));
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sluice_status st = check_fields(c, root, "", f);
    if (st != SLUICE_OK)
        return st;
    char p[256];
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(root, "description");
    if (v && !cJSON_IsString(v))
        return jfail(c, "description", "expected a string, got %s", type_name(v));
    if ((v = cJSON_GetObjectItemCaseSensitive(root, "materials"))) {
        if ((st = want_object(c, v, "materials")) != SLUICE_OK)
            return st;
        for (const cJSON *m = v->child; m; m = m->next) {
            sub(p, sizeof p, "materials", m->string);
            if ((st = parse_material(c, m, p)) != SLUICE_OK)
                return st;
        }
    }
    const char *arrays[] = {"meshes", "lights"};
    for (int a = 0; a < 2; ++a) {
        if (!(v = cJSON_GetObjectItemCaseSensitive(root, arrays[a])))
            continue;
        if (!cJSON_IsArray(v))
            return jfail(c, arrays[a], "expected an array, got %s", type_name(v));
        int i = 0;
        for (const cJSON *e = v->child; e; e = e->next, ++i) {
            snprintf(p, sizeof p, "%s[%d]", arrays[a], i);
            st = a == 0 ? parse_mesh(c, e, p) : parse_light(c, e, p);
            if (st != SLUICE_OK)
                return st;
        }
    }
    if ((v = cJSON_GetObjectItemCaseSensitive(root, "camera")) &&
        (st = parse_camera(c, v, "camera")) != SLUICE_OK)
        return st;
    if ((v = cJSON_GetObjectItemCaseSensitive(root, "render")) &&
        (st = parse_render(c, v, "render")) != SLUICE_OK)
        return st;
    return SLUICE_OK;
}

/* Reads the whole file; NOT_FOUND / IO / LIMIT / OUT_OF_MEMORY with a message. */
static sluice_status read_file(const char *path, char **out, size_t *len, char *err,
                               size_t err_size)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) {
        int e = errno;
        sr_set_error(err, err_size, "%s: cannot open: %s", path,
                     e == ENOENT ? "no such file" : strerror(e));
        return e == ENOENT ? SLUICE_ERROR_NOT_FOUND : SLUICE_ERROR_IO;
    }
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap + 1);
    sluice_status st = buf ? SLUICE_OK : SLUICE_ERROR_OUT_OF_MEMORY;
    while (st == SLUICE_OK) {
        if (n == cap) {
            if (cap >= MAX_JSON_BYTES) {
                st = SLUICE_ERROR_LIMIT;
                break;
            }
            char *nb = realloc(buf, 2 * cap + 1);
            if (!nb) {
                st = SLUICE_ERROR_OUT_OF_MEMORY;
                break;
            }
            buf = nb;
            cap *= 2;
        }
        size_t r = fread(buf + n, 1, cap - n, f);
        n += r;
        if (r == 0) {
            if (ferror(f))
                st = SLUICE_ERROR_IO;
            break;
        }
    }
    fclose(f);
    if (st != SLUICE_OK) {
        free(buf);
        sr_set_error(err, err_size, "%s: %s", path,
                     st == SLUICE_ERROR_LIMIT ? "larger than 64 MiB: not a scene file"
                     : st == SLUICE_ERROR_IO  ? "read error"
                                              : "out of memory");
        return st;
    }
    buf[n] = '\0';
    *out = buf;
    *len = n;
    return SLUICE_OK;
}

sluice_status sr_scene_load_json(const char *path, const sr_scene_load_options *opts,
                                 sr_scene **out, char *err, size_t err_size)
{
    if (!out || !path) {
        sr_set_error(err, err_size, "load_json: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    *out = NULL;
    char *text = NULL;
    size_t len = 0;
    sluice_status st = read_file(path, &text, &len, err, err_size);
    if (st != SLUICE_OK)
        return st;
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    if (!root) {
        /* cJSON points at where parsing stopped: turn it into line:column */
        size_t off = end && end >= text && end <= text + len ? (size_t)(end - text) : len;
        size_t line = 1, col = 1;
        for (size_t i = 0; i < off; ++i) {
            if (text[i] == '\n')
                line++, col = 1;
            else
                col++;
        }
        char near[24];
        size_t k = 0;
        for (; k + 1 < sizeof near && off + k < len && text[off + k] != '\n'; ++k)
            near[k] = text[off + k];
        near[k] = '\0';
        sr_set_error(err, err_size,
                     "%s: line %zu, column %zu (byte %zu): JSON syntax error near '%s'", path, line,
                     col, off, off >= len ? "end of file" : near);
        free(text);
        return SLUICE_ERROR_IO;
    }
    free(text);

    jctx c;
    memset(&c, 0, sizeof c);
    c.file = path;
    c.err = err;
    c.err_size = err_size;
    const char *slash = strrchr(path, '/');
    size_t dl = slash ? (size_t)(slash - path) : 0;
    c.dir = malloc(dl + 2);
    if (!c.dir || sr_scene_builder_create(path, &c.b) != SLUICE_OK) {
        free(c.dir);
        cJSON_Delete(root);
        sr_set_error(err, err_size, "%s: out of memory", path);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    if (slash && dl == 0)
        snprintf(c.dir, 2, "/"); /* "/scene.json" */
    else
        snprintf(c.dir, dl + 1, "%s", path);
    unsigned flags = 0;
    if (opts) {
        sr_scene_builder_set_warning_callback(c.b, opts->warning, opts->warning_user);
        flags = opts->flags;
        sr_scene_builder_set_max_triangles(c.b, opts->max_triangles);
    }
    st = parse_scene(&c, root);
    if (st == SLUICE_OK)
        st = sr_scene_builder_finish(c.b, flags, out, err, err_size);
    sr_scene_builder_destroy(c.b);
    free(c.dir);
    cJSON_Delete(root);
    return st;
}
