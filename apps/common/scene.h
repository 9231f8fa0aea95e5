/*
 * Scenes for the apps: triangles, materials, lights, a pinhole camera and
 * render settings, in flat arrays a renderer can upload as they are.
 *
 * Purcell's ray tracer (thesis ch. 3) handles triangles only: every shape is
 * tessellated before rendering, and a triangle is three indices into a vertex
 * array (ch. 4.2, "triangle vertex texture"). This module keeps that layout:
 *
 *   positions   3 floats per vertex (x, y, z)
 *   normals     3 floats per vertex, or NULL when no mesh had normals; a zero
 *               normal means "use the geometric normal" (flat shading)
 *   indices     3 uint32 per triangle, counter-clockwise seen from the front;
 *               the geometric normal is (v1 - v0) x (v2 - v0)
 *   materials   1 uint32 per triangle: an index into the material table
 *
 * Lights are point lights and area lights. Any triangle whose material has a
 * non-zero emission is part of an area light; it emits from its front side
 * only, with the material's emission as constant radiance. The scene lists
 * those triangles with their areas and a cumulative distribution, so a
 * renderer can pick one in proportion to its area (Purcell ch. 6.1, photon
 * emission; ch. 5 samples the CORNELL BOX light for soft shadows).
 *
 * A scene comes from sr_scene_load() (a built-in scene, a JSON scene file
 * or a mesh file read with assimp), or from a builder: add materials, meshes
 * (with a transform), lights and a camera, then finish. Finishing validates
 * everything and yields an immutable sr_scene.
 *
 * Conventions are those of <sluice/sluice.h>: fallible functions return a
 * sluice_status; nothing aborts, exits or prints; destroy accepts NULL. A
 * failing function writes a NUL-terminated message of at most `err_size`
 * bytes into `err` (which may be NULL) that names the file, the field, the
 * vertex or the triangle involved. Warnings (dropped degenerate triangles,
 * a glossy material that is not energy conserving, ...) never fail a call:
 * they are counted in the statistics, kept as text (sr_scene_warnings)
 * and passed to an optional callback as they happen.
 */
#ifndef SR_APPS_SCENE_H
#define SR_APPS_SCENE_H

#include "sluice/sluice.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------ */
/* Plain data: materials, lights, camera, render settings, statistics  */
/* ------------------------------------------------------------------ */

/** What a surface does with light. */
typedef enum sr_material_kind {
    /** Lambertian: reflects `albedo` / pi in every direction. */
    SR_MATERIAL_DIFFUSE = 0,
    /** Perfect specular reflection, scaled by `specular`. */
    SR_MATERIAL_MIRROR = 1,
    /** Dielectric: reflects and refracts by Fresnel's equations with index of
     *  refraction `ior` (outside is vacuum); `specular` tints both. */
    SR_MATERIAL_GLASS = 2,
    /** Modified Blinn-Phong (Jakob 2007, §2.4.1, eq. 2.16):
     *  f = ks (n + 2) / (2 pi) cos^n(N, H) + kd / pi, with kd = `albedo`,
     *  ks = `specular`, n = `exponent`; energy conserving when kd + ks <= 1. */
    SR_MATERIAL_GLOSSY = 3,
    /** A light source surface: emits `emission` (required to be non-zero) and
     *  reflects diffusely with `albedo` (usually black). */
    SR_MATERIAL_EMISSIVE = 4,
} sr_material_kind;

/** Number of material kinds (the size of per-kind arrays). */
#define SR_MATERIAL_KIND_COUNT 5

/** Longest material name kept, including the terminating NUL. */
#define SR_MATERIAL_NAME_SIZE 64

/**
 * A material: plain data, uploaded as is. Colours are linear RGB. Fields a
 * kind does not use are ignored by renderers but still validated (finite,
 * not negative). Any kind may emit: a non-zero `emission` makes every
 * triangle of the material part of an area light.
 */
