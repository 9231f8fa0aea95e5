/*
 * The `stream` execution mode: Purcell's multipass ray tracer (thesis 3.1 and
 * 4.1.2) on a sluice_loop.
 *
 * Every live ray is in one of two streams of ray ids: "traverse" (its voxel
 * has not been looked at) or "intersect" (its voxel has triangles left to
 * test). What a ray has done so far is kept by ray, as Purcell keeps it in
 * textures: its voxel and list position in `walk`, its best hit and work
 * counts in its own hit record, both updated in place by the one work-item
 * that handles the ray in a pass. A pass runs one of two kernels over one of
 * the id streams; it writes each ray's next stream as a code aligned with its
 * input, and the route kernel sends the ids on to the traverse or intersect
 * stream by conditional outputs (16 at a time); finished rays go nowhere,
 * their hit already in place. The input stream and its output are a
 * ping-pong pair, swapped after the pass on the device (no round trip).
 * The setup kernel clips every ray to the grid and takes it through the
 * first traverse pass too (the rays are read once for both), and
 * rt_route_setup sends the ray indices to the two streams.
 * After each pass the loop reads both lengths and the counters in one read
 * and the oracle picks the next pass by Purcell's rule: intersect once at
 * least a fraction (20% by default) of the live rays wait for it, else
 * traverse. On his hardware that rule keeps the SIMD units busy; here it
 * keeps launches large.
 */
#include "tracer_internal.h"

#include <string.h>

enum { PASS_TRAVERSE = 0, PASS_INTERSECT = 1 };

/* Watched values: the two stream lengths, then the trace counters. */
enum {
    W_TRAV = 0,
    W_ISECT = 1,
    W_VOXELS = 2 + RT_CTR_VOXELS,
    W_TESTS = 2 + RT_CTR_TESTS,
    W_ENTERED = 2 + RT_CTR_ENTERED
};

static unsigned oracle(void *user, unsigned pass, const uint32_t *v, size_t count)
{
    rt_tracer *t = user;
    (void)count;
    t->stats.voxels += v[W_VOXELS];
    t->stats.tests += v[W_TESTS];
    /* rt_setup ran the first traverse pass over every ray that entered the
     * grid: Purcell's pass count has it as one */
    if (pass == 0 && v[W_ENTERED] > 0) {
        t->stats.live_fraction_sum += 1.0;
        t->stats.passes++;
        t->stats.traverse_passes++;
    }
    uint64_t live = (uint64_t)v[W_TRAV] + v[W_ISECT];
    if (live == 0)
        return SLUICE_LOOP_STOP;
    unsigned choice;
    if (v[W_TRAV] == 0)
        choice = PASS_INTERSECT;
    else if (v[W_ISECT] == 0)
        choice = PASS_TRAVERSE;
    else
        choice = (double)v[W_ISECT] >= (double)t->opt.intersect_threshold * (double)live
                     ? PASS_INTERSECT
                     : PASS_TRAVERSE;
    uint32_t processed = choice == PASS_INTERSECT ? v[W_ISECT] : v[W_TRAV];
    t->stats.live_fraction_sum += (double)processed / (double)live;
    t->stats.passes++;
    if (choice == PASS_INTERSECT)
        t->stats.intersect_passes++;
    else
        t->stats.traverse_passes++;
    return choice;
}

static sluice_status pass_fn(void *user, unsigned pass, unsigned choice)
{
    rt_tracer *t = user;
    (void)pass;
    sluice_status st;
    if (choice == PASS_TRAVERSE) {
        st = sluice_stream_clear(t->trav_out);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch(t->k_traverse);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch(t->k_route_t);
        if (st == SLUICE_OK)
            st = sluice_stream_swap(t->trav_in, t->trav_out);
    } else {
        st = sluice_stream_clear(t->isect_out);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch(t->k_intersect);
        if (st == SLUICE_OK)
            st = sluice_kernel_launch(t->k_route_i);
        if (st == SLUICE_OK)
            st = sluice_stream_swap(t->isect_in, t->isect_out);
    }
    return st;
}

void rt_stream_release(rt_tracer *t)
{
    sluice_loop_destroy(t->loop);
    t->loop = NULL;
    sluice_stream **s[] = {&t->trav_in,   &t->trav_out, &t->isect_in,
                           &t->isect_out, &t->codes,    &t->walk};
    for (size_t i = 0; i < sizeof s / sizeof *s; ++i) {
        sluice_stream_destroy(*s[i]);
        *s[i] = NULL;
    }
    t->state_capacity = 0;
}

/* Makes the id streams and the per-ray state hold n rays and binds what does
 * not change between calls. */
