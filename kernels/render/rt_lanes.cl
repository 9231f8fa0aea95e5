/*
 * rt_lanes.cl: 16 rays in the lanes of one work-item, the form in which both
 * execution modes (rt_stream.cl, rt_fused.cl) do their heavy work.
 *
 * PoCL runs the work-items of a group one after another on a CPU core, and a
 * loop whose trip count differs per ray (the DDA, a triangle list) keeps it
 * from vectorising across them. So a work-item takes its rays 16 at a time,
 * one per lane of 16-wide vectors. Every lane runs exactly the operations of
 * the scalar functions of rt_trace.cl (same order, no contraction), so a
 * ray's voxels, tests and hit do not depend on which mode or path ran it.
 * Loads of per-lane addresses are AVX-512 gathers, or two 8-lane AVX2
 * gathers, where the compiler offers them (PoCL builds for the host CPU),
 * plain loads otherwise.
 */

#if defined(SLUICE_AVX512_) && __has_builtin(__builtin_ia32_gathersiv16sf) &&                      \
    __has_builtin(__builtin_ia32_gathersiv16si)
#define RT_GATHER512_ 1
#endif

#if defined(SLUICE_AVX512_) && __has_builtin(__builtin_ia32_permvarsf512)
#define RT_PERMUTE512_ 1
#endif

#if defined(SLUICE_AVX2_) && __has_builtin(__builtin_ia32_gatherd_ps256) &&                        \
    __has_builtin(__builtin_ia32_gatherd_d256) && __has_builtin(__builtin_ia32_permvarsf256)
#define RT_AVX2_ 1
#endif

/* p[idx] in the lanes where m is set (0 elsewhere; nothing is read there). */
inline float16 rt_gather_f(global const float *p, int16 idx, int16 m)
{
#ifdef RT_GATHER512_
    return __builtin_ia32_gathersiv16sf((float16)0.0f, (const void *)(size_t)p, idx,
                                        sluice_mask16(m), 4);
#elif defined(RT_AVX2_)
    const float *q = (const float *)(size_t)p;
    float8 lo = __builtin_ia32_gatherd_ps256((float8)0.0f, q, idx.lo, as_float8(m.lo), 4);
    float8 hi = __builtin_ia32_gatherd_ps256((float8)0.0f, q, idx.hi, as_float8(m.hi), 4);
    return (float16)(lo, hi);
#else
    int ix[16], mk[16];
    float r[16];
    vstore16(idx, 0, ix);
    vstore16(m, 0, mk);
    for (int k = 0; k < 16; ++k)
        r[k] = mk[k] ? p[ix[k]] : 0.0f;
    return vload16(0, r);
#endif
}

inline int16 rt_gather_i(global const uint *p, int16 idx, int16 m)
{
#ifdef RT_GATHER512_
    return __builtin_ia32_gathersiv16si((int16)0, (const void *)(size_t)p, idx, sluice_mask16(m),
                                        4);
#elif defined(RT_AVX2_)
    const int *q = (const int *)(size_t)p;
    int8 lo = __builtin_ia32_gatherd_d256((int8)0, q, idx.lo, m.lo, 4);
    int8 hi = __builtin_ia32_gatherd_d256((int8)0, q, idx.hi, m.hi, 4);
    return (int16)(lo, hi);
#else
    int ix[16], mk[16], r[16];
    vstore16(idx, 0, ix);
    vstore16(m, 0, mk);
    for (int k = 0; k < 16; ++k)
        r[k] = mk[k] ? (int)p[ix[k]] : 0;
    return vload16(0, r);
#endif
}

/* The list bounds cell_start[ci] and cell_start[ci + 1] of voxels ci in the
 * lanes where m is set (0 elsewhere). With AVX-512 or AVX2 each pair is one
 * 8-byte gather element (two 8-lane or four 4-lane gathers): half the
 * elements of gathering the two bounds apart, and a gather costs about a
 * cycle an element. */
