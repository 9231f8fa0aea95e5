/* The kNN-grid search (apps/photonmap/knn.c; Purcell 6.2.3, Fig. 6.6).
 * sr_program_create prepends rt_types.h, pg_types.h (the point grid's cell
 * function, shared with its build) and pm_types.h.
 *
 * Per call, pm_knn_gather copies the photons in cell order (a row of cells
 * along x is then one run of photons) and pm_knn_sat_* sum the cell counts
 * (any box of cells is counted with eight reads). One pass = pm_knn_pass
 * over the live query ids, each exploring one more shell of cells (the
 * cells at Chebyshev distance `shells` from the query's cell; shells and
 * faces without photons are jumped over by the counts) and deciding whether
 * it is done, then pm_knn_live, which emits those still searching into the
 * next live stream. Live streams hold places in the search order (queries
 * sorted by cell, pm_knn_order_keys), order[place] the query. The heavy work is in a kernel without
 * conditional outputs, since an emitting body runs twice. */
#include "sluice.cl"

/* Squared distance from x to where the photons of cell j of an axis of n
 * cells can lie, shrunk by the margin: the cell's slab (the boundary cells
 * reach to infinity: points outside the box are clamped into them) cut to
 * the photons' bounding box [blo, bhi]. */
static inline float pm_gap2(float x, int j, int n, float lo, float cell, float margin, float blo,
                            float bhi)
{
    float l = j > 0 ? fmax(lo + (float)j * cell, blo) : blo;
    float h = j < n - 1 ? fmin(lo + (float)(j + 1) * cell, bhi) : bhi;
    float gap = x < l ? l - x : (x > h ? x - h : 0.0f);
    gap -= margin;
    return gap > 0.0f ? gap * gap : 0.0f;
}

/* Squared distance from the point to the photons' bounding box, shrunk by
 * the margins: no photon is nearer. */
static inline float pm_box_d2(const float *qp, const pm_knn_params *p)
{
    float d2 = 0.0f;
    for (int a = 0; a < 3; ++a) {
        float gap = qp[a] < p->box_lo[a] ? p->box_lo[a] - qp[a]
                                         : (qp[a] > p->box_hi[a] ? qp[a] - p->box_hi[a] : 0.0f);
        gap -= p->margin[a];
        d2 += gap > 0.0f ? gap * gap : 0.0f;
    }
    return d2;
}

/* A photon's squared distance from a query, and the dot product of the
 * normal filter, as every kernel here computes them at every width: the
 * same fused multiply-adds (the program's FP_CONTRACT is off, pg_types.h,
 * so nothing else is fused), so that a radius one search sets from a
 * photon holds that photon in another, and test_knn's host references
 * (fmaf) agree bit for bit. Three operations each where products and sums
 * took five. */
#define PM_D2_(dx, dy, dz) fma((dz), (dz), fma((dy), (dy), (dx) * (dx)))
#define PM_DOT_(nx, ny, nz, x, y, z) fma((nz), (z), fma((ny), (y), (nx) * (x)))

/* Narrows the cells [*a, *b] of an axis to those whose slab may lie within
 * sqrt(t) of x, by the cell function (monotonic in x), where t is what a
 * bound on the squared distance leaves along this axis. The reach takes in
 * the rounding: t and a photon's squared distance are sums of three rounded
 * terms, each within a few ulps of the bound, and the margin covers the
 * cell function's own rounding. (Widening by a whole cell each way instead
 * examined 14% more photons on Purcell's cornell.) */
#define PM_REACH_(t, bound, margin) (sqrt(fmax((t), 0.0f) + (bound)*0x1p-18f) + (margin))

static inline void pm_trim(float x, float t, float bound, float lo, float inv_cell, uint n,
                           float margin, int *a, int *b)
{
    float reach = PM_REACH_(t, bound, margin);
    *a = max(*a, (int)pg_axis(x - reach, lo, inv_cell, n));
    *b = min(*b, (int)pg_axis(x + reach, lo, inv_cell, n));
}

/* The summed count at cell (x, y, z): the photons of the cells [0, x] x
 * [0, y] x [0, z] (pm_knn_sat_*); 0 below the grid. */
static inline uint pm_sat_at(global const uint *sat, const int *n, int x, int y, int z)
{
    if (x < 0 || y < 0 || z < 0)
        return 0u;
    return sat[(uint)x + (uint)n[0] * ((uint)y + (uint)n[1] * (uint)z)];
}

/* Photons in the cells [x0, x1] x [y0, y1] x [z0, z1] (inclusive) by
 * inclusion-exclusion; unsigned wrap-around keeps it exact. */
static inline uint pm_box(global const uint *sat, const int *n, int x0, int x1, int y0, int y1,
                          int z0, int z1)
{
    --x0;
    --y0;
    --z0;
    return pm_sat_at(sat, n, x1, y1, z1) - pm_sat_at(sat, n, x0, y1, z1) -
           pm_sat_at(sat, n, x1, y0, z1) - pm_sat_at(sat, n, x1, y1, z0) +
           pm_sat_at(sat, n, x0, y0, z1) + pm_sat_at(sat, n, x0, y1, z0) +
           pm_sat_at(sat, n, x1, y0, z0) - pm_sat_at(sat, n, x0, y0, z0);
}

/* Photons in the cube of cells [qc - s, qc + s], clipped to the grid. */
static inline uint pm_cube_count(global const uint *sat, const int *qc, int s, const int *n)
{
    return pm_box(sat, n, max(qc[0] - s, 0), min(qc[0] + s, n[0] - 1), max(qc[1] - s, 0),
                  min(qc[1] + s, n[1] - 1), max(qc[2] - s, 0), min(qc[2] + s, n[2] - 1));
}

/* The cells within reach of radius^2 r2 about qp (the sweep's box [b0, b1]):
 * returns how many shells about qc they span, and sets *covered when they
 * are the whole grid. */
static inline int pm_reach_cells(const float *qp, float r2, const int *qc, const int *n,
                                 const pg_params *g, const pm_knn_params *p, int *b0, int *b1,
                                 int *covered)
{
    int ext = 0;
    *covered = 1;
    for (int a = 0; a < 3; ++a) {
        b0[a] = 0;
        b1[a] = n[a] - 1;
        pm_trim(qp[a], r2, r2, g->lo[a], g->inv_cell[a], g->dims[a], p->margin[a], &b0[a], &b1[a]);
        *covered &= b0[a] == 0 && b1[a] == n[a] - 1;
        ext = max(ext, max(qc[a] - b0[a], b1[a] - qc[a]));
    }
    return ext;
}

/* The cube of shells 0 .. u about qc, clipped to the grid, as a box. */
static inline void pm_cube_cells(const int *qc, int u, const int *n, int *b0, int *b1)
{
    for (int a = 0; a < 3; ++a) {
        b0[a] = max(qc[a] - u, 0);
        b1[a] = min(qc[a] + u, n[a] - 1);
    }
}

/* The last shell about qc that holds cells of the grid (at least s). */
static inline int pm_last_shell(const int *qc, const int *n, int s)
{
    for (int a = 0; a < 3; ++a)
        s = max(s, max(qc[a], n[a] - 1 - qc[a]));
    return s;
}

/* Where a box of shells from s on ends (pm_knn_pass, pm_knn_reach): at the
 * first shell v >= s where the caller's test says stop, 1 when shell v
 * would let the search reach k photons (by the summed counts: the box ends
 * at v - 1) or 2 when the search ends at v (its cube reaches the maximum
 * radius or covers the grid: the box ends at v). Both only turn true as v
 * grows, and the grid's last shell covers it, so v is found by doubling
 * steps and then halving them; one shell at a time, crossing many shells
 * without photons near the maximum radius took most of pm_knn_reach's own
 * time. The caller asks:
 *   pm_box_end f = pm_box_end_start(s, last);
 *   for (int v; pm_box_end_next(&f, &v);) pm_box_end_tell(&f, test(v));
 *   u = pm_box_end_last(&f);   (s - 1: no box) */
typedef struct pm_box_end {
    int lo, hi, last, step, r, probe; /* no stop up to lo, a stop r at hi (-1: not yet) */
} pm_box_end;

static inline pm_box_end pm_box_end_start(int s, int last)
{
    pm_box_end f = {s - 1, -1, last, 1, 0, s};
    return f;
}

static inline int pm_box_end_next(const pm_box_end *f, int *v)
{
    *v = f->probe;
    return f->hi < 0 || f->hi - f->lo > 1;
}

static inline void pm_box_end_tell(pm_box_end *f, int r)
{
    if (r || f->probe >= f->last) {
        f->hi = f->probe;
        f->r = r;
    } else {
        f->lo = f->probe;
    }
    if (f->hi < 0) {
        f->probe = min(f->lo + f->step, f->last);
        f->step *= 2;
    } else {
        f->probe = f->lo + (f->hi - f->lo) / 2;
    }
}

static inline int pm_box_end_last(const pm_box_end *f)
{
    return f->r == 1 ? f->hi - 1 : f->hi;
}

/* Face `side` (0 .. 5: -x, +x, -y, +y, -z, +z) of shell s about cell qc as
 * a box of cells [b0, b1], each cell of the shell in one face only: the
 * faces across x whole, those across y without the x faces' cells, those
 * across z without either. Returns 0 for a face outside the grid, empty or
 * without photons (by the summed counts). */
static inline int pm_face(global const uint *sat, const int *qc, int s, const int *n, int side,
                          int *b0, int *b1)
{
    int a = side >> 1, at = (side & 1) ? qc[a] + s : qc[a] - s;
    if (at < 0 || at >= n[a] || ((side & 1) && s == 0))
        return 0;
    for (int c = 0; c < 3; ++c) {
        /* axes before a: inside the faces already done */
        b0[c] = c == a ? at : max(qc[c] - s + (c > a ? 0 : 1), 0);
        b1[c] = c == a ? at : min(qc[c] + s - (c > a ? 0 : 1), n[c] - 1);
    }
    return b0[0] <= b1[0] && b0[1] <= b1[1] && b0[2] <= b1[2] &&
           pm_box(sat, n, b0[0], b1[0], b0[1], b1[1], b0[2], b1[2]) != 0u;
}

/* The explored cube [qc - s, qc + s]: the square of its inscribed radius d_s
 * (shrunk by the margin), and whether it covers the grid (a side on the
 * grid's boundary is infinitely far: nothing lies beyond it; then d_s is
 * infinite). No photon outside the cube is nearer than d_s, nor nearer than
 * the photons' bounding box: the larger of the two is returned. */
