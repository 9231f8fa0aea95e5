/* The photons and queries of the kNN benchmarks (bench_knn, bench_knn_ab):
 * the surfaces of a Cornell-box-like scene in the unit box (five walls and
 * the visible sides and tops of two boxes), 80% of the photons uniform on
 * them by area and 20% in a bright caustic-like spot on the floor; the
 * queries are points on the same surfaces, uniform by area (what eye rays
 * would hit), in random order. Deterministic: the same arrays every run. */
#ifndef SLUICE_BENCH_KNN_SCENE_H
#define SLUICE_BENCH_KNN_SCENE_H

#include "knn.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

static inline uint32_t bench_knn_rnd(uint32_t *s)
{
    uint32_t x = *s;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *s = x;
}

static inline float bench_knn_frand(uint32_t *s)
{
    return (float)(bench_knn_rnd(s) >> 8) * (1.0f / 16777216.0f);
}

/* A quad: corner o, edges u and v. */
typedef struct bench_knn_quad {
    float o[3], u[3], v[3];
} bench_knn_quad;

/* The surfaces: floor, ceiling, back, left and right walls of [0,1]^3, and
 * the four visible sides and tops of two boxes. At most 16. */
static inline size_t bench_knn_quads(bench_knn_quad *q)
{
    size_t n = 0;
    q[n++] = (bench_knn_quad){{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
    q[n++] = (bench_knn_quad){{0, 1, 0}, {1, 0, 0}, {0, 0, 1}};
    q[n++] = (bench_knn_quad){{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
    q[n++] = (bench_knn_quad){{0, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    q[n++] = (bench_knn_quad){{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    /* short box 0.15..0.45 x 0..0.3 x 0.2..0.5, tall box 0.55..0.85 x 0..0.6 x 0.5..0.8 */
    const float b[2][5] = {{0.15f, 0.45f, 0.3f, 0.2f, 0.5f}, {0.55f, 0.85f, 0.6f, 0.5f, 0.8f}};
    for (int i = 0; i < 2; ++i) {
        float x0 = b[i][0], x1 = b[i][1], h = b[i][2], z0 = b[i][3], z1 = b[i][4];
        q[n++] = (bench_knn_quad){{x0, h, z0}, {x1 - x0, 0, 0}, {0, 0, z1 - z0}};
        q[n++] = (bench_knn_quad){{x0, 0, z0}, {x1 - x0, 0, 0}, {0, h, 0}};
        q[n++] = (bench_knn_quad){{x0, 0, z0}, {0, h, 0}, {0, 0, z1 - z0}};
        q[n++] = (bench_knn_quad){{x1, 0, z0}, {0, h, 0}, {0, 0, z1 - z0}};
    }
    return n;
}

static inline double bench_knn_quad_area(const bench_knn_quad *q)
{
    double c[3] = {q->u[1] * q->v[2] - q->u[2] * q->v[1], q->u[2] * q->v[0] - q->u[0] * q->v[2],
                   q->u[0] * q->v[1] - q->u[1] * q->v[0]};
    return sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
}

/* A point on the surfaces, uniform by area (cdf: the quads' running areas). */
static inline void bench_knn_surface_point(const bench_knn_quad *q, const double *cdf, size_t nq,
                                           uint32_t *s, float p[3])
{
    double u = bench_knn_frand(s) * cdf[nq - 1];
    size_t i = 0;
    while (i + 1 < nq && cdf[i] < u)
        ++i;
    float a = bench_knn_frand(s), b = bench_knn_frand(s);
    for (int k = 0; k < 3; ++k)
        p[k] = q[i].o[k] + a * q[i].u[k] + b * q[i].v[k];
}

/* Fills np photons (ph, and their positions as xyz triples in pos) and nq
 * queries. Returns the surfaces' area. */
static inline double bench_knn_scene(pm_photon *ph, float *pos, size_t np, pm_query *qs, size_t nq)
{
    bench_knn_quad q[16];
    size_t nquads = bench_knn_quads(q);
    double cdf[16], area = 0.0;
    for (size_t i = 0; i < nquads; ++i)
        cdf[i] = area += bench_knn_quad_area(&q[i]);
    uint32_t seed = 1;
    for (size_t i = 0; i < np; ++i) {
        float p[3];
        if (i % 5 == 0) {
            float a = 6.2831853f * bench_knn_frand(&seed),
                  rr = 0.08f * sqrtf(bench_knn_frand(&seed));
            p[0] = 0.7f + rr * cosf(a), p[1] = 0.0f, p[2] = 0.3f + rr * sinf(a);
        } else {
            bench_knn_surface_point(q, cdf, nquads, &seed, p);
        }
        ph[i].px = pos[3 * i] = p[0];
        ph[i].py = pos[3 * i + 1] = p[1];
        ph[i].pz = pos[3 * i + 2] = p[2];
        ph[i].pr = ph[i].pg = ph[i].pb = 1.0f / (float)np;
        ph[i].dy = -1.0f;
    }
    for (size_t i = 0; i < nq; ++i) {
        float p[3];
        bench_knn_surface_point(q, cdf, nquads, &seed, p);
        qs[i].px = p[0], qs[i].py = p[1], qs[i].pz = p[2];
        qs[i].ny = 1.0f;
        qs[i].id = (uint32_t)i;
    }
    return area;
}

#endif /* SLUICE_BENCH_KNN_SCENE_H */
