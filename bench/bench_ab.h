/* What the A/B benchmarks (bench_raytrace_ab, bench_knn_ab) share: a context
 * per variant with its own kernel build options, and the summary of timed
 * pairs run alternately (A B, then B A), so that drift in a shared machine's
 * speed falls on both variants alike. */
#ifndef SLUICE_BENCH_AB_H
#define SLUICE_BENCH_AB_H

#include "sluice/sluice.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static inline int bench_ab_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* A context whose kernel builds append `options` (the context option
 * build_options); 0 after saying why on stderr. */
static inline int bench_ab_context(const char *prog, char name, const char *options,
                                   sluice_context **out)
{
    char err[512];
    sluice_context_options co;
    memset(&co, 0, sizeof co);
    co.build_options = options;
    if (sluice_context_create(&co, out, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "%s: variant %c: %s\n", prog, name, err);
        return 0;
    }
    return 1;
}

/* B's speed over A's (A's time over B's) in every pair: its lower quartile,
 * median and upper quartile in q[0..2]. Sorts each variant's times (best
 * first) for the caller's own figures. 0 when out of memory. */
static inline int bench_ab_ratio(double *a, double *b, unsigned pairs, double q[3])
{
    double *ratio = malloc(pairs * sizeof *ratio);
    if (!ratio)
        return 0;
    for (unsigned f = 0; f < pairs; ++f)
        ratio[f] = a[f] / b[f];
    qsort(ratio, pairs, sizeof *ratio, bench_ab_cmp_double);
    qsort(a, pairs, sizeof *a, bench_ab_cmp_double);
    qsort(b, pairs, sizeof *b, bench_ab_cmp_double);
    q[0] = ratio[pairs / 4];
    q[1] = ratio[pairs / 2];
    q[2] = ratio[(3 * pairs) / 4];
    free(ratio);
    return 1;
}

#endif /* SLUICE_BENCH_AB_H */