static inline float pm_cube_d2(const float *qp, const int *qc, int s, const int *n,
                               const pg_params *g, const pm_knn_params *p, int *covered)
{
    float d = INFINITY;
    *covered = 1;
    for (int a = 0; a < 3; ++a) {
        if (qc[a] - s > 0) {
            *covered = 0;
            d = fmin(d, qp[a] - (g->lo[a] + (float)(qc[a] - s) * g->cell[a]) - p->margin[a]);
        }
        if (qc[a] + s < n[a] - 1) {
            *covered = 0;
            d = fmin(d, g->lo[a] + (float)(qc[a] + s + 1) * g->cell[a] - qp[a] - p->margin[a]);
        }
    }
    return *covered ? INFINITY : fmax(d > 0.0f ? d * d : 0.0f, pm_box_d2(qp, p));
}

/* A query's running estimate while it is in a kernel. */
typedef struct pm_state {
    float px, py, pz, nx, ny, nz;
    float sr, sg, sb, r2;
    float gx; /* squared distance along x to the photons' box (pm_gap2) */
    uint count, flags, q;
    global float *hd; /* exact: heap of squared distances (max at 0) */
    global uint *hi;  /* exact: heap of places in the cell-ordered map */
} pm_state;

/* The squared distance beyond which nothing can enter the estimate now. */
static inline float pm_bound(const pm_state *st, const pm_knn_params *p, uint exact)
{
    if (exact)
        return st->count == p->k ? st->hd[0] : p->max_r2;
    return st->count >= p->k ? st->r2 : p->max_r2;
}

/* Jensen's max-heap of the k nearest: push while not full, else replace
 * the farthest when closer. */
static inline void pm_heap_add(pm_state *st, uint k, float d2, uint id)
{
    global float *hd = st->hd;
    global uint *hi = st->hi;
    uint j;
    if (st->count < k) {
        j = st->count++;
        while (j > 0u) {
            uint parent = (j - 1u) / 2u;
            if (hd[parent] >= d2)
                break;
            hd[j] = hd[parent];
            hi[j] = hi[parent];
            j = parent;
        }
    } else {
        if (!(d2 < hd[0]))
            return;
        j = 0u;
        for (;;) {
            uint c = 2u * j + 1u;
            if (c >= k)
                break;
            if (c + 1u < k && hd[c + 1u] > hd[c])
                ++c;
            if (!(hd[c] > d2))
                break;
            hd[j] = hd[c];
            hi[j] = hi[c];
            j = c;
        }
    }
    hd[j] = d2;
    hi[j] = id;
}

/* Horizontal sums and maximum of a block. */
static inline float pm_hsum8(float8 v)
{
    float4 a = v.lo + v.hi;
    float2 b = a.lo + a.hi;
    return b.x + b.y;
}

static inline float pm_hmax8(float8 v)
{
    float4 a = fmax(v.lo, v.hi);
    float2 b = fmax(a.lo, a.hi);
    return fmax(b.x, b.y);
}

/* Lists photon j of the map as the estimate's photon number c (its index in
 * the caller's stream), or marks the list cut. */
static inline void pm_index(pm_state *st, const pm_knn_params *p, global const float *map, uint j,
                            uint c, global uint *indices)
{
    if (c < p->index_cap)
        indices[(ulong)st->q * p->index_cap + c] = as_uint(map[PM_MAP_ID * p->map_stride + j]);
    else
        st->flags |= PM_KNN_INDICES_CUT;
}

/* Takes the photons of block map[j .. j + PM_MAP_BLOCK) selected by m, in
 * order: lists them (pm_index), adds their power to the lane sums and counts
 * them. Shared by the dense and the hashed scans. */
static inline void pm_take8(pm_state *st, const pm_knn_params *p, global const float *map, uint j,
                            int8 m, float8 *ar, float8 *ag, float8 *ab, global uint *indices)
{
    uint stride = p->map_stride;
    if (p->index_cap) {
        int mm[PM_MAP_BLOCK];
        vstore8(m, 0, mm);
        uint c = st->count;
        for (int l = 0; l < PM_MAP_BLOCK; ++l)
            if (mm[l])
                pm_index(st, p, map, j + (uint)l, c++, indices);
    }
    *ar += select((float8)(0.0f), vload8(0, map + PM_MAP_R * stride + j), m);
    *ag += select((float8)(0.0f), vload8(0, map + PM_MAP_G * stride + j), m);
    *ab += select((float8)(0.0f), vload8(0, map + PM_MAP_B * stride + j), m);
    st->count += (uint)popcount((uint)sluice_mask8(m));
}

/* Runs shorter than this are examined one photon at a time. Since the box
 * scan keeps its sums in lanes across runs, a block costs little more than
 * a photon: from two photons up the blocks' branch-free tests win (on
 * Purcell's 25x25x50 and 250x1x250 grids and on bench_knn's; measured,
 * bench/README.md). */
#ifndef PM_SHORT_RUN
#define PM_SHORT_RUN 2u
#endif
/* The same for a hashed grid's buckets, whose blocks also test each
 * photon's cell: there eight stays the faster threshold (measured). */
#ifndef PM_SHORT_BUCKET
#define PM_SHORT_BUCKET 8u
#endif

/* Examines the photons map[b .. e) (Purcell Fig. 6.6): in the cell-ordered
 * copy of the map (pm_knn_gather) a run of cells along x is one contiguous
 * run of photons, examined in the order of their cells. The planes are read
 * in blocks of PM_MAP_BLOCK photons, their distances and filters computed
 * side by side (explicit vectors: the CPU's SIMD lanes whatever the
 * work-group vectorizer makes of the loop around it); the photons a block
 * takes are added in order, so the result is the one-at-a-time search's,
 * except for the order of the power sums. Short runs go one at a time.
 * Inlined, as is pm_scan_row, into the box scan: its state and sums stay in
 * registers (measured, bench/README.md). */
__attribute__((always_inline)) static inline void
pm_scan_run(pm_state *st, uint b, uint e, const pm_knn_params *p, uint exact,
            global const float *map, global uint *indices, float8 *ar, float8 *ag, float8 *ab)
{
    uint stride = p->map_stride;
    if (e - b < PM_SHORT_RUN) {
        for (uint j = b; j < e; ++j) {
            float dx = map[PM_MAP_X * stride + j] - st->px,
                  dy = map[PM_MAP_Y * stride + j] - st->py,
                  dz = map[PM_MAP_Z * stride + j] - st->pz;
            float d2 = PM_D2_(dx, dy, dz);
            if (!(d2 <= p->max_r2))
                continue;
            if (p->normal_filter &&
                !(PM_DOT_(st->nx, st->ny, st->nz, map[PM_MAP_DX * stride + j],
                          map[PM_MAP_DY * stride + j], map[PM_MAP_DZ * stride + j]) < 0.0f))
                continue;
            if (exact) {
                pm_heap_add(st, p->k, d2, j);
                continue;
            }
            if (st->count < p->k)
                st->r2 = fmax(st->r2, d2);
            else if (!(d2 <= st->r2))
                continue;
            if (p->index_cap)
                pm_index(st, p, map, j, st->count, indices);
            st->sr += map[PM_MAP_R * stride + j];
            st->sg += map[PM_MAP_G * stride + j];
            st->sb += map[PM_MAP_B * stride + j];
            st->count++;
        }
        return;
    }
    const int8 lane = (int8)(0, 1, 2, 3, 4, 5, 6, 7);
    for (uint j = b; j < e; j += PM_MAP_BLOCK) {
        float8 dx = vload8(0, map + PM_MAP_X * stride + j) - st->px;
        float8 dy = vload8(0, map + PM_MAP_Y * stride + j) - st->py;
        float8 dz = vload8(0, map + PM_MAP_Z * stride + j) - st->pz;
        float8 d2 = PM_D2_(dx, dy, dz);
        int8 m = (lane < (int8)((int)(e - j))) & (d2 <= (float8)(p->max_r2));
        if (p->normal_filter) {
            float8 c = PM_DOT_((float8)(st->nx), (float8)(st->ny), (float8)(st->nz),
                               vload8(0, map + PM_MAP_DX * stride + j),
                               vload8(0, map + PM_MAP_DY * stride + j),
                               vload8(0, map + PM_MAP_DZ * stride + j));
            m &= c < (float8)(0.0f);
        }
        if (!exact && st->count >= p->k)
            m &= d2 <= (float8)(st->r2);
        if (exact && st->count == p->k)
            m &= d2 < (float8)(st->hd[0]);
            /* Outside exact mode a block is taken as its mask says, with no
             * branch on whether it holds any photon that passed: a coin toss
             * the branch predictor lost often enough to cost more than the
             * masked adds of nothing (bench/README.md); -DPM_SKIP_EMPTY keeps
             * the branch, for measuring */
#ifdef PM_SKIP_EMPTY
        if (!sluice_mask8(m))
            continue;
#endif
        if (!exact && st->count >= p->k) { /* the radius frozen */
            pm_take8(st, p, map, j, m, ar, ag, ab, indices);
            continue;
        }
        if (exact) {
            if (!sluice_mask8(m))
                continue;
            /* Jensen's heap, one photon at a time, in order */
            float dd[PM_MAP_BLOCK];
            int mm[PM_MAP_BLOCK];
            vstore8(d2, 0, dd);
            vstore8(m, 0, mm);
            for (int l = 0; l < PM_MAP_BLOCK; ++l)
                if (mm[l])
                    pm_heap_add(st, p->k, dd[l], j + (uint)l);
            continue;
        }
        if (st->count < p->k) {
            /* each of the first k photons grows the radius: all of the
             * block's when they come before the k-th, else one at a time */
            if (st->count + (uint)popcount((uint)sluice_mask8(m)) <= p->k) {
                st->r2 = fmax(st->r2, pm_hmax8(select((float8)(0.0f), d2, m)));
            } else {
                float dd[PM_MAP_BLOCK];
                int mm[PM_MAP_BLOCK];
                vstore8(d2, 0, dd);
                vstore8(m, 0, mm);
                uint c = st->count;
                for (int l = 0; l < PM_MAP_BLOCK; ++l) {
                    if (!mm[l])
                        continue;
                    if (c < p->k)
                        st->r2 = fmax(st->r2, dd[l]);
                    else if (!(dd[l] <= st->r2))
                        mm[l] = 0;
                    c += mm[l] ? 1u : 0u;
                }
                m = vload8(0, mm);
            }
        }
        pm_take8(st, p, map, j, m, ar, ag, ab, indices);
    }
}

