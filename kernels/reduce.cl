/*
 * Reductions (streams/reduce.c) over contiguous chunks:
 *
 *   pass 1  reduce_part_OP_T   one work-item per chunk reduces its records,
 *                              16 at a time (SLUICE_REDUCE16_), into parts[id]
 *   pass 2  reduce_final_OP_T  one work-item (a work-group on GPUs) reduces
 *                              parts[0..m) into parts[m]
 *
 * On GPUs (the runtime's interleaved layout) pass 1 runs one work-group per
 * chunk instead (reduce_part_wg_OP_T), its work-items reading neighbouring
 * records.
 *
 * Empty chunks give the identity, so an empty stream reduces to it. Float MIN
 * and MAX follow fmin/fmax (SLUICE_FMIN_): a NaN is ignored unless every
 * record is NaN.
 *
 * The input length is `n_fixed` when the host knows it, otherwise the
 * device-side variable vars[in_var]; past `limit` (the capacity) the input
 * overflowed: nothing is read and parts[m + 1] is set, so the host reports
 * the overflow instead of a result.
 */
#include "sluice.cl"

#define REDUCE_NONE 0xffffffffu

inline uint reduce_length_(global const uint *vars, uint in_var, uint n_fixed, uint limit)
{
    return n_fixed != REDUCE_NONE ? n_fixed : sluice_stream_length_(vars, in_var, limit);
}

#define REDUCE_KERNELS(T, T16, NAME, IDENTITY, OP)                                                 \
    __kernel void reduce_part_##NAME(global const uint *vars, uint in_var, uint n_fixed,           \
                                     uint limit, uint chunk, global const T *in, global T *parts)  \
    {                                                                                              \
        uint n = reduce_length_(vars, in_var, n_fixed, limit);                                     \
        ulong b = (ulong)get_global_id(0) * chunk;                                                 \
        uint begin = (uint)min(b, (ulong)n), end = (uint)min(b + chunk, (ulong)n);                 \
        T r;                                                                                       \
        SLUICE_REDUCE16_(T, T16, in, begin, end, IDENTITY, OP, r);                                 \
        parts[get_global_id(0)] = r;                                                               \
        if (get_global_id(0) == 0)                                                                 \
            parts[get_global_size(0) + 1u] = (T)(n_fixed == REDUCE_NONE && vars[in_var] > limit);  \
    }                                                                                              \
                                                                                                   \
    /* The GPU layout's pass 1: one work-group per chunk (SLUICE_GROUP_REDUCE_). */                \
    __kernel void reduce_part_wg_##NAME(global const uint *vars, uint in_var, uint n_fixed,        \
                                        uint limit, uint chunk, global const T *in,                \
                                        global T *parts, local T *part)                            \
    {                                                                                              \
        uint n = reduce_length_(vars, in_var, n_fixed, limit);                                     \
        ulong b = (ulong)get_group_id(0) * chunk;                                                  \
        uint begin = (uint)min(b, (ulong)n), end = (uint)min(b + chunk, (ulong)n);                 \
        SLUICE_GROUP_REDUCE_(T, in, begin, end, IDENTITY, OP, part);                               \
        if (get_local_id(0) != 0)                                                                  \
            return;                                                                                \
        parts[get_group_id(0)] = part[0];                                                          \
        if (get_group_id(0) == 0)                                                                  \
            parts[get_num_groups(0) + 1u] = (T)(n_fixed == REDUCE_NONE && vars[in_var] > limit);   \
    }                                                                                              \
                                                                                                   \
    /* One work-group (one work-item on a CPU, a group on a GPU). */                               \
    __kernel void reduce_final_##NAME(global T *parts, uint m, local T *part)                      \
    {                                                                                              \
        if (get_group_id(0) != 0)                                                                  \
            return;                                                                                \
        SLUICE_GROUP_REDUCE_(T, parts, 0u, m, IDENTITY, OP, part);                                 \
        if (get_local_id(0) == 0)                                                                  \
            parts[m] = part[0];                                                                    \
    }

REDUCE_KERNELS(uint, uint16, sum_u32, 0u, SLUICE_ADD_)
REDUCE_KERNELS(uint, uint16, min_u32, 0xffffffffu, SLUICE_MIN_)
REDUCE_KERNELS(uint, uint16, max_u32, 0u, SLUICE_MAX_)
REDUCE_KERNELS(float, float16, sum_f32, 0.0f, SLUICE_ADD_)
REDUCE_KERNELS(float, float16, min_f32, INFINITY, SLUICE_FMIN_)
REDUCE_KERNELS(float, float16, max_f32, -INFINITY, SLUICE_FMAX_)
