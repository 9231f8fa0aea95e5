/* The kNN-grid search (apps/photonmap/knn.c; Purcell 6.2.3, Fig. 6.6).
 * sr_program_create prepends rt_types.h, pg_types.h (the point grid's cell
 * function, shared with its build) and pm_types.h.
 *
 * One pass = pm_knn_pass over the live query ids, each exploring one more
 * shell of cells (the cells at Chebyshev distance `shells` from the query's
 * cell) and deciding whether it is done, then pm_knn_live, which emits the
 * ids still searching into the next live stream. The heavy work is in a
 * kernel without conditional outputs, since an emitting body runs twice. */
#include "sluice.cl"

/* Squared distance from x to the slab of cell j of an axis of n cells,
 * shrunk by the margin. The boundary cells reach to infinity: points
 * outside the box are clamped into them. */
static inline float pm_gap2(float x, int j, int n, float lo, float cell, float margin)
{
    float gap = 0.0f;
    if (j > 0) {
        float l = lo + (float)j * cell;
        if (x < l)
            gap = l - x;
    }
    if (j < n - 1) {
        float h = lo + (float)(j + 1) * cell;
        if (x > h)
            gap = x - h;
    }
    gap -= margin;
    return gap > 0.0f ? gap * gap : 0.0f;
}