/* The cell-ordered copy of the photon map, one work-item per cell: cell c's
 * photons go to map[map_start[c] ..) of every plane, their power scaled by
 * the cell's arrived / stored count (Purcell's power redistribution for the
 * stencil build; exactly 1 for the others) and their index in the caller's
 * photon stream kept. The search then reads each cell as one contiguous run
 * instead of through the order indirection. */
__kernel void pm_knn_gather(SLUICE_PARAMS, global const uint *order, global const uint *cell_start,
                            global const uint *cell_count, global const uint *cell_arrived,
                            global const uint *map_start, global const pm_photon *photons,
                            global float *map, uint stride)
{
    SLUICE_FOR_EACH (c) {
        uint n = cell_count[c], from = cell_start[c], to = map_start[c];
        float scale = n ? (float)cell_arrived[c] / (float)n : 1.0f;
        for (uint j = 0; j < n; ++j) {
            uint id = order[from + j];
            pm_photon ph = photons[id];
            global float *o = map + to + j;
            o[PM_MAP_X * stride] = ph.px;
            o[PM_MAP_Y * stride] = ph.py;
            o[PM_MAP_Z * stride] = ph.pz;
            o[PM_MAP_DX * stride] = ph.dx;
            o[PM_MAP_DY * stride] = ph.dy;
            o[PM_MAP_DZ * stride] = ph.dz;
            o[PM_MAP_R * stride] = ph.pr * scale;
            o[PM_MAP_G * stride] = ph.pg * scale;
            o[PM_MAP_B * stride] = ph.pb * scale;
            o[PM_MAP_ID * stride] = as_float(id);
        }
    }
}

/* The bounding box of the map's n photons: work-item i takes the minimum
 * (i < 3) or the maximum (i >= 3) along axis i % 3. Empty: +inf / -inf. */
__kernel void pm_knn_bounds(SLUICE_PARAMS, global const float *map, uint stride, uint n,
                            global float *box)
{
    SLUICE_FOR_EACH (i) {
        global const float *v = map + (i % 3u) * stride;
        float b = i < 3u ? INFINITY : -INFINITY;
        for (uint j = 0; j < n; ++j)
            b = i < 3u ? fmin(b, v[j]) : fmax(b, v[j]);
        box[i] = b;
    }
}

/* The summed-count table of pm_sat_at in three sweeps, one per axis, a
 * work-item per line of cells. Along x (line = y + ny z): running sums of
 * the cell counts. */
__kernel void pm_knn_sat_x(SLUICE_PARAMS, global const uint *cell_count, pg_params g,
                           global uint *sat)
{
    SLUICE_FOR_EACH (line) {
        ulong at = (ulong)line * g.dims[0];
        uint acc = 0u;
        for (uint x = 0; x < g.dims[0]; ++x) {
            acc += cell_count[at + x];
            sat[at + x] = acc;
        }
    }
}

/* Along y (line = x + nx z), in place. */
__kernel void pm_knn_sat_y(SLUICE_PARAMS, pg_params g, global uint *sat)
{
    SLUICE_FOR_EACH (line) {
        uint nx = g.dims[0];
        global uint *o = sat + line % nx + (ulong)nx * g.dims[1] * (line / nx);
        for (uint y = 1; y < g.dims[1]; ++y)
            o[(ulong)y * nx] += o[(ulong)(y - 1u) * nx];
    }
}

/* Along z (line = x + nx y), in place. */
__kernel void pm_knn_sat_z(SLUICE_PARAMS, pg_params g, global uint *sat)
{
    SLUICE_FOR_EACH (line) {
        ulong plane = (ulong)g.dims[0] * g.dims[1];
        global uint *o = sat + line;
        for (uint z = 1; z < g.dims[2]; ++z)
            o[z * plane] += o[(z - 1u) * plane];
    }
}

/* The order the search takes the queries in: by their cells (keys, for
 * the radix sort; a query with a coordinate that is not finite sorts
 * last), so that queries taken one after another read the same photons
 * from cache (in the order given, bench_knn's random queries, each reads
 * its cells from memory). */
__kernel void pm_knn_order_keys(SLUICE_PARAMS, global const pm_query *queries, pg_params g,
                                global uint *keys, global uint *order)
{
    SLUICE_FOR_EACH (i) {
        pm_query Q = queries[i];
        keys[i] = pg_cell(Q.px, Q.py, Q.pz, &g);
        order[i] = i;
    }
}

/* The queries copied in the search order, so that the passes read them
 * (and their results, kept in the same order) one after another. */
__kernel void pm_knn_sort_queries(SLUICE_PARAMS, global const uint *order,
                                  global const pm_query *queries, global pm_query *sorted)
{
    SLUICE_FOR_EACH (j) {
        sorted[j] = queries[order[j]];
    }
}

/* The results back in the queries' order. */
__kernel void pm_knn_unsort_results(SLUICE_PARAMS, global const uint *order,
                                    global const pm_knn_result *sorted,
                                    global pm_knn_result *results)
{
    SLUICE_FOR_EACH (j) {
        results[order[j]] = sorted[j];
    }
}

/* Lists the places base .. base+n of the search order as live. */
__kernel void pm_knn_init(SLUICE_PARAMS, global uint *live, uint base)
{
    SLUICE_FOR_EACH (i) {
        live[i] = base + i;
    }
}

/* pg_axis in 8 lanes. */
static inline int8 pm_axis8(float8 x, float lo, float inv_cell, uint n)
{
    float8 f = (x - lo) * inv_cell;
    int8 c = select((int8)((int)n - 1), convert_int8(f), f < (float8)((float)(n - 1u)));
    return select((int8)0, c, f > (float8)0.0f);
}

/* pm_gap2 of cells j (8 lanes) of an axis. */
static inline float8 pm_gap2_8(float x, int8 j, int n, float lo, float cell, float margin,
                               float blo, float bhi)
{
    float8 l = select((float8)blo, fmax(lo + convert_float8(j) * cell, blo), j > 0);
    float8 h = select((float8)bhi, fmin(lo + convert_float8(j + 1) * cell, bhi), j < n - 1);
    float8 gap = select(select((float8)0.0f, x - h, (float8)x > h), l - x, (float8)x < l);
    gap -= margin;
    return select((float8)0.0f, gap * gap, gap > 0.0f);
}

/* Whether the cells [a, b] of row `row` hold photons: two reads. */
static inline int pm_row_holds(global const uint *map_start, global const uint *cell_count,
                               uint row, int a, int b)
{
    return map_start[row + (uint)a] != map_start[row + (uint)b] + cell_count[row + (uint)b];
}

/* Adds the lane sums of a box's photons to the estimate and clears them:
 * once a box, not once a run (measured, bench/README.md). */
static inline void pm_fold_sums(pm_state *st, float8 *ar, float8 *ag, float8 *ab)
{
    st->sr += pm_hsum8(*ar);
    st->sg += pm_hsum8(*ag);
    st->sb += pm_hsum8(*ab);
    *ar = *ag = *ab = (float8)(0.0f);
}

/* Scans the cells [xa, xb] of row `row` (y, z): one run of photons, or two on
 * either side of the hole (the cells already explored, a cube of half-side
 * `hole` about hole_c; none when hole < 0). */
__attribute__((always_inline)) static inline void
pm_scan_row(pm_state *st, uint row, int y, int z, int xa, int xb, const pm_knn_params *p,
            uint exact, global const float *map, global const uint *map_start,
            global const uint *cell_count, global uint *indices, const int *hole_c, int hole,
            float8 *ar, float8 *ag, float8 *ab)
{
    int ha = xb + 1, hb = xb;
    if (hole >= 0 && abs(y - hole_c[1]) <= hole && abs(z - hole_c[2]) <= hole) {
        ha = max(xa, hole_c[0] - hole);
        hb = min(xb, hole_c[0] + hole);
    }
    if (ha > hb) { /* the hole misses the row's cells */
        ha = xb + 1;
        hb = xb;
    }
    if (xa < ha)
        pm_scan_run(st, map_start[row + (uint)xa],
                    map_start[row + (uint)(ha - 1)] + cell_count[row + (uint)(ha - 1)], p, exact,
                    map, indices, ar, ag, ab);
    if (hb + 1 <= xb)
        pm_scan_run(st, map_start[row + (uint)(hb + 1)],
                    map_start[row + (uint)xb] + cell_count[row + (uint)xb], p, exact, map, indices,
                    ar, ag, ab);
}

/* Boxes at least this many rows high (along y) take their rows 8 at a time
 * in pm_scan_box; lower ones (the faces of a shell across y, Purcell's
 * planar 250x1x250 grids) one at a time, where the 8-row block's setup cost
 * more than it saved (measured, bench/README.md). */
#ifndef PM_ROWS8_MIN
#define PM_ROWS8_MIN 4
#endif

/* Scans the cells [b0, b1] (inclusive, within the grid) row by row along x:
 * a row's cells are one run of photons, trimmed to the cells within reach of
 * the bound; an empty row costs two reads. In boxes of PM_ROWS8_MIN rows and
 * more, rows go 8 at a time: which are empty, their gaps and trims (a
 * square root each) side by side, then the rows left one after another, in
 * order. The bound can only shrink while the 8 rows are scanned: trims made
 * with it at their start reach at least as far as the bound of the moment
 * needs, and the photons beyond are rejected one by one, so the estimate is
 * the row-at-a-time scan's. */
