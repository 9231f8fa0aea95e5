/* sluice-info: lists OpenCL devices and their limits, then runs a one-second
 * self-test of the runtime on the selected device (a copy kernel and a
 * conditional split, checked against plain C). */
#include "sluice/sluice.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char *self_test_src =
    "#include \"sluice.cl\"\n"
    "__kernel void copy(SLUICE_PARAMS, global const uint *in, global uint *out)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i) out[i] = in[i];\n"
    "}\n"
    "__kernel void split(SLUICE_PARAMS, global const uint *in, global uint *lo, global uint *hi)\n"
    "{\n"
    "    SLUICE_FOR_EACH(i) {\n"
    "        uint x = in[i];\n"
    "        SLUICE_EMIT_IF(0, lo, x, x < 0x80000000u);\n"
    "        SLUICE_EMIT_IF(1, hi, x, x >= 0x80000000u);\n"
    "        SLUICE_COUNT(0, x & 1u);\n"
    "    }\n"
    "}\n";

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: sluice-info [--list] [--device SUBSTRING] [--help]\n"
               "Lists the OpenCL devices, then runs a one-second self-test on the device\n"
               "Sluice picks (the first CPU device, or SLUICE_DEVICE / --device).\n"
               "  --list     only list devices\n"
               "  --device   pick the device whose \"platform / name\" contains SUBSTRING\n");
}

#define FAIL(...)                                                                                  \
    do {                                                                                           \
        fprintf(stderr, "sluice-info: self-test failed: " __VA_ARGS__);                            \
        fprintf(stderr, ": %s\n", sluice_context_error(ctx));                                      \
        goto done;                                                                                 \
    } while (0)

