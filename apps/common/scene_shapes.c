/* Tessellated shapes for the builder: geodesic spheres, quads, boxes, rings
 * and the Utah teapot. Purcell's ray tracer takes triangles only (thesis
 * ch. 3.1: "all scene geometry is represented as triangles"), so every
 * shape becomes a mesh here and goes through sr_scene_builder_add_mesh,
 * with its validation and transform. */
#include "scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

static void set_err(char *err, size_t err_size, const char *msg, const char *what)
{
    if (err && err_size)
        snprintf(err, err_size, "%s: %s", what, msg);
}

/* Scratch arrays of one shape, freed together. */
typedef struct mesh_buf {
    float *pos, *nrm;
    uint32_t *idx;
    size_t nv, nt; /* filled so far */
} mesh_buf;

static int buf_alloc(mesh_buf *m, size_t nv, size_t nt, int normals)
{
    memset(m, 0, sizeof *m);
    m->pos = malloc(3 * nv * sizeof(float));
    m->nrm = normals ? malloc(3 * nv * sizeof(float)) : NULL;
    m->idx = malloc(3 * nt * sizeof(uint32_t));
    return m->pos && m->idx && (!normals || m->nrm);
}

static void buf_free(mesh_buf *m)
{
    free(m->pos);
    free(m->nrm);
    free(m->idx);
}

static uint32_t buf_vertex(mesh_buf *m, double x, double y, double z, double nx, double ny,
                           double nz)
{
    float *p = m->pos + 3 * m->nv;
    p[0] = (float)x;
    p[1] = (float)y;
    p[2] = (float)z;
    if (m->nrm) {
        float *n = m->nrm + 3 * m->nv;
        n[0] = (float)nx;
        n[1] = (float)ny;
        n[2] = (float)nz;
    }
    return (uint32_t)m->nv++;
}

static void buf_tri(mesh_buf *m, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t *t = m->idx + 3 * m->nt++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
}

/* Hands the finished buffer to the builder and frees it. */
static sluice_status buf_add(sr_scene_builder *b, mesh_buf *m, const char *source,
                             uint32_t material, const float *transform, char *err, size_t err_size)
{
    sr_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.source = source;
    d.positions = m->pos;
    d.vertex_count = m->nv;
    d.normals = m->nrm;
    d.indices = m->idx;
    d.triangle_count = m->nt;
    d.material = material;
    d.transform = transform;
    sluice_status st = sr_scene_builder_add_mesh(b, &d, err, err_size);
    buf_free(m);
    return st;
}

static int finite3(const float *v)
{
    return v && isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

/* ------------------------------------------------------------------ */
/* Geodesic sphere                                                     */
/* ------------------------------------------------------------------ */

/* The 12 icosahedron vertices are the cyclic permutations of (0, +-1, +-g)
 * with g the golden ratio; its 20 faces are the vertex triples at mutual
 * distance 2, found by search so no face table has to be typed in. */
static void icosahedron(double v[12][3], int f[20][3], int edge[12][12])
{
    const double g = (1.0 + sqrt(5.0)) / 2.0;
    int n = 0;
    for (int axis = 0; axis < 3; ++axis) {
        for (int s1 = -1; s1 <= 1; s1 += 2) {
            for (int s2 = -1; s2 <= 1; s2 += 2) {
                v[n][axis] = 0.0;
                v[n][(axis + 1) % 3] = s1;
                v[n][(axis + 2) % 3] = s2 * g;
                n++;
            }
        }
    }
    int nf = 0, ne = 0;
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j)
            edge[i][j] = -1;
    for (int i = 0; i < 12; ++i) {
        for (int j = i + 1; j < 12; ++j) {
            double d = 0.0;
            for (int k = 0; k < 3; ++k)
                d += (v[i][k] - v[j][k]) * (v[i][k] - v[j][k]);
            if (fabs(d - 4.0) < 1e-9)
                edge[i][j] = edge[j][i] = ne++;
        }
    }
    for (int i = 0; i < 12; ++i) {
        for (int j = i + 1; j < 12; ++j) {
            for (int k = j + 1; k < 12; ++k) {
                if (edge[i][j] < 0 || edge[j][k] < 0 || edge[i][k] < 0)
                    continue;
                /* orient counter-clockwise seen from outside */
                double e1[3], e2[3], c = 0.0;
                for (int a = 0; a < 3; ++a) {
                    e1[a] = v[j][a] - v[i][a];
                    e2[a] = v[k][a] - v[i][a];
                }
                for (int a = 0; a < 3; ++a) {
                    int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
                    c += (e1[a1] * e2[a2] - e1[a2] * e2[a1]) * (v[i][a] + v[j][a] + v[k][a]);
                }
                f[nf][0] = i;
                f[nf][1] = c > 0.0 ? j : k;
                f[nf][2] = c > 0.0 ? k : j;
                nf++;
            }
        }
    }
}