static inline void pm_scan_box(pm_state *st, const int *b0, const int *b1, const int *n,
                               const pg_params *g, const pm_knn_params *p, uint exact,
                               global const float *map, global const uint *map_start,
                               global const uint *cell_count, global uint *indices,
                               const int *hole_c, int hole)
{
    const int8 lane = (int8)(0, 1, 2, 3, 4, 5, 6, 7);
    float8 ar = (float8)(0.0f), ag = (float8)(0.0f), ab = (float8)(0.0f);
    for (int z = b0[2]; z <= b1[2]; ++z) {
        float gz = pm_gap2(st->pz, z, n[2], g->lo[2], g->cell[2], p->margin[2], p->box_lo[2],
                           p->box_hi[2]);
        if (gz > pm_bound(st, p, exact))
            continue;
        uint plane = (uint)n[0] * (uint)n[1] * (uint)z;
        if (b1[1] - b0[1] + 1 < PM_ROWS8_MIN) {
            for (int y = b0[1]; y <= b1[1]; ++y) {
                uint row = plane + (uint)n[0] * (uint)y;
                if (!pm_row_holds(map_start, cell_count, row, b0[0], b1[0]))
                    continue;
                float bound = pm_bound(st, p, exact);
                float t = bound - gz -
                          pm_gap2(st->py, y, n[1], g->lo[1], g->cell[1], p->margin[1], p->box_lo[1],
                                  p->box_hi[1]);
                if (t < st->gx)
                    continue;
                int xa = b0[0], xb = b1[0];
                pm_trim(st->px, t, bound, g->lo[0], g->inv_cell[0], g->dims[0], p->margin[0], &xa,
                        &xb);
                pm_scan_row(st, row, y, z, xa, xb, p, exact, map, map_start, cell_count, indices,
                            hole_c, hole, &ar, &ag, &ab);
            }
            continue;
        }
        for (int y0 = b0[1]; y0 <= b1[1]; y0 += 8) {
            int rows = min(8, b1[1] - y0 + 1);
            uint todo = 0u;
            for (int l = 0; l < rows; ++l)
                todo |= (uint)pm_row_holds(map_start, cell_count,
                                           plane + (uint)n[0] * (uint)(y0 + l), b0[0], b1[0])
                        << l;
            if (!todo)
                continue;
            float bound = pm_bound(st, p, exact);
            float8 t = bound - gz -
                       pm_gap2_8(st->py, (int8)y0 + lane, n[1], g->lo[1], g->cell[1], p->margin[1],
                                 p->box_lo[1], p->box_hi[1]);
            todo &= sluice_mask8(t >= (float8)st->gx);
            if (!todo)
                continue;
            float8 reach = PM_REACH_(t, bound, p->margin[0]);
            int xas[8], xbs[8];
            vstore8(
                max((int8)b0[0], pm_axis8(st->px - reach, g->lo[0], g->inv_cell[0], g->dims[0])), 0,
                xas);
            vstore8(
                min((int8)b1[0], pm_axis8(st->px + reach, g->lo[0], g->inv_cell[0], g->dims[0])), 0,
                xbs);
            while (todo) {
                int l = popcount((todo & (0u - todo)) - 1u); /* the lowest set bit */
                todo &= todo - 1u;
                pm_scan_row(st, plane + (uint)n[0] * (uint)(y0 + l), y0 + l, z, xas[l], xbs[l], p,
                            exact, map, map_start, cell_count, indices, hole_c, hole, &ar, &ag,
                            &ab);
            }
        }
    }
    pm_fold_sums(st, &ar, &ag, &ab);
}

/* One shell for every live query (see the top of the file). */
__kernel void pm_knn_pass(SLUICE_PARAMS, global const uint *live, global const uint *order,
                          global const pm_query *queries, global const float *map,
                          global const uint *map_start, global const uint *cell_count,
                          global const uint *sat, pg_params g, pm_knn_params p, uint exact,
                          uint base, global pm_knn_result *results, global float *heap_d2,
                          global uint *heap_id, global uint *indices)
{
    SLUICE_FOR_EACH (i) {
        /* queries and results in the search order; q indexes the lists */
        uint at = live[i], q = order[at];
        pm_query Q = queries[at];
        pm_knn_result r = results[at];
        pm_state st;
        st.px = Q.px;
        st.py = Q.py;
        st.pz = Q.pz;
        st.nx = Q.nx;
        st.ny = Q.ny;
        st.nz = Q.nz;
        st.sr = r.sr;
        st.sg = r.sg;
        st.sb = r.sb;
        st.r2 = r.r2;
        st.count = r.count;
        st.flags = r.flags;
        st.q = q;
        st.hd = heap_d2 + (ulong)(at - base) * (exact ? p.k : 0u);
        st.hi = heap_id + (ulong)(at - base) * (exact ? p.k : 0u);
        if (!pg_finite(Q.px) || !pg_finite(Q.py) || !pg_finite(Q.pz)) {
            r.flags |= PM_KNN_DONE | PM_KNN_BAD_QUERY;
            results[at] = r;
            continue;
        }
        float qp[3] = {Q.px, Q.py, Q.pz};
        st.gx = pm_gap2(Q.px, 0, 1, g.lo[0], g.cell[0], p.margin[0], p.box_lo[0], p.box_hi[0]);
        int qc[3], n[3];
        for (int a = 0; a < 3; ++a) {
            n[a] = (int)g.dims[a];
            qc[a] = (int)pg_axis(qp[a], g.lo[a], g.inv_cell[a], g.dims[a]);
        }
        int s = (int)r.shells, covered = 0, done = 0, full = 0;
        float reach = 0.0f;
        for (uint step = 0u; !done && (p.shells_per_pass == 0u || step < p.shells_per_pass);
             ++step) {
            if (step)
                ++s;
            full = exact ? st.count == p.k : st.count >= p.k;
            reach = exact ? (st.count ? st.hd[0] : 0.0f) : st.r2;
            if (full) {
                /* Holding k photons, the search is a radius search: in
                 * at-least mode the radius is frozen, so the order in which
                 * the rest is found changes nothing; exact mode's only
                 * shrinks. Every cell within the radius outside the shells
                 * explored (0 .. s - 1) is swept in one step, row by row,
                 * instead of one shell after another, whose faces across x
                 * are rows of one cell each: the same photons. */
                int b0[3], b1[3];
                int ext = pm_reach_cells(qp, reach, qc, n, &g, &p, b0, b1, &covered);
                if (b0[0] <= b1[0] && b0[1] <= b1[1] && b0[2] <= b1[2])
                    pm_scan_box(&st, b0, b1, n, &g, &p, exact, map, map_start, cell_count, indices,
                                qc, s - 1);
                s = max(s, ext);
                reach = exact ? st.hd[0] : st.r2;
                done = 1;
                break;
            }
            /* Shells that cannot bring the estimate to k photons (by the
             * summed counts, which include photons the radius or the normals
             * will reject) take every photon they hold that passes: their
             * order changes nothing, so shells s .. u are swept as one box of
             * whole rows, the cube of u less the cube explored. u stops where
             * the shells would have stopped: at d_u >= the maximum radius, or
             * covering the grid. */
            uint before = s > 0 ? pm_cube_count(sat, qc, s - 1, n) : 0u;
            pm_box_end f = pm_box_end_start(s, pm_last_shell(qc, n, s));
            for (int v; pm_box_end_next(&f, &v);) {
                int cov = 0;
                int r = st.count + (pm_cube_count(sat, qc, v, n) - before) >= p.k;
                if (!r) {
                    float dv = pm_cube_d2(qp, qc, v, n, &g, &p, &cov);
                    r = cov || dv >= p.max_r2 ? 2 : 0;
                }
                pm_box_end_tell(&f, r);
            }
            int u = pm_box_end_last(&f);
            if (u > s) {
                int b0[3], b1[3];
                pm_cube_cells(qc, u, n, b0, b1);
                pm_scan_box(&st, b0, b1, n, &g, &p, exact, map, map_start, cell_count, indices, qc,
                            s - 1);
                s = u;
            } else {
                /* Shells without photons change nothing: the search jumps to the
                 * first shell u >= s that holds photons or at which it would have
                 * ended, by the summed counts (Purcell explores every shell, one a
                 * pass; the estimate is the same, in fewer passes). */
                uint at_s = pm_cube_count(sat, qc, s, n);
                if (at_s == before) {
                    int lo = s, hi = pm_last_shell(qc, n, s);
                    while (lo < hi) {
                        int mid = lo + (hi - lo) / 2, cov;
                        float dm = pm_cube_d2(qp, qc, mid, n, &g, &p, &cov);
                        if (pm_cube_count(sat, qc, mid, n) != before || cov || dm >= p.max_r2 ||
                            (full && dm >= reach))
                            hi = mid;
                        else
                            lo = mid + 1;
                    }
                    s = lo;
                    at_s = pm_cube_count(sat, qc, s, n);
                }
                if (at_s != before) {
                    /* the shell's six faces, each cell once */
                    for (int side = 0; side < 6; ++side) {
                        int b0[3], b1[3];
                        if (pm_face(sat, qc, s, n, side, b0, b1))
                            pm_scan_box(&st, b0, b1, n, &g, &p, exact, map, map_start, cell_count,
                                        indices, qc, -1);
                    }
                }
            }
            float ds2 = pm_cube_d2(qp, qc, s, n, &g, &p, &covered);
            full = exact ? st.count == p.k : st.count >= p.k;
            reach = exact ? (st.count ? st.hd[0] : 0.0f) : st.r2;
            done = covered || ds2 >= p.max_r2 || (full && ds2 >= reach);
        }
        r.shells = (uint)s + 1u;
        r.count = st.count;
        r.flags = st.flags;
        if (done) {
            r.flags |= PM_KNN_DONE;
            if (covered)
                r.flags |= PM_KNN_COVERED_GRID;
            else if (!full)
                r.flags |= PM_KNN_HIT_MAX_RADIUS;
        }
        if (exact && done) {
            /* the estimate from the heap */
            float sr = 0.0f, sg = 0.0f, sb = 0.0f;
            for (uint j = 0; j < st.count; ++j) {
                uint at = st.hi[j];
                sr += map[PM_MAP_R * p.map_stride + at];
                sg += map[PM_MAP_G * p.map_stride + at];
                sb += map[PM_MAP_B * p.map_stride + at];
                if (p.index_cap && j < p.index_cap)
                    indices[(ulong)q * p.index_cap + j] =
                        as_uint(map[PM_MAP_ID * p.map_stride + at]);
            }
            if (p.index_cap && st.count > p.index_cap)
                r.flags |= PM_KNN_INDICES_CUT;
            st.sr = sr;
            st.sg = sg;
            st.sb = sb;
            st.r2 = reach;
        }
        r.sr = st.sr;
        r.sg = st.sg;
        r.sb = st.sb;
        r.r2 = st.r2;
        results[at] = r;
    }
}

/* pm_knn_sum takes PM_KNN_SUM_QUERIES queries (pm_types.h) side by side:
 * 8 or 16 lanes. */
