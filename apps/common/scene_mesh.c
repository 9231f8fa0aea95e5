/* Mesh files through assimp's C API: OBJ with MTL, PLY, glTF 2 and whatever
 * else assimp reads, flattened into the builder's triangle arrays (the node
 * hierarchy's transforms applied, one copy of a mesh per node that uses it).
 *
 * Positions are checked for NaN and infinity before assimp joins identical
 * vertices: the join compares positions, and a NaN compares unequal to
 * everything, so checking afterwards could report a vertex that no longer
 * matches the file's face order, or none at all. */
#include "scene.h"
#include "app_error.h"
#include "scene_mesh_guard.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Deeper node hierarchies are refused rather than recursed into. */
#define MAX_NODE_DEPTH 256

/* Nodes visited per file: a hierarchy that names one child node several
 * times is a graph whose walk can take 2^depth steps. */
#define MAX_NODE_VISITS (1u << 20)

/* State of one file being added. */
typedef struct mesh_file {
    sr_scene_builder *b;
    const struct aiScene *scene;
    const char *label;
    const uint32_t *override; /* material for everything, or NULL */
    uint32_t *material_map;   /* assimp material -> builder index, UINT32_MAX: not yet */
    size_t nodes;             /* nodes visited */
    size_t triangles;         /* triangles added, every instance counted */
    char *err;
    size_t err_size;
} mesh_file;

static float max3(const float *v)
{
    return fmaxf(v[0], fmaxf(v[1], v[2]));
}

static void get_color(const struct aiMaterial *am, const char *key, unsigned type, unsigned index,
                      float *out, float dflt)
{
    struct aiColor4D c;
    if (aiGetMaterialColor(am, key, type, index, &c) == aiReturn_SUCCESS) {
        out[0] = c.r;
        out[1] = c.g;
        out[2] = c.b;
    } else {
        out[0] = out[1] = out[2] = dflt;
    }
}

static float get_float(const struct aiMaterial *am, const char *key, unsigned type, unsigned index,
                       float dflt)
{
    ai_real v;
    unsigned max = 1;
    if (aiGetMaterialFloatArray(am, key, type, index, &v, &max) == aiReturn_SUCCESS && max == 1)
        return (float)v;
    return dflt;
}

/* Maps an assimp material (OBJ/MTL terms in the comments) to ours; the rules
 * are listed at sr_scene_builder_add_mesh_file. */
static sr_material map_material(sr_scene_builder *b, const char *label, const struct aiMaterial *am)
{
    struct aiString name;
    name.length = 0;
    name.data[0] = '\0';
    aiGetMaterialString(am, AI_MATKEY_NAME, &name);
    sr_material m = sr_material_make(SR_MATERIAL_DIFFUSE, name.data);
    float kd[3], ks[3], ke[3], tf[3];
    get_color(am, AI_MATKEY_COLOR_DIFFUSE, kd, 0.8f);
    get_color(am, AI_MATKEY_COLOR_SPECULAR, ks, 0.0f);
    get_color(am, AI_MATKEY_COLOR_EMISSIVE, ke, 0.0f);
    get_color(am, AI_MATKEY_COLOR_TRANSPARENT, tf, 1.0f); /* MTL Tf */
    float ns = get_float(am, AI_MATKEY_SHININESS, 0.0f);
    float ni = get_float(am, AI_MATKEY_REFRACTI, 1.5f);
    int illum = -1;
    unsigned max = 1;
    /* assimp 5.2's OBJ importer keeps MTL's illum as "$mat.illum" (its
     * $mat.shadingm only distinguishes flat, Gouraud and Phong). */
    if (aiGetMaterialIntegerArray(am, "$mat.illum", 0, 0, &illum, &max) != aiReturn_SUCCESS)
        illum = -1;
    memcpy(m.albedo, kd, sizeof kd);
    memcpy(m.specular, ks, sizeof ks);
    m.exponent = ns > 0.0f ? ns : 0.0f;
    m.ior = ni > 0.0f ? ni : 1.5f;
    int black_ks = !(max3(ks) > 0.0f);
    switch (illum) {
    case -1: /* not an OBJ: glossy when it has a specular lobe */
        m.kind = !black_ks && ns > 0.0f ? SR_MATERIAL_GLOSSY : SR_MATERIAL_DIFFUSE;
        break;
    case 0:
    case 1:
    case 10:
        m.kind = SR_MATERIAL_DIFFUSE;
        break;
    case 2:
        m.kind = black_ks ? SR_MATERIAL_DIFFUSE : SR_MATERIAL_GLOSSY;
        break;
    case 3:
    case 5:
    case 8:
        m.kind = SR_MATERIAL_MIRROR;
        if (black_ks)
            m.specular[0] = m.specular[1] = m.specular[2] = 1.0f;
        break;
    case 4:
    case 6:
    case 7:
    case 9:
        m.kind = SR_MATERIAL_GLASS;
        memcpy(m.specular, tf, sizeof tf);
        if (ni == 1.0f)
            sr_scene_builder_warn(b,
                                  "%s: material '%s': glass with index of refraction 1 "
                                  "refracts nothing (Ni missing?)",
                                  label, m.name);
        break;
    default:
        m.kind = SR_MATERIAL_DIFFUSE;
        sr_scene_builder_warn(b, "%s: material '%s': unknown illum %d, taken as diffuse", label,
                              m.name, illum);
        break;
    }
    if (max3(ke) > 0.0f) {
        m.kind = SR_MATERIAL_EMISSIVE;
        memcpy(m.emission, ke, sizeof ke);
    }
    return m;
}

