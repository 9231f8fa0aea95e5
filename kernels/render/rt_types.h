/*
 * Records the ray tracer keeps in streams and buffers, shared by the host (C11)
 * and the kernels (OpenCL C 1.2): the same text is compiled on both sides, so
 * the layouts agree. Every field is a 4-byte scalar (no float3: its 16-byte
 * alignment has no C counterpart), as README.md "Writing a kernel" asks.
 *
 * Purcell's ray tracer (thesis ch. 3.1, Fig. 3.1) moves rays between kernels
 * as streams: a ray record (origin, direction, what it carries), the traversal
 * state of a ray in the grid (its voxel), and the hit record the intersector
 * leaves for the shader. The ray tracer here has the same three records.
 */
#ifndef SLUICE_RT_TYPES_H
#define SLUICE_RT_TYPES_H

#ifdef __OPENCL_VERSION__
typedef uint rt_u32;
typedef int rt_i32;
#else
#include <stdint.h>
typedef uint32_t rt_u32;
typedef int32_t rt_i32;
#endif

/** A triangle index that means "no triangle": a miss. */
#define RT_NO_HIT 0xffffffffu

/* Ray kinds (the low 3 bits of rt_ray.flags), counted separately in the
 * statistics like Purcell's Table 5.2 (eye, shadow, reflected rays). */
#define RT_KIND_EYE 0u
#define RT_KIND_SHADOW 1u
#define RT_KIND_REFLECT 2u
#define RT_KIND_REFRACT 3u
#define RT_KIND_PATH 4u
#define RT_KIND_COUNT 5u  /* the kinds the ray tracer makes and counts */
#define RT_KIND_PHOTON 5u /* a photon's flight (the photon mapper, Purcell 6.2.1) */
#define RT_KIND_MASK 7u

/* Other bits of rt_ray.flags. */
#define RT_FLAG_ANY_HIT 8u     /* shadow ray: any hit before tmax ends it */
#define RT_FLAG_COUNT_EMIT 16u /* a hit emitter adds its emission (eye, specular) */
#define RT_DEPTH_SHIFT 8u      /* bounces so far in bits 8..15 */
#define RT_DEPTH_MASK 0xff00u

/**
 * One ray: the segment o + t d for t in [tmin, tmax], the pixel it adds to,
 * the weight it carries (for a shadow ray: the whole contribution it adds when
 * nothing blocks it), the key of its random numbers, kind and depth. 64 bytes.
 */
typedef struct rt_ray {
    float ox, oy, oz;
    float dx, dy, dz;
    float tmin, tmax;
    float wr, wg, wb;
    rt_u32 pixel;
    rt_u32 key;   /* counter-based RNG key of this ray's path (see rt_rng.cl) */
    rt_u32 flags; /* kind | RT_FLAG_* | depth << RT_DEPTH_SHIFT */
    rt_u32 pad0, pad1;
} rt_ray;

/**
 * What the intersector found for one ray: the nearest triangle (RT_NO_HIT for
 * a miss), the ray parameter t and the barycentrics (u, v) of the hit, and the
 * work the ray cost: voxels visited and triangle tests (Purcell's v and t,
 * Table 5.2, per ray). 24 bytes.
 */
typedef struct rt_hit {
    rt_u32 tri;
    float t, u, v;
    rt_u32 steps, tests;
} rt_hit;

/**
 * Where a ray stands in the grid in the stream execution mode, kept in a
 * buffer indexed by ray (Purcell keeps ray state in textures indexed by ray;
 * the streams between passes carry only 4-byte ray ids): its voxel and the
 * position of the next triangle to test in that voxel's list. The best hit
 * so far and the work counts live in the ray's rt_hit record, updated in
 * place. The voxel's entry and exit along the ray are recomputed from the
 * voxel index (rt_trace.cl), so no t is carried that could drift. 16 bytes.
 */
typedef struct rt_walk {
    rt_i32 cx, cy, cz;
    rt_u32 pos; /* next index into cell_tris (intersect) */
} rt_walk;

/* Where a ray goes after a pass of the stream mode (the code stream the
 * route kernel reads, one per ray of the pass). */
#define RT_NEXT_TRAVERSE 0u
#define RT_NEXT_INTERSECT 1u
#define RT_NEXT_DONE 2u

/**
 * The grid as the kernels see it (a plain struct argument): the box the
 * voxels tile, the voxel edge per axis and its inverse, and the voxel counts.
 */
typedef struct rt_grid_args {
    float lo[3];
    float hi[3];
    float cell[3];
    float inv_cell[3];
    rt_i32 dims[3];
    rt_u32 pad;
} rt_grid_args;

/**
 * A material as the shader reads it (a reduced sr_material): kind,
 * colours and the two scalars. 48 bytes.
 */
typedef struct rt_material {
    rt_u32 kind; /* sr_material_kind */
    float ar, ag, ab;
    float sr, sg, sb;
    float exponent, ior;
    float er, eg, eb;
} rt_material;

/** A point light as the shader reads it. */
typedef struct rt_point_light {
    float px, py, pz;
    float ir, ig, ib;
} rt_point_light;

/**
 * Everything the shading kernels need besides buffers: the camera frame (eye,
 * the direction through the top-left pixel's corner and the steps per pixel
 * right and down), image size, sample, seed, lights and what the render mode
 * asks for. Passed by value.
 */
typedef struct rt_frame {
    float eye[3];
    float corner[3]; /* direction to the image plane's top-left corner */
    float du[3];     /* one pixel to the right */
    float dv[3];     /* one pixel down */
    rt_u32 width, height;
    rt_u32 sample; /* sample index (progressive rendering) */
    rt_u32 seed;
    rt_u32 mode; /* RT_MODE_* */
    rt_u32 max_depth;
    rt_u32 light_samples;
    rt_u32 point_lights;
    rt_u32 area_lights; /* emissive triangles */
    float area_total;   /* their total area */
    float scene_eps;    /* offset for secondary ray origins, scaled to the scene */
    rt_u32 jitter;      /* non-zero: jitter the eye ray inside its pixel */
    rt_u32 film_half;   /* film slot offset of this sample: (sample & 1) *
                           pixels (the film's halves, apps/render/film.h) */
} rt_frame;

/**
 * A gather point: a diffuse or glossy surface that an eye path reached, where
 * the photon mapper adds its radiance estimate (Purcell 6.2.4): position,
 * unit normal facing the viewer, the pixel, and the weight the estimate is
 * multiplied by (the path's throughput times the diffuse BRDF, albedo / pi).
 * Emitted by rt_shade when the shading program is built with RT_GATHER.
 * 40 bytes.
 */
typedef struct rt_gather {
    float px, py, pz;
    float nx, ny, nz;
    rt_u32 pixel;
    float wr, wg, wb;
} rt_gather;

/* Render modes (rt_frame.mode). */
#define RT_MODE_CAST 0u
#define RT_MODE_SHADOW 1u
#define RT_MODE_WHITTED 2u
#define RT_MODE_PATH 3u

/* Fixed-point scale of the per-sample accumulation buffer: contributions are
 * added as 64-bit integers so that the sum does not depend on the order in
 * which rays of the same pixel finish (integer addition is associative, float
 * addition is not): same seed, same image, bit for bit. */
#define RT_FIXED_SCALE 16777216.0f

#endif /* SLUICE_RT_TYPES_H */