#if PM_KNN_SUM_QUERIES == 16
typedef float16 pm_sumf;
typedef int16 pm_sumi;
#define PM_SUM_VLOAD vload16
#define PM_SUM_VSTORE vstore16
#define PM_SUM_MASK sluice_mask16
#define PM_SUM_CONVERT_INT convert_int16
#else
typedef float8 pm_sumf;
typedef int8 pm_sumi;
#define PM_SUM_VLOAD vload8
#define PM_SUM_VSTORE vstore8
#define PM_SUM_MASK sluice_mask8
#define PM_SUM_CONVERT_INT convert_int8
#endif
#define PM_SUM_W PM_KNN_SUM_QUERIES

/* pg_axis of the lanes' points x (as pm_axis8). */
static inline pm_sumi pm_sum_axis(pm_sumf x, float lo, float inv_cell, uint n)
{
    pm_sumf f = (x - lo) * inv_cell;
    pm_sumi c =
        select((pm_sumi)((int)n - 1), PM_SUM_CONVERT_INT(f), f < (pm_sumf)((float)(n - 1u)));
    return select((pm_sumi)0, c, f > (pm_sumf)0.0f);
}

/* The largest lane (and, of -v, the smallest; no lane is INT_MIN). */
static inline int pm_sum_hmax(pm_sumi v)
{
    /* halves folded in vectors (a store and a scalar loop cost more, per
     * row, in pm_row_span) */
#if PM_KNN_SUM_QUERIES == 16
    int8 a8 = max(v.lo, v.hi);
#else
    int8 a8 = v;
#endif
    int4 a4 = max(a8.lo, a8.hi);
    int2 a2 = max(a4.lo, a4.hi);
    return max(a2.x, a2.y);
}

/* pm_gap2 of cell j for the points x of the lanes. */
static inline pm_sumf pm_gap2_lanes(pm_sumf x, int j, int n, float lo, float cell, float margin,
                                    float blo, float bhi)
{
    float l = j > 0 ? fmax(lo + (float)j * cell, blo) : blo;
    float h = j < n - 1 ? fmin(lo + (float)(j + 1) * cell, bhi) : bhi;
    pm_sumf gap =
        select(select((pm_sumf)(0.0f), x - h, x > (pm_sumf)(h)), (pm_sumf)(l)-x, x < (pm_sumf)(l));
    gap -= margin;
    return select((pm_sumf)(0.0f), gap * gap, gap > 0.0f);
}

/* Queries side by side, one a lane (pm_knn_sum, pm_knn_reach): where they
 * are, their squared radius and their running estimates. */
typedef struct pm_lanes {
    pm_sumf px, py, pz, nx, ny, nz, gx;
    pm_sumf box2; /* squared distance to the photons' box (pm_box_d2) */
    pm_sumf r2, sr, sg, sb;
    pm_sumi cnt;
} pm_lanes;

/* The lanes' queries: points and normals from arrays of PM_SUM_W. */
static inline void pm_lanes_load(pm_lanes *L, const float *x, const float *y, const float *z,
                                 const float *nx, const float *ny, const float *nz,
                                 const pg_params *g, const pm_knn_params *p)
{
    L->px = PM_SUM_VLOAD(0, x);
    L->py = PM_SUM_VLOAD(0, y);
    L->pz = PM_SUM_VLOAD(0, z);
    L->nx = PM_SUM_VLOAD(0, nx);
    L->ny = PM_SUM_VLOAD(0, ny);
    L->nz = PM_SUM_VLOAD(0, nz);
    /* pm_gap2_lanes of a grid of one cell: the gap to the photons' box */
    L->gx =
        pm_gap2_lanes(L->px, 0, 1, g->lo[0], g->cell[0], p->margin[0], p->box_lo[0], p->box_hi[0]);
    L->box2 =
        L->gx +
        pm_gap2_lanes(L->py, 0, 1, g->lo[1], g->cell[1], p->margin[1], p->box_lo[1], p->box_hi[1]) +
        pm_gap2_lanes(L->pz, 0, 1, g->lo[2], g->cell[2], p->margin[2], p->box_lo[2], p->box_hi[2]);
}

/* The squared length of (dx, dy, dz), lane by lane (PM_D2_, as
 * pm_scan_run computes it). */
__attribute__((always_inline)) static inline pm_sumf pm_sum_d2(pm_sumf dx, pm_sumf dy, pm_sumf dz)
{
    return PM_D2_(dx, dy, dz);
}

/* The squared distance from the lanes' queries to photon m[0] (planes
 * `stride` apart). */
__attribute__((always_inline)) static inline pm_sumf pm_photon_d2(global const float *m,
                                                                  uint stride, const pm_lanes *L)
{
    return pm_sum_d2(m[PM_MAP_X * stride] - L->px, m[PM_MAP_Y * stride] - L->py,
                     m[PM_MAP_Z * stride] - L->pz);
}

/* The lanes whose query the photon arrives at from the side its normal
 * faces (the normal filter). */
__attribute__((always_inline)) static inline pm_sumi pm_facing(global const float *m, uint stride,
                                                               const pm_lanes *L)
{
    return PM_DOT_(L->nx, L->ny, L->nz, (pm_sumf)(m[PM_MAP_DX * stride]),
                   (pm_sumf)(m[PM_MAP_DY * stride]),
                   (pm_sumf)(m[PM_MAP_DZ * stride])) < (pm_sumf)(0.0f);
}

/* pm_knn_sum's test of photon m[0] for the lanes `on`: within the radius
 * and, with the normal filter, arriving on the query's side. */
__attribute__((always_inline)) static inline pm_sumi
pm_sum_take(global const float *m, uint stride, const pm_lanes *L, pm_sumi on, uint normal_filter)
{
    pm_sumi take = on & (pm_photon_d2(m, stride, L) <= L->r2);
    if (normal_filter)
        take &= pm_facing(m, stride, L);
    return take;
}

/* Adds the photon's power to the lanes that take it. */
__attribute__((always_inline)) static inline void pm_sum_power(global const float *m, uint stride,
                                                               pm_sumi take, pm_lanes *L)
{
    /* a masked add (one instruction with AVX-512), not an add of a select */
    L->sr = select(L->sr, L->sr + m[PM_MAP_R * stride], take);
    L->sg = select(L->sg, L->sg + m[PM_MAP_G * stride], take);
    L->sb = select(L->sb, L->sb + m[PM_MAP_B * stride], take);
}

/* Counts the photon for the lanes that take it and adds its power. */
__attribute__((always_inline)) static inline void pm_sum_add(global const float *m, uint stride,
                                                             pm_sumi take, pm_lanes *L)
{
    L->cnt -= take; /* a true lane is -1 */
    pm_sum_power(m, stride, take, L);
}

/* Lists photon `id` as photon number cnt of each lane of `take` (lane l the
 * query at place first + l of the search order), or marks the lane's list
 * cut (bit l of *cut). */
__attribute__((always_inline)) static inline void pm_sum_list(pm_sumi take, pm_sumi cnt, uint id,
                                                              global const uint *order, uint first,
                                                              uint cap, global uint *indices,
                                                              int *cut)
{
    int tk[PM_SUM_W], c[PM_SUM_W];
    PM_SUM_VSTORE(take, 0, tk);
    PM_SUM_VSTORE(cnt, 0, c);
    for (int l = 0; l < PM_SUM_W; ++l) {
        if (!tk[l])
            continue;
        if ((uint)c[l] < cap)
            indices[(ulong)order[first + (uint)l] * cap + (uint)c[l]] = id;
        else
            *cut |= 1 << l;
    }
}

/* pm_sum_add for the photons m[0 .. len), counted in floats: a masked add
 * a photon, where the integer count took three instructions (the mask made
 * a vector and back). Exact: at most 2^20 photons are counted before the
 * count goes to L->cnt. Every lane tests every photon, not only those of
 * `on`: a lane without a query has a radius of -1, and a lane the row's
 * gaps leave out (pm_knn_sum) has no photon of the row within its radius,
 * so they take nothing; testing `on` cost one instruction of the loop's
 * twenty-odd a photon. */
__attribute__((always_inline)) static inline void
pm_sum_counted(global const float *m, uint len, uint stride, pm_lanes *L, uint normal_filter)
{
    for (uint b = 0; b < len; b += 1u << 20) {
        uint e = min(len, b + (1u << 20));
        pm_sumf cf = (pm_sumf)(0.0f);
        for (uint j = b; j < e; ++j) {
            pm_sumi take = pm_sum_take(m + j, stride, L, (pm_sumi)(-1), normal_filter);
            cf = select(cf, cf + 1.0f, take);
            pm_sum_power(m + j, stride, take, L);
        }
        L->cnt += PM_SUM_CONVERT_INT(cf);
    }
}

/* pm_knn_sum over the photons m[0 .. len) for the lanes `on` (without an
 * index list, every lane: pm_sum_counted), one photon at a time. */
__attribute__((always_inline)) static inline void pm_sum_run(global const float *m, uint len,
                                                             uint stride, pm_lanes *L, pm_sumi on,
                                                             const pm_knn_params *p,
                                                             global const uint *order, uint first,
                                                             global uint *indices, int *cut)
{
    if (p->index_cap) {
        for (uint j = 0; j < len; ++j) {
            pm_sumi take = pm_sum_take(m + j, stride, L, on, p->normal_filter);
            if (!PM_SUM_MASK(take))
                continue;
            pm_sum_list(take, L->cnt, as_uint(m[PM_MAP_ID * stride + j]), order, first,
                        p->index_cap, indices, cut);
            pm_sum_add(m + j, stride, take, L);
        }
    } else if (p->normal_filter) { /* every lane: see pm_sum_counted */
        pm_sum_counted(m, len, stride, L, 1u);
    } else {
        pm_sum_counted(m, len, stride, L, 0u);
    }
}

/* The cells [*xa, *xb] of a row (those between lo and hi) within reach of
 * any lane of `on`: t is what the bound leaves each lane along x. */
__attribute__((always_inline)) static inline int
pm_row_span(const pm_lanes *L, pm_sumf t, pm_sumf bound, pm_sumi on, int lo, int hi,
            const pg_params *g, const pm_knn_params *p, int *xa, int *xb)
{
    pm_sumf reach = PM_REACH_(t, bound, p->margin[0]);
    *xa = max(lo, -pm_sum_hmax(-select(
                      (pm_sumi)(INT_MAX),
                      pm_sum_axis(L->px - reach, g->lo[0], g->inv_cell[0], g->dims[0]), on)));
    *xb = min(hi, pm_sum_hmax(select(
                      (pm_sumi)(-1),
                      pm_sum_axis(L->px + reach, g->lo[0], g->inv_cell[0], g->dims[0]), on)));
    return *xa <= *xb;
}