inline void rt_cell_bounds16(global const uint *cell_start, int16 ci, int16 m, int16 *a, int16 *b)
{
#if defined(RT_GATHER512_) && __has_builtin(__builtin_ia32_gathersiv8di)
    ushort k = sluice_mask16(m);
    const void *base = (const void *)(size_t)cell_start;
    long8 lo = __builtin_ia32_gathersiv8di((long8)0, base, ci.lo, (uchar)k, 4);
    long8 hi = __builtin_ia32_gathersiv8di((long8)0, base, ci.hi, (uchar)(k >> 8), 4);
    int16 l = as_int16(lo), h = as_int16(hi);
    *a = __builtin_shufflevector(l, h, 0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    *b = __builtin_shufflevector(l, h, 1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31);
#elif defined(RT_AVX2_) && __has_builtin(__builtin_ia32_gatherd_q256)
    const long *base = (const long *)(size_t)cell_start;
    long4 q0 = __builtin_ia32_gatherd_q256((long4)0, base, ci.s0123, convert_long4(m.s0123), 4);
    long4 q1 = __builtin_ia32_gatherd_q256((long4)0, base, ci.s4567, convert_long4(m.s4567), 4);
    long4 q2 = __builtin_ia32_gatherd_q256((long4)0, base, ci.s89ab, convert_long4(m.s89ab), 4);
    long4 q3 = __builtin_ia32_gatherd_q256((long4)0, base, ci.scdef, convert_long4(m.scdef), 4);
    int16 l = (int16)(as_int8(q0), as_int8(q1)), h = (int16)(as_int8(q2), as_int8(q3));
    *a = __builtin_shufflevector(l, h, 0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    *b = __builtin_shufflevector(l, h, 1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31);
#else
    *a = rt_gather_i(cell_start, ci, m);
    *b = rt_gather_i(cell_start, ci + 1, m);
#endif
}

/* The number of the lowest set bit of m (m != 0). */
inline int rt_lowest_bit(uint m)
{
    return 31 - (int)clz(m & (0u - m));
}

/* The value of x in the first lane set in mask am (am != 0). */
inline int rt_first_lane(int16 x, ushort am)
{
#ifdef SLUICE_AVX512_
    int16 c = __builtin_ia32_compresssi512_mask(x, (int16)0, am);
    return c.s0;
#else
    int l[16];
    vstore16(x, 0, l);
    return l[rt_lowest_bit((uint)am)];
#endif
}

/* Lane l of x in every lane. */
inline float16 rt_lane_bcast(float16 x, int l)
{
#if defined(RT_PERMUTE512_)
    return __builtin_ia32_permvarsf512(x, (int16)l);
#elif defined(RT_AVX2_)
    float8 r = __builtin_ia32_permvarsf256(l < 8 ? x.lo : x.hi, (int8)(l & 7));
    return (float16)(r, r);
#else
    float a[16];
    vstore16(x, 0, a);
    return (float16)a[l];
#endif
}

/* Whether any lane of a mask (lanes 0 or -1) is set: one mask test on
 * AVX-512 or two sign-bit gathers on AVX2 (the generic any() tests sign
 * bits lane by lane there). */
inline int rt_any16(int16 m)
{
#if defined(SLUICE_AVX512_) || defined(SLUICE_AVX2_)
    return sluice_mask16(m) != 0;
#else
    return any(m);
#endif
}

/* The sum of the 16 lanes of x. */
inline uint rt_sum16(uint16 x)
{
    uint8 a = x.lo + x.hi;
    uint4 b = a.lo + a.hi;
    return b.x + b.y + b.z + b.w;
}

/* rt_any16 for 8 lanes (one AVX2 register). */
inline int rt_any8(int8 m)
{
#if defined(SLUICE_AVX2_)
    return __builtin_ia32_movmskps256(as_float8(m)) != 0;
#else
    return any(m);
#endif
}

/* Records of n 4-byte fields written for 16 rays at once: field j of the 16
 * rays is a vector, and the 16n words of the records are n vectors made by
 * two-vector permutes (Clang's, PoCL's compiler), each stored whole, where a
 * loop over the rays takes a scalar load and store per word. Elsewhere the
 * callers loop. */
#if defined(__has_builtin)
#if __has_builtin(__builtin_shufflevector)
#define RT_AOS16_ 1
#endif
#endif

#ifdef RT_AOS16_
/* Word i of output vector k, n fields a record, as an index into the pair
 * of field vectors (2j, 2j + 1) that holds it: record (16k + i) / n, the
 * pair's second vector for an odd field. */
#define RT_AOS_W_(n, k, i) (((16 * (k) + (i)) / (n)) + 16 * (((16 * (k) + (i)) % (n)) & 1))
#define RT_AOS_W16_(n, k)                                                                          \
    RT_AOS_W_(n, k, 0), RT_AOS_W_(n, k, 1), RT_AOS_W_(n, k, 2), RT_AOS_W_(n, k, 3),                \
        RT_AOS_W_(n, k, 4), RT_AOS_W_(n, k, 5), RT_AOS_W_(n, k, 6), RT_AOS_W_(n, k, 7),            \
        RT_AOS_W_(n, k, 8), RT_AOS_W_(n, k, 9), RT_AOS_W_(n, k, 10), RT_AOS_W_(n, k, 11),          \
        RT_AOS_W_(n, k, 12), RT_AOS_W_(n, k, 13), RT_AOS_W_(n, k, 14), RT_AOS_W_(n, k, 15)
/* The pair holding word i of output vector k: 0, 1 or 2. */
#define RT_AOS_PAIR_(n, k)                                                                         \
    ((((int16)(16 * (k)) + (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15)) % (n)) / \
     2)

/* Output vector k of records of 4 fields w[0..3]. */
#define RT_AOS4_VEC_(w, k)                                                                         \
    select(__builtin_shufflevector(w[2], w[3], RT_AOS_W16_(4, k)),                                 \
           __builtin_shufflevector(w[0], w[1], RT_AOS_W16_(4, k)), RT_AOS_PAIR_(4, k) == 0)
/* Output vector k of records of 6 fields w[0..5]. */
#define RT_AOS6_VEC_(w, k)                                                                         \
    select(select(__builtin_shufflevector(w[4], w[5], RT_AOS_W16_(6, k)),                          \
                  __builtin_shufflevector(w[2], w[3], RT_AOS_W16_(6, k)),                          \
                  RT_AOS_PAIR_(6, k) == 1),                                                        \
           __builtin_shufflevector(w[0], w[1], RT_AOS_W16_(6, k)), RT_AOS_PAIR_(6, k) == 0)

/* 16 consecutive rt_hit records at out, field by field from vectors. */
inline void rt_store_hits16(global rt_hit *out, int16 tri, float16 t, float16 u, float16 v,
                            uint16 steps, uint16 tests)
{
    global uint *o = (global uint *)out;
    uint16 w[6] = {as_uint16(tri), as_uint16(t), as_uint16(u), as_uint16(v), steps, tests};
    vstore16(RT_AOS6_VEC_(w, 0), 0, o);
    vstore16(RT_AOS6_VEC_(w, 1), 1, o);
    vstore16(RT_AOS6_VEC_(w, 2), 2, o);
    vstore16(RT_AOS6_VEC_(w, 3), 3, o);
    vstore16(RT_AOS6_VEC_(w, 4), 4, o);
    vstore16(RT_AOS6_VEC_(w, 5), 5, o);
}

/* 16 consecutive rt_walk records at out. */
inline void rt_store_walks16(global rt_walk *out, int16 cx, int16 cy, int16 cz, uint16 pos)
{
    global uint *o = (global uint *)out;
    uint16 w[4] = {as_uint16(cx), as_uint16(cy), as_uint16(cz), pos};
    vstore16(RT_AOS4_VEC_(w, 0), 0, o);
    vstore16(RT_AOS4_VEC_(w, 1), 1, o);
    vstore16(RT_AOS4_VEC_(w, 2), 2, o);
    vstore16(RT_AOS4_VEC_(w, 3), 3, o);
}
#endif

/* The rays of a packet, one per lane (as rt_rayp), and the best hits. */
typedef struct rt_packet {
    float16 ox, oy, oz, dx, dy, dz, ix, iy, iz, tmin, tmax;
    int16 any_hit;
    int16 tri; /* RT_NO_HIT as -1 */
    float16 t, u, v;
} rt_packet;

/* The smallest and the largest value of x in the lanes where m is set. */
inline int2 rt_minmax16(int16 x, int16 m)
{
    int16 lo = select((int16)INT_MAX, x, m), hi = select((int16)INT_MIN, x, m);
    int8 l8 = min(lo.lo, lo.hi), h8 = max(hi.lo, hi.hi);
    int4 l4 = min(l8.lo, l8.hi), h4 = max(h8.lo, h8.hi);
    int2 l2 = min(l4.lo, l4.hi), h2 = max(h4.lo, h4.hi);
    return (int2)(min(l2.x, l2.y), max(h2.x, h2.y));
}

/* The rest of a packet's load, its rays' o, d, tmin and tmax read: the
 * inverse directions, the any-hit flags (from the rays' flags), no hit yet. */
inline void rt_packet_start_(rt_packet *P, int16 flags)
{
    P->ix = select((float16)0.0f, 1.0f / P->dx, P->dx != 0.0f);
    P->iy = select((float16)0.0f, 1.0f / P->dy, P->dy != 0.0f);
    P->iz = select((float16)0.0f, 1.0f / P->dz, P->dz != 0.0f);
    P->any_hit = (flags & (int)RT_FLAG_ANY_HIT) != 0;
    P->tri = (int16)(-1);
    P->t = P->tmax;
    P->u = (float16)0.0f;
    P->v = (float16)0.0f;
}

/* Loads rays idx[l] (in the lanes where live is set) as rt_prepare does, with
 * no hit yet: tri -1 (RT_NO_HIT), t = tmax. */
inline void rt_packet_load(global const rt_ray *rays, int16 idx, int16 live, rt_packet *P)
{
    global const float *rf = (global const float *)rays;
    int16 at = idx * (int)(sizeof(rt_ray) / sizeof(float));
    P->ox = rt_gather_f(rf, at, live);
    P->oy = rt_gather_f(rf, at + 1, live);
    P->oz = rt_gather_f(rf, at + 2, live);
    P->dx = rt_gather_f(rf, at + 3, live);
    P->dy = rt_gather_f(rf, at + 4, live);
    P->dz = rt_gather_f(rf, at + 5, live);
    P->tmin = rt_gather_f(rf, at + 6, live);
    P->tmax = rt_gather_f(rf, at + 7, live);
    rt_packet_start_(P, rt_gather_i((global const uint *)rf, at + 13, live));
}

#ifdef RT_AOS16_
/* Stage s of an 8x8 transpose in each half of 16 lanes, on rows a (bit s of
 * the row clear) and b: lane L of each as an index into (a, b). */
#define RT_TR_A_(s, L) (((L) & (1 << (s))) ? 16 + (L) - (1 << (s)) : (L))
#define RT_TR_B_(s, L) (((L) & (1 << (s))) ? 16 + (L) : (L) + (1 << (s)))
#define RT_TR16_(M, s)                                                                             \
    M(s, 0), M(s, 1), M(s, 2), M(s, 3), M(s, 4), M(s, 5), M(s, 6), M(s, 7), M(s, 8), M(s, 9),      \
        M(s, 10), M(s, 11), M(s, 12), M(s, 13), M(s, 14), M(s, 15)
#define RT_TR_PAIR_(a, b, s)                                                                       \
    do {                                                                                           \
        float16 a_ = (a), b_ = (b);                                                                \
        (a) = __builtin_shufflevector(a_, b_, RT_TR16_(RT_TR_A_, s));                              \
        (b) = __builtin_shufflevector(a_, b_, RT_TR16_(RT_TR_B_, s));                              \
    } while (0)
/* Stage s on the four row pairs (a, b), (c, d), (e, f), (g, h). */
#define RT_TR_STAGE_(s, a, b, c, d, e, f, g, h)                                                    \
    do {                                                                                           \
        RT_TR_PAIR_(a, b, s);                                                                      \
        RT_TR_PAIR_(c, d, s);                                                                      \
        RT_TR_PAIR_(e, f, s);                                                                      \
        RT_TR_PAIR_(g, h, s);                                                                      \
    } while (0)
/* The first 8 fields of rays r and r + 8 of 16 at p, side by side. */
#define RT_TR_ROWS_(p, r)                                                                          \
    __builtin_shufflevector(vload16((r), (p)), vload16((r) + 8, (p)), 0, 1, 2, 3, 4, 5, 6, 7, 16,  \
                            17, 18, 19, 20, 21, 22, 23)

/* rt_packet_load for the 16 rays from `first` on. A ray record is one
 * 64-byte line, so each ray is one vector load, and the 8 fields the packet
 * takes (o, d, tmin, tmax) are turned into 8 vectors of 16 lanes by three
 * stages of permutes, where 8 gathers take 16 loads each (measured in
 * bench/README.md). */
inline void rt_packet_load_run(global const rt_ray *rays, uint first, rt_packet *P)
{
    global const float *rf = (global const float *)(rays + first);
    float16 x0 = RT_TR_ROWS_(rf, 0), x1 = RT_TR_ROWS_(rf, 1), x2 = RT_TR_ROWS_(rf, 2);
    float16 x3 = RT_TR_ROWS_(rf, 3), x4 = RT_TR_ROWS_(rf, 4), x5 = RT_TR_ROWS_(rf, 5);
    float16 x6 = RT_TR_ROWS_(rf, 6), x7 = RT_TR_ROWS_(rf, 7);
    /* rows 2^s apart pair up at stage s */
    RT_TR_STAGE_(0, x0, x1, x2, x3, x4, x5, x6, x7);
    RT_TR_STAGE_(1, x0, x2, x1, x3, x4, x6, x5, x7);
    RT_TR_STAGE_(2, x0, x4, x1, x5, x2, x6, x3, x7);
    P->ox = x0;
    P->oy = x1;
    P->oz = x2;
    P->dx = x3;
    P->dy = x4;
    P->dz = x5;
    P->tmin = x6;
    P->tmax = x7;
    int16 lane = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    rt_packet_start_(P, rt_gather_i((global const uint *)rf, lane * 16 + 13, (int16)(-1)));
}
#endif

/* rt_voxel_exit in 16 lanes: the exit parameter of voxel (cx, cy, cz) and the
 * axis (0, 1, 2) the ray leaves it through. */
inline float16 rt_voxel_exit16(const rt_grid_args *g, const rt_packet *P, int16 cx, int16 cy,
                               int16 cz, int16 *axis)
{
    /* the far faces: c + (d > 0) (a vector compare is -1 for true) */
    float16 bx = g->lo[0] + convert_float16(cx - (P->dx > 0.0f)) * g->cell[0];
    float16 by = g->lo[1] + convert_float16(cy - (P->dy > 0.0f)) * g->cell[1];
    float16 bz = g->lo[2] + convert_float16(cz - (P->dz > 0.0f)) * g->cell[2];
    float16 tx = select((float16)INFINITY, (bx - P->ox) * P->ix, P->dx != 0.0f);
    float16 ty = select((float16)INFINITY, (by - P->oy) * P->iy, P->dy != 0.0f);
    float16 tz = select((float16)INFINITY, (bz - P->oz) * P->iz, P->dz != 0.0f);
    int16 my = ty < tx;
    float16 t = select(tx, ty, my);
    int16 mz = tz < t;
    t = select(t, tz, mz);
    *axis = select(select((int16)0, (int16)1, my), (int16)2, mz);
    return t;
}

/* The cell index of voxel (cx, cy, cz) (rt_cell_index). */
inline int16 rt_cell_index16(const rt_grid_args *g, int16 cx, int16 cy, int16 cz)
{
    return as_int16(as_uint16(cx) +
                    (uint)g->dims[0] * (as_uint16(cy) + (uint)g->dims[1] * as_uint16(cz)));
}

#ifndef RT_WATERTIGHT
/* a b - c d, and a b + c d + e f, rounded as rt_cross and rt_dot round
 * (any vector width). */
#define RT_FMS_(a, b, c, d) fma((a), (b), -((c) * (d)))
#define RT_DOT_(a, b, c, d, e, f) fma((e), (f), fma((c), (d), (a) * (b)))

/* The Moller-Trumbore test of rt_intersect_tri, lanewise on vectors of type
 * F (floats) and I (ints) of one width: rays (o, d, tmin) against triangles
 * (v0, e1, e2) in the lanes of mask m, keeping hits nearer than t and not
 * past limit in (tri, t, u, v), which are lvalues. With quit set (a
 * constant) it stops after u when `any` (rt_any16 or rt_any8) finds no lane
 * left (rt_intersect16_core); with pre set too, before u's division when a
 * conservative test finds none (16 lanes: cornell's shadow rays 8-12%
 * faster with AVX-512 kernels; with AVX2's halves of 8, 2.5% slower on
 * cornell's eye rays, so they go without; bench/README.md). */
#define RT_MT_(F, I, quit, pre, any, itri, mask, ox, oy, oz, dx, dy, dz, tmin, limit, tri, t, u,   \
               v, v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z)                                     \
    do {                                                                                           \
        F pvx_ = RT_FMS_(dy, e2z, dz, e2y), pvy_ = RT_FMS_(dz, e2x, dx, e2z),                      \
          pvz_ = RT_FMS_(dx, e2y, dy, e2x);                                                        \
        F det_ = RT_DOT_(e1x, pvx_, e1y, pvy_, e1z, pvz_);                                         \
        I m_ = (mask) & (det_ != 0.0f);                                                            \
        F sx_ = (ox) - (v0x), sy_ = (oy) - (v0y), sz_ = (oz) - (v0z);                              \
        F un_ = RT_DOT_(sx_, pvx_, sy_, pvy_, sz_, pvz_);                                          \
        if ((quit) && (pre)) {                                                                     \
            /* before the division: lanes whose u = un / det is surely out                         \
             * of [0, 1] (un against det's sign below -2^-100 |det| or above                       \
             * (1 + 2^-20) |det|: the rounded u below is then out too), so                         \
             * that a triangle no lane can hit costs no division */                                \
            F ad_ = fabs(det_), su_ = select(un_, -un_, det_ < 0.0f);                              \
            if (!any(m_ & ~((su_ < ad_ * -0x1p-100f) | (su_ > ad_ * (1.0f + 0x1p-20f)))))          \
                break;                                                                             \
        }                                                                                          \
        F inv_ = 1.0f / det_;                                                                      \
        F u_ = un_ * inv_;                                                                         \
        m_ &= ~((u_ < 0.0f) | (u_ > 1.0f));                                                        \
        if ((quit) && !any(m_))                                                                    \
            break;                                                                                 \
        F qx_ = RT_FMS_(sy_, e1z, sz_, e1y), qy_ = RT_FMS_(sz_, e1x, sx_, e1z),                    \
          qz_ = RT_FMS_(sx_, e1y, sy_, e1x);                                                       \
        F v_ = RT_DOT_(dx, qx_, dy, qy_, dz, qz_) * inv_;                                          \
        m_ &= ~((v_ < 0.0f) | (u_ + v_ > 1.0f));                                                   \
        F t_ = RT_DOT_(e2x, qx_, e2y, qy_, e2z, qz_) * inv_;                                       \
        m_ &= (t_ >= (tmin)) & (t_ <= (limit)) & (t_ < (t));                                       \
        tri = select(tri, itri, m_);                                                               \
        t = select(t, t_, m_);                                                                     \
        u = select(u, u_, m_);                                                                     \
        v = select(v, v_, m_);                                                                     \
    } while (0)

/* RT_MT_ on the half h (lo or hi) of 16 lanes, 8 lanes wide. */
#define RT_MT_HALF_(h, quit, tri, m, P, limit, v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z)        \
    RT_MT_(float8, int8, quit, 0, rt_any8, (tri).h, (m).h, (P)->ox.h, (P)->oy.h, (P)->oz.h,        \
           (P)->dx.h, (P)->dy.h, (P)->dz.h, (P)->tmin.h, (limit).h, (P)->tri.h, (P)->t.h,          \
           (P)->u.h, (P)->v.h, (v0x).h, (v0y).h, (v0z).h, (e1x).h, (e1y).h, (e1z).h, (e2x).h,      \
           (e2y).h, (e2z).h)

/* The Moller-Trumbore test of rt_intersect_tri in the lanes where m is set,
 * against the triangle (v0, e1, e2) of each lane; keeps hits in P. With
 * AVX2 the 16 lanes go as two halves of 8, each one register wide: on
 * 16-lane vectors the compiler packed the comparisons' masks into bytes and
 * unpacked them for every select. With quit (a constant) the test stops
 * after u when no lane passes it: where the lanes are coherent rays, most
 * triangles that one tests the others miss as well (a voxel's list
 * broadcast to a packet in that voxel), and elsewhere the branch costs more
 * than it saves (bench/README.md). */
__attribute__((always_inline)) inline void
rt_intersect16_core(int16 tri, int16 m, rt_packet *P, float16 limit, float16 v0x, float16 v0y,
                    float16 v0z, float16 e1x, float16 e1y, float16 e1z, float16 e2x, float16 e2y,
                    float16 e2z, int quit)
{
#ifdef RT_AVX2_
    /* a half with no lane to test is skipped: short lists in the turned
     * test (rt_intersect16_turned), small groups of rays */
    uint mm = sluice_mask16(m);
    if (mm & 0xffu)
        RT_MT_HALF_(lo, quit, tri, m, P, limit, v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z);
    if (mm >> 8)
        RT_MT_HALF_(hi, quit, tri, m, P, limit, v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z);
#else
    RT_MT_(float16, int16, quit, 1, rt_any16, tri, m, P->ox, P->oy, P->oz, P->dx, P->dy, P->dz,
           P->tmin, limit, P->tri, P->t, P->u, P->v, v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z);
#endif
}

/* rt_intersect16 for one triangle that every lane of m tests (broadcast);
 * quit as for rt_intersect16_core. */
__attribute__((always_inline)) inline void
rt_intersect16_one(global const float *tv, uint tri, int16 m, rt_packet *P, float16 limit, int quit)
{
    global const float *q = tv + 9u * (size_t)tri;
    /* v0, e1, e2 one float at a time: each is a broadcast load */
    rt_intersect16_core((int16)(int)tri, m, P, limit, (float16)q[0], (float16)q[1], (float16)q[2],
                        (float16)q[3], (float16)q[4], (float16)q[5], (float16)q[6], (float16)q[7],
                        (float16)q[8], quit);
}

#ifdef RT_LIST_COPY
/* rt_intersect16_one for the triangle of entry r of the list copy (the
 * layout of rt_intersect16_turned), broadcast. */
__attribute__((always_inline)) inline void
rt_intersect16_copy_one(global const float *r, int16 m, rt_packet *P, float16 limit, int quit)
{
    rt_intersect16_core((int16)as_int(r[9 * RT_LIST_STRIDE]), m, P, limit, (float16)r[0],
                        (float16)r[RT_LIST_STRIDE], (float16)r[2 * RT_LIST_STRIDE],
                        (float16)r[3 * RT_LIST_STRIDE], (float16)r[4 * RT_LIST_STRIDE],
                        (float16)r[5 * RT_LIST_STRIDE], (float16)r[6 * RT_LIST_STRIDE],
                        (float16)r[7 * RT_LIST_STRIDE], (float16)r[8 * RT_LIST_STRIDE], quit);
}
#endif

/* The records (v0, e1, e2) of triangles tri in the lanes of m, gathered:
 * r[0..2] v0, r[3..5] e1, r[6..8] e2. */
__attribute__((always_inline)) inline void rt_tri_gather16(global const float *tv, int16 tri,
                                                           int16 m, float16 r[9])
{
    int16 at = tri * 9;
    for (int j = 0; j < 9; ++j)
        r[j] = rt_gather_f(tv, at + j, m);
}

/* rt_intersect_tri (Moller-Trumbore) in the lanes where m is set. When all of
 * them test the same triangle (coherent rays), its vertices are read once
 * and broadcast instead of gathered. */
__attribute__((always_inline)) inline void rt_intersect16(global const float *tv, int16 tri,
                                                          int16 m, rt_packet *P, float16 limit)
{
    int2 mm = rt_minmax16(tri, m);
    if (mm.x == mm.y) {
        rt_intersect16_one(tv, (uint)mm.x, m, P, limit, 0);
        return;
    }
    float16 r[9];
    rt_tri_gather16(tv, tri, m, r);
    rt_intersect16_core(tri, m, P, limit, r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], 0);
}

