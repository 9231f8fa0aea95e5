/* The scene model: the builder that collects and validates meshes,
 * materials, lights and a camera, and the immutable scene it produces with
 * its area-light table and statistics. Loaders (scene_mesh.c, scene_json.c,
 * scene_builtin.c) and shapes (scene_shapes.c) all go through the builder. */
#include "scene.h"
#include "app_error.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Warnings kept as text; the rest are only counted. */
#define WARNINGS_KEPT 32

/* A triangle is degenerate when twice its area is at most this fraction of
 * its longest edge squared: a needle thinner than float precision (2^-23 is
 * about 1.2e-7) along its length, or two equal corners. Such triangles have
 * no well-defined normal and make Moller-Trumbore's determinant vanish. */
#define DEGENERATE_REL 1e-7

/* Vertex and triangle indices are uint32 (Purcell ch. 4.2 stores them in
 * textures; here in uint32 buffers); UINT32_MAX stays free as a marker. */
#define MAX_ELEMENTS ((size_t)UINT32_MAX - 1u)

static const double PI = 3.14159265358979323846;

struct sr_scene_builder {
    char *source;
    float *positions, *normals;                    /* normals: NULL until a mesh has them */
    size_t vertex_count, position_cap, normal_cap; /* capacities in floats */
    uint32_t *indices, *tri_materials;
    size_t triangle_count, index_cap, tri_material_cap; /* capacities in uint32 */
    sr_material *materials;
    size_t material_count, material_cap;
    sr_point_light *lights;
    size_t light_count, light_cap;
    sr_camera camera;
    int has_camera;
    sr_render_settings render;
    size_t degenerate;
    char *warnings; /* newline-separated */
    size_t warnings_len, warning_count;
    sr_scene_warning_fn warn_fn;
    void *warn_user;
    size_t max_triangles; /* the caller's limit; 0: MAX_ELEMENTS */
    int finished;
};

struct sr_scene {
    char *source;
    float *positions, *normals;
    size_t vertex_count;
    uint32_t *indices, *tri_materials;
    size_t triangle_count;
    sr_material *materials;
    size_t material_count;
    sr_point_light *lights;
    size_t light_count;
    uint32_t *emissive;
    float *emissive_area, *emissive_cdf;
    size_t emissive_count;
    double emissive_total_area, emissive_power[3];
    sr_camera camera;
    sr_render_settings render;
    sr_scene_stats stats;
    char *warnings;
};

static const char *src_name(const char *s)
{
    return s && *s ? s : "mesh";
}

static char *dup_str(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

/* Makes room for `need` elements of `size` bytes (doubling), without
 * changing anything on failure. */
static int reserve(void **p, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap)
        return 1;
    size_t n = *cap ? *cap : 16;
    while (n < need)
        n = n > SIZE_MAX / 2 ? need : n * 2;
    if (n > SIZE_MAX / size)
        return 0;
    void *q = realloc(*p, n * size);
    if (!q)
        return 0;
    *p = q;
    *cap = n;
    return 1;
}

/* ------------------------------------------------------------------ */
/* Materials, modes, settings                                          */
/* ------------------------------------------------------------------ */

static const char *const kind_names[SR_MATERIAL_KIND_COUNT] = {"diffuse", "mirror", "glass",
                                                               "glossy", "emissive"};

const char *sr_material_kind_name(sr_material_kind kind)
{
    return (unsigned)kind < SR_MATERIAL_KIND_COUNT ? kind_names[kind] : "?";
}

sluice_status sr_material_kind_parse(const char *name, sr_material_kind *kind)
{
    if (!name || !kind)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    for (int k = 0; k < SR_MATERIAL_KIND_COUNT; ++k) {
        if (strcmp(name, kind_names[k]) == 0) {
            *kind = (sr_material_kind)k;
            return SLUICE_OK;
        }
    }
    return SLUICE_ERROR_NOT_FOUND;
}

static void set3(float *d, float x, float y, float z)
{
    d[0] = x;
    d[1] = y;
    d[2] = z;
}

sr_material sr_material_make(sr_material_kind kind, const char *name)
{
    sr_material m;
    memset(&m, 0, sizeof m);
    m.kind = kind;
    set3(m.albedo, 0.8f, 0.8f, 0.8f);
    set3(m.specular, 0.0f, 0.0f, 0.0f);
    m.exponent = 50.0f;
    m.ior = 1.5f;
    switch (kind) {
    case SR_MATERIAL_MIRROR:
    case SR_MATERIAL_GLASS:
        set3(m.specular, 1.0f, 1.0f, 1.0f);
        break;
    case SR_MATERIAL_GLOSSY:
        set3(m.albedo, 0.6f, 0.6f, 0.6f);
        set3(m.specular, 0.2f, 0.2f, 0.2f);
        break;
    case SR_MATERIAL_EMISSIVE:
        set3(m.albedo, 0.0f, 0.0f, 0.0f);
        set3(m.emission, 1.0f, 1.0f, 1.0f);
        break;
    default:
        break;
    }
    if (name)
        snprintf(m.name, sizeof m.name, "%s", name);
    return m;
}