/* The at-least estimates of queries whose search stopped at k photons
 * (pm_knn_reach), PM_KNN_SUM_QUERIES queries (consecutive in the search order, so
 * near one another) a work-item. Their radius is fixed: the at-least rule
 * (pm_scan_run) takes every photon before the k-th, each within the radius
 * (the farthest of them), and every photon within the radius after it, and
 * the shells and the sweep reach every cell within the radius; so the
 * estimate is every photon that passes the filters within the radius, in
 * any order. Here each row of cells is read once for all of them, each
 * photon tested against all of them side by side (the lanes are queries),
 * instead of once per query: the rows, their trims and the branches they
 * cost are shared. The count and the sums are replaced (the pass's were
 * partial) and the index list is written anew; r2, shells and the other
 * flags are the pass's. The distance is computed as pm_scan_run computes it,
 * so the photon that set the radius is within it here too. */
__kernel void pm_knn_sum(SLUICE_PARAMS, global const uint *order, global const pm_query *queries,
                         global const float *map, global const uint *map_start,
                         global const uint *cell_count, pg_params g, pm_knn_params p, uint n,
                         global pm_knn_result *results, global uint *indices)
{
    SLUICE_FOR_EACH (w) {
        uint first = w * PM_SUM_W, stride = p.map_stride;
        float lx[PM_SUM_W], ly[PM_SUM_W], lz[PM_SUM_W], lnx[PM_SUM_W], lny[PM_SUM_W], lnz[PM_SUM_W],
            lr2[PM_SUM_W];
        int lon[PM_SUM_W], lo[3] = {INT_MAX, INT_MAX, INT_MAX}, hi[3] = {-1, -1, -1}, any = 0;
        for (int l = 0; l < PM_SUM_W; ++l) {
            uint i = first + (uint)l;
            lx[l] = ly[l] = lz[l] = lnx[l] = lny[l] = lnz[l] = 0.0f;
            lr2[l] = -1.0f; /* no photon within */
            lon[l] = 0;
            if (i >= n)
                continue;
            pm_knn_result r = results[i];
            if (r.count < p.k || (r.flags & PM_KNN_BAD_QUERY))
                continue;
            pm_query Q = queries[i];
            float qp[3] = {Q.px, Q.py, Q.pz};
            lx[l] = Q.px;
            ly[l] = Q.py;
            lz[l] = Q.pz;
            lnx[l] = Q.nx;
            lny[l] = Q.ny;
            lnz[l] = Q.nz;
            lr2[l] = r.r2;
            lon[l] = -1;
            any = 1;
            /* the cells within reach of the radius, as the sweep trims them */
            for (int a = 0; a < 3; ++a) {
                int b0 = 0, b1 = (int)g.dims[a] - 1;
                pm_trim(qp[a], r.r2, r.r2, g.lo[a], g.inv_cell[a], g.dims[a], p.margin[a], &b0,
                        &b1);
                lo[a] = min(lo[a], b0);
                hi[a] = max(hi[a], b1);
            }
        }
        if (!any)
            continue;
        pm_lanes L;
        pm_lanes_load(&L, lx, ly, lz, lnx, lny, lnz, &g, &p);
        L.r2 = PM_SUM_VLOAD(0, lr2);
        L.cnt = (pm_sumi)(0);
        L.sr = L.sg = L.sb = (pm_sumf)(0.0f);
        pm_sumi on = PM_SUM_VLOAD(0, lon);
        int flag_cut = 0;
        uint nx0 = g.dims[0], plane_cells = g.dims[0] * g.dims[1];
        for (int z = lo[2]; z <= hi[2]; ++z) {
            pm_sumf gz = pm_gap2_lanes(L.pz, z, (int)g.dims[2], g.lo[2], g.cell[2], p.margin[2],
                                       p.box_lo[2], p.box_hi[2]);
            pm_sumi zon = on & (gz <= L.r2);
            if (!PM_SUM_MASK(zon))
                continue;
            for (int y = lo[1]; y <= hi[1]; ++y) {
                uint row = plane_cells * (uint)z + nx0 * (uint)y;
                if (!pm_row_holds(map_start, cell_count, row, lo[0], hi[0]))
                    continue;
                pm_sumf t = L.r2 - gz -
                            pm_gap2_lanes(L.py, y, (int)g.dims[1], g.lo[1], g.cell[1], p.margin[1],
                                          p.box_lo[1], p.box_hi[1]);
                pm_sumi ron = zon & (t >= L.gx);
                int xa, xb;
                if (!PM_SUM_MASK(ron) ||
                    !pm_row_span(&L, t, L.r2, ron, lo[0], hi[0], &g, &p, &xa, &xb))
                    continue;
                uint b = map_start[row + (uint)xa],
                     e = map_start[row + (uint)xb] + cell_count[row + (uint)xb];
                pm_sum_run(map + b, e - b, stride, &L, ron, &p, order, first, indices, &flag_cut);
            }
        }
        int c[PM_SUM_W];
        float fr[PM_SUM_W], fg[PM_SUM_W], fb[PM_SUM_W];
        PM_SUM_VSTORE(L.cnt, 0, c);
        PM_SUM_VSTORE(L.sr, 0, fr);
        PM_SUM_VSTORE(L.sg, 0, fg);
        PM_SUM_VSTORE(L.sb, 0, fb);
        for (int l = 0; l < PM_SUM_W; ++l) {
            if (!lon[l])
                continue;
            global pm_knn_result *r = results + first + (uint)l;
            r->count = (uint)c[l];
            r->sr = fr[l];
            r->sg = fg[l];
            r->sb = fb[l];
            if (flag_cut & (1 << l))
                r->flags |= PM_KNN_INDICES_CUT;
        }
    }
}

/* pm_cube_d2 for the lanes' points, whose cell is qc for all: the same
 * arithmetic lane by lane, so the same shells end the same searches. */
static inline pm_sumf pm_cube_d2_lanes(const pm_lanes *L, const int *qc, int s, const int *n,
                                       const pg_params *g, const pm_knn_params *p, int *covered)
{
    /* the least and the greatest by compares: the lanes' points are finite
     * (a lane of no query is 0), so no NaN needs fmin's and fmax's care,
     * which cost four instructions each; the box term is the lanes' own
     * (pm_lanes_load) */
    pm_sumf x[3] = {L->px, L->py, L->pz};
    pm_sumf d = (pm_sumf)(INFINITY);
    *covered = 1;
    for (int a = 0; a < 3; ++a) {
        if (qc[a] - s > 0) {
            *covered = 0;
            pm_sumf f = x[a] - (g->lo[a] + (float)(qc[a] - s) * g->cell[a]) - p->margin[a];
            d = select(d, f, f < d);
        }
        if (qc[a] + s < n[a] - 1) {
            *covered = 0;
            pm_sumf f = g->lo[a] + (float)(qc[a] + s + 1) * g->cell[a] - x[a] - p->margin[a];
            d = select(d, f, f < d);
        }
    }
    if (*covered)
        return (pm_sumf)(INFINITY);
    pm_sumf dd = select((pm_sumf)(0.0f), d * d, d > 0.0f);
    return select(L->box2, dd, dd > L->box2);
}

/* The at-least rule for photons map[b .. e) and the lanes `on`, one photon
 * at a time, in order: a lane still short of k takes every photon that
 * passes (within the maximum radius and, with the normal filter, arriving
 * on its side), its radius growing to take it in (pm_scan_run, before the
 * k-th photon); a lane holding k takes nothing more (its radius fixed). Lanes
 * short of k list what they take (pm_knn_sum lists anew for the others). */
__attribute__((always_inline)) static inline void pm_reach_run(pm_lanes *L, pm_sumi on, uint b,
                                                               uint e, const pm_knn_params *p,
                                                               global const float *map,
                                                               global const uint *order, uint first,
                                                               global uint *indices, int *cut)
{
    /* the lanes and the parameters in registers for the loop: through the
     * pointers, every photon loaded and stored the running sums, count and
     * radius, and loaded the parameters (the list's global stores may
     * alias them, as far as the compiler knows) */
    pm_lanes l = *L;
    const uint stride = p->map_stride, cap = p->index_cap, nf = p->normal_filter;
    const pm_sumf bound = (pm_sumf)(p->max_r2);
    const pm_sumi k = (pm_sumi)((int)p->k);
    for (uint j = b; j < e; ++j) {
        global const float *m = map + j;
        pm_sumf d2 = pm_photon_d2(m, stride, &l);
        pm_sumi take = on & (l.cnt < k) & (d2 <= bound);
        if (nf)
            take &= pm_facing(m, stride, &l);
        if (cap && PM_SUM_MASK(take))
            pm_sum_list(take, l.cnt, as_uint(m[PM_MAP_ID * stride]), order, first, cap, indices,
                        cut);
        l.r2 = select(l.r2, fmax(l.r2, d2), take);
        pm_sum_add(m, stride, take, &l);
    }
    L->cnt = l.cnt;
    L->r2 = l.r2;
    L->sr = l.sr;
    L->sg = l.sg;
    L->sb = l.sb;
}

/* Rows holding at most this many photons are not trimmed to the cells the
 * lanes reach (pm_row_span: a square root and two reductions across the
 * lanes): testing their photons costs less. Purcell's planar 250x1x250 grids
 * hold a photon or two a cell, and the faces of a shell across x are columns
 * of one-cell rows (measured, bench/README.md). */
#ifndef PM_REACH_TRIM_MIN
#define PM_REACH_TRIM_MIN 4u
#endif

/* pm_scan_box for the lanes `on` in lockstep, before the k-th photon (the
 * bound is the maximum radius): the cells [b0, b1] row by row along x, each
 * row trimmed to the cells any lane still short of k can reach, and split
 * about the hole (the cube of half-side `hole` about qc, already explored;
 * none when hole < 0) as pm_scan_row splits it. So every lane meets its
 * photons in the order its own scan would, and those it would not meet lie
 * beyond its reach. Stops when no lane is short of k. An empty row costs
 * three reads: a plane's gap is worked out at its first row with photons,
 * and rows of a few photons are not trimmed (PM_REACH_TRIM_MIN). */