typedef struct sr_material {
    sr_material_kind kind;
    float albedo[3];                  /**< diffuse albedo (DIFFUSE, EMISSIVE), kd (GLOSSY) */
    float specular[3];                /**< reflectance (MIRROR), tint (GLASS), ks (GLOSSY) */
    float exponent;                   /**< Blinn-Phong exponent n (GLOSSY), >= 0 */
    float ior;                        /**< index of refraction (GLASS), > 0 */
    float emission[3];                /**< emitted radiance from the front side, >= 0 */
    char name[SR_MATERIAL_NAME_SIZE]; /**< for messages and listings */
} sr_material;

/** A material of `kind` with the defaults: albedo 0.8, specular 1 for MIRROR
 *  and GLASS and 0.2 for GLOSSY (then albedo 0.6), exponent 50, ior 1.5, no
 *  emission (an EMISSIVE one gets emission 1 and albedo 0), and `name`
 *  (truncated; NULL gives ""). */
sr_material sr_material_make(sr_material_kind kind, const char *name);

/** "diffuse", "mirror", "glass", "glossy" or "emissive" ("?" otherwise). */
const char *sr_material_kind_name(sr_material_kind kind);

/** Parses a kind name (as above, exact). Returns SLUICE_ERROR_NOT_FOUND for
 *  anything else. */
sluice_status sr_material_kind_parse(const char *name, sr_material_kind *kind);

/** Non-zero when any component of the material's emission is above zero. */
int sr_material_is_emissive(const sr_material *m);

/** An isotropic point light: radiant intensity `intensity` (power per
 *  steradian, RGB) in every direction; its power is 4 pi times that. */
typedef struct sr_point_light {
    float position[3];
    float intensity[3];
} sr_point_light;

/**
 * The area lights: the emissive triangles. All arrays have `count` entries
 * and belong to the scene. `area_cdf` is the running sum of `area` divided by
 * `total_area` (the last entry is exactly 1): to sample a point uniformly by
 * area, find the first entry >= a uniform number in [0, 1), then a uniform
 * point on that triangle. `total_power` is the sum of pi * emission * area
 * (the flux of a one-sided Lambertian emitter).
 */
typedef struct sr_area_lights {
    size_t count;
    const uint32_t *triangles; /**< indices of emissive triangles, ascending */
    const float *area;         /**< area of each */
    const float *area_cdf;     /**< cumulative area, normalised */
    double total_area;
    double total_power[3];
} sr_area_lights;

/** Largest image width or height a camera may ask for. */
#define SR_SCENE_MAX_IMAGE_SIDE 65536u

/** A pinhole camera: the image plane's vertical extent is set by `vfov`
 *  (degrees, in (0, 180)); pixels are square, so the horizontal field of view
 *  follows from width / height. `up` need not be orthogonal to the view
 *  direction, only not parallel to it. */
typedef struct sr_camera {
    float eye[3];
    float look_at[3];
    float up[3];
    float vfov;      /**< vertical field of view, degrees */
    uint32_t width;  /**< image width in pixels, 1 .. SR_SCENE_MAX_IMAGE_SIDE */
    uint32_t height; /**< image height in pixels, 1 .. SR_SCENE_MAX_IMAGE_SIDE */
} sr_camera;

/** What a scene file suggests to render (Purcell fig. 3.3 and ch. 6); apps
 *  may ignore it. */
typedef enum sr_render_mode {
    SR_RENDER_AUTO = 0,    /**< the app decides */
    SR_RENDER_CAST = 1,    /**< eye rays only */
    SR_RENDER_SHADOW = 2,  /**< eye rays and shadow rays */
    SR_RENDER_WHITTED = 3, /**< shadows, reflection and refraction */
    SR_RENDER_PATH = 4,    /**< path tracing */
    SR_RENDER_PHOTON = 5,  /**< ray tracing with a photon map (ch. 6) */
} sr_render_mode;

/** "auto", "cast", "shadow", "whitted", "path" or "photon" ("?" otherwise). */
const char *sr_render_mode_name(sr_render_mode mode);

/** Parses a mode name (as above, exact); SLUICE_ERROR_NOT_FOUND otherwise. */
sluice_status sr_render_mode_parse(const char *name, sr_render_mode *mode);

/** Render settings a scene carries. 0 in `photons` or `photon_lookup` means
 *  "the app decides". */