static int self_test(const char *device)
{
    char err[512];
    sluice_context_options o = {0};
    o.device = device;
    sluice_context *ctx = NULL;
    if (sluice_context_create(&o, &ctx, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "sluice-info: %s\n", err);
        return 1;
    }
    sluice_device_info info;
    sluice_context_device(ctx, &info);
    printf("\nself-test on %s / %s\n", info.platform, info.name);
    int rc = 1;
    const size_t n = 1u << 22;
    uint32_t *host = malloc(n * 4), *back = malloc(n * 4);
    sluice_program *p = NULL;
    sluice_kernel *copy = NULL, *split = NULL;
    sluice_stream *in = NULL, *out = NULL, *lo = NULL, *hi = NULL;
    sluice_counters *odd = NULL;
    if (!host || !back) {
        fprintf(stderr, "sluice-info: out of memory\n");
        goto done;
    }
    uint32_t s = 2463534242u, want_odd = 0;
    size_t want_lo = 0;
    for (size_t i = 0; i < n; ++i) {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        host[i] = s;
        want_lo += s < 0x80000000u;
        want_odd += s & 1u;
    }
    double t0 = now();
    if (sluice_program_create_source(ctx, "self_test.cl", self_test_src, NULL, &p) ||
        sluice_kernel_create(p, "copy", &copy) || sluice_kernel_create(p, "split", &split))
        FAIL("building kernels");
    printf("  build            %8.3f s (cached builds take a few tens of ms)\n", now() - t0);
    if (sluice_stream_create(ctx, 4, n, &in) || sluice_stream_create(ctx, 4, n, &out) ||
        sluice_stream_create(ctx, 4, n, &lo) || sluice_stream_create(ctx, 4, n, &hi) ||
        sluice_counters_create(ctx, 1, NULL, &odd) || sluice_stream_upload(in, host, n))
        FAIL("allocating streams");
    if (sluice_kernel_set_input(copy, 0, in) || sluice_kernel_set_stream(copy, 1, out, 1) ||
        sluice_kernel_set_input(split, 0, in) ||
        sluice_kernel_set_output(split, 1, 0, lo, SLUICE_ORDERED) ||
        sluice_kernel_set_output(split, 2, 1, hi, SLUICE_UNORDERED) ||
        sluice_kernel_set_counters(split, odd))
        FAIL("binding arguments");
    /* Copy bandwidth for about half a second. */
    int reps = 0;
    t0 = now();
    double t1 = t0;
    while (t1 - t0 < 0.5) {
        if (sluice_kernel_launch(copy) || sluice_context_finish(ctx))
            FAIL("copy launch");
        ++reps;
        t1 = now();
    }
    printf("  copy             %8.2f GB/s (%d launches of %zu records)\n",
           2.0 * 4.0 * (double)n * reps / (t1 - t0) / 1e9, reps, n);
    size_t got = 0;
    if (sluice_stream_download(out, back, n, &got) || got != n || memcmp(host, back, n * 4) != 0)
        FAIL("copy result differs from its input");
    reps = 0;
    t0 = now();
    t1 = t0;
    while (t1 - t0 < 0.5) {
        if (sluice_stream_clear(lo) || sluice_stream_clear(hi) || sluice_counters_reset(odd) ||
            sluice_kernel_launch(split) || sluice_context_finish(ctx))
            FAIL("split launch");
        ++reps;
        t1 = now();
    }
    printf("  split            %8.2f M records/s (ordered + unordered outputs)\n",
           (double)n * reps / (t1 - t0) / 1e6);
    size_t nlo = 0, nhi = 0;
    uint32_t c = 0;
    if (sluice_stream_download(lo, back, n, &nlo) || sluice_stream_length(hi, &nhi) ||
        sluice_counters_read(odd, &c))
        FAIL("reading the split");
    size_t j = 0, bad = 0;
    for (size_t i = 0; i < n; ++i)
        if (host[i] < 0x80000000u)
            bad += j < nlo && back[j++] != host[i];
    if (nlo != want_lo || nhi != n - want_lo || c != want_odd || bad)
        FAIL("split gave %zu/%zu records and counter %u, want %zu/%zu and %u", nlo, nhi, c, want_lo,
             n - want_lo, want_odd);
    printf("  self-test passed\n");
    rc = 0;
done:
    sluice_kernel_destroy(copy);
    sluice_kernel_destroy(split);
    sluice_program_destroy(p);
    sluice_stream_destroy(in);
    sluice_stream_destroy(out);
    sluice_stream_destroy(lo);
    sluice_stream_destroy(hi);
    sluice_counters_destroy(odd);
    sluice_context_destroy(ctx);
    free(host);
    free(back);
    return rc;
}

int main(int argc, char **argv)
{
    int list_only = 0;
    const char *device = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(argv[i], "--list")) {
            list_only = 1;
        } else if (!strcmp(argv[i], "--device") && i + 1 < argc) {
            device = argv[++i];
        } else {
            fprintf(stderr, "sluice-info: unknown argument '%s'\n", argv[i]);
            usage(stderr);
            return 2;
        }
    }
    size_t count = 0;
    sluice_status st = sluice_devices_list(NULL, 0, &count);
    if (st != SLUICE_OK || count == 0) {
        fprintf(stderr, "sluice-info: no OpenCL device found: is an ICD such as pocl-opencl-icd "
                        "installed?\n");
        return 1;
    }
    sluice_device_info *devs = calloc(count, sizeof *devs);
    if (!devs)
        return 1;
    sluice_devices_list(devs, count, &count);
    for (size_t i = 0; i < count; ++i) {
        const sluice_device_info *d = &devs[i];
        printf("device %zu: %s / %s\n", i, d->platform, d->name);
        printf("  type %s, %s, %u compute units, max work-group %zu\n", d->is_cpu ? "CPU" : "other",
               d->version, d->compute_units, d->max_work_group_size);
        printf("  global memory %.1f GiB, largest buffer %.1f GiB, local memory %.0f KiB, "
               "cache %.1f MiB\n",
               (double)d->global_mem_bytes / (1 << 30), (double)d->max_alloc_bytes / (1 << 30),
               (double)d->local_mem_bytes / 1024, (double)d->cache_bytes / (1 << 20));
    }
    free(devs);
    return list_only ? 0 : self_test(device);
}