static inline void pm_reach_box(pm_lanes *L, pm_sumi on, const int *b0, const int *b1, const int *n,
                                const int *qc, int hole, const pg_params *g, const pm_knn_params *p,
                                global const float *map, global const uint *map_start,
                                global const uint *cell_count, global const uint *order, uint first,
                                global uint *indices, int *cut)
{
    pm_sumi k = (pm_sumi)((int)p->k);
    pm_sumf bound = (pm_sumf)(p->max_r2);
    for (int z = b0[2]; z <= b1[2]; ++z) {
        pm_sumi want = on & (L->cnt < k);
        if (!PM_SUM_MASK(want))
            return;
        uint plane = (uint)n[0] * (uint)n[1] * (uint)z;
        pm_sumf gz = (pm_sumf)(0.0f);
        pm_sumi zon = want;
        int z_tested = 0;
        for (int y = b0[1]; y <= b1[1]; ++y) {
            uint row = plane + (uint)n[0] * (uint)y;
            uint rb = map_start[row + (uint)b0[0]],
                 re = map_start[row + (uint)b1[0]] + cell_count[row + (uint)b1[0]];
            if (rb == re)
                continue;
            if (!z_tested) {
                gz = pm_gap2_lanes(L->pz, z, n[2], g->lo[2], g->cell[2], p->margin[2], p->box_lo[2],
                                   p->box_hi[2]);
                zon = want & (gz <= bound);
                z_tested = 1;
            }
            if (!PM_SUM_MASK(zon))
                break;
            pm_sumf t = bound - gz -
                        pm_gap2_lanes(L->py, y, n[1], g->lo[1], g->cell[1], p->margin[1],
                                      p->box_lo[1], p->box_hi[1]);
            pm_sumi ron = zon & (L->cnt < k) & (t >= L->gx);
            if (!PM_SUM_MASK(ron))
                continue;
            int xa = b0[0], xb = b1[0];
            if (re - rb > PM_REACH_TRIM_MIN &&
                !pm_row_span(L, t, bound, ron, b0[0], b1[0], g, p, &xa, &xb))
                continue;
            int ha = xb + 1, hb = xb;
            if (hole >= 0 && abs(y - qc[1]) <= hole && abs(z - qc[2]) <= hole) {
                ha = max(xa, qc[0] - hole);
                hb = min(xb, qc[0] + hole);
            }
            if (ha > hb) {
                ha = xb + 1;
                hb = xb;
            }
            if (xa < ha)
                pm_reach_run(L, ron, map_start[row + (uint)xa],
                             map_start[row + (uint)(ha - 1)] + cell_count[row + (uint)(ha - 1)], p,
                             map, order, first, indices, cut);
            if (hb + 1 <= xb)
                pm_reach_run(L, ron, map_start[row + (uint)(hb + 1)],
                             map_start[row + (uint)xb] + cell_count[row + (uint)xb], p, map, order,
                             first, indices, cut);
        }
    }
}

/* The at-least search up to each query's k-th photon (the one-pass
 * search's first step: pm_knn_pass's search, stopped there, for the queries
 * of one cell at a time), PM_KNN_SUM_QUERIES consecutive places of the search order a
 * work-item, and those of them in one cell (the order is by cell) in
 * lockstep, one query a lane. Queries of one cell explore the same shells
 * and faces, so each photon is read once for all of them and tested side by
 * side; the choices pm_knn_pass makes per query (how many shells a box
 * sweeps, where an empty run of shells ends) are made here for all the
 * lanes at once, the most cautious of theirs: a box only where no lane can
 * reach k in it, a jump no farther than the nearest lane's end. A lane thus
 * takes the photons of its own search in its order up to the k-th, and its
 * search ends at the same shell with the same radius, count, shells and
 * flags; a query that never holds k photons gets its power summed (in
 * another order) and its list here, the others get theirs from pm_knn_sum.
 * Results start zeroed (the call's fill); only the first pass runs it. */
__kernel void pm_knn_reach(SLUICE_PARAMS, global const uint *order, global const pm_query *queries,
                           global const float *map, global const uint *map_start,
                           global const uint *cell_count, global const uint *sat, pg_params g,
                           pm_knn_params p, uint n, global pm_knn_result *results,
                           global uint *indices)
{
    SLUICE_FOR_EACH (w) {
        uint first = w * PM_SUM_W;
        float lx[PM_SUM_W], ly[PM_SUM_W], lz[PM_SUM_W], lnx[PM_SUM_W], lny[PM_SUM_W], lnz[PM_SUM_W];
        int lane_id[PM_SUM_W], qcs[PM_SUM_W][3];
        uint key[PM_SUM_W];
        for (int l = 0; l < PM_SUM_W; ++l) {
            uint i = first + (uint)l;
            lx[l] = ly[l] = lz[l] = lnx[l] = lny[l] = lnz[l] = 0.0f;
            lane_id[l] = l;
            key[l] = UINT_MAX; /* no query, or a bad one */
            if (i >= n)
                continue;
            pm_query Q = queries[i];
            if (!pg_finite(Q.px) || !pg_finite(Q.py) || !pg_finite(Q.pz)) {
                results[i].flags |= PM_KNN_DONE | PM_KNN_BAD_QUERY;
                continue;
            }
            float qp[3] = {Q.px, Q.py, Q.pz};
            for (int a = 0; a < 3; ++a)
                qcs[l][a] = (int)pg_axis(qp[a], g.lo[a], g.inv_cell[a], g.dims[a]);
            key[l] = (uint)qcs[l][0] + g.dims[0] * ((uint)qcs[l][1] + g.dims[1] * (uint)qcs[l][2]);
            lx[l] = Q.px;
            ly[l] = Q.py;
            lz[l] = Q.pz;
            lnx[l] = Q.nx;
            lny[l] = Q.ny;
            lnz[l] = Q.nz;
        }
        pm_lanes L;
        pm_lanes_load(&L, lx, ly, lz, lnx, lny, lnz, &g, &p);
        const pm_sumi lane = PM_SUM_VLOAD(0, lane_id);
        const pm_sumi k = (pm_sumi)((int)p.k);
        int n3[3] = {(int)g.dims[0], (int)g.dims[1], (int)g.dims[2]};
        for (int l0 = 0; l0 < PM_SUM_W;) {
            if (key[l0] == UINT_MAX) {
                ++l0;
                continue;
            }
            int l1 = l0 + 1;
            while (l1 < PM_SUM_W && key[l1] == key[l0])
                ++l1;
            const int qc[3] = {qcs[l0][0], qcs[l0][1], qcs[l0][2]};
            pm_sumi on = (lane >= (pm_sumi)(l0)) & (lane < (pm_sumi)(l1));
            L.r2 = L.sr = L.sg = L.sb = (pm_sumf)(0.0f);
            L.cnt = (pm_sumi)(0);
            int sh[PM_SUM_W], fl[PM_SUM_W], cut = 0;
            pm_sumi live = on;
            for (int s = 0, step = 0; PM_SUM_MASK(live); ++step) {
                if (step)
                    ++s;
                /* lanes holding k: their search ends here, at the cells
                 * their radius reaches (pm_knn_pass's full branch) */
                pm_sumi full = live & (L.cnt >= k);
                if (PM_SUM_MASK(full)) {
                    int fm[PM_SUM_W];
                    float fr2[PM_SUM_W];
                    PM_SUM_VSTORE(full, 0, fm);
                    PM_SUM_VSTORE(L.r2, 0, fr2);
                    for (int l = l0; l < l1; ++l) {
                        if (!fm[l])
                            continue;
                        float qp[3] = {lx[l], ly[l], lz[l]};
                        int b0[3], b1[3], covered;
                        int ext = pm_reach_cells(qp, fr2[l], qc, n3, &g, &p, b0, b1, &covered);
                        sh[l] = max(s, ext) + 1;
                        fl[l] = PM_KNN_DONE | (covered ? PM_KNN_COVERED_GRID : 0);
                    }
                    live &= ~full;
                    if (!PM_SUM_MASK(live))
                        break;
                }
                /* shells no lane can reach k in: one box */
                uint before = s > 0 ? pm_cube_count(sat, qc, s - 1, n3) : 0u;
                uint most = (uint)pm_sum_hmax(select((pm_sumi)(0), L.cnt, live));
                pm_box_end f = pm_box_end_start(s, pm_last_shell(qc, n3, s));
                for (int v; pm_box_end_next(&f, &v);) {
                    int cov = 0;
                    int r = most + (pm_cube_count(sat, qc, v, n3) - before) >= p.k;
                    if (!r) {
                        pm_sumf dv = pm_cube_d2_lanes(&L, qc, v, n3, &g, &p, &cov);
                        r = cov || PM_SUM_MASK(live & (dv >= (pm_sumf)(p.max_r2))) ? 2 : 0;
                    }
                    pm_box_end_tell(&f, r);
                }
                int u = pm_box_end_last(&f);
                if (u > s) {
                    int b0[3], b1[3];
                    pm_cube_cells(qc, u, n3, b0, b1);
                    pm_reach_box(&L, live, b0, b1, n3, qc, s - 1, &g, &p, map, map_start,
                                 cell_count, order, first, indices, &cut);
                    s = u;
                } else {
                    /* empty shells jumped over, to the first that holds
                     * photons or where a lane's search ends */
                    uint at_s = pm_cube_count(sat, qc, s, n3);
                    if (at_s == before) {
                        int lo = s, hi = pm_last_shell(qc, n3, s);
                        while (lo < hi) {
                            int mid = lo + (hi - lo) / 2, cov;
                            pm_sumf dm = pm_cube_d2_lanes(&L, qc, mid, n3, &g, &p, &cov);
                            if (pm_cube_count(sat, qc, mid, n3) != before || cov ||
                                PM_SUM_MASK(live & (dm >= (pm_sumf)(p.max_r2))))
                                hi = mid;
                            else
                                lo = mid + 1;
                        }
                        s = lo;
                        at_s = pm_cube_count(sat, qc, s, n3);
                    }
                    if (at_s != before) {
                        /* the shell's faces, as pm_knn_pass takes them */
                        for (int side = 0; side < 6; ++side) {
                            int b0[3], b1[3];
                            if (pm_face(sat, qc, s, n3, side, b0, b1))
                                pm_reach_box(&L, live, b0, b1, n3, qc, -1, &g, &p, map, map_start,
                                             cell_count, order, first, indices, &cut);
                        }
                    }
                }
                /* each lane's end, as pm_knn_pass decides it */
                int covered;
                pm_sumf ds2 = pm_cube_d2_lanes(&L, qc, s, n3, &g, &p, &covered);
                pm_sumi now_full = L.cnt >= k;
                pm_sumi done = live & ((pm_sumi)(covered ? -1 : 0) | (ds2 >= (pm_sumf)(p.max_r2)) |
                                       (now_full & (ds2 >= L.r2)));
                if (PM_SUM_MASK(done)) {
                    int dm[PM_SUM_W], fm[PM_SUM_W];
                    PM_SUM_VSTORE(done, 0, dm);
                    PM_SUM_VSTORE(now_full, 0, fm);
                    for (int l = l0; l < l1; ++l)
                        if (dm[l]) {
                            sh[l] = s + 1;
                            fl[l] = PM_KNN_DONE | (covered ? PM_KNN_COVERED_GRID
                                                           : (fm[l] ? 0 : PM_KNN_HIT_MAX_RADIUS));
                        }
                    live &= ~done;
                }
            }
            int c[PM_SUM_W];
            float fr[PM_SUM_W], fg[PM_SUM_W], fb[PM_SUM_W], f2[PM_SUM_W];
            PM_SUM_VSTORE(L.cnt, 0, c);
            PM_SUM_VSTORE(L.sr, 0, fr);
            PM_SUM_VSTORE(L.sg, 0, fg);
            PM_SUM_VSTORE(L.sb, 0, fb);
            PM_SUM_VSTORE(L.r2, 0, f2);
            for (int l = l0; l < l1; ++l) {
                global pm_knn_result *r = results + first + (uint)l;
                r->sr = fr[l];
                r->sg = fg[l];
                r->sb = fb[l];
                r->r2 = f2[l];
                r->count = (uint)c[l];
                r->shells = (uint)sh[l];
                r->flags = (uint)fl[l] | ((cut >> l) & 1 ? PM_KNN_INDICES_CUT : 0u);
            }
            l0 = l1;
        }
    }
}

