/* Command-line helpers shared by the benchmark programs. */
#ifndef SLUICE_BENCH_ARGS_H
#define SLUICE_BENCH_ARGS_H

#include <errno.h>
#include <stdlib.h>

/* Parses a whole decimal number of at most `max` into *out; 0 on anything
 * else (empty, a sign, trailing characters, overflow). */
static inline int bench_parse_uint(const char *s, unsigned max, unsigned *out)
{
    if (!s || *s < '0' || *s > '9')
        return 0;
    char *end;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (errno || *end || v > max)
        return 0;
    *out = (unsigned)v;
    return 1;
}

#endif /* SLUICE_BENCH_ARGS_H */