typedef struct sr_render_settings {
    uint32_t samples_per_pixel; /**< eye rays per pixel, >= 1 (default 1) */
    uint32_t max_depth;         /**< longest path or reflection chain (default 5) */
    uint32_t light_samples;     /**< shadow rays per area-light hit, >= 1 (default 1) */
    uint32_t photons;           /**< photons to store (ch. 6.2; default 0) */
    uint32_t photon_lookup;     /**< photons per radiance estimate (ch. 6.3; default 0) */
    sr_render_mode mode;        /**< default SR_RENDER_AUTO */
} sr_render_settings;

/** The default render settings (see the field comments). */
sr_render_settings sr_render_settings_default(void);

/** Bit of sr_scene_stats.kinds_present for a material kind. */
#define SR_KIND_BIT(kind) (1u << (unsigned)(kind))

/** What a scene holds, so that apps can skip what it does not need (no glass:
 *  no refraction rays; no area light: no light sampling, ...). */
typedef struct sr_scene_stats {
    size_t triangles;
    size_t vertices;
    float bounds_min[3]; /**< of all vertices */
    float bounds_max[3];
    size_t materials;
    /** Triangles per material kind, indexed by sr_material_kind. */
    size_t triangles_by_kind[SR_MATERIAL_KIND_COUNT];
    /** SR_KIND_BIT(kind) for every kind with at least one triangle. */
    unsigned kinds_present;
    size_t point_lights;
    size_t emissive_triangles; /**< area-light triangles (of any kind) */
    double emissive_area;
    size_t degenerate_dropped; /**< zero-area triangles dropped while building */
    size_t warnings;           /**< warnings issued while building */
    int has_normals;           /**< non-zero when sr_scene_normals() is not NULL */
} sr_scene_stats;

/* ------------------------------------------------------------------ */
/* Scenes                                                              */
/* ------------------------------------------------------------------ */

typedef struct sr_scene sr_scene;

/** Flags for sr_scene_builder_finish() and sr_scene_load_options. */
enum {
    /** Accept a scene with no point light and no emissive triangle (ray
     *  casting tests). Without it such a scene is an error. */
    SR_SCENE_ALLOW_NO_LIGHT = 1u << 0,
    /** When the scene has no light at all, add the default point light (see
     *  sr_scene_builder_finish) instead of failing. */
    SR_SCENE_DEFAULT_LIGHT = 1u << 1,
};

/** Receives each warning as it is issued (the text has no newline). */
typedef void (*sr_scene_warning_fn)(void *user, const char *message);

/** Options for sr_scene_load(); zero-initialise, then set fields. NULL
 *  options mean all zero. */
typedef struct sr_scene_load_options {
    unsigned flags;              /**< SR_SCENE_ALLOW_NO_LIGHT */
    sr_scene_warning_fn warning; /**< optional */
    void *warning_user;          /**< passed to `warning` */
    /** The most triangles a JSON scene or mesh file may produce (0: no limit
     *  beyond the builder's 2^32 - 1): a short JSON file can ask for
     *  millions of sphere triangles; this bounds the work (fuzzing, servers). */
    size_t max_triangles;
} sr_scene_load_options;

/**
 * Loads a scene by name or path, in this order:
 *   1. a built-in scene name (sr_scene_builtin_names(); "spheres:N");
 *   2. a path ending in ".json" (any case): a JSON scene file (docs/scenes.md);
 *   3. any other path: a mesh file read with assimp (OBJ with MTL, PLY, glTF 2
 *      .gltf/.glb and whatever else assimp reads), see sr_scene_load_mesh.
 * (A file named like a built-in scene is reached as "./NAME".) On failure
 * `*out` is NULL and `err` says why: SLUICE_ERROR_NOT_FOUND for a missing
 * file, SLUICE_ERROR_IO for a file that cannot be read or parsed,
 * SLUICE_ERROR_INVALID_ARGUMENT for invalid content, SLUICE_ERROR_LIMIT for
 * a scene beyond the limits, SLUICE_ERROR_OUT_OF_MEMORY.
 */
sluice_status sr_scene_load(const char *name_or_path, const sr_scene_load_options *opts,
                            sr_scene **out, char *err, size_t err_size);