/* The lanes of m (not empty) whose list starts where the list of the first
 * lane of m starts: a position in cell_tris belongs to one voxel, so equal
 * starts mean the same list. Writes that start and the smallest and the
 * largest end among the group's lanes (ends differ only in the stream mode,
 * whose passes stop after m tests). */
inline int16 rt_list_group(int16 m, int16 from, int16 to, uint *start, int2 *span)
{
    int f0 = rt_first_lane(from, sluice_mask16(m));
    int16 in = m & (from == f0);
    *start = (uint)f0;
    *span = rt_minmax16(to, in);
    return in;
}

/* The lanes of a group (rt_list_group) test their list one triangle at a
 * time, each triangle read once with scalar loads and broadcast to the lanes
 * still inside their range. With the list copy (`lists`, the layout of
 * rt_intersect16_turned) a list's records are neighbours, plane by plane,
 * where each entry of cell_tris sends the loads to a record of its own. */
__attribute__((always_inline)) inline void
rt_intersect16_group(global const float *tv, global const float *lists,
                     global const uint *cell_tris, int16 in, uint start, int2 span, int16 to,
                     rt_packet *P, float16 limit)
{
    for (uint k = start; k < (uint)span.y; ++k) {
        int16 lm = in;
        if (span.x != span.y)
            lm &= as_uint16(to) > k;
#ifdef RT_LIST_COPY
        if (lists)
            rt_intersect16_copy_one(lists + k, lm, P, limit, 0);
        else
#endif
            rt_intersect16_one(tv, cell_tris[k], lm, P, limit, 0);
    }
#ifndef RT_LIST_COPY
    (void)lists;
#endif
}