static sluice_status material_for(mesh_file *f, unsigned ai_index, uint32_t *out)
{
    if (f->override) {
        *out = *f->override;
        return SLUICE_OK;
    }
    if (ai_index >= f->scene->mNumMaterials) {
        sr_set_error(f->err, f->err_size, "%s: material index %u out of range", f->label, ai_index);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (f->material_map[ai_index] == UINT32_MAX) {
        sr_material m = map_material(f->b, f->label, f->scene->mMaterials[ai_index]);
        sluice_status st = sr_scene_builder_add_material(f->b, &m, &f->material_map[ai_index],
                                                         f->err, f->err_size);
        if (st != SLUICE_OK)
            return st;
    }
    *out = f->material_map[ai_index];
    return SLUICE_OK;
}

/* Row-major product c = a b of 4x4 matrices. */
static void mat_mul(const double *a, const double *b, double *c)
{
    for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k)
            c[r * 4 + k] = a[r * 4] * b[k] + a[r * 4 + 1] * b[4 + k] + a[r * 4 + 2] * b[8 + k] +
                           a[r * 4 + 3] * b[12 + k];
}

static sluice_status add_one_mesh(mesh_file *f, unsigned mi, const double *xf)
{
    const struct aiMesh *am = f->scene->mMeshes[mi];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) || am->mNumFaces == 0)
        return SLUICE_OK; /* points and lines only */
    size_t nv = am->mNumVertices, nt = 0;
    for (unsigned i = 0; i < am->mNumFaces; ++i)
        nt += am->mFaces[i].mNumIndices == 3;
    /* a mesh used by many nodes is copied for each: bound the copies too */
    f->triangles += nt;
    if (f->triangles > SR_MESH_MAX_TRIANGLES) {
        sr_set_error(f->err, f->err_size,
                     "%s: more than %u triangles once the node hierarchy's instances are "
                     "counted (the limit for a mesh file)",
                     f->label, SR_MESH_MAX_TRIANGLES);
        return SLUICE_ERROR_LIMIT;
    }
    float *pos = malloc((nv ? nv : 1) * 3 * sizeof *pos);
    float *nrm = am->mNormals ? malloc((nv ? nv : 1) * 3 * sizeof *nrm) : NULL;
    uint32_t *idx = malloc((nt ? nt : 1) * 3 * sizeof *idx);
    if (!pos || !idx || (am->mNormals && !nrm)) {
        free(pos);
        free(nrm);
        free(idx);
        sr_set_error(f->err, f->err_size, "%s: out of memory", f->label);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < nv; ++i) {
        pos[3 * i + 0] = (float)am->mVertices[i].x;
        pos[3 * i + 1] = (float)am->mVertices[i].y;
        pos[3 * i + 2] = (float)am->mVertices[i].z;
        if (nrm) {
            /* assimp marks missing normals (points, lines) with NaN */
            float n[3] = {(float)am->mNormals[i].x, (float)am->mNormals[i].y,
                          (float)am->mNormals[i].z};
            int ok = isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2]);
            for (int k = 0; k < 3; ++k)
                nrm[3 * i + k] = ok ? n[k] : 0.0f;
        }
    }
    size_t t = 0;
    for (unsigned i = 0; i < am->mNumFaces; ++i) {
        const struct aiFace *face = &am->mFaces[i];
        if (face->mNumIndices != 3)
            continue;
        for (int k = 0; k < 3; ++k)
            idx[3 * t + k] = face->mIndices[k];
        t++;
    }
    float m[16];
    for (int k = 0; k < 16; ++k)
        m[k] = (float)xf[k];
    char source[1600]; /* aiString holds up to 1024 bytes */
    int r = snprintf(source, sizeof source, "%s: mesh %u '%s'", f->label, mi, am->mName.data);
    (void)r; /* a long name is cut short: it only names the mesh in messages */
    sr_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.source = source;
    d.positions = pos;
    d.vertex_count = nv;
    d.normals = nrm;
    d.indices = idx;
    d.triangle_count = nt;
    d.transform = m;
    sluice_status st = material_for(f, am->mMaterialIndex, &d.material);
    if (st == SLUICE_OK)
        st = sr_scene_builder_add_mesh(f->b, &d, f->err, f->err_size);
    free(pos);
    free(nrm);
    free(idx);
    return st;
}