/**
 * Loads a mesh file with assimp: triangulated, identical vertices joined,
 * points and lines dropped, the node hierarchy's transforms applied, normals
 * kept when the file has them. Materials map as described at
 * sr_scene_builder_add_mesh_file. The scene gets the default camera
 * framing its bounds and, when no material emits, the default point light
 * (both described at sr_scene_builder_finish).
 */
sluice_status sr_scene_load_mesh(const char *path, const sr_scene_load_options *opts,
                                 sr_scene **out, char *err, size_t err_size);

/** Loads a JSON scene file (format: docs/scenes.md). Errors name the file and
 *  the field, e.g. "s.json: meshes[2].transform.scale: expected a number or
 *  an array of 3 numbers", or the line and column of a syntax error. */
sluice_status sr_scene_load_json(const char *path, const sr_scene_load_options *opts,
                                 sr_scene **out, char *err, size_t err_size);

/** Builds a built-in scene by name; SLUICE_ERROR_NOT_FOUND for an unknown
 *  name, SLUICE_ERROR_INVALID_ARGUMENT for a bad "spheres:N". */
sluice_status sr_scene_load_builtin(const char *name, const sr_scene_load_options *opts,
                                    sr_scene **out, char *err, size_t err_size);

/** The names of the built-in scenes, NULL-terminated, in a fixed order. The
 *  parametrised one appears as "spheres:N". */
const char *const *sr_scene_builtin_names(void);

/** A one-line description of a built-in scene (a name from the list above,
 *  or "spheres:<anything>"), or NULL when there is no such scene. */
const char *sr_scene_builtin_description(const char *name);

/** Non-zero when `name` selects a built-in scene: one of the names above, or
 *  "spheres:" followed by anything (a bad count fails when loading). */
int sr_scene_is_builtin(const char *name);

/** Frees the scene (NULL is fine). */
void sr_scene_destroy(sr_scene *scene);

/** Where the scene came from: the built-in name or the path it was loaded
 *  from, or the builder's `source`. */
const char *sr_scene_source(const sr_scene *scene);

/** Number of vertices. */
size_t sr_scene_vertex_count(const sr_scene *scene);

/** Number of triangles. */
size_t sr_scene_triangle_count(const sr_scene *scene);

/** Vertex positions, 3 floats per vertex. */
const float *sr_scene_positions(const sr_scene *scene);

/** Vertex normals, 3 floats per vertex, unit length or zero (zero: use the
 *  geometric normal), or NULL when no mesh of the scene had normals. */
const float *sr_scene_normals(const sr_scene *scene);

/** Triangle vertex indices, 3 per triangle. */
const uint32_t *sr_scene_indices(const sr_scene *scene);

/** The material index of each triangle. */
const uint32_t *sr_scene_triangle_materials(const sr_scene *scene);

/** Number of materials. */
size_t sr_scene_material_count(const sr_scene *scene);

/** The material table. */
const sr_material *sr_scene_materials(const sr_scene *scene);

/** Number of point lights. */
size_t sr_scene_point_light_count(const sr_scene *scene);

/** The point lights. */
const sr_point_light *sr_scene_point_lights(const sr_scene *scene);

/** Number of lights: point lights plus emissive triangles. */
size_t sr_scene_light_count(const sr_scene *scene);

/** Describes the area lights (pointers into the scene). */
void sr_scene_area_lights(const sr_scene *scene, sr_area_lights *out);

/** The camera. */
const sr_camera *sr_scene_camera(const sr_scene *scene);

/** The render settings. */
const sr_render_settings *sr_scene_render_settings(const sr_scene *scene);

/** The statistics. */
const sr_scene_stats *sr_scene_statistics(const sr_scene *scene);

/** The warnings issued while building, one per line ("" when none). After 32
 *  of them only a count of the rest is kept; stats.warnings counts them all. */
const char *sr_scene_warnings(const sr_scene *scene);

/* ------------------------------------------------------------------ */
/* Building scenes                                                     */
/* ------------------------------------------------------------------ */

typedef struct sr_scene_builder sr_scene_builder;

/** Creates an empty builder. `source` (may be NULL) names the scene in
 *  messages and becomes sr_scene_source(). */