static sluice_status prepare(rt_tracer *t, size_t n)
{
    if (t->state_capacity >= n && t->loop)
        return SLUICE_OK;
    rt_stream_release(t);
    sluice_context *ctx = t->ctx;
    sluice_stream **s[] = {&t->trav_in, &t->trav_out, &t->isect_in, &t->isect_out, &t->codes};
    sluice_status st = SLUICE_OK;
    for (size_t i = 0; i < sizeof s / sizeof *s && st == SLUICE_OK; ++i)
        st = sluice_stream_create(ctx, sizeof(uint32_t), n, s[i]);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof(rt_walk), n, &t->walk);
    if (st != SLUICE_OK) {
        rt_stream_release(t);
        return st;
    }
    t->state_capacity = n;
    sluice_output_mode mode = t->opt.ordered ? SLUICE_ORDERED : SLUICE_UNORDERED;

    /* rt_setup(rays, codes, walk, hits, maxima, cell_start, g, voxel_bits):
     * rays and hits bound per call */
    sluice_kernel *k = t->k_setup;
    st = sluice_kernel_set_stream(k, 1, t->codes, 1);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 2, t->walk, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 4, t->maxima, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 5, t->grid.cell_start, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(k, 6, sizeof t->grid_args, &t->grid_args);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 7, t->voxel_bits, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_counters(k, t->counters);

    /* rt_traverse(ids, codes, walk, rays, hits, maxima, cell_start, g,
     * voxel_bits) and
     * rt_intersect(ids, codes, walk, rays, hits, maxima, cell_start,
     * cell_tris, tv, g) */
    sluice_kernel *heavy[2] = {t->k_traverse, t->k_intersect};
    sluice_stream *ids[2] = {t->trav_in, t->isect_in};
    for (int j = 0; j < 2; ++j) {
        k = heavy[j];
        if (st == SLUICE_OK)
            st = sluice_kernel_set_input(k, 0, ids[j]);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(k, 1, t->codes, 1);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(k, 2, t->walk, 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(k, 5, t->maxima, 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(k, 6, t->grid.cell_start, 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_counters(k, t->counters);
    }
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(t->k_traverse, 7, sizeof t->grid_args, &t->grid_args);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(t->k_traverse, 8, t->voxel_bits, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(t->k_intersect, 7, t->grid.cell_tris, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(t->k_intersect, 8, t->ds->tri_records, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_arg(t->k_intersect, 9, sizeof t->grid_args, &t->grid_args);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(t->k_intersect, 10,
                                      t->list_records ? t->list_records : t->ds->tri_records, 0);

    /* rt_route(codes, ids, trav, isect): after a traverse pass into
     * (trav_out, isect_in), after an intersect pass into (trav_in,
     * isect_out); rt_route_setup(codes, trav, isect) into (trav_in,
     * isect_in) */
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(t->k_route_t, 0, t->codes);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(t->k_route_t, 1, t->trav_in, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(t->k_route_t, 2, 0, t->trav_out, mode);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(t->k_route_t, 3, 1, t->isect_in, mode);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(t->k_route_i, 0, t->codes);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(t->k_route_i, 1, t->isect_in, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(t->k_route_i, 2, 0, t->trav_in, mode);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(t->k_route_i, 3, 1, t->isect_out, mode);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(t->k_route_setup, 0, t->codes);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(t->k_route_setup, 1, 0, t->trav_in, mode);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(t->k_route_setup, 2, 1, t->isect_in, mode);

    if (st == SLUICE_OK) {
        sluice_loop_desc d;
        memset(&d, 0, sizeof d);
        d.pass = pass_fn;
        d.oracle = oracle;
        d.user = t;
        t->watched[0] = t->trav_in;
        t->watched[1] = t->isect_in;
        d.streams = t->watched;
        d.stream_count = 2;
        d.counters = t->counters;
        d.reset_counters = 1;
        d.max_passes = 10000000u;
        st = sluice_loop_create(ctx, &d, &t->loop);
    }
    if (st != SLUICE_OK)
        rt_stream_release(t);
    return st;
}

sluice_status rt_stream_trace(rt_tracer *t, sluice_stream *rays, size_t n, sluice_stream *hits)
{
    size_t cap = sluice_stream_capacity(rays);
    sluice_status st = prepare(t, cap > n ? cap : n);
    if (st != SLUICE_OK)
        return st;
    st = sluice_stream_clear(t->trav_in);
    if (st == SLUICE_OK)
        st = sluice_stream_clear(t->isect_in);
    if (st == SLUICE_OK)
        st = sluice_counters_reset(t->counters);
    /* per-call bindings: the rays and the hits, which hold each ray's best
     * hit while it is traced */
    sluice_kernel *k[3] = {t->k_setup, t->k_traverse, t->k_intersect};
    if (st == SLUICE_OK)
        st = sluice_kernel_set_input(t->k_setup, 0, rays);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(t->k_setup, 3, hits, 0);
    for (int j = 1; j < 3; ++j) {
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(k[j], 3, rays, 0);
        if (st == SLUICE_OK)
            st = sluice_kernel_set_stream(k[j], 4, hits, 0);
    }
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(t->k_setup);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch(t->k_route_setup);
    if (st == SLUICE_OK)
        st = sluice_loop_run(t->loop);
    /* hits are written by ray, not a mapped output: give them the length */
    if (st == SLUICE_OK)
        st = sluice_stream_set_length(hits, n);
    return st;
}