static sluice_status add_node(mesh_file *f, const struct aiNode *node, const double *parent,
                              int depth)
{
    if (depth > MAX_NODE_DEPTH) {
        sr_set_error(f->err, f->err_size, "%s: node hierarchy deeper than %d", f->label,
                     MAX_NODE_DEPTH);
        return SLUICE_ERROR_LIMIT;
    }
    if (++f->nodes > MAX_NODE_VISITS) {
        sr_set_error(f->err, f->err_size, "%s: node hierarchy of more than %u nodes", f->label,
                     MAX_NODE_VISITS);
        return SLUICE_ERROR_LIMIT;
    }
    /* ValidateDataStructure refuses these; checked again because a walk
     * that met one would crash */
    if (!node || (node->mNumMeshes && !node->mMeshes) || (node->mNumChildren && !node->mChildren)) {
        sr_set_error(f->err, f->err_size, "%s: assimp returned a broken node hierarchy (%s)",
                     f->label, node ? "a node without its children or meshes" : "a NULL node");
        return SLUICE_ERROR_IO;
    }
    const struct aiMatrix4x4 *t = &node->mTransformation;
    /* assimp's matrices are row-major and act on column vectors, like ours */
    double local[16] = {t->a1, t->a2, t->a3, t->a4, t->b1, t->b2, t->b3, t->b4,
                        t->c1, t->c2, t->c3, t->c4, t->d1, t->d2, t->d3, t->d4};
    double global[16];
    mat_mul(parent, local, global);
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
        if (node->mMeshes[i] >= f->scene->mNumMeshes) {
            sr_set_error(f->err, f->err_size, "%s: node '%s' names mesh %u of %u", f->label,
                         node->mName.data, node->mMeshes[i], f->scene->mNumMeshes);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
        sluice_status st = add_one_mesh(f, node->mMeshes[i], global);
        if (st != SLUICE_OK)
            return st;
    }
    for (unsigned i = 0; i < node->mNumChildren; ++i) {
        sluice_status st = add_node(f, node->mChildren[i], global, depth + 1);
        if (st != SLUICE_OK)
            return st;
    }
    return SLUICE_OK;
}

