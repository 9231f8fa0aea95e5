/*
 * Records of the photon mapper (Purcell, thesis ch. 6), shared by the host
 * (C11) and the kernels (OpenCL C 1.2) like kernels/render/rt_types.h, which
 * must come first (rt_u32). Every field is a 4-byte scalar.
 */
#ifndef SLUICE_PM_TYPES_H
#define SLUICE_PM_TYPES_H

/** pm_photon.flags: bounces before the photon was stored (bits 0-7). */
#define PM_PHOTON_BOUNCE_MASK 0xffu
/** pm_photon.flags: the photon went through a mirror or glass (a caustic
 *  photon, Jensen's caustic map). */
#define PM_PHOTON_CAUSTIC 256u

/** A stored photon (Purcell 6.2.1): its position first, so that the point
 *  grid (apps/render/point_grid.h) can bin a photon stream directly with a
 *  stride of 40 bytes. */
typedef struct pm_photon {
    float px, py, pz; /* where it was stored */
    float pr, pg, pb; /* power (flux) it carries */
    float dx, dy, dz; /* unit direction of travel when it arrived */
    rt_u32 flags;     /* bounces | PM_PHOTON_CAUSTIC */
} pm_photon;

/** One radiance-estimate query of the kNN-grid search (Purcell 6.2.3): a
 *  surface point, its unit normal (used only by the normal filter) and an id
 *  of the caller's (a pixel, say) that the search does not read. 28 bytes. */
typedef struct pm_query {
    float px, py, pz;
    float nx, ny, nz;
    rt_u32 id;
} pm_query;

/** pm_knn_result.flags: the search reached the maximum radius (it ended
 *  with fewer than k photons or because its shells passed the radius). */
#define PM_KNN_HIT_MAX_RADIUS 1u
/** pm_knn_result.flags: the search covered the whole grid. */
#define PM_KNN_COVERED_GRID 2u
/** pm_knn_result.flags: more photons were found than the index list of
 *  pm_knn_query_indices could hold (the list is cut). */
#define PM_KNN_INDICES_CUT 4u
/** pm_knn_result.flags: the search has ended (it leaves the live stream). */
#define PM_KNN_DONE 8u
/** pm_knn_result.flags: the query's position is not finite (nothing found). */
#define PM_KNN_BAD_QUERY 16u

/** The radiance estimate of one query: the summed power of the photons
 *  found, how many, and the squared radius they lie in (the caller computes
 *  f_r * sum / (pi r^2)). Also the search's state between passes: the
 *  shells explored so far. 28 bytes. */
typedef struct pm_knn_result {
    float sr, sg, sb; /* summed power */
    float r2;         /* squared radius of the estimate (0 when nothing found) */
    rt_u32 count;     /* photons in the estimate */
    rt_u32 shells;    /* shells of cells explored (1 = the query's cell only) */
    rt_u32 flags;     /* PM_KNN_* */
} pm_knn_result;

/** The search's description as the kernels take it (by value). */
typedef struct pm_knn_params {
    rt_u32 k;               /* photons sought */
    float max_r2;           /* squared maximum radius */
    rt_u32 normal_filter;   /* non-zero: only photons with dot(n, d) < 0 */
    rt_u32 index_cap;       /* places per query in the index list (0: none) */
    rt_u32 shells_per_pass; /* shells holding photons a pass explores (0: all) */
    float margin[3];        /* per axis: how much the shell distances are shrunk
                               so that rounding in the cell function never makes
                               a shell look farther than a photon in it */
    rt_u32 map_stride;      /* floats per plane of the cell-ordered map */
    float box_lo[3];        /* the stored photons' bounding box (lo > hi when */
    float box_hi[3];        /* there are none): no photon lies outside it */
} pm_knn_params;

/** The kNN search's cell-ordered copy of the photon map is a structure of
 *  arrays, PM_MAP_PLANES planes of pm_knn_params.map_stride floats each, in
 *  this order (PM_MAP_ID holds the photon's index in the caller's stream, as
 *  bits). The search reads the planes in blocks of PM_MAP_BLOCK floats, which
 *  may run PM_MAP_BLOCK - 1 past the last photon: the stride leaves that room. */
#define PM_MAP_X 0
#define PM_MAP_Y 1
#define PM_MAP_Z 2
#define PM_MAP_DX 3
#define PM_MAP_DY 4
#define PM_MAP_DZ 5
#define PM_MAP_R 6
#define PM_MAP_G 7
#define PM_MAP_B 8
#define PM_MAP_ID 9
#define PM_MAP_PLANES 10
#define PM_MAP_BLOCK 8
/** Queries pm_knn_sum takes side by side (8 or 16). */
#ifndef PM_KNN_SUM_QUERIES
#define PM_KNN_SUM_QUERIES 16
#endif

/** rt_ray.flags of a photon ray whose path so far went only through
 *  mirrors and glass (it becomes a PM_PHOTON_CAUSTIC photon). */
#define PM_RAY_SPECULAR 32u

/** What pm_emit (pm_photon.cl) needs besides buffers (by value). */
typedef struct pm_emit_args {
    rt_u32 seed, base;  /* key seed, index of the first photon of this batch */
    rt_u32 area_lights; /* emissive triangles */
    rt_u32 point_lights;
    float area_prob;  /* probability of leaving an area light */
    float area_total; /* total emissive area */
    float scene_eps;
    float spec_prob;              /* share of the photons sent toward
                                     the mirrors and glass: cone_count / n */
    rt_u32 cone_count;            /* the batch's first photons, sent there */
    float spec_x, spec_y, spec_z; /* their bounding sphere: centre */
    float spec_r;                 /* and radius */
} pm_emit_args;

#endif /* SLUICE_PM_TYPES_H */