sluice_status sr_scene_builder_create(const char *source, sr_scene_builder **out);

/** Frees the builder and everything it holds (NULL is fine). */
void sr_scene_builder_destroy(sr_scene_builder *b);

/** Sets the most triangles the builder accepts (0: 2^32 - 1, the default);
 *  a mesh or shape that would go past it fails with SLUICE_ERROR_LIMIT. */
void sr_scene_builder_set_max_triangles(sr_scene_builder *b, size_t max_triangles);

/** Sets the warning callback (NULL: none). */
void sr_scene_builder_set_warning_callback(sr_scene_builder *b, sr_scene_warning_fn fn, void *user);

/** Issues a warning: counted, kept and passed to the callback. Loaders use it
 *  for what they skip or guess. */
void sr_scene_builder_warn(sr_scene_builder *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/**
 * Adds a material and writes its index to `*index` (may be NULL). Fails with
 * SLUICE_ERROR_INVALID_ARGUMENT, naming the material, for a value that is not
 * finite, a negative colour, exponent or emission, an ior <= 0, an unknown
 * kind, or an EMISSIVE material without emission. Warns when a GLOSSY
 * material has kd + ks > 1 in some channel (not energy conserving, Jakob
 * §2.4.1).
 */
sluice_status sr_scene_builder_add_material(sr_scene_builder *b, const sr_material *m,
                                            uint32_t *index, char *err, size_t err_size);

/** Finds the first material named `name`; SLUICE_ERROR_NOT_FOUND if none. */
sluice_status sr_scene_builder_find_material(const sr_scene_builder *b, const char *name,
                                             uint32_t *index);

/** Number of materials added so far. */
size_t sr_scene_builder_material_count(const sr_scene_builder *b);

/** Number of triangles kept so far. */
size_t sr_scene_builder_triangle_count(const sr_scene_builder *b);

/** A mesh to add: arrays in the scene's layout, read during the call only. */
typedef struct sr_mesh_desc {
    /** Names the mesh in messages ("bunny.obj", "meshes[2]"); may be NULL. */
    const char *source;
    const float *positions; /**< 3 per vertex */
    size_t vertex_count;
    const float *normals;    /**< 3 per vertex, optional (NULL) */
    const uint32_t *indices; /**< 3 per triangle */
    size_t triangle_count;
    /** Material of every triangle, used when `materials` is NULL. */
    uint32_t material;
    /** Per-triangle materials, optional (NULL). */
    const uint32_t *materials;
    /** 4x4 row-major affine transform applied to column vectors
     *  (p' = M [p 1]^T), or NULL for the identity. Normals go through the
     *  inverse transpose; a mirroring transform also reverses the winding,
     *  so the front side stays the front side. */
    const float *transform;
} sr_mesh_desc;

/**
 * Adds a mesh. Everything is checked before anything is added, so a failed
 * call leaves the builder as it was. Errors (SLUICE_ERROR_INVALID_ARGUMENT)
 * name the mesh's source and the vertex or triangle: a coordinate or normal
 * that is NaN or infinite (before or after the transform), an index or
 * material out of range, a transform that is not affine, not finite or
 * singular. SLUICE_ERROR_LIMIT when the scene would exceed 2^32 - 1
 * vertices or triangles. Degenerate triangles (zero area: two equal corners
 * or three collinear ones, to float precision) are dropped, counted in the
 * statistics and reported by one warning per mesh. Only the vertices that
 * kept triangles use are added.
 */
sluice_status sr_scene_builder_add_mesh(sr_scene_builder *b, const sr_mesh_desc *mesh, char *err,
                                        size_t err_size);

/**
 * Reads a mesh file with assimp and adds its meshes, transformed by the
 * file's node transforms and then by `transform` (row-major, NULL: identity).
 * When `material` is not NULL every triangle gets that material index;
 * otherwise the file's materials are added, mapped from assimp's (and the
 * OBJ MTL's) properties:
 *   Kd -> albedo; Ks -> specular; Ns -> exponent; Ni -> ior; Ke -> emission;
 *   illum 0, 1 -> DIFFUSE; 2 -> GLOSSY when Ks > 0, else DIFFUSE;
 *   3, 5, 8 -> MIRROR (specular = Ks, or 1 when Ks is black);
 *   4, 6, 7, 9 -> GLASS (tint Tf, white by default); 10 -> DIFFUSE; other
 *   illum values -> DIFFUSE with a warning; no illum (formats other than OBJ):
 *   GLOSSY when Ks > 0 and Ns > 0, else DIFFUSE;
 *   any Ke > 0 -> EMISSIVE, whatever illum says.
 * `label` (may be NULL: the path) names the file in messages. Errors:
 * SLUICE_ERROR_NOT_FOUND for a missing file, SLUICE_ERROR_IO for a path that
 * is not a regular file, an empty file, or with assimp's message when it
 * cannot read it (unknown format, syntax, a structure its validation
 * refuses), SLUICE_ERROR_LIMIT beyond the limits below, and those of
 * sr_scene_builder_add_mesh. On failure the builder is left with the
 * materials and meshes added before the failing mesh; callers destroy it.
 *
 * Limits, so that a malformed file takes bounded time and memory (assimp
 * allocates what a header declares before reading it): at most
 * SR_MESH_MAX_FILE_BYTES bytes; an OFF or PLY header may not declare more
 * elements than the file's size can hold; at most SR_MESH_MAX_VERTICES
 * vertices and SR_MESH_MAX_TRIANGLES faces as assimp returns them, and
 * SR_MESH_MAX_TRIANGLES triangles once every node's copy is counted; node
 * hierarchies at most 256 deep and 2^20 nodes.
 */
sluice_status sr_scene_builder_add_mesh_file(sr_scene_builder *b, const char *path,
                                             const float *transform, const uint32_t *material,
                                             const char *label, char *err, size_t err_size);

/** The largest mesh file (or buffer) sr_scene_builder_add_mesh_file reads. */
#define SR_MESH_MAX_FILE_BYTES (256u << 20)
/** The most vertices a mesh file may hold. */
#define SR_MESH_MAX_VERTICES (1u << 26)
/** The most faces a mesh file may hold, and triangles it may add. */
#define SR_MESH_MAX_TRIANGLES (1u << 26)

/**
 * As sr_scene_builder_add_mesh_file, from `size` bytes at `data` in the
 * format `hint` names (a file extension without the dot: "obj", "ply",
 * "gltf", "glb", "off", "stl", ...; NULL or "" lets assimp guess from the
 * content). Files the data refers to (an OBJ's MTL, a glTF's buffers) are
 * looked for relative to the working directory. `label` (may be NULL:
 * "(memory)") names the data in messages. For tests and fuzzing.
 */
sluice_status sr_scene_builder_add_mesh_memory(sr_scene_builder *b, const void *data, size_t size,
                                               const char *hint, const float *transform,
                                               const uint32_t *material, const char *label,
                                               char *err, size_t err_size);

/**
 * Adds a sphere of `radius` around `center`: a geodesic sphere (an
 * icosahedron whose faces are split into `frequency`^2 triangles, projected
 * onto the sphere) with 20 f^2 triangles, 10 f^2 + 2 shared vertices and
 * exact radial normals; 1 <= frequency <= 256.
 */
sluice_status sr_scene_builder_add_sphere(sr_scene_builder *b, const float center[3], float radius,
                                          unsigned frequency, uint32_t material,
                                          const float *transform, char *err, size_t err_size);

/** Adds the parallelogram corner, corner + u, corner + u + v, corner + v as
 *  2 triangles; its front side faces u x v. */
sluice_status sr_scene_builder_add_quad(sr_scene_builder *b, const float corner[3],
                                        const float u[3], const float v[3], uint32_t material,
                                        const float *transform, char *err, size_t err_size);

/** Adds an axis-aligned box from `lo` to `hi`: 12 triangles facing out, 8
 *  shared vertices, no normals (flat). */
sluice_status sr_scene_builder_add_box(sr_scene_builder *b, const float lo[3], const float hi[3],
                                       uint32_t material, const float *transform, char *err,
                                       size_t err_size);

/**
 * Adds a ring standing on the plane y = center[1]: a closed band between the
 * radii `radius` - `thickness` and `radius` around the vertical axis through
 * `center`, `height` tall, with `segments` (3 .. 65536) facets around: outer
 * and inner walls with smooth normals, flat top and bottom, 8 * segments
 * triangles. Purcell's RING scene (ch. 6, fig. 6.7) is a mirror one.
 */
sluice_status sr_scene_builder_add_ring(sr_scene_builder *b, const float center[3], float radius,
                                        float thickness, float height, unsigned segments,
                                        uint32_t material, const float *transform, char *err,
                                        size_t err_size);

/**
 * Adds the Utah teapot (Newell's 32 bicubic Bezier patches), each patch
 * tessellated into `n` x `n` quads (2 <= n <= 64: with n = 1 the four corners
 * of each spout-tip patch lie on one line) with normals from the patch
 * derivatives; the triangles that collapse at the lid's knob and the bottom's
 * centre are left out, giving SR_TEAPOT_TRIANGLES(n) triangles. Below
 * n = 3 the spout's tip is too coarse for its normals to agree with the
 * winding everywhere. In the
 * patch data's own frame (z up, spout along +x, bottom at z = 0) the teapot
 * spans about x in [-3, 3.43], y in [-2, 2], z in [0, 3.15]; the builder maps
 * it to y up ((x, y, z) -> (x, z, -y)) before `transform`.
 */
sluice_status sr_scene_builder_add_teapot(sr_scene_builder *b, unsigned n, uint32_t material,
                                          const float *transform, char *err, size_t err_size);

/** Triangles of a teapot tessellated with n x n quads per patch: 32 patches
 *  of 2 n^2, less n for each of the 8 patches with a collapsed edge. */
#define SR_TEAPOT_TRIANGLES(n) (64u * (n) * (n)-8u * (n))

/** Adds a point light; fails for a non-finite position or a negative or
 *  non-finite intensity. */
sluice_status sr_scene_builder_add_point_light(sr_scene_builder *b, const sr_point_light *light,
                                               char *err, size_t err_size);

/** Sets the camera. Fails (naming the field) for non-finite vectors, eye ==
 *  look_at, up parallel to the view direction, vfov outside (0, 180), or a
 *  width or height of 0 or above SR_SCENE_MAX_IMAGE_SIDE. */
sluice_status sr_scene_builder_set_camera(sr_scene_builder *b, const sr_camera *camera, char *err,
                                          size_t err_size);

/** Sets the render settings. Fails when samples_per_pixel or light_samples
 *  is 0 or the mode is unknown. */
sluice_status sr_scene_builder_set_render_settings(sr_scene_builder *b,
                                                   const sr_render_settings *settings, char *err,
                                                   size_t err_size);

/**
 * Validates and produces the scene; `flags` are SR_SCENE_* flags.
 * Fails with SLUICE_ERROR_INVALID_ARGUMENT for a scene with no triangles, or
 * with no light (no point light and no emissive triangle) unless
 * SR_SCENE_ALLOW_NO_LIGHT or SR_SCENE_DEFAULT_LIGHT is given.
 *
 * Defaults filled in here:
 *  - No camera set: the default camera frames the bounds. It looks at the
 *    centre c of the bounding box from the +z side and a little above, from
 *    e = c + d (0, 0.25, 1) / |(0, 0.25, 1)|, with up +y, vfov 40 degrees,
 *    512 x 512 pixels, and d = 1.1 r / sin(20 deg) so that the bounding
 *    sphere (radius r, half the box diagonal) fits the view.
 *  - SR_SCENE_DEFAULT_LIGHT and no light: one white point light at
 *    c + 2 r (0.4, 1, 0.6) / |(0.4, 1, 0.6)| (above, right of and in front of
 *    the centre) with intensity 4 r^2, so a surface at c facing it receives
 *    irradiance 1.
 *
 * On success the builder is left empty (its arrays move into the scene) and
 * only sr_scene_builder_destroy may follow; on failure it is unchanged.
 */
sluice_status sr_scene_builder_finish(sr_scene_builder *b, unsigned flags, sr_scene **out,
                                      char *err, size_t err_size);

#ifdef __cplusplus
}
#endif

#endif