/* Finds the first NaN or infinite position, naming the face that uses it. */
static sluice_status check_finite(const struct aiScene *sc, const char *label, char *err,
                                  size_t err_size)
{
    for (unsigned mi = 0; mi < sc->mNumMeshes; ++mi) {
        const struct aiMesh *am = sc->mMeshes[mi];
        for (unsigned v = 0; v < am->mNumVertices; ++v) {
            const struct aiVector3D *p = &am->mVertices[v];
            float c[3] = {(float)p->x, (float)p->y, (float)p->z};
            int k = !isfinite(c[0]) ? 0 : !isfinite(c[1]) ? 1 : !isfinite(c[2]) ? 2 : -1;
            if (k < 0)
                continue;
            long face = -1;
            int corner = 0;
            for (unsigned fi = 0; fi < am->mNumFaces && face < 0; ++fi) {
                for (unsigned j = 0; j < am->mFaces[fi].mNumIndices; ++j) {
                    if (am->mFaces[fi].mIndices[j] == v) {
                        face = (long)fi;
                        corner = (int)j;
                        break;
                    }
                }
            }
            /* assimp numbers vertices per face corner, not by the file's
             * vertex list: name the face too */
            sr_set_error(err, err_size,
                         "%s: mesh %u '%s': face %ld, corner %d (vertex %u): coordinate %c is %s "
                         "(%g, %g, %g)",
                         label, mi, am->mName.data, face, corner, v, "xyz"[k],
                         isnan(c[k]) ? "NaN" : "infinite", c[0], c[1], c[2]);
            return SLUICE_ERROR_INVALID_ARGUMENT;
        }
    }
    return SLUICE_OK;
}

/* Checks what assimp returned before anything reads it: a loader may leave
 * a NULL where a count says there is something (5.2's RAW loader gives the
 * root node a NULL child), and counts past the limits would make us copy
 * more than a file of SR_MESH_MAX_FILE_BYTES can mean. Node pointers are
 * checked while walking the hierarchy (add_node). */
static sluice_status check_structure(const struct aiScene *sc, const char *label, char *err,
                                     size_t err_size)
{
    if ((sc->mNumMeshes && !sc->mMeshes) || (sc->mNumMaterials && !sc->mMaterials)) {
        sr_set_error(err, err_size, "%s: assimp returned a scene without its %s", label,
                     sc->mMeshes ? "materials" : "meshes");
        return SLUICE_ERROR_IO;
    }
    for (unsigned i = 0; i < sc->mNumMaterials; ++i) {
        if (!sc->mMaterials[i]) {
            sr_set_error(err, err_size, "%s: assimp returned material %u as NULL", label, i);
            return SLUICE_ERROR_IO;
        }
    }
    size_t vertices = 0, faces = 0;
    for (unsigned mi = 0; mi < sc->mNumMeshes; ++mi) {
        const struct aiMesh *am = sc->mMeshes[mi];
        if (!am || (am->mNumVertices && !am->mVertices) || (am->mNumFaces && !am->mFaces)) {
            sr_set_error(err, err_size, "%s: assimp returned mesh %u %s", label, mi,
                         am ? "without its vertices or faces" : "as NULL");
            return SLUICE_ERROR_IO;
        }
        vertices += am->mNumVertices;
        faces += am->mNumFaces;
        if (vertices > SR_MESH_MAX_VERTICES || faces > SR_MESH_MAX_TRIANGLES) {
            sr_set_error(err, err_size,
                         "%s: more than %u vertices or %u faces (the limits for a mesh file)",
                         label, SR_MESH_MAX_VERTICES, SR_MESH_MAX_TRIANGLES);
            return SLUICE_ERROR_LIMIT;
        }
        unsigned types = 0;
        for (unsigned fi = 0; fi < am->mNumFaces; ++fi) {
            const struct aiFace *face = &am->mFaces[fi];
            if (!face->mNumIndices || !face->mIndices) {
                sr_set_error(err, err_size, "%s: mesh %u '%s': face %u has no vertices", label, mi,
                             am->mName.data, fi);
                return SLUICE_ERROR_IO;
            }
            types |= face->mNumIndices == 1   ? aiPrimitiveType_POINT
                     : face->mNumIndices == 2 ? aiPrimitiveType_LINE
                     : face->mNumIndices == 3 ? aiPrimitiveType_TRIANGLE
                                              : aiPrimitiveType_POLYGON;
            for (unsigned k = 0; k < face->mNumIndices; ++k) {
                if (face->mIndices[k] >= am->mNumVertices) {
                    sr_set_error(err, err_size,
                                 "%s: mesh %u '%s': face %u: vertex index %u out of range (%u "
                                 "vertices)",
                                 label, mi, am->mName.data, fi, face->mIndices[k],
                                 am->mNumVertices);
                    return SLUICE_ERROR_INVALID_ARGUMENT;
                }
            }
        }
        /* Triangulate and SortByPType trust the primitive types a loader
         * claims, and assert when they are wrong: set them from the faces
         * (assimp's own steps change the scene the same way) */
        if (am->mNumFaces)
            ((struct aiMesh *)am)->mPrimitiveTypes =
                types | (am->mPrimitiveTypes & aiPrimitiveType_NGONEncodingFlag);
    }
    return SLUICE_OK;
}