/* Lanes of m test the triangles cell_tris[from .. to) of their lists, in
 * order (rt_intersect_list). The first RT_GROUPS groups of lanes with the
 * same list (rt_list_group) have each triangle broadcast to them, and only
 * lanes left over gather a triangle each per round. Broadcasting beats
 * gathering: RT_GROUPS 4 against 0 measured 18% faster on cornell and 16% on
 * bunny (fused mode, 512x512 primary rays, one process). */
#ifndef RT_GROUPS
#define RT_GROUPS 4
#endif
__attribute__((always_inline)) inline void rt_intersect16_lists(global const float *tv,
                                                                global const uint *cell_tris,
                                                                int16 from, int16 to, int16 m,
                                                                rt_packet *P, float16 limit)
{
    m &= as_uint16(from) < as_uint16(to);
    for (int grp = 0; grp < RT_GROUPS && rt_any16(m); ++grp) {
        uint start;
        int2 span;
        int16 in = rt_list_group(m, from, to, &start, &span);
        rt_intersect16_group(tv, 0, cell_tris, in, start, span, to, P, limit);
        m &= ~in;
    }
    if (rt_any16(m)) {
        int16 k = from;
        do {
            int16 tri = rt_gather_i(cell_tris, k, m);
            rt_intersect16(tv, tri, m, P, limit);
            k += 1;
            m &= as_uint16(k) < as_uint16(to);
        } while (rt_any16(m));
    }
}

