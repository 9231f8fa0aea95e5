/* A minimal test harness: CHECK records a failure and goes on; each test
 * program ends with check_summary(), which prints "N passed, N failed" and
 * returns the exit status. */
#ifndef SLUICE_TESTS_CHECK_H
#define SLUICE_TESTS_CHECK_H

#include "sluice/sluice.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

static int check_passed_, check_failed_;

#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (cond) {                                                                                \
            check_passed_++;                                                                       \
        } else {                                                                                   \
            check_failed_++;                                                                       \
            fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond);               \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
        }                                                                                          \
    } while (0)

/* Checks that a sluice call returned SLUICE_OK, printing the context error. */
#define CHECK_OK(ctx, call)                                                                        \
    do {                                                                                           \
        sluice_status st_ = (call);                                                                \
        CHECK(st_ == SLUICE_OK, "%s -> %s: %s", #call, sluice_status_string(st_),                  \
              sluice_context_error(ctx));                                                          \
    } while (0)

/* Runs the shell command `cmd` with stderr joined to stdout, keeps the first
 * out_size - 1 bytes of its output in `out` (NUL-terminated) and returns its
 * exit status (128 + signal when killed, -1 when it could not run). For the
 * tests of the command-line tools. */
static inline int check_run(const char *cmd, char *out, size_t out_size)
{
    char full[4096];
    snprintf(full, sizeof full, "%s 2>&1", cmd);
    FILE *p = popen(full, "r");
    if (!p)
        return -1;
    size_t n = fread(out, 1, out_size - 1, p);
    out[n] = '\0';
    while (fgetc(p) != EOF) {
    }
    int st = pclose(p);
    if (WIFEXITED(st))
        return WEXITSTATUS(st);
    return WIFSIGNALED(st) ? 128 + WTERMSIG(st) : -1;
}

static inline int check_summary(void)
{
    printf("%d passed, %d failed\n", check_passed_, check_failed_);
    return check_failed_ ? 1 : 0;
}

/* Creates the test context or exits with a message (tests only). */
static inline sluice_context *check_context(int profile)
{
    char err[512];
    sluice_context_options o = {0};
    o.profile = profile;
    sluice_context *ctx = NULL;
    if (sluice_context_create(&o, &ctx, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "cannot create a context: %s\n", err);
        exit(2);
    }
    return ctx;
}

/* Makes `*out` a stream of `cap` uint32 records into which kernel
 * check_fill emitted the n records 0 .. n-1 at output slot 0: past its
 * capacity when n > cap. With `read` 0 its length stays on the device, as
 * after any launch; with 1 the host reads it (which reports the overflow),
 * so it is known on the host. For the tests of how overflow is reported;
 * the caller destroys the stream. */
static inline sluice_status check_overflowed(sluice_context *ctx, size_t n, size_t cap, int read,
                                             sluice_stream **out)
{
    static const char src[] = "#include \"sluice.cl\"\n"
                              "__kernel void check_fill(SLUICE_PARAMS, global uint *out)\n"
                              "{\n"
                              "    SLUICE_FOR_EACH(i)\n"
                              "        SLUICE_EMIT(0, out, i);\n"
                              "}\n";
    sluice_program *p = NULL;
    sluice_kernel *k = NULL;
    sluice_status st = sluice_stream_create(ctx, 4, cap, out);
    if (st == SLUICE_OK)
        st = sluice_program_create_source(ctx, "check_fill.cl", src, NULL, &p);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(p, "check_fill", &k);
    if (st == SLUICE_OK)
        st = sluice_kernel_set_output(k, 0, 0, *out, SLUICE_UNORDERED);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, n);
    sluice_kernel_destroy(k);
    sluice_program_destroy(p);
    size_t len;
    if (st == SLUICE_OK && read && sluice_stream_length(*out, &len) != SLUICE_ERROR_OVERFLOW)
        st = SLUICE_ERROR_INVALID_ARGUMENT; /* n <= cap: it did not overflow */
    return st;
}

/* Whether the context's error message names check_fill's overflow (see
 * check_overflowed): the kernel, the output slot, the capacity and the
 * records emitted. */
static inline int check_overflow_named(sluice_context *ctx, size_t n, size_t cap)
{
    char want[160];
    snprintf(want, sizeof want,
             "%zu records were emitted into output slot 0 of kernel check_fill, a stream of "
             "capacity %zu",
             n, cap);
    return strstr(sluice_context_error(ctx), want) != NULL;
}

/* Sorts `n` records of `rs` bytes in place, stably, by the key that
 * key(record, b, arg) gives byte b of (b = 0 the least significant; `bytes`
 * of them): an LSD radix sort, a pass per byte that varies. The multiset
 * comparisons of unordered outputs sorted with qsort, whose comparator
 * calls were most of those tests' time under the sanitizers. Returns 0 when
 * out of memory (nothing sorted). */
static inline int check_radix(void *records, size_t n, size_t rs, size_t bytes,
                              unsigned (*key)(const unsigned char *, size_t, size_t), size_t arg)
{
    unsigned char *a = (unsigned char *)records, *b = (unsigned char *)malloc(n * rs + 1);
    if (!b)
        return 0;
    for (size_t byte = 0; byte < bytes; ++byte) {
        size_t count[257] = {0};
        for (size_t i = 0; i < n; ++i)
            ++count[key(a + i * rs, byte, arg) + 1];
        int one = 0; /* every record has the same byte: the pass changes nothing */
        for (size_t d = 1; d <= 256; ++d)
            one |= count[d] == n;
        if (one)
            continue;
        for (size_t d = 1; d <= 256; ++d)
            count[d] += count[d - 1];
        for (size_t i = 0; i < n; ++i)
            memcpy(b + rs * count[key(a + i * rs, byte, arg)]++, a + i * rs, rs);
        unsigned char *t = a;
        a = b;
        b = t;
    }
    if (a != (unsigned char *)records) {
        memcpy(records, a, n * rs);
        b = a;
    }
    free(b);
    return 1;
}

static inline unsigned check_byte_u32_(const unsigned char *r, size_t byte, size_t arg)
{
    (void)arg;
    uint32_t v;
    memcpy(&v, r, sizeof v);
    return (v >> (8 * byte)) & 255u;
}

/* memcmp's order: byte b of the key is byte rs - 1 - b of the record. */
static inline unsigned check_byte_mem_(const unsigned char *r, size_t byte, size_t rs)
{
    return r[rs - 1 - byte];
}

/* Sorts n records of rs bytes stably by the uint32 each starts with
 * (ascending). Returns 0 when out of memory. */
static inline int check_sort_by_u32(void *records, size_t n, size_t rs)
{
    return check_radix(records, n, rs, sizeof(uint32_t), check_byte_u32_, 0);
}

/* Sorts n uint32 values into ascending order. Returns 0 when out of
 * memory. */
static inline int check_sort_u32(uint32_t *v, size_t n)
{
    return check_sort_by_u32(v, n, sizeof *v);
}

/* Sorts n records of rs bytes into memcmp's order. Returns 0 when out of
 * memory. */
static inline int check_sort_records(void *records, size_t n, size_t rs)
{
    return check_radix(records, n, rs, rs, check_byte_mem_, rs);
}

/* xorshift32: reproducible random inputs. */
static inline uint32_t check_rand(uint32_t *state)
{
    uint32_t x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *state = x;
}

#endif