/* Fails unless some mesh has a face of 3 or more corners. SortByPType would
 * drop every mesh of a file of points and lines, aiApplyPostProcessing would
 * fail with "No meshes remaining", and on that failure assimp 5.2's C API
 * releases the scene through an importer it has already destroyed (a crash
 * in Importer::~Importer): no post-processing step may fail. */
static sluice_status check_surfaces(const struct aiScene *sc, const char *label, char *err,
                                    size_t err_size)
{
    for (unsigned mi = 0; mi < sc->mNumMeshes; ++mi) {
        if (sc->mMeshes[mi]->mPrimitiveTypes & (aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON))
            return SLUICE_OK;
    }
    sr_set_error(err, err_size, "%s: the file has no triangles or polygons%s", label,
                 sc->mNumMeshes ? " (only points or lines)" : "");
    return SLUICE_ERROR_IO;
}

/* Where the mesh comes from: a file (path) or a buffer (data, size, hint). */
typedef struct mesh_source {
    const char *path;
    const void *data;
    size_t size;
    const char *hint;
} mesh_source;

/* Reads, validates and post-processes the scene; on success the caller
 * releases *out with aiReleaseImport. */
static sluice_status import_scene(const mesh_source *src, const char *label,
                                  const struct aiScene **out, char *err, size_t err_size)
{
    *out = NULL;
    /* assimp's "Unable to open file" does not say why: the guard does */
    size_t size = src->size;
    sluice_status st = src->path
                           ? sr_mesh_guard_file(src->path, label, err, err_size)
                           : sr_mesh_guard_memory(src->data, size, src->hint, label, err, err_size);
    if (st != SLUICE_OK)
        return st;

    struct aiPropertyStore *props = aiCreatePropertyStore();
    if (!props) {
        sr_set_error(err, err_size, "%s: out of memory", label);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    /* SortByPType splits meshes by primitive type and, with this property,
     * drops the points and lines: a ray tracer has nothing to hit there. */
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_SBP_REMOVE,
                               aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    /* Only ValidateDataStructure while reading: it turns a loader's
     * inconsistent output (NULL nodes, indices past the vertices) into an
     * error. The other steps run once check_structure has seen the result:
     * Debian's assimp is built with its assertions on, and Triangulate
     * aborts the process on a mesh whose primitive types claim polygons it
     * does not have (a PLY whose face data is missing). */
    const struct aiScene *sc =
        src->path
            ? aiImportFileExWithProperties(src->path, aiProcess_ValidateDataStructure, NULL, props)
            : aiImportFileFromMemoryWithProperties(src->data, (unsigned)size,
                                                   aiProcess_ValidateDataStructure,
                                                   src->hint ? src->hint : "", props);
    aiReleasePropertyStore(props);
    if (!sc) {
        sr_set_error(err, err_size, "%s: assimp cannot read it: %s", label, aiGetErrorString());
        return SLUICE_ERROR_IO;
    }
    st = check_structure(sc, label, err, err_size);
    if (st == SLUICE_OK)
        st = check_surfaces(sc, label, err, err_size);
    if (st == SLUICE_OK)
        st = check_finite(sc, label, err, err_size);
    if (st != SLUICE_OK) {
        aiReleaseImport(sc);
        return st;
    }
    /* the importer kept the properties (AI_CONFIG_PP_SBP_REMOVE) */
    sc = aiApplyPostProcessing(sc, aiProcess_Triangulate | aiProcess_SortByPType);
    if (!sc) {
        /* not expected after check_surfaces (and on a failure here assimp
         * 5.2's C API crashes releasing the scene) */
        sr_set_error(err, err_size, "%s: assimp cannot triangulate it: %s", label,
                     aiGetErrorString());
        return SLUICE_ERROR_IO;
    }
    st = check_structure(sc, label, err, err_size);
    if (st != SLUICE_OK) {
        aiReleaseImport(sc);
        return st;
    }
    const struct aiScene *joined = aiApplyPostProcessing(sc, aiProcess_JoinIdenticalVertices);
    if (!joined) {
        sr_set_error(err, err_size, "%s: assimp cannot join vertices: %s", label,
                     aiGetErrorString());
        return SLUICE_ERROR_IO;
    }
    if (!joined->mRootNode) {
        aiReleaseImport(joined);
        sr_set_error(err, err_size, "%s: the file has no scene graph", label);
        return SLUICE_ERROR_IO;
    }
    *out = joined;
    return SLUICE_OK;
}

/* Adds a mesh file or buffer: the shared part of the two entry points. */
static sluice_status add_mesh_source(sr_scene_builder *b, const mesh_source *src,
                                     const float *transform, const uint32_t *material,
                                     const char *label, char *err, size_t err_size)
{
    if (material && *material >= sr_scene_builder_material_count(b)) {
        sr_set_error(err, err_size, "%s: material %u out of range", label, *material);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    const struct aiScene *sc = NULL;
    sluice_status st = import_scene(src, label, &sc, err, err_size);
    if (st != SLUICE_OK)
        return st;

    mesh_file f;
    memset(&f, 0, sizeof f);
    f.b = b;
    f.scene = sc;
    f.label = label;
    f.override = material;
    f.err = err;
    f.err_size = err_size;
    f.material_map = malloc((sc->mNumMaterials ? sc->mNumMaterials : 1) * sizeof(uint32_t));
    if (!f.material_map) {
        aiReleaseImport(sc);
        sr_set_error(err, err_size, "%s: out of memory", label);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    for (unsigned i = 0; i < sc->mNumMaterials; ++i)
        f.material_map[i] = UINT32_MAX;
    double root[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    if (transform) {
        for (int k = 0; k < 16; ++k)
            root[k] = transform[k];
    }
    size_t before = sr_scene_builder_triangle_count(b);
    st = add_node(&f, sc->mRootNode, root, 0);
    if (st == SLUICE_OK && sr_scene_builder_triangle_count(b) == before)
        sr_scene_builder_warn(b, "%s: the file has no triangles", label);
    free(f.material_map);
    aiReleaseImport(sc);
    return st;
}

sluice_status sr_scene_builder_add_mesh_file(sr_scene_builder *b, const char *path,
                                             const float *transform, const uint32_t *material,
                                             const char *label, char *err, size_t err_size)
{
    if (!b || !path) {
        sr_set_error(err, err_size, "add_mesh_file: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    mesh_source src = {path, NULL, 0, NULL};
    return add_mesh_source(b, &src, transform, material, label ? label : path, err, err_size);
}

sluice_status sr_scene_builder_add_mesh_memory(sr_scene_builder *b, const void *data, size_t size,
                                               const char *hint, const float *transform,
                                               const uint32_t *material, const char *label,
                                               char *err, size_t err_size)
{
    if (!b || (!data && size)) {
        sr_set_error(err, err_size, "add_mesh_memory: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    mesh_source src = {NULL, data, size, hint};
    return add_mesh_source(b, &src, transform, material, label ? label : "(memory)", err, err_size);
}

sluice_status sr_scene_load_mesh(const char *path, const sr_scene_load_options *opts,
                                 sr_scene **out, char *err, size_t err_size)
{
    if (!out || !path) {
        sr_set_error(err, err_size, "load_mesh: invalid argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    *out = NULL;
    sr_scene_builder *b = NULL;
    if (sr_scene_builder_create(path, &b) != SLUICE_OK) {
        sr_set_error(err, err_size, "%s: out of memory", path);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    unsigned flags = SR_SCENE_DEFAULT_LIGHT;
    if (opts) {
        sr_scene_builder_set_warning_callback(b, opts->warning, opts->warning_user);
        flags |= opts->flags;
        sr_scene_builder_set_max_triangles(b, opts->max_triangles);
    }
    sluice_status st = sr_scene_builder_add_mesh_file(b, path, NULL, NULL, path, err, err_size);
    if (st == SLUICE_OK)
        st = sr_scene_builder_finish(b, flags, out, err, err_size);
    sr_scene_builder_destroy(b);
    return st;
}