/* The radius search over a hashed grid (Purcell 6.4.4): the photons of
 * map[b .. e), one bucket, that lie in lattice cell `c` (a bucket holds
 * every cell hashed to it: the others' photons are skipped, by the build's
 * own cell function, so a bucket visited for two cells gives each its own
 * photons and none twice) and within the maximum radius. The radius mode's
 * rule of pm_scan_run (every photon within max_r2 is added, r2 the farthest
 * one's), in blocks of PM_MAP_BLOCK, short runs one at a time. */
static inline int8 pm_hash_axis8(float8 x, float lo, float inv_cell)
{
    /* pg_hash_axis, lane by lane: the same subtraction and product, and
     * clamping before the truncating conversion gives its three cases */
    float8 f = (x - lo) * inv_cell;
    return convert_int8(fmin(fmax(f, (float8)(0.0f)), (float8)((float)PG_HASH_MAX_COORD)));
}

static inline void pm_scan_bucket(pm_state *st, uint b, uint e, const int *c,
                                  const pg_hash_params *h, const pm_knn_params *p,
                                  global const float *map, global uint *indices)
{
    uint stride = p->map_stride;
    if (e - b < PM_SHORT_BUCKET) {
        for (uint j = b; j < e; ++j) {
            float x = map[PM_MAP_X * stride + j], y = map[PM_MAP_Y * stride + j],
                  z = map[PM_MAP_Z * stride + j];
            float dx = x - st->px, dy = y - st->py, dz = z - st->pz;
            float d2 = PM_D2_(dx, dy, dz);
            if (!(d2 <= p->max_r2))
                continue;
            if ((int)pg_hash_axis(x, h->lo[0], h->inv_cell) != c[0] ||
                (int)pg_hash_axis(y, h->lo[1], h->inv_cell) != c[1] ||
                (int)pg_hash_axis(z, h->lo[2], h->inv_cell) != c[2])
                continue;
            if (p->normal_filter &&
                !(PM_DOT_(st->nx, st->ny, st->nz, map[PM_MAP_DX * stride + j],
                          map[PM_MAP_DY * stride + j], map[PM_MAP_DZ * stride + j]) < 0.0f))
                continue;
            st->r2 = fmax(st->r2, d2);
            if (p->index_cap)
                pm_index(st, p, map, j, st->count, indices);
            st->sr += map[PM_MAP_R * stride + j];
            st->sg += map[PM_MAP_G * stride + j];
            st->sb += map[PM_MAP_B * stride + j];
            st->count++;
        }
        return;
    }
    const int8 lane = (int8)(0, 1, 2, 3, 4, 5, 6, 7);
    float8 ar = (float8)(0.0f), ag = (float8)(0.0f), ab = (float8)(0.0f);
    for (uint j = b; j < e; j += PM_MAP_BLOCK) {
        float8 x = vload8(0, map + PM_MAP_X * stride + j);
        float8 y = vload8(0, map + PM_MAP_Y * stride + j);
        float8 z = vload8(0, map + PM_MAP_Z * stride + j);
        float8 dx = x - st->px, dy = y - st->py, dz = z - st->pz;
        float8 d2 = PM_D2_(dx, dy, dz);
        int8 m = (lane < (int8)((int)(e - j))) & (d2 <= (float8)(p->max_r2));
#ifdef PM_SKIP_EMPTY /* as in pm_scan_run */
        if (!sluice_mask8(m))
            continue;
#endif
        m &= (pm_hash_axis8(x, h->lo[0], h->inv_cell) == (int8)(c[0])) &
             (pm_hash_axis8(y, h->lo[1], h->inv_cell) == (int8)(c[1])) &
             (pm_hash_axis8(z, h->lo[2], h->inv_cell) == (int8)(c[2]));
        if (p->normal_filter) {
            float8 n = PM_DOT_((float8)(st->nx), (float8)(st->ny), (float8)(st->nz),
                               vload8(0, map + PM_MAP_DX * stride + j),
                               vload8(0, map + PM_MAP_DY * stride + j),
                               vload8(0, map + PM_MAP_DZ * stride + j));
            m &= n < (float8)(0.0f);
        }
#ifdef PM_SKIP_EMPTY
        if (!sluice_mask8(m))
            continue;
#endif
        st->r2 = fmax(st->r2, pm_hmax8(select((float8)(0.0f), d2, m)));
        pm_take8(st, p, map, j, m, &ar, &ag, &ab, indices);
    }
    st->sr += pm_hsum8(ar);
    st->sg += pm_hsum8(ag);
    st->sb += pm_hsum8(ab);
}

/* The radius search (pm_knn_params.k unread: every photon within the
 * maximum radius) over a hashed grid, one work-item per query, in one pass:
 * the lattice cells that the query's sphere, widened for rounding, overlaps
 * (cut to the cells of the photons' bounding box), each looked up in its
 * bucket. The widening: a photon the distance test takes lies within
 * r (1 + 2^-21) of the query along each axis, and computing q -+ reach
 * rounds by at most 2^-24 (|q| + reach); reach = r + (|q| + r) 2^-20 covers
 * both, and the cell function is monotone, so the photon's cell is in the
 * range. Results as the dense search's radius mode: the same photons, r2
 * the farthest one's, flags PM_KNN_DONE | PM_KNN_HIT_MAX_RADIUS; `shells`
 * holds the cells looked up. */
__kernel void pm_knn_hash(SLUICE_PARAMS, global const pm_query *queries, global const float *map,
                          global const uint *map_start, global const uint *bucket_count,
                          pg_hash_params h, pm_knn_params p, global pm_knn_result *results,
                          global uint *indices)
{
    SLUICE_FOR_EACH (q) {
        pm_query Q = queries[q];
        pm_knn_result r = {0.0f, 0.0f, 0.0f, 0.0f, 0u, 0u, PM_KNN_DONE};
        if (!pg_finite(Q.px) || !pg_finite(Q.py) || !pg_finite(Q.pz)) {
            r.flags |= PM_KNN_BAD_QUERY;
            results[q] = r;
            continue;
        }
        pm_state st;
        st.px = Q.px;
        st.py = Q.py;
        st.pz = Q.pz;
        st.nx = Q.nx;
        st.ny = Q.ny;
        st.nz = Q.nz;
        st.sr = st.sg = st.sb = st.r2 = 0.0f;
        st.gx = 0.0f;
        st.count = 0u;
        st.flags = 0u;
        st.q = q;
        st.hd = 0;
        st.hi = 0;
        float qp[3] = {Q.px, Q.py, Q.pz};
        uint looked = 0u;
        if (pm_box_d2(qp, &p) <= p.max_r2) {
            float rad = sqrt(p.max_r2);
            int a0[3], a1[3];
            for (int a = 0; a < 3; ++a) {
                float reach = rad + (fabs(qp[a]) + rad) * 0x1p-20f;
                a0[a] = (int)max(pg_hash_axis(qp[a] - reach, h.lo[a], h.inv_cell),
                                 pg_hash_axis(p.box_lo[a], h.lo[a], h.inv_cell));
                a1[a] = (int)min(pg_hash_axis(qp[a] + reach, h.lo[a], h.inv_cell),
                                 pg_hash_axis(p.box_hi[a], h.lo[a], h.inv_cell));
            }
            int c[3];
            for (c[2] = a0[2]; c[2] <= a1[2]; ++c[2])
                for (c[1] = a0[1]; c[1] <= a1[1]; ++c[1])
                    for (c[0] = a0[0]; c[0] <= a1[0]; ++c[0]) {
                        uint bk = pg_hash_bucket((uint)c[0], (uint)c[1], (uint)c[2], h.mask);
                        uint n = bucket_count[bk];
                        ++looked;
                        if (n)
                            pm_scan_bucket(&st, map_start[bk], map_start[bk] + n, c, &h, &p, map,
                                           indices);
                    }
        }
        r.sr = st.sr;
        r.sg = st.sg;
        r.sb = st.sb;
        r.r2 = st.r2;
        r.count = st.count;
        r.shells = looked;
        r.flags |= st.flags | PM_KNN_HIT_MAX_RADIUS;
        results[q] = r;
    }
}

/* The live queries that are not done, into the next live stream (results
 * in the search order). */
__kernel void pm_knn_live(SLUICE_PARAMS, global const uint *live,
                          global const pm_knn_result *results, global uint *next)
{
    SLUICE_FOR_EACH (i) {
        uint at = live[i];
        SLUICE_EMIT_IF(0, next, at, (results[at].flags & PM_KNN_DONE) == 0u);
    }
}