/* The test turned around, for groups of few lanes: each lane of the group in
 * turn tests up to 16 triangles of its list at once, one per lane, its own
 * ray broadcast. A lane's hit is then the nearest of those, the first in
 * list order among equals, which is what testing them one after another
 * (rt_intersect_list) keeps, so the hits are the same.
 *
 * The triangles come from `lists`, a copy of the triangle records in list
 * order (built with RT_LIST_COPY: ten planes of RT_LIST_STRIDE floats, the
 * nine of the record and the triangle index, so 16 neighbours are one load
 * per plane), or, when `lists` is 0, are gathered through cell_tris: 8%
 * slower on bunny's fused walk. */
inline void rt_intersect16_turned(global const float *tv, global const float *lists,
                                  global const uint *cell_tris, int16 in, uint start, uint end,
                                  int16 to, rt_packet *P, float16 limit)
{
    int16 lane = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    for (uint k = start; k < end; k += 16u) {
        int16 cm = lane < (int)(end - k);
        int16 tri;
        float16 r[9];
#ifdef RT_LIST_COPY
        if (lists) {
            tri = as_int16(vload16(0, lists + k + 9 * RT_LIST_STRIDE));
            for (int j = 0; j < 9; ++j)
                r[j] = vload16(0, lists + k + j * RT_LIST_STRIDE);
        } else
#endif
        {
            tri = rt_gather_i(cell_tris, (int)k + lane, cm);
            rt_tri_gather16(tv, tri, cm, r);
        }
        uint todo = (uint)sluice_mask16(in & (as_uint16(to) > k));
        while (todo) {
            int l = rt_lowest_bit(todo);
            todo &= todo - 1u;
            rt_packet Q; /* lane l's ray in every lane */
            Q.ox = rt_lane_bcast(P->ox, l);
            Q.oy = rt_lane_bcast(P->oy, l);
            Q.oz = rt_lane_bcast(P->oz, l);
            Q.dx = rt_lane_bcast(P->dx, l);
            Q.dy = rt_lane_bcast(P->dy, l);
            Q.dz = rt_lane_bcast(P->dz, l);
            Q.tmin = rt_lane_bcast(P->tmin, l);
            Q.t = rt_lane_bcast(P->t, l);
            Q.tri = (int16)(-1);
            uint lend = (uint)rt_first_lane(to, (ushort)(1u << l));
            rt_intersect16_core(tri, cm & (lane < (int)(lend - k)), &Q, rt_lane_bcast(limit, l),
                                r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], 0);
            int16 hit = Q.tri != -1;
            ushort hm = sluice_mask16(hit);
            if (hm) {
                /* the nearest; the first of equals (list order) */
                float16 th = select((float16)INFINITY, Q.t, hit);
                float8 t8 = fmin(th.lo, th.hi);
                float4 t4 = fmin(t8.lo, t8.hi);
                float2 t2 = fmin(t4.lo, t4.hi);
                float tn = fmin(t2.x, t2.y);
                uint eq = (uint)(hm & sluice_mask16(Q.t == tn));
                int j = rt_lowest_bit(eq);
                int16 sel = lane == l;
                P->tri = select(P->tri, (int16)rt_first_lane(Q.tri, (ushort)(1u << j)), sel);
                P->t = select(P->t, (float16)tn, sel);
                P->u = select(P->u, rt_lane_bcast(Q.u, j), sel);
                P->v = select(P->v, rt_lane_bcast(Q.v, j), sel);
            }
        }
    }
}