/* A query's running estimate while it is in a kernel. */
typedef struct pm_state {
    float px, py, pz, nx, ny, nz;
    float sr, sg, sb, r2;
    uint count, flags, q;
    global float *hd; /* exact: heap of squared distances (max at 0) */
    global uint *hi;  /* exact: heap of photon ids */
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

/* Examines the photons of cell c (Purcell Fig. 6.6). */
static inline void pm_scan_cell(pm_state *st, uint c, const pm_knn_params *p, uint exact,
                                global const pm_photon *photons, global const uint *order,
                                global const uint *cell_start, global const uint *cell_count,
                                global const uint *cell_arrived, global uint *indices)
{
    uint b = cell_start[c], n = cell_count[c];
    if (n == 0u)
        return;
    /* Purcell's power redistribution: exactly 1 unless the stencil build
     * dropped photons of this cell. */
    float scale = (float)cell_arrived[c] / (float)n;
    for (uint j = b; j < b + n; ++j) {
        uint id = order[j];
        global const pm_photon *ph = photons + id;
        if (p->normal_filter && !(st->nx * ph->dx + st->ny * ph->dy + st->nz * ph->dz < 0.0f))
            continue;
        float dx = ph->px - st->px, dy = ph->py - st->py, dz = ph->pz - st->pz;
        float d2 = dx * dx + dy * dy + dz * dz;
        if (!(d2 <= p->max_r2))
            continue;
        if (exact) {
            pm_heap_add(st, p->k, d2, id);
            continue;
        }
        if (st->count < p->k)
            st->r2 = fmax(st->r2, d2);
        else if (!(d2 <= st->r2))
            continue;
        st->sr += ph->pr * scale;
        st->sg += ph->pg * scale;
        st->sb += ph->pb * scale;
        if (p->index_cap) {
            if (st->count < p->index_cap)
                indices[(ulong)st->q * p->index_cap + st->count] = id;
            else
                st->flags |= PM_KNN_INDICES_CUT;
        }
        st->count++;
    }
}

/* Zeroes the results of queries base .. base+n and lists them as live. */
__kernel void pm_knn_init(SLUICE_PARAMS, global pm_knn_result *results, global uint *live,
                          uint base)
{
    SLUICE_FOR_EACH (i) {
        pm_knn_result r = {0.0f, 0.0f, 0.0f, 0.0f, 0u, 0u, 0u};
        results[base + i] = r;
        live[i] = base + i;
    }
}

/* One shell for every live query (see the top of the file). */
__kernel void pm_knn_pass(SLUICE_PARAMS, global const uint *live, global const pm_query *queries,
                          global const pm_photon *photons, global const uint *order,
                          global const uint *cell_start, global const uint *cell_count,
                          global const uint *cell_arrived, pg_params g, pm_knn_params p, uint exact,
                          uint base, global pm_knn_result *results, global float *heap_d2,
                          global uint *heap_id, global uint *indices)
{
    SLUICE_FOR_EACH (i) {
        uint q = live[i];
        pm_query Q = queries[q];
        pm_knn_result r = results[q];
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
        st.hd = heap_d2 + (ulong)(q - base) * (exact ? p.k : 0u);
        st.hi = heap_id + (ulong)(q - base) * (exact ? p.k : 0u);
        if (!pg_finite(Q.px) || !pg_finite(Q.py) || !pg_finite(Q.pz)) {
            r.flags |= PM_KNN_DONE | PM_KNN_BAD_QUERY;
            results[q] = r;
            continue;
        }
        float qp[3] = {Q.px, Q.py, Q.pz};
        int qc[3], n[3];
        for (int a = 0; a < 3; ++a) {
            n[a] = (int)g.dims[a];
            qc[a] = (int)pg_axis(qp[a], g.lo[a], g.inv_cell[a], g.dims[a]);
        }
        int s = (int)r.shells;
        int z0 = max(qc[2] - s, 0), z1 = min(qc[2] + s, n[2] - 1);
        int y0 = max(qc[1] - s, 0), y1 = min(qc[1] + s, n[1] - 1);
        int x0 = max(qc[0] - s, 0), x1 = min(qc[0] + s, n[0] - 1);
        for (int z = z0; z <= z1; ++z) {
            int zedge = abs(z - qc[2]) == s;
            float gz = pm_gap2(st.pz, z, n[2], g.lo[2], g.cell[2], p.margin[2]);
            for (int y = y0; y <= y1; ++y) {
                int edge = zedge || abs(y - qc[1]) == s;
                float gyz = gz + pm_gap2(st.py, y, n[1], g.lo[1], g.cell[1], p.margin[1]);
                if (gyz > pm_bound(&st, &p, exact))
                    continue;
                uint row = (uint)n[0] * ((uint)y + (uint)n[1] * (uint)z);
                /* inside the shell's faces only its two ends along x are new */
                int step = edge ? 1 : 2 * s;
                int xa = edge ? x0 : qc[0] - s;
                for (int x = xa; x <= x1; x += step) {
                    if (x < 0)
                        continue;
                    float d2 = gyz + pm_gap2(st.px, x, n[0], g.lo[0], g.cell[0], p.margin[0]);
                    if (d2 > pm_bound(&st, &p, exact))
                        continue;
                    pm_scan_cell(&st, row + (uint)x, &p, exact, photons, order, cell_start,
                                 cell_count, cell_arrived, indices);
                }
            }
        }
        /* The explored cube [qc - s, qc + s]: its inscribed radius d_s, and
         * whether it covers the grid (a side on the grid's boundary is
         * infinitely far: nothing lies beyond it). */
        float d = INFINITY;
        int covered = 1;
        for (int a = 0; a < 3; ++a) {
            if (qc[a] - s > 0) {
                covered = 0;
                d = fmin(d, qp[a] - (g.lo[a] + (float)(qc[a] - s) * g.cell[a]) - p.margin[a]);
            }
            if (qc[a] + s < n[a] - 1) {
                covered = 0;
                d = fmin(d, g.lo[a] + (float)(qc[a] + s + 1) * g.cell[a] - qp[a] - p.margin[a]);
            }
        }
        float ds2 = covered ? INFINITY : (d > 0.0f ? d * d : 0.0f);
        int full = exact ? st.count == p.k : st.count >= p.k;
        float reach = exact ? (st.count ? st.hd[0] : 0.0f) : st.r2;
        int done = covered || ds2 >= p.max_r2 || (full && ds2 >= reach);
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
                uint id = st.hi[j];
                global const pm_photon *ph = photons + id;
                uint c = pg_cell(ph->px, ph->py, ph->pz, &g);
                float scale = (float)cell_arrived[c] / (float)cell_count[c];
                sr += ph->pr * scale;
                sg += ph->pg * scale;
                sb += ph->pb * scale;
                if (p.index_cap && j < p.index_cap)
                    indices[(ulong)q * p.index_cap + j] = id;
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
        results[q] = r;
    }
}

/* The live queries that are not done, into the next live stream. */
__kernel void pm_knn_live(SLUICE_PARAMS, global const uint *live,
                          global const pm_knn_result *results, global uint *next)
{
    SLUICE_FOR_EACH (i) {
        uint q = live[i];
        SLUICE_EMIT_IF(0, next, q, (results[q].flags & PM_KNN_DONE) == 0u);
    }
}