int sr_material_is_emissive(const sr_material *m)
{
    return m && (m->emission[0] > 0.0f || m->emission[1] > 0.0f || m->emission[2] > 0.0f);
}

static const char *const mode_names[] = {"auto", "cast", "shadow", "whitted", "path", "photon"};
#define MODE_COUNT (sizeof mode_names / sizeof mode_names[0])

const char *sr_render_mode_name(sr_render_mode mode)
{
    return (unsigned)mode < MODE_COUNT ? mode_names[mode] : "?";
}

sluice_status sr_render_mode_parse(const char *name, sr_render_mode *mode)
{
    if (!name || !mode)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    for (size_t k = 0; k < MODE_COUNT; ++k) {
        if (strcmp(name, mode_names[k]) == 0) {
            *mode = (sr_render_mode)k;
            return SLUICE_OK;
        }
    }
    return SLUICE_ERROR_NOT_FOUND;
}

sr_render_settings sr_render_settings_default(void)
{
    sr_render_settings r;
    memset(&r, 0, sizeof r);
    r.samples_per_pixel = 1;
    r.max_depth = 5;
    r.light_samples = 1;
    r.mode = SR_RENDER_AUTO;
    return r;
}

/* ------------------------------------------------------------------ */
/* Builder                                                             */
/* ------------------------------------------------------------------ */