sluice_status sr_scene_builder_add_sphere(sr_scene_builder *b, const float center[3], float radius,
                                          unsigned frequency, uint32_t material,
                                          const float *transform, char *err, size_t err_size)
{
    if (!b || !finite3(center) || !(radius > 0.0f) || !isfinite(radius) || frequency < 1 ||
        frequency > 256) {
        set_err(err, err_size, "needs a finite center, radius > 0 and 1 <= frequency <= 256",
                "sphere");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    double v[12][3];
    int face[20][3], edge[12][12];
    icosahedron(v, face, edge);
    const size_t f = frequency;
    mesh_buf m;
    if (!buf_alloc(&m, 10 * f * f + 2, 20 * f * f, 1)) {
        buf_free(&m);
        set_err(err, err_size, "out of memory", "sphere");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    /* Vertex numbering: 12 corners, then f - 1 points on each of the 30
     * edges (from its lower-numbered corner), then each face's interior. A
     * shared point is made once, so the sphere is watertight. */
    uint32_t *lattice = malloc((f + 1) * (f + 1) * sizeof *lattice);
    if (!lattice) {
        buf_free(&m);
        set_err(err, err_size, "out of memory", "sphere");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    double cx = center[0], cy = center[1], cz = center[2], r = radius;
#define SPHERE_POINT(px, py, pz)                                                                   \
    do {                                                                                           \
        double l_ = sqrt((px) * (px) + (py) * (py) + (pz) * (pz));                                 \
        double ux_ = (px) / l_, uy_ = (py) / l_, uz_ = (pz) / l_;                                  \
        buf_vertex(&m, cx + r * ux_, cy + r * uy_, cz + r * uz_, ux_, uy_, uz_);                   \
    } while (0)
    for (int i = 0; i < 12; ++i)
        SPHERE_POINT(v[i][0], v[i][1], v[i][2]);
    for (int i = 0; i < 12; ++i) {
        for (int j = i + 1; j < 12; ++j) {
            if (edge[i][j] < 0)
                continue;
            for (size_t s = 1; s < f; ++s) {
                double a = (double)(f - s), c = (double)s;
                SPHERE_POINT(a * v[i][0] + c * v[j][0], a * v[i][1] + c * v[j][1],
                             a * v[i][2] + c * v[j][2]);
            }
        }
    }
    for (int t = 0; t < 20; ++t) {
        const double *A = v[face[t][0]], *B = v[face[t][1]], *C = v[face[t][2]];
        /* lattice point (i, j): weights (f - i - j, i, j) on (A, B, C) */
        for (size_t j = 0; j <= f; ++j) {
            for (size_t i = 0; i + j <= f; ++i) {
                size_t k = f - i - j;
                uint32_t id = 0;
                int ea = -1, eb = -1; /* corners of the edge the point is on */
                size_t along = 0;     /* steps from ea towards eb */
                if (i == 0 && j == 0)
                    id = (uint32_t)face[t][0];
                else if (i == f)
                    id = (uint32_t)face[t][1];
                else if (j == f)
                    id = (uint32_t)face[t][2];
                else if (j == 0)
                    ea = face[t][0], eb = face[t][1], along = i;
                else if (i == 0)
                    ea = face[t][0], eb = face[t][2], along = j;
                else if (k == 0)
                    ea = face[t][1], eb = face[t][2], along = j;
                if (ea >= 0) {
                    if (ea > eb) {
                        int tmp = ea;
                        ea = eb;
                        eb = tmp;
                        along = f - along;
                    }
                    id = (uint32_t)(12 + (size_t)edge[ea][eb] * (f - 1) + along - 1);
                } else if (i > 0 && j > 0 && k > 0) {
                    id = (uint32_t)m.nv;
                    SPHERE_POINT(k * A[0] + i * B[0] + j * C[0], k * A[1] + i * B[1] + j * C[1],
                                 k * A[2] + i * B[2] + j * C[2]);
                }
                lattice[j * (f + 1) + i] = id;
            }
        }
        for (size_t j = 0; j < f; ++j) {
            for (size_t i = 0; i + j < f; ++i) {
                uint32_t p00 = lattice[j * (f + 1) + i], p10 = lattice[j * (f + 1) + i + 1],
                         p01 = lattice[(j + 1) * (f + 1) + i];
                buf_tri(&m, p00, p10, p01);
                if (i + j + 1 < f)
                    buf_tri(&m, p10, lattice[(j + 1) * (f + 1) + i + 1], p01);
            }
        }
    }
#undef SPHERE_POINT
    free(lattice);
    return buf_add(b, &m, "sphere", material, transform, err, err_size);
}

/* ------------------------------------------------------------------ */
/* Quad, box, ring                                                     */
/* ------------------------------------------------------------------ */

sluice_status sr_scene_builder_add_quad(sr_scene_builder *b, const float corner[3],
                                        const float u[3], const float v[3], uint32_t material,
                                        const float *transform, char *err, size_t err_size)
{
    if (!b || !finite3(corner) || !finite3(u) || !finite3(v)) {
        set_err(err, err_size, "needs finite corner, u and v", "quad");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    float p[12];
    for (int k = 0; k < 3; ++k) {
        p[k] = corner[k];
        p[3 + k] = corner[k] + u[k];
        p[6 + k] = corner[k] + u[k] + v[k];
        p[9 + k] = corner[k] + v[k];
    }
    static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    sr_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.source = "quad";
    d.positions = p;
    d.vertex_count = 4;
    d.indices = idx;
    d.triangle_count = 2;
    d.material = material;
    d.transform = transform;
    return sr_scene_builder_add_mesh(b, &d, err, err_size);
}

sluice_status sr_scene_builder_add_box(sr_scene_builder *b, const float lo[3], const float hi[3],
                                       uint32_t material, const float *transform, char *err,
                                       size_t err_size)
{
    if (!b || !finite3(lo) || !finite3(hi) || !(lo[0] < hi[0] && lo[1] < hi[1] && lo[2] < hi[2])) {
        set_err(err, err_size, "needs finite corners with lo < hi on every axis", "box");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    /* corner c has x from bit 0, y from bit 1, z from bit 2 */
    float p[24];
    for (int c = 0; c < 8; ++c)
        for (int k = 0; k < 3; ++k)
            p[3 * c + k] = (c >> k) & 1 ? hi[k] : lo[k];
    uint32_t idx[36];
    int n = 0;
    for (int a = 0; a < 3; ++a) {
        int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
        for (int side = 0; side < 2; ++side) {
            /* e_a1 x e_a2 = e_a: (a1, a2) winds outward on the high side */
            int bu = 1 << (side ? a1 : a2), bv = 1 << (side ? a2 : a1), base = side << a;
            uint32_t q[4] = {(uint32_t)base, (uint32_t)(base | bu), (uint32_t)(base | bu | bv),
                             (uint32_t)(base | bv)};
            static const int order[6] = {0, 1, 2, 0, 2, 3};
            for (int k = 0; k < 6; ++k)
                idx[n++] = q[order[k]];
        }
    }
    sr_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.source = "box";
    d.positions = p;
    d.vertex_count = 8;
    d.indices = idx;
    d.triangle_count = 12;
    d.material = material;
    d.transform = transform;
    return sr_scene_builder_add_mesh(b, &d, err, err_size);
}

sluice_status sr_scene_builder_add_ring(sr_scene_builder *b, const float center[3], float radius,
                                        float thickness, float height, unsigned segments,
                                        uint32_t material, const float *transform, char *err,
                                        size_t err_size)
{
    if (!b || !finite3(center) || !isfinite(radius) || !isfinite(thickness) || !isfinite(height) ||
        !(thickness > 0.0f) || !(thickness < radius) || !(height > 0.0f) || segments < 3 ||
        segments > 65536) {
        set_err(err, err_size,
                "needs a finite center, 0 < thickness < radius, height > 0 and "
                "3 <= segments <= 65536",
                "ring");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    const size_t n = segments;
    mesh_buf m;
    if (!buf_alloc(&m, 8 * n, 8 * n, 1)) {
        buf_free(&m);
        set_err(err, err_size, "out of memory", "ring");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    const double ro = radius, ri = (double)radius - thickness, y0 = center[1],
                 y1 = (double)center[1] + height;
    /* 8 vertices per step: outer wall bottom/top, inner wall bottom/top (all
     * with radial normals), then top outer/inner and bottom outer/inner
     * (flat: zero normals). */
    for (size_t i = 0; i < n; ++i) {
        double a = 2.0 * PI * (double)i / (double)n, c = cos(a), s = sin(a);
        double xo = center[0] + ro * c, zo = center[2] + ro * s;
        double xi = center[0] + ri * c, zi = center[2] + ri * s;
        buf_vertex(&m, xo, y0, zo, c, 0, s);
        buf_vertex(&m, xo, y1, zo, c, 0, s);
        buf_vertex(&m, xi, y0, zi, -c, 0, -s);
        buf_vertex(&m, xi, y1, zi, -c, 0, -s);
        buf_vertex(&m, xo, y1, zo, 0, 0, 0);
        buf_vertex(&m, xi, y1, zi, 0, 0, 0);
        buf_vertex(&m, xo, y0, zo, 0, 0, 0);
        buf_vertex(&m, xi, y0, zi, 0, 0, 0);
    }
    for (size_t i = 0; i < n; ++i) {
        uint32_t a = (uint32_t)(8 * i), c = (uint32_t)(8 * ((i + 1) % n));
        /* outer wall faces out, inner wall faces the axis */
        buf_tri(&m, a + 0, a + 1, c + 0);
        buf_tri(&m, c + 0, a + 1, c + 1);
        buf_tri(&m, a + 2, c + 2, a + 3);
        buf_tri(&m, c + 2, c + 3, a + 3);
        /* top faces +y, bottom faces -y */
        buf_tri(&m, a + 4, a + 5, c + 4);
        buf_tri(&m, c + 4, a + 5, c + 5);
        buf_tri(&m, a + 6, c + 6, a + 7);
        buf_tri(&m, c + 6, c + 7, a + 7);
    }
    return buf_add(b, &m, "ring", material, transform, err, err_size);
}

/* ------------------------------------------------------------------ */
/* Utah teapot                                                         */
/* ------------------------------------------------------------------ */

/* Martin Newell's teapot (1975) as published by F. Crow, "The origins of the
 * teapot", IEEE CG&A 7(1), 1987, and distributed since as the 32-patch,
 * 306-point data set: 32 bicubic Bezier patches (rim 4, body 8, handle 4,
 * spout 4, lid 8, bottom 4), each 16 control points numbered from 1 (row by
 * row: row = u, column = v), z up. Points 205, 206, 216 and 223 are in the
 * published list but no patch uses them. Checked here (see tests): the rim,
 * body, lid and bottom patches are 90-degree rotations of each other, the
 * handle and spout halves are mirror images, and every shared patch edge is
 * traversed in opposite directions, so dv x du points outward everywhere. */
static const uint16_t teapot_patch[32][16] = {
    {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16},
    {4, 17, 18, 19, 8, 20, 21, 22, 12, 23, 24, 25, 16, 26, 27, 28},
    {19, 29, 30, 31, 22, 32, 33, 34, 25, 35, 36, 37, 28, 38, 39, 40},
    {31, 41, 42, 1, 34, 43, 44, 5, 37, 45, 46, 9, 40, 47, 48, 13},
    {13, 14, 15, 16, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59, 60},
    {16, 26, 27, 28, 52, 61, 62, 63, 56, 64, 65, 66, 60, 67, 68, 69},
    {28, 38, 39, 40, 63, 70, 71, 72, 66, 73, 74, 75, 69, 76, 77, 78},
    {40, 47, 48, 13, 72, 79, 80, 49, 75, 81, 82, 53, 78, 83, 84, 57},
    {57, 58, 59, 60, 85, 86, 87, 88, 89, 90, 91, 92, 93, 94, 95, 96},
    {60, 67, 68, 69, 88, 97, 98, 99, 92, 100, 101, 102, 96, 103, 104, 105},
    {69, 76, 77, 78, 99, 106, 107, 108, 102, 109, 110, 111, 105, 112, 113, 114},
    {78, 83, 84, 57, 108, 115, 116, 85, 111, 117, 118, 89, 114, 119, 120, 93},
    {121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132, 133, 134, 135, 136},
    {124, 137, 138, 121, 128, 139, 140, 125, 132, 141, 142, 129, 136, 143, 144, 133},
    {133, 134, 135, 136, 145, 146, 147, 148, 149, 150, 151, 152, 69, 153, 154, 155},
    {136, 143, 144, 133, 148, 156, 157, 145, 152, 158, 159, 149, 155, 160, 161, 69},
    {162, 163, 164, 165, 166, 167, 168, 169, 170, 171, 172, 173, 174, 175, 176, 177},
    {165, 178, 179, 162, 169, 180, 181, 166, 173, 182, 183, 170, 177, 184, 185, 174},
    {174, 175, 176, 177, 186, 187, 188, 189, 190, 191, 192, 193, 194, 195, 196, 197},
    {177, 184, 185, 174, 189, 198, 199, 186, 193, 200, 201, 190, 197, 202, 203, 194},
    {204, 204, 204, 204, 207, 208, 209, 210, 211, 211, 211, 211, 212, 213, 214, 215},
    {204, 204, 204, 204, 210, 217, 218, 219, 211, 211, 211, 211, 215, 220, 221, 222},
    {204, 204, 204, 204, 219, 224, 225, 226, 211, 211, 211, 211, 222, 227, 228, 229},
    {204, 204, 204, 204, 226, 230, 231, 207, 211, 211, 211, 211, 229, 232, 233, 212},
    {212, 213, 214, 215, 234, 235, 236, 237, 238, 239, 240, 241, 242, 243, 244, 245},
    {215, 220, 221, 222, 237, 246, 247, 248, 241, 249, 250, 251, 245, 252, 253, 254},
    {222, 227, 228, 229, 248, 255, 256, 257, 251, 258, 259, 260, 254, 261, 262, 263},
    {229, 232, 233, 212, 257, 264, 265, 234, 260, 266, 267, 238, 263, 268, 269, 242},
    {270, 270, 270, 270, 279, 280, 281, 282, 275, 276, 277, 278, 271, 272, 273, 274},
    {270, 270, 270, 270, 282, 289, 290, 291, 278, 286, 287, 288, 274, 283, 284, 285},
    {270, 270, 270, 270, 291, 298, 299, 300, 288, 295, 296, 297, 285, 292, 293, 294},
    {270, 270, 270, 270, 300, 305, 306, 279, 297, 303, 304, 275, 294, 301, 302, 271},
};

static const double teapot_point[306][3] = {
    {1.4, 0.0, 2.4},
    {1.4, -0.784, 2.4},
    {0.784, -1.4, 2.4},
    {0.0, -1.4, 2.4},
    {1.3375, 0.0, 2.53125},
    {1.3375, -0.749, 2.53125},
    {0.749, -1.3375, 2.53125},
    {0.0, -1.3375, 2.53125},
    {1.4375, 0.0, 2.53125},
    {1.4375, -0.805, 2.53125},
    {0.805, -1.4375, 2.53125},
    {0.0, -1.4375, 2.53125},
    {1.5, 0.0, 2.4},
    {1.5, -0.84, 2.4},
    {0.84, -1.5, 2.4},
    {0.0, -1.5, 2.4},
    {-0.784, -1.4, 2.4},
    {-1.4, -0.784, 2.4},
    {-1.4, 0.0, 2.4},
    {-0.749, -1.3375, 2.53125},
    {-1.3375, -0.749, 2.53125},
    {-1.3375, 0.0, 2.53125},
    {-0.805, -1.4375, 2.53125},
    {-1.4375, -0.805, 2.53125},
    {-1.4375, 0.0, 2.53125},
    {-0.84, -1.5, 2.4},
    {-1.5, -0.84, 2.4},
    {-1.5, 0.0, 2.4},
    {-1.4, 0.784, 2.4},
    {-0.784, 1.4, 2.4},
    {0.0, 1.4, 2.4},
    {-1.3375, 0.749, 2.53125},
    {-0.749, 1.3375, 2.53125},
    {0.0, 1.3375, 2.53125},
    {-1.4375, 0.805, 2.53125},
    {-0.805, 1.4375, 2.53125},
    {0.0, 1.4375, 2.53125},
    {-1.5, 0.84, 2.4},
    {-0.84, 1.5, 2.4},
    {0.0, 1.5, 2.4},
    {0.784, 1.4, 2.4},
    {1.4, 0.784, 2.4},
    {0.749, 1.3375, 2.53125},
    {1.3375, 0.749, 2.53125},
    {0.805, 1.4375, 2.53125},
    {1.4375, 0.805, 2.53125},
    {0.84, 1.5, 2.4},
    {1.5, 0.84, 2.4},
    {1.75, 0.0, 1.875},
    {1.75, -0.98, 1.875},
    {0.98, -1.75, 1.875},
    {0.0, -1.75, 1.875},
    {2.0, 0.0, 1.35},
    {2.0, -1.12, 1.35},
    {1.12, -2.0, 1.35},
    {0.0, -2.0, 1.35},
    {2.0, 0.0, 0.9},
    {2.0, -1.12, 0.9},
    {1.12, -2.0, 0.9},
    {0.0, -2.0, 0.9},
    {-0.98, -1.75, 1.875},
    {-1.75, -0.98, 1.875},
    {-1.75, 0.0, 1.875},
    {-1.12, -2.0, 1.35},
    {-2.0, -1.12, 1.35},
    {-2.0, 0.0, 1.35},
    {-1.12, -2.0, 0.9},
    {-2.0, -1.12, 0.9},
    {-2.0, 0.0, 0.9},
    {-1.75, 0.98, 1.875},
    {-0.98, 1.75, 1.875},
    {0.0, 1.75, 1.875},
    {-2.0, 1.12, 1.35},
    {-1.12, 2.0, 1.35},
    {0.0, 2.0, 1.35},
    {-2.0, 1.12, 0.9},
    {-1.12, 2.0, 0.9},
    {0.0, 2.0, 0.9},
    {0.98, 1.75, 1.875},
    {1.75, 0.98, 1.875},
    {1.12, 2.0, 1.35},
    {2.0, 1.12, 1.35},
    {1.12, 2.0, 0.9},
    {2.0, 1.12, 0.9},
    {2.0, 0.0, 0.45},
    {2.0, -1.12, 0.45},
    {1.12, -2.0, 0.45},
    {0.0, -2.0, 0.45},
    {1.5, 0.0, 0.225},
    {1.5, -0.84, 0.225},
    {0.84, -1.5, 0.225},
    {0.0, -1.5, 0.225},
    {1.5, 0.0, 0.15},
    {1.5, -0.84, 0.15},
    {0.84, -1.5, 0.15},
    {0.0, -1.5, 0.15},
    {-1.12, -2.0, 0.45},
    {-2.0, -1.12, 0.45},
    {-2.0, 0.0, 0.45},
    {-0.84, -1.5, 0.225},
    {-1.5, -0.84, 0.225},
    {-1.5, 0.0, 0.225},
    {-0.84, -1.5, 0.15},
    {-1.5, -0.84, 0.15},
    {-1.5, 0.0, 0.15},
    {-2.0, 1.12, 0.45},
    {-1.12, 2.0, 0.45},
    {0.0, 2.0, 0.45},
    {-1.5, 0.84, 0.225},
    {-0.84, 1.5, 0.225},
    {0.0, 1.5, 0.225},
    {-1.5, 0.84, 0.15},
    {-0.84, 1.5, 0.15},
    {0.0, 1.5, 0.15},
    {1.12, 2.0, 0.45},
    {2.0, 1.12, 0.45},
    {0.84, 1.5, 0.225},
    {1.5, 0.84, 0.225},
    {0.84, 1.5, 0.15},
    {1.5, 0.84, 0.15},
    {-1.6, 0.0, 2.025},
    {-1.6, -0.3, 2.025},
    {-1.5, -0.3, 2.25},
    {-1.5, 0.0, 2.25},
    {-2.3, 0.0, 2.025},
    {-2.3, -0.3, 2.025},
    {-2.5, -0.3, 2.25},
    {-2.5, 0.0, 2.25},
    {-2.7, 0.0, 2.025},
    {-2.7, -0.3, 2.025},
    {-3.0, -0.3, 2.25},
    {-3.0, 0.0, 2.25},
    {-2.7, 0.0, 1.8},
    {-2.7, -0.3, 1.8},
    {-3.0, -0.3, 1.8},
    {-3.0, 0.0, 1.8},
    {-1.5, 0.3, 2.25},
    {-1.6, 0.3, 2.025},
    {-2.5, 0.3, 2.25},
    {-2.3, 0.3, 2.025},
    {-3.0, 0.3, 2.25},
    {-2.7, 0.3, 2.025},
    {-3.0, 0.3, 1.8},
    {-2.7, 0.3, 1.8},
    {-2.7, 0.0, 1.575},
    {-2.7, -0.3, 1.575},
    {-3.0, -0.3, 1.35},
    {-3.0, 0.0, 1.35},
    {-2.5, 0.0, 1.125},
    {-2.5, -0.3, 1.125},
    {-2.65, -0.3, 0.9375},
    {-2.65, 0.0, 0.9375},
    {-2.0, -0.3, 0.9},
    {-1.9, -0.3, 0.6},
    {-1.9, 0.0, 0.6},
    {-3.0, 0.3, 1.35},
    {-2.7, 0.3, 1.575},
    {-2.65, 0.3, 0.9375},
    {-2.5, 0.3, 1.125},
    {-1.9, 0.3, 0.6},
    {-2.0, 0.3, 0.9},
    {1.7, 0.0, 1.425},
    {1.7, -0.66, 1.425},
    {1.7, -0.66, 0.6},
    {1.7, 0.0, 0.6},
    {2.6, 0.0, 1.425},
    {2.6, -0.66, 1.425},
    {3.1, -0.66, 0.825},
    {3.1, 0.0, 0.825},
    {2.3, 0.0, 2.1},
    {2.3, -0.25, 2.1},
    {2.4, -0.25, 2.025},
    {2.4, 0.0, 2.025},
    {2.7, 0.0, 2.4},
    {2.7, -0.25, 2.4},
    {3.3, -0.25, 2.4},
    {3.3, 0.0, 2.4},
    {1.7, 0.66, 0.6},
    {1.7, 0.66, 1.425},
    {3.1, 0.66, 0.825},
    {2.6, 0.66, 1.425},
    {2.4, 0.25, 2.025},
    {2.3, 0.25, 2.1},
    {3.3, 0.25, 2.4},
    {2.7, 0.25, 2.4},
    {2.8, 0.0, 2.475},
    {2.8, -0.25, 2.475},
    {3.525, -0.25, 2.49375},
    {3.525, 0.0, 2.49375},
    {2.9, 0.0, 2.475},
    {2.9, -0.15, 2.475},
    {3.45, -0.15, 2.5125},
    {3.45, 0.0, 2.5125},
    {2.8, 0.0, 2.4},
    {2.8, -0.15, 2.4},
    {3.2, -0.15, 2.4},
    {3.2, 0.0, 2.4},
    {3.525, 0.25, 2.49375},
    {2.8, 0.25, 2.475},
    {3.45, 0.15, 2.5125},
    {2.9, 0.15, 2.475},
    {3.2, 0.15, 2.4},
    {2.8, 0.15, 2.4},
    {0.0, 0.0, 3.15},
    {0.0, -0.002, 3.15},
    {0.002, 0.0, 3.15},
    {0.8, 0.0, 3.15},
    {0.8, -0.45, 3.15},
    {0.45, -0.8, 3.15},
    {0.0, -0.8, 3.15},
    {0.0, 0.0, 2.85},
    {0.2, 0.0, 2.7},
    {0.2, -0.112, 2.7},
    {0.112, -0.2, 2.7},
    {0.0, -0.2, 2.7},
    {-0.002, 0.0, 3.15},
    {-0.45, -0.8, 3.15},
    {-0.8, -0.45, 3.15},
    {-0.8, 0.0, 3.15},
    {-0.112, -0.2, 2.7},
    {-0.2, -0.112, 2.7},
    {-0.2, 0.0, 2.7},
    {0.0, 0.002, 3.15},
    {-0.8, 0.45, 3.15},
    {-0.45, 0.8, 3.15},
    {0.0, 0.8, 3.15},
    {-0.2, 0.112, 2.7},
    {-0.112, 0.2, 2.7},
    {0.0, 0.2, 2.7},
    {0.45, 0.8, 3.15},
    {0.8, 0.45, 3.15},
    {0.112, 0.2, 2.7},
    {0.2, 0.112, 2.7},
    {0.4, 0.0, 2.55},
    {0.4, -0.224, 2.55},
    {0.224, -0.4, 2.55},
    {0.0, -0.4, 2.55},
    {1.3, 0.0, 2.55},
    {1.3, -0.728, 2.55},
    {0.728, -1.3, 2.55},
    {0.0, -1.3, 2.55},
    {1.3, 0.0, 2.4},
    {1.3, -0.728, 2.4},
    {0.728, -1.3, 2.4},
    {0.0, -1.3, 2.4},
    {-0.224, -0.4, 2.55},
    {-0.4, -0.224, 2.55},
    {-0.4, 0.0, 2.55},
    {-0.728, -1.3, 2.55},
    {-1.3, -0.728, 2.55},
    {-1.3, 0.0, 2.55},
    {-0.728, -1.3, 2.4},
    {-1.3, -0.728, 2.4},
    {-1.3, 0.0, 2.4},
    {-0.4, 0.224, 2.55},
    {-0.224, 0.4, 2.55},
    {0.0, 0.4, 2.55},
    {-1.3, 0.728, 2.55},
    {-0.728, 1.3, 2.55},
    {0.0, 1.3, 2.55},
    {-1.3, 0.728, 2.4},
    {-0.728, 1.3, 2.4},
    {0.0, 1.3, 2.4},
    {0.224, 0.4, 2.55},
    {0.4, 0.224, 2.55},
    {0.728, 1.3, 2.55},
    {1.3, 0.728, 2.55},
    {0.728, 1.3, 2.4},
    {1.3, 0.728, 2.4},
    {0.0, 0.0, 0.0},
    {1.5, 0.0, 0.15},
    {1.5, 0.84, 0.15},
    {0.84, 1.5, 0.15},
    {0.0, 1.5, 0.15},
    {1.5, 0.0, 0.075},
    {1.5, 0.84, 0.075},
    {0.84, 1.5, 0.075},
    {0.0, 1.5, 0.075},
    {1.425, 0.0, 0.0},
    {1.425, 0.798, 0.0},
    {0.798, 1.425, 0.0},
    {0.0, 1.425, 0.0},
    {-0.84, 1.5, 0.15},
    {-1.5, 0.84, 0.15},
    {-1.5, 0.0, 0.15},
    {-0.84, 1.5, 0.075},
    {-1.5, 0.84, 0.075},
    {-1.5, 0.0, 0.075},
    {-0.798, 1.425, 0.0},
    {-1.425, 0.798, 0.0},
    {-1.425, 0.0, 0.0},
    {-1.5, -0.84, 0.15},
    {-0.84, -1.5, 0.15},
    {0.0, -1.5, 0.15},
    {-1.5, -0.84, 0.075},
    {-0.84, -1.5, 0.075},
    {0.0, -1.5, 0.075},
    {-1.425, -0.798, 0.0},
    {-0.798, -1.425, 0.0},
    {0.0, -1.425, 0.0},
    {0.84, -1.5, 0.15},
    {1.5, -0.84, 0.15},
    {0.84, -1.5, 0.075},
    {1.5, -0.84, 0.075},
    {0.798, -1.425, 0.0},
    {1.425, -0.798, 0.0},
};

static void bernstein(double t, double b[4], double db[4])
{
    double s = 1.0 - t;
    b[0] = s * s * s;
    b[1] = 3.0 * t * s * s;
    b[2] = 3.0 * t * t * s;
    b[3] = t * t * t;
    db[0] = -3.0 * s * s;
    db[1] = 3.0 * s * s - 6.0 * t * s;
    db[2] = 6.0 * t * s - 3.0 * t * t;
    db[3] = 3.0 * t * t;
}

/* Evaluates patch `p` at (u, v): position and dv x du (the outward
 * normal, unnormalised). */
static void teapot_eval(int p, double u, double v, double pos[3], double nrm[3])
{
    double bu[4], dbu[4], bv[4], dbv[4], du[3] = {0, 0, 0}, dv[3] = {0, 0, 0};
    bernstein(u, bu, dbu);
    bernstein(v, bv, dbv);
    pos[0] = pos[1] = pos[2] = 0.0;
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
            const double *q = teapot_point[teapot_patch[p][4 * r + c] - 1];
            for (int k = 0; k < 3; ++k) {
                pos[k] += bu[r] * bv[c] * q[k];
                du[k] += dbu[r] * bv[c] * q[k];
                dv[k] += bu[r] * dbv[c] * q[k];
            }
        }
    }
    nrm[0] = dv[1] * du[2] - dv[2] * du[1];
    nrm[1] = dv[2] * du[0] - dv[0] * du[2];
    nrm[2] = dv[0] * du[1] - dv[1] * du[0];
}

/* When grid point (i, j) lies on a patch edge whose four control points are
 * one point (the lid's knob, the bottom's centre), returns that point: the
 * Bernstein weights do not sum to exactly 1 in floating point, and the
 * collapsed triangles are recognised by equal corners. NULL otherwise. */
static const double *teapot_pinned(int p, size_t i, size_t j, size_t n)
{
    const uint16_t *q = teapot_patch[p];
    int edges[4][4] = {{0, 1, 2, 3}, {12, 13, 14, 15}, {0, 4, 8, 12}, {3, 7, 11, 15}};
    int on[4] = {i == 0, i == n, j == 0, j == n};
    for (int e = 0; e < 4; ++e) {
        if (on[e] && q[edges[e][0]] == q[edges[e][1]] && q[edges[e][0]] == q[edges[e][2]] &&
            q[edges[e][0]] == q[edges[e][3]])
            return teapot_point[q[edges[e][0]] - 1];
    }
    return NULL;
}

sluice_status sr_scene_builder_add_teapot(sr_scene_builder *b, unsigned n, uint32_t material,
                                          const float *transform, char *err, size_t err_size)
{
    if (!b || n < 2 || n > 64) {
        set_err(err, err_size, "needs 2 <= n <= 64 quads per patch side", "teapot");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    const size_t g = (size_t)n + 1;
    mesh_buf m;
    if (!buf_alloc(&m, 32 * g * g, 32 * 2 * (size_t)n * n, 1)) {
        buf_free(&m);
        set_err(err, err_size, "out of memory", "teapot");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    for (int p = 0; p < 32; ++p) {
        uint32_t base = (uint32_t)m.nv;
        for (size_t i = 0; i <= n; ++i) {
            for (size_t j = 0; j <= n; ++j) {
                double u = (double)i / n, v = (double)j / n, pos[3], nr[3], dummy[3];
                teapot_eval(p, u, v, pos, nr);
                const double *pin = teapot_pinned(p, i, j, n);
                if (pin)
                    memcpy(pos, pin, sizeof pos);
                double l = sqrt(nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2]);
                if (!(l > 1e-9)) {
                    /* a collapsed edge (the lid's knob, the bottom's centre):
                     * take the normal a little way into the patch */
                    teapot_eval(p, u + (u < 0.5 ? 1e-4 : -1e-4), v + (v < 0.5 ? 1e-4 : -1e-4),
                                dummy, nr);
                    l = sqrt(nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2]);
                }
                if (!(l > 0.0))
                    l = 1.0, nr[0] = nr[1] = nr[2] = 0.0;
                /* y up: (x, y, z) -> (x, z, -y), a rotation about x */
                buf_vertex(&m, pos[0], pos[2], -pos[1], nr[0] / l, nr[2] / l, -nr[1] / l);
            }
        }
        for (size_t i = 0; i < n; ++i) {
            for (size_t j = 0; j < n; ++j) {
                uint32_t a = base + (uint32_t)(i * g + j), d = a + 1, bb = a + (uint32_t)g,
                         c = bb + 1;
                /* (a, d, b) runs along v then u: its normal is dv x du */
                const float *pa = m.pos + 3 * (size_t)a, *pd = m.pos + 3 * (size_t)d,
                            *pb = m.pos + 3 * (size_t)bb, *pc = m.pos + 3 * (size_t)c;
                if (memcmp(pa, pd, 3 * sizeof(float)) != 0 &&
                    memcmp(pa, pb, 3 * sizeof(float)) != 0)
                    buf_tri(&m, a, d, bb);
                if (memcmp(pd, pc, 3 * sizeof(float)) != 0 &&
                    memcmp(pc, pb, 3 * sizeof(float)) != 0)
                    buf_tri(&m, d, c, bb);
            }
        }
    }
    return buf_add(b, &m, "teapot", material, transform, err, err_size);
}
