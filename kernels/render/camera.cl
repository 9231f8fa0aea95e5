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
    uint tiles_x = (f.width + 7u) / 8u;
    /* 16 rays at a time: their positions, keys, jitter and directions in
     * vectors (one ray per loop turn ran scalar, several times slower than
     * the tracing of the ray), the same operations as one at a time, so the
     * same rays; normalize and the stores one by one */
    SLUICE_FOR_EACH_RANGE (b, e) {
        for (uint i0 = b; i0 < e; i0 += 16u) {
            uint n = min(16u, e - i0);
            uint tx[16], ty[16];
            uint last = UINT_MAX, lx = 0u, ly = 0u;
            for (uint l = 0; l < 16u; ++l) {
                uint tile = tiles[(i0 + min(l, n - 1u)) / 64u];
                if (tile != last) {
                    last = tile;
                    lx = tile % tiles_x;
                    ly = tile / tiles_x;
                }
                tx[l] = lx;
                ty[l] = ly;
            }
            uint16 within = ((uint16)(i0) + SLUICE_LANE16) % 64u;
            uint16 x = vload16(0, tx) * 8u + (within >> 4 & 1u) * 4u + (within & 3u);
            uint16 y = vload16(0, ty) * 8u + (within >> 5) * 4u + (within >> 2 & 3u);
            int16 inside = (x < f.width) & (y < f.height);
            int ins[16];
            vstore16(inside, 0, ins);
            if (!SLUICE_WRITING) {
                for (uint l = 0; l < n; ++l)
                    (void)SLUICE_EMIT_INDEX(0, ins[l]);
                continue;
            }
            uint16 pixel = y * f.width + x;
            uint16 key = rt_key16(rt_key16((uint16)(f.seed), pixel), (uint16)(f.sample));
            float16 jx = (float16)(0.5f), jy = (float16)(0.5f);
            if (f.jitter) {
                jx = rt_rand16(key, 0u);
                jy = rt_rand16(key, 1u);
            }
            float16 px = convert_float16(x) + jx, py = convert_float16(y) + jy;
            float dx[16], dy[16], dz[16];
            uint pk[16], kk[16];
            vstore16(f.corner[0] + f.du[0] * px + f.dv[0] * py, 0, dx);
            vstore16(f.corner[1] + f.du[1] * px + f.dv[1] * py, 0, dy);
            vstore16(f.corner[2] + f.du[2] * px + f.dv[2] * py, 0, dz);
            vstore16(pixel, 0, pk);
            vstore16(key, 0, kk);
            for (uint l = 0; l < n; ++l) {
                uint at = SLUICE_EMIT_INDEX(0, ins[l]);
                if (!ins[l])
                    continue;
                float3 d = normalize((float3)(dx[l], dy[l], dz[l]));
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
                r.pixel = pk[l] + f.film_half;
                r.key = kk[l];
                r.flags = RT_KIND_EYE | RT_FLAG_COUNT_EMIT;
                r.pad0 = r.pad1 = 0u;
                rays[at] = r;
            }
        }
    }
}