/* rt_intersect16_lists where lanes seldom share a list (the fused mode's
 * walk, the stream mode's intersect passes): every group of lanes with the
 * same list takes the cheaper way, by the count of 16-lane tests each
 * needs: a broadcast test per triangle (rt_intersect16_group) or a turned
 * test per lane and 16 triangles (rt_intersect16_turned; `lists` as there).
 * On bunny a fused packet meets about 2.7 such groups of 1 to 8 lanes and
 * about 10 triangles each: 28 broadcast tests, or 8 with each group's
 * cheaper way. */
__attribute__((always_inline)) inline void
rt_intersect16_lists_either(global const float *tv, global const float *lists,
                            global const uint *cell_tris, int16 from, int16 to, int16 m,
                            rt_packet *P, float16 limit)
{
    m &= as_uint16(from) < as_uint16(to);
    while (rt_any16(m)) {
        uint start;
        int2 span;
        int16 in = rt_list_group(m, from, to, &start, &span);
        uint lanes = popcount((uint)sluice_mask16(in)), n = (uint)span.y - start;
        if (lanes * ((n + 15u) / 16u) < n)
            rt_intersect16_turned(tv, lists, cell_tris, in, start, (uint)span.y, to, P, limit);
        else
            rt_intersect16_group(tv, lists, cell_tris, in, start, span, to, P, limit);
        m &= ~in;
    }
}
#endif /* RT_WATERTIGHT */