sluice_status sr_scene_builder_create(const char *source, sr_scene_builder **out)
{
    if (!out)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    sr_scene_builder *b = calloc(1, sizeof *b);
    if (!b)
        return SLUICE_ERROR_OUT_OF_MEMORY;
    b->source = dup_str(source ? source : "scene");
    if (!b->source) {
        free(b);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    b->render = sr_render_settings_default();
    *out = b;
    return SLUICE_OK;
}

void sr_scene_builder_set_max_triangles(sr_scene_builder *b, size_t max_triangles)
{
    if (b)
        b->max_triangles = max_triangles;
}

void sr_scene_builder_destroy(sr_scene_builder *b)
{
    if (!b)
        return;
    free(b->source);
    free(b->positions);
    free(b->normals);
    free(b->indices);
    free(b->tri_materials);
    free(b->materials);
    free(b->lights);
    free(b->warnings);
    free(b);
}

void sr_scene_builder_set_warning_callback(sr_scene_builder *b, sr_scene_warning_fn fn, void *user)
{
    if (!b)
        return;
    b->warn_fn = fn;
    b->warn_user = user;
}

/* Appends a line to the kept warnings; silently keeps fewer lines when memory
 * is short (a warning must never fail the build). */
static void keep_warning(sr_scene_builder *b, const char *msg)
{
    size_t n = strlen(msg);
    char *w = realloc(b->warnings, b->warnings_len + n + 2);
    if (!w)
        return;
    b->warnings = w;
    memcpy(w + b->warnings_len, msg, n);
    w[b->warnings_len + n] = '\n';
    w[b->warnings_len + n + 1] = '\0';
    b->warnings_len += n + 1;
}

void sr_scene_builder_warn(sr_scene_builder *b, const char *fmt, ...)
{
    if (!b || !fmt)
        return;
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    b->warning_count++;
    if (b->warning_count <= WARNINGS_KEPT)
        keep_warning(b, msg);
    if (b->warn_fn)
        b->warn_fn(b->warn_user, msg);
}

static int finite3(const float *v)
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static int nonneg3(const float *v)
{
    return v[0] >= 0.0f && v[1] >= 0.0f && v[2] >= 0.0f;
}

/* Checks one colour field of a material: finite and not negative. */
static int check_color(const sr_scene_builder *b, const sr_material *m, const char *field,
                       const float *v, char *err, size_t err_size)
{
    if (!finite3(v) || !nonneg3(v)) {
        sr_set_error(err, err_size, "%s: material '%s': %s (%g, %g, %g) must be finite and >= 0",
                     b->source, m->name, field, v[0], v[1], v[2]);
        return 0;
    }
    return 1;
}

sluice_status sr_scene_builder_add_material(sr_scene_builder *b, const sr_material *m,
                                            uint32_t *index, char *err, size_t err_size)
{
    if (!b || !m || b->finished) {
        sr_set_error(err, err_size, "add_material: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if ((unsigned)m->kind >= SR_MATERIAL_KIND_COUNT) {
        sr_set_error(err, err_size, "%s: material '%.*s': unknown kind %d", b->source,
                     SR_MATERIAL_NAME_SIZE, m->name, (int)m->kind);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sr_material c = *m;
    c.name[SR_MATERIAL_NAME_SIZE - 1] = '\0';
    if (!check_color(b, &c, "albedo", c.albedo, err, err_size) ||
        !check_color(b, &c, "specular", c.specular, err, err_size) ||
        !check_color(b, &c, "emission", c.emission, err, err_size))
        return SLUICE_ERROR_INVALID_ARGUMENT;
    if (!isfinite(c.exponent) || c.exponent < 0.0f) {
        sr_set_error(err, err_size, "%s: material '%s': exponent %g must be finite and >= 0",
                     b->source, c.name, c.exponent);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (!isfinite(c.ior) || c.ior <= 0.0f) {
        sr_set_error(err, err_size, "%s: material '%s': ior %g must be finite and > 0", b->source,
                     c.name, c.ior);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (c.kind == SR_MATERIAL_EMISSIVE && !sr_material_is_emissive(&c)) {
        sr_set_error(err, err_size, "%s: material '%s': kind emissive needs a non-zero emission",
                     b->source, c.name);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (b->material_count >= MAX_ELEMENTS) {
        sr_set_error(err, err_size, "%s: too many materials", b->source);
        return SLUICE_ERROR_LIMIT;
    }
    if (!reserve((void **)&b->materials, &b->material_cap, b->material_count + 1,
                 sizeof *b->materials)) {
        sr_set_error(err, err_size, "%s: out of memory", b->source);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    if (c.kind == SR_MATERIAL_GLOSSY) {
        for (int k = 0; k < 3; ++k) {
            if (c.albedo[k] + c.specular[k] > 1.0f) {
                sr_scene_builder_warn(b,
                                      "%s: material '%s': glossy kd + ks = %g > 1 in channel "
                                      "%d: not energy conserving (Jakob 2.4.1)",
                                      b->source, c.name, c.albedo[k] + c.specular[k], k);
                break;
            }
        }
    }
    b->materials[b->material_count] = c;
    if (index)
        *index = (uint32_t)b->material_count;
    b->material_count++;
    return SLUICE_OK;
}

sluice_status sr_scene_builder_find_material(const sr_scene_builder *b, const char *name,
                                             uint32_t *index)
{
    if (!b || !name)
        return SLUICE_ERROR_INVALID_ARGUMENT;
    for (size_t i = 0; i < b->material_count; ++i) {
        if (strcmp(b->materials[i].name, name) == 0) {
            if (index)
                *index = (uint32_t)i;
            return SLUICE_OK;
        }
    }
    return SLUICE_ERROR_NOT_FOUND;
}

size_t sr_scene_builder_material_count(const sr_scene_builder *b)
{
    return b ? b->material_count : 0;
}

size_t sr_scene_builder_triangle_count(const sr_scene_builder *b)
{
    return b ? b->triangle_count : 0;
}

/* The transform's linear part, translation, and cofactor matrix (the inverse
 * transpose times the determinant), all in double. */
typedef struct xform {
    double a[3][3], t[3], cof[3][3], det;
    int identity;
} xform;

static sluice_status make_xform(const sr_scene_builder *b, const char *src, const float *m,
                                xform *x, char *err, size_t err_size)
{
    memset(x, 0, sizeof *x);
    if (!m) {
        x->identity = 1;
        for (int i = 0; i < 3; ++i)
            x->a[i][i] = x->cof[i][i] = 1.0;
        x->det = 1.0;
        return SLUICE_OK;
    }
    for (int i = 0; i < 16; ++i) {
        if (!isfinite(m[i])) {
            sr_set_error(err, err_size, "%s: %s: transform element %d is not finite", b->source,
                         src, i);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
    }
    if (m[12] != 0.0f || m[13] != 0.0f || m[14] != 0.0f || m[15] != 1.0f) {
        sr_set_error(err, err_size, "%s: %s: transform is not affine (last row must be 0 0 0 1)",
                     b->source, src);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    double norm = 0.0;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            x->a[r][c] = m[r * 4 + c];
            norm = fmax(norm, fabs(x->a[r][c]));
        }
        x->t[r] = m[r * 4 + 3];
    }
    const double(*a)[3] = x->a;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            x->cof[r][c] = a[r1][c1] * a[r2][c2] - a[r1][c2] * a[r2][c1];
        }
    }
    x->det = a[0][0] * x->cof[0][0] + a[0][1] * x->cof[0][1] + a[0][2] * x->cof[0][2];
    if (!(fabs(x->det) > 1e-12 * norm * norm * norm)) {
        sr_set_error(err, err_size, "%s: %s: transform is singular (determinant %g)", b->source,
                     src, x->det);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    return SLUICE_OK;
}

static const char *nonfinite_name(float v)
{
    return isnan(v) ? "NaN" : "infinite";
}

/* Twice the area of a triangle compared with its longest edge (see
 * DEGENERATE_REL). */
static int is_degenerate(const float *p0, const float *p1, const float *p2)
{
    double e1[3], e2[3], e3[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = (double)p1[k] - p0[k];
        e2[k] = (double)p2[k] - p0[k];
        e3[k] = (double)p2[k] - p1[k];
    }
    double cx = e1[1] * e2[2] - e1[2] * e2[1];
    double cy = e1[2] * e2[0] - e1[0] * e2[2];
    double cz = e1[0] * e2[1] - e1[1] * e2[0];
    double c = sqrt(cx * cx + cy * cy + cz * cz);
    double l1 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
    double l2 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    double l3 = e3[0] * e3[0] + e3[1] * e3[1] + e3[2] * e3[2];
    double l = fmax(l1, fmax(l2, l3));
    return !(c > DEGENERATE_REL * l);
}

sluice_status sr_scene_builder_add_mesh(sr_scene_builder *b, const sr_mesh_desc *mesh, char *err,
                                        size_t err_size)
{
    if (!b || !mesh || b->finished || (mesh->vertex_count && !mesh->positions) ||
        (mesh->triangle_count && !mesh->indices)) {
        sr_set_error(err, err_size, "add_mesh: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    const char *src = src_name(mesh->source);
    size_t nv = mesh->vertex_count, nt = mesh->triangle_count;
    if (nv > MAX_ELEMENTS || nt > MAX_ELEMENTS || b->vertex_count + nv > MAX_ELEMENTS ||
        b->triangle_count + nt > MAX_ELEMENTS) {
        sr_set_error(err, err_size, "%s: %s: the scene would exceed %zu vertices or triangles",
                     b->source, src, MAX_ELEMENTS);
        return SLUICE_ERROR_LIMIT;
    }
    if (b->max_triangles && b->triangle_count + nt > b->max_triangles) {
        sr_set_error(err, err_size, "%s: %s: the scene would exceed the limit of %zu triangles",
                     b->source, src, b->max_triangles);
        return SLUICE_ERROR_LIMIT;
    }
    /* 1. inputs: finite positions and normals, indices and materials in range */
    for (size_t i = 0; i < nv; ++i) {
        const float *p = mesh->positions + 3 * i;
        for (int k = 0; k < 3; ++k) {
            if (!isfinite(p[k])) {
                sr_set_error(err, err_size, "%s: vertex %zu: coordinate %c is %s (%g, %g, %g)", src,
                             i, "xyz"[k], nonfinite_name(p[k]), p[0], p[1], p[2]);
                return SLUICE_ERROR_INVALID_ARGUMENT;
            }
        }
        if (mesh->normals && !finite3(mesh->normals + 3 * i)) {
            sr_set_error(err, err_size, "%s: vertex %zu: normal is not finite", src, i);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
    }
    for (size_t t = 0; t < nt; ++t) {
        for (int k = 0; k < 3; ++k) {
            if (mesh->indices[3 * t + k] >= nv) {
                sr_set_error(err, err_size,
                             "%s: triangle %zu: vertex index %u out of range (%zu vertices)", src,
                             t, mesh->indices[3 * t + k], nv);
                return SLUICE_ERROR_INVALID_ARGUMENT;
            }
        }
        uint32_t mat = mesh->materials ? mesh->materials[t] : mesh->material;
        if (mat >= b->material_count) {
            sr_set_error(err, err_size,
                         "%s: triangle %zu: material %u out of range (%zu materials)", src, t, mat,
                         b->material_count);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
    }
    xform x;
    sluice_status st = make_xform(b, src, mesh->transform, &x, err, err_size);
    if (st != SLUICE_OK)
        return st;

    /* 2. transform into scratch, find degenerate triangles and used vertices */
    float *tp = NULL;
    uint32_t *remap = malloc((nv ? nv : 1) * sizeof *remap);
    unsigned char *keep = malloc(nt ? nt : 1);
    if (!x.identity)
        tp = malloc((nv ? nv : 1) * 3 * sizeof *tp);
    if (!remap || !keep || (!x.identity && !tp)) {
        free(remap);
        free(keep);
        free(tp);
        sr_set_error(err, err_size, "%s: %s: out of memory", b->source, src);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    const float *pos = mesh->positions;
    if (!x.identity) {
        for (size_t i = 0; i < nv; ++i) {
            const float *p = mesh->positions + 3 * i;
            int ok = 1;
            for (int r = 0; r < 3; ++r) {
                double v = x.a[r][0] * p[0] + x.a[r][1] * p[1] + x.a[r][2] * p[2] + x.t[r];
                /* converting a double beyond float's range is undefined */
                ok &= fabs(v) <= FLT_MAX;
                tp[3 * i + r] = ok ? (float)v : 0.0f;
            }
            if (!ok) {
                sr_set_error(err, err_size,
                             "%s: vertex %zu: transformed position overflows a float", src, i);
                free(remap);
                free(keep);
                free(tp);
                return SLUICE_ERROR_INVALID_ARGUMENT;
            }
        }
        pos = tp;
    }
    for (size_t i = 0; i < nv; ++i)
        remap[i] = UINT32_MAX;
    size_t kept_t = 0, kept_v = 0, first_bad = 0, dropped = 0;
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t *ix = mesh->indices + 3 * t;
        keep[t] = !is_degenerate(pos + 3 * ix[0], pos + 3 * ix[1], pos + 3 * ix[2]);
        if (!keep[t]) {
            if (!dropped++)
                first_bad = t;
            continue;
        }
        kept_t++;
        for (int k = 0; k < 3; ++k) {
            if (remap[ix[k]] == UINT32_MAX)
                remap[ix[k]] = (uint32_t)(b->vertex_count + kept_v++);
        }
    }

    /* 3. make room for everything, then append (nothing can fail after this) */
    int need_normals = mesh->normals != NULL || b->normals != NULL;
    size_t nvf = 3 * (b->vertex_count + kept_v);
    int ok = reserve((void **)&b->positions, &b->position_cap, nvf, sizeof(float));
    if (ok && need_normals) {
        int fresh = b->normals == NULL;
        ok = reserve((void **)&b->normals, &b->normal_cap, nvf, sizeof(float));
        /* earlier meshes had no normals: zero means "none". With nothing
         * kept yet (a first mesh of degenerate triangles only) reserve had
         * nothing to allocate and b->normals is still NULL. */
        if (ok && fresh && b->normals)
            memset(b->normals, 0, 3 * b->vertex_count * sizeof(float));
    }
    ok = ok && reserve((void **)&b->indices, &b->index_cap, 3 * (b->triangle_count + kept_t),
                       sizeof(uint32_t));
    ok = ok && reserve((void **)&b->tri_materials, &b->tri_material_cap, b->triangle_count + kept_t,
                       sizeof(uint32_t));
    if (!ok) {
        free(remap);
        free(keep);
        free(tp);
        sr_set_error(err, err_size, "%s: %s: out of memory", b->source, src);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < nv; ++i) {
        if (remap[i] == UINT32_MAX)
            continue;
        float *dp = b->positions + 3 * (size_t)remap[i];
        memcpy(dp, pos + 3 * i, 3 * sizeof(float));
        if (!need_normals)
            continue;
        float *dn = b->normals + 3 * (size_t)remap[i];
        set3(dn, 0.0f, 0.0f, 0.0f);
        if (!mesh->normals)
            continue;
        const float *n = mesh->normals + 3 * i;
        double v[3];
        for (int r = 0; r < 3; ++r)
            v[r] = x.cof[r][0] * n[0] + x.cof[r][1] * n[1] + x.cof[r][2] * n[2];
        double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (len > 0.0 && isfinite(len)) {
            double s = (x.det < 0.0 ? -1.0 : 1.0) / len;
            set3(dn, (float)(v[0] * s), (float)(v[1] * s), (float)(v[2] * s));
        }
    }
    /* A mirroring transform turns counter-clockwise into clockwise: swap two
     * corners so the front side (and a one-sided emitter) stays in front. */
    int flip = x.det < 0.0;
    size_t o = b->triangle_count;
    for (size_t t = 0; t < nt; ++t) {
        if (!keep[t])
            continue;
        const uint32_t *ix = mesh->indices + 3 * t;
        b->indices[3 * o + 0] = remap[ix[0]];
        b->indices[3 * o + 1] = remap[ix[flip ? 2 : 1]];
        b->indices[3 * o + 2] = remap[ix[flip ? 1 : 2]];
        b->tri_materials[o] = mesh->materials ? mesh->materials[t] : mesh->material;
        o++;
    }
    b->vertex_count += kept_v;
    b->triangle_count += kept_t;
    free(remap);
    free(keep);
    free(tp);
    if (dropped) {
        b->degenerate += dropped;
        sr_scene_builder_warn(b,
                              "%s: dropped %zu degenerate (zero-area) triangle%s of %zu "
                              "(first: triangle %zu)",
                              src, dropped, dropped == 1 ? "" : "s", nt, first_bad);
    }
    return SLUICE_OK;
}

sluice_status sr_scene_builder_add_point_light(sr_scene_builder *b, const sr_point_light *light,
                                               char *err, size_t err_size)
{
    if (!b || !light || b->finished) {
        sr_set_error(err, err_size, "add_point_light: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (!finite3(light->position)) {
        sr_set_error(err, err_size, "%s: point light %zu: position is not finite", b->source,
                     b->light_count);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (!finite3(light->intensity) || !nonneg3(light->intensity)) {
        sr_set_error(err, err_size, "%s: point light %zu: intensity must be finite and >= 0",
                     b->source, b->light_count);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (!reserve((void **)&b->lights, &b->light_cap, b->light_count + 1, sizeof *b->lights)) {
        sr_set_error(err, err_size, "%s: out of memory", b->source);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    b->lights[b->light_count++] = *light;
    return SLUICE_OK;
}

sluice_status sr_scene_builder_set_camera(sr_scene_builder *b, const sr_camera *c, char *err,
                                          size_t err_size)
{
    if (!b || !c || b->finished) {
        sr_set_error(err, err_size, "set_camera: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (c->width == 0 || c->height == 0 || c->width > SR_SCENE_MAX_IMAGE_SIDE ||
        c->height > SR_SCENE_MAX_IMAGE_SIDE) {
        sr_set_error(err, err_size, "%s: camera: image size %ux%u is out of range (1..%u per side)",
                     b->source, c->width, c->height, SR_SCENE_MAX_IMAGE_SIDE);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (!finite3(c->eye) || !finite3(c->look_at) || !finite3(c->up)) {
        sr_set_error(err, err_size, "%s: camera: eye, look_at and up must be finite", b->source);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (!(c->vfov > 0.0f && c->vfov < 180.0f)) {
        sr_set_error(err, err_size,
                     "%s: camera: vfov %g is out of range (0..180 degrees, exclusive)", b->source,
                     c->vfov);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    double d[3], u[3];
    for (int k = 0; k < 3; ++k) {
        d[k] = (double)c->look_at[k] - c->eye[k];
        u[k] = c->up[k];
    }
    double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(dl > 0.0)) {
        sr_set_error(err, err_size, "%s: camera: eye and look_at are the same point", b->source);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    double cx = d[1] * u[2] - d[2] * u[1], cy = d[2] * u[0] - d[0] * u[2],
           cz = d[0] * u[1] - d[1] * u[0];
    if (!(ul > 0.0) || !(sqrt(cx * cx + cy * cy + cz * cz) > 1e-6 * dl * ul)) {
        sr_set_error(err, err_size, "%s: camera: up is zero or parallel to the view direction",
                     b->source);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    b->camera = *c;
    b->has_camera = 1;
    return SLUICE_OK;
}

sluice_status sr_scene_builder_set_render_settings(sr_scene_builder *b, const sr_render_settings *s,
                                                   char *err, size_t err_size)
{
    if (!b || !s || b->finished) {
        sr_set_error(err, err_size, "set_render_settings: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (s->samples_per_pixel == 0 || s->light_samples == 0) {
        sr_set_error(err, err_size, "%s: render: samples_per_pixel and light_samples must be >= 1",
                     b->source);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if ((unsigned)s->mode >= MODE_COUNT) {
        sr_set_error(err, err_size, "%s: render: unknown mode %d", b->source, (int)s->mode);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    b->render = *s;
    return SLUICE_OK;
}

/* ------------------------------------------------------------------ */
/* Finishing                                                           */
/* ------------------------------------------------------------------ */

static double tri_area(const float *pos, const uint32_t *ix)
{
    const float *p0 = pos + 3 * (size_t)ix[0], *p1 = pos + 3 * (size_t)ix[1],
                *p2 = pos + 3 * (size_t)ix[2];
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = (double)p1[k] - p0[k];
        e2[k] = (double)p2[k] - p0[k];
    }
    double cx = e1[1] * e2[2] - e1[2] * e2[1];
    double cy = e1[2] * e2[0] - e1[0] * e2[2];
    double cz = e1[0] * e2[1] - e1[1] * e2[0];
    return 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
}

static void unit(double *v)
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; ++k)
        v[k] /= l;
}

sluice_status sr_scene_builder_finish(sr_scene_builder *b, unsigned flags, sr_scene **out,
                                      char *err, size_t err_size)
{
    if (!out) {
        sr_set_error(err, err_size, "finish: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    *out = NULL;
    if (!b || b->finished) {
        sr_set_error(err, err_size, "finish: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (b->triangle_count == 0) {
        sr_set_error(err, err_size, "%s: the scene is empty (no triangles%s)", b->source,
                     b->degenerate ? " left after dropping degenerate ones" : "");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    /* Emissive triangles, counted first: whether a default light is needed
     * depends on them. */
    size_t ne = 0;
    for (size_t t = 0; t < b->triangle_count; ++t)
        ne += sr_material_is_emissive(&b->materials[b->tri_materials[t]]) != 0;
    int add_light = b->light_count == 0 && ne == 0 && (flags & SR_SCENE_DEFAULT_LIGHT);
    if (b->light_count == 0 && ne == 0 && !add_light && !(flags & SR_SCENE_ALLOW_NO_LIGHT)) {
        sr_set_error(err, err_size,
                     "%s: the scene has no light (no point light and no emissive material)",
                     b->source);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }

    sr_scene *s = calloc(1, sizeof *s);
    if (!s) {
        sr_set_error(err, err_size, "%s: out of memory", b->source);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    s->emissive = malloc((ne ? ne : 1) * sizeof *s->emissive);
    s->emissive_area = malloc((ne ? ne : 1) * sizeof *s->emissive_area);
    s->emissive_cdf = malloc((ne ? ne : 1) * sizeof *s->emissive_cdf);
    s->warnings = NULL;
    int ok = s->emissive && s->emissive_area && s->emissive_cdf;
    if (ok && add_light)
        ok = reserve((void **)&b->lights, &b->light_cap, b->light_count + 1, sizeof *b->lights);
    if (!ok) {
        free(s->emissive);
        free(s->emissive_area);
        free(s->emissive_cdf);
        free(s);
        sr_set_error(err, err_size, "%s: out of memory", b->source);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }

    /* Bounds and per-kind statistics. */
    sr_scene_stats *st = &s->stats;
    for (int k = 0; k < 3; ++k) {
        st->bounds_min[k] = INFINITY;
        st->bounds_max[k] = -INFINITY;
    }
    for (size_t i = 0; i < b->vertex_count; ++i) {
        for (int k = 0; k < 3; ++k) {
            float v = b->positions[3 * i + k];
            st->bounds_min[k] = v < st->bounds_min[k] ? v : st->bounds_min[k];
            st->bounds_max[k] = v > st->bounds_max[k] ? v : st->bounds_max[k];
        }
    }
    double sum = 0.0;
    size_t e = 0;
    for (size_t t = 0; t < b->triangle_count; ++t) {
        const sr_material *m = &b->materials[b->tri_materials[t]];
        st->triangles_by_kind[m->kind]++;
        st->kinds_present |= SR_KIND_BIT(m->kind);
        if (!sr_material_is_emissive(m))
            continue;
        double a = tri_area(b->positions, b->indices + 3 * t);
        s->emissive[e] = (uint32_t)t;
        s->emissive_area[e] = (float)a;
        sum += a;
        s->emissive_cdf[e] = (float)sum;
        for (int k = 0; k < 3; ++k)
            s->emissive_power[k] += PI * m->emission[k] * a;
        e++;
    }
    for (size_t i = 0; i < ne; ++i)
        s->emissive_cdf[i] = sum > 0.0 ? (float)(s->emissive_cdf[i] / sum) : 1.0f;
    if (ne)
        s->emissive_cdf[ne - 1] = 1.0f;
    s->emissive_count = ne;
    s->emissive_total_area = sum;

    /* Defaults, from the bounds (see the header). */
    double c[3], r = 0.0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)st->bounds_min[k] + st->bounds_max[k]);
        double h = 0.5 * ((double)st->bounds_max[k] - st->bounds_min[k]);
        r += h * h;
    }
    r = sqrt(r);
    if (!(r > 0.0))
        r = 1.0;
    if (add_light) {
        double d[3] = {0.4, 1.0, 0.6};
        unit(d);
        sr_point_light l;
        for (int k = 0; k < 3; ++k) {
            l.position[k] = (float)(c[k] + 2.0 * r * d[k]);
            l.intensity[k] = (float)(4.0 * r * r);
        }
        b->lights[b->light_count++] = l;
        sr_scene_builder_warn(b, "%s: no light in the scene: added the default point light",
                              b->source);
    }
    if (!b->has_camera) {
        double d[3] = {0.0, 0.25, 1.0};
        unit(d);
        double dist = 1.1 * r / sin(20.0 * PI / 180.0);
        sr_camera cam;
        for (int k = 0; k < 3; ++k) {
            cam.eye[k] = (float)(c[k] + dist * d[k]);
            cam.look_at[k] = (float)c[k];
        }
        set3(cam.up, 0.0f, 1.0f, 0.0f);
        cam.vfov = 40.0f;
        cam.width = cam.height = 512;
        b->camera = cam;
    }

    /* Move the arrays; shrink them to size (a failed shrink keeps the
     * larger block, which is fine). */
    s->source = b->source;
    b->source = NULL;
    s->vertex_count = b->vertex_count;
    s->triangle_count = b->triangle_count;
    s->positions = b->positions;
    s->normals = b->normals;
    s->indices = b->indices;
    s->tri_materials = b->tri_materials;
    s->materials = b->materials;
    s->material_count = b->material_count;
    s->lights = b->lights;
    s->light_count = b->light_count;
    s->camera = b->camera;
    s->render = b->render;
    s->warnings = b->warnings;
    b->positions = b->normals = NULL;
    b->indices = b->tri_materials = NULL;
    b->materials = NULL;
    b->lights = NULL;
    b->warnings = NULL;
    b->finished = 1;
    float *fp = realloc(s->positions, 3 * s->vertex_count * sizeof(float));
    if (fp)
        s->positions = fp;
    if (s->normals) {
        fp = realloc(s->normals, 3 * s->vertex_count * sizeof(float));
        if (fp)
            s->normals = fp;
    }
    uint32_t *up = realloc(s->indices, 3 * s->triangle_count * sizeof(uint32_t));
    if (up)
        s->indices = up;
    up = realloc(s->tri_materials, s->triangle_count * sizeof(uint32_t));
    if (up)
        s->tri_materials = up;

    st->triangles = s->triangle_count;
    st->vertices = s->vertex_count;
    st->materials = s->material_count;
    st->point_lights = s->light_count;
    st->emissive_triangles = ne;
    st->emissive_area = sum;
    st->degenerate_dropped = b->degenerate;
    st->warnings = b->warning_count;
    st->has_normals = s->normals != NULL;
    if (b->warning_count > WARNINGS_KEPT) {
        char line[96];
        snprintf(line, sizeof line, "... and %zu more warnings", b->warning_count - WARNINGS_KEPT);
        b->warnings = s->warnings;
        keep_warning(b, line);
        s->warnings = b->warnings;
        b->warnings = NULL;
    }
    *out = s;
    return SLUICE_OK;
}

/* ------------------------------------------------------------------ */
/* Scene getters                                                       */
/* ------------------------------------------------------------------ */

void sr_scene_destroy(sr_scene *s)
{
    if (!s)
        return;
    free(s->source);
    free(s->positions);
    free(s->normals);
    free(s->indices);
    free(s->tri_materials);
    free(s->materials);
    free(s->lights);
    free(s->emissive);
    free(s->emissive_area);
    free(s->emissive_cdf);
    free(s->warnings);
    free(s);
}

const char *sr_scene_source(const sr_scene *s)
{
    return s ? s->source : NULL;
}

size_t sr_scene_vertex_count(const sr_scene *s)
{
    return s ? s->vertex_count : 0;
}

size_t sr_scene_triangle_count(const sr_scene *s)
{
    return s ? s->triangle_count : 0;
}

const float *sr_scene_positions(const sr_scene *s)
{
    return s ? s->positions : NULL;
}

const float *sr_scene_normals(const sr_scene *s)
{
    return s ? s->normals : NULL;
}

const uint32_t *sr_scene_indices(const sr_scene *s)
{
    return s ? s->indices : NULL;
}

const uint32_t *sr_scene_triangle_materials(const sr_scene *s)
{
    return s ? s->tri_materials : NULL;
}

size_t sr_scene_material_count(const sr_scene *s)
{
    return s ? s->material_count : 0;
}

const sr_material *sr_scene_materials(const sr_scene *s)
{
    return s ? s->materials : NULL;
}

size_t sr_scene_point_light_count(const sr_scene *s)
{
    return s ? s->light_count : 0;
}

const sr_point_light *sr_scene_point_lights(const sr_scene *s)
{
    return s ? s->lights : NULL;
}

size_t sr_scene_light_count(const sr_scene *s)
{
    return s ? s->light_count + s->emissive_count : 0;
}

void sr_scene_area_lights(const sr_scene *s, sr_area_lights *out)
{
    if (!out)
        return;
    memset(out, 0, sizeof *out);
    if (!s)
        return;
    out->count = s->emissive_count;
    out->triangles = s->emissive;
    out->area = s->emissive_area;
    out->area_cdf = s->emissive_cdf;
    out->total_area = s->emissive_total_area;
    for (int k = 0; k < 3; ++k)
        out->total_power[k] = s->emissive_power[k];
}

const sr_camera *sr_scene_camera(const sr_scene *s)
{
    return s ? &s->camera : NULL;
}

const sr_render_settings *sr_scene_render_settings(const sr_scene *s)
{
    return s ? &s->render : NULL;
}

const sr_scene_stats *sr_scene_statistics(const sr_scene *s)
{
    return s ? &s->stats : NULL;
}

const char *sr_scene_warnings(const sr_scene *s)
{
    return s && s->warnings ? s->warnings : "";
}
