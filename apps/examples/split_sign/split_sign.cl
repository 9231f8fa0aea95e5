/*
 * split_sign.cl: the kernel of the split_sign example.
 *
 * One input stream of floats, three conditional output streams:
 *   slot 0  negative  x < 0
 *   slot 1  small     0 <= x < threshold
 *   slot 2  large     x >= threshold
 * and two counters:
 *   counter 0  near_zero  records with |x| < epsilon
 *   counter 1  kept       records that are not NaN (NaNs go nowhere)
 *
 * The host (main.c) binds the streams and counters to these parameters and
 * chooses for each output whether it keeps the input order (ORDERED) or not
 * (UNORDERED); the kernel is the same either way.
 */
#include "sluice.cl"

__kernel void split_sign(SLUICE_PARAMS,          /* hidden parameters, always first */
                         global const float *in, /* argument 0: the input stream */
                         global float *negative, /* argument 1: output slot 0 */
                         global float *small,    /* argument 2: output slot 1 */
                         global float *large,    /* argument 3: output slot 2 */
                         float threshold,        /* argument 4 */
                         float epsilon)          /* argument 5 */
{
    SLUICE_FOR_EACH (i) {
        float x = in[i];

        /* Not a number: emit nothing, count nothing more. `continue`, never
         * `return` or `break`. */
        if (isnan(x))
            continue;

        SLUICE_EMIT_IF(0, negative, x, x < 0.0f);
        SLUICE_EMIT_IF(1, small, x, x >= 0.0f && x < threshold);
        SLUICE_EMIT_IF(2, large, x, x >= threshold);

        SLUICE_COUNT(0, fabs(x) < epsilon);
        SLUICE_COUNT(1, 1u); /* reached only by records that are not NaN */
    }
}
