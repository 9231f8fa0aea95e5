/*
 * triangle.cl: reading the scene's triangle records (sr_device_scene.
 * tri_records, 9 floats per triangle), for the tracer and every shader.
 * Records hold (v0, v1 - v0, v2 - v0) for Moller-Trumbore, or (v0, v1, v2)
 * when the program is built with RT_WATERTIGHT (see rt_trace.cl for why).
 *
 * Floating point contraction is off in every renderer program, so kernels and
 * the plain C references round the same way (rt_trace.cl says more).
 */
#ifndef SR_TRIANGLE_CL
#define SR_TRIANGLE_CL

#pragma OPENCL FP_CONTRACT OFF

/* Triangle `tri` of the triangle records as a vertex and two edges, in
 * either layout. */
inline void rt_tri_edges(global const float *tv, uint tri, float3 *v0, float3 *e1, float3 *e2)
{
    global const float *p = tv + 9u * (size_t)tri;
    *v0 = vload3(0, p);
#ifdef RT_WATERTIGHT
    *e1 = vload3(1, p) - *v0;
    *e2 = vload3(2, p) - *v0;
#else
    *e1 = vload3(1, p);
    *e2 = vload3(2, p);
#endif
}

#endif
