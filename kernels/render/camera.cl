/*
 * camera.cl: eye rays from the scene's pinhole camera (the first kernel of
 * Purcell's Fig. 3.1), shared by the renderers. The frame (rt_frame in
 * rt_types.h) is filled on the host by sr_camera_frame (apps/render/camera.h).
 */
#include "sluice.cl"

/* One eye ray per pixel, in 8x8 tiles so that neighbouring rays (which take
 * nearly the same path through the grid) are neighbours in the stream, each
 * tile as four 4x4 blocks (left to right, top to bottom), so that the 16
 * rays of a packet (rt_lanes.cl) are a square rather than two rows: the
 * fused mode's coherent packets cross fewer voxels (bench/README.md). The
 * launch covers whole tiles, those listed in `tiles` (the ones still taking
 * samples, apps/render/adaptive.h); positions outside the image emit
 * nothing. Output 0 (ordered) receives the rays, each adding to its pixel's
 * slot in the film half of this sample (f.film_half). The first sample goes
 * through pixel centres; with f.jitter set, rays are jittered inside their
 * pixel. */
__kernel void rt_raygen(SLUICE_PARAMS, global rt_ray *rays, const rt_frame f,
                        global const uint *tiles)
{
    SLUICE_FOR_EACH (i) {
        uint tiles_x = (f.width + 7u) / 8u;
        uint tile = tiles[i / 64u], within = i % 64u;
        uint x = (tile % tiles_x) * 8u + (within >> 4 & 1u) * 4u + (within & 3u);
        uint y = (tile / tiles_x) * 8u + (within >> 5) * 4u + (within >> 2 & 3u);
        int inside = x < f.width && y < f.height;
        uint at = SLUICE_EMIT_INDEX(0, inside);
        if (SLUICE_WRITING && inside) {
            uint pixel = y * f.width + x;
            uint key = rt_key(rt_key(f.seed, pixel), f.sample);
            float jx = 0.5f, jy = 0.5f;
            if (f.jitter) {
                jx = rt_rand(key, 0u);
                jy = rt_rand(key, 1u);
            }
            float px = (float)x + jx, py = (float)y + jy;
            float3 d = (float3)(f.corner[0] + f.du[0] * px + f.dv[0] * py,
                                f.corner[1] + f.du[1] * px + f.dv[1] * py,
                                f.corner[2] + f.du[2] * px + f.dv[2] * py);
            d = normalize(d);
            rt_ray r;
            r.ox = f.eye[0];
            r.oy = f.eye[1];
            r.oz = f.eye[2];
            r.dx = d.x;
            r.dy = d.y;
            r.dz = d.z;
            r.tmin = 0.0f;
            r.tmax = INFINITY;
            r.wr = r.wg = r.wb = 1.0f;
            r.pixel = pixel + f.film_half;
            r.key = key;
            r.flags = RT_KIND_EYE | RT_FLAG_COUNT_EMIT;
            r.pad0 = r.pad1 = 0u;
            rays[at] = r;
        }
    }
}
