/* What a benchmark ran on, for every result file: the CPU's model and
 * vector ISA (from /proc/cpuinfo), and the vector path the kernels were
 * compiled for (PoCL compiles for the host's features unless told
 * otherwise, e.g. POCL_KERNELLIB_NAME=avx2 on an AVX-512 machine). */
#ifndef SLUICE_BENCH_MACHINE_H
#define SLUICE_BENCH_MACHINE_H

#include "sluice/sluice.h"

#include <stdio.h>
#include <string.h>

/* The CPU and its widest vector ISA. */
typedef struct bench_machine {
    char cpu[256];     /* "model name (family F, model M)" of /proc/cpuinfo, or
                          "unknown" */
    const char *isa;   /* "AVX-512", "AVX2", "SSE" or "unknown" */
    const char *block; /* SLUICE_EMIT16's path in the kernels: "avx512"
                          (compress), "avx2" (vpermd), "portable", or
                          "unknown" when the probe failed */
} bench_machine;

/* The kernel that says which path kernels/sluice.cl took. */
static const char bench_block_probe_cl_[] = "#include \"sluice.cl\"\n"
                                            "__kernel void probe(SLUICE_PARAMS, global uint *out)\n"
                                            "{\n"
                                            "    SLUICE_FOR_EACH (i) {\n"
                                            "#if defined(SLUICE_AVX512_)\n"
                                            "        out[i] = 2u;\n"
                                            "#elif defined(SLUICE_AVX2_)\n"
                                            "        out[i] = 1u;\n"
                                            "#else\n"
                                            "        out[i] = 0u;\n"
                                            "#endif\n"
                                            "    }\n"
                                            "}\n";

static inline const char *bench_block_path_(sluice_context *ctx)
{
    sluice_program *p = NULL;
    sluice_kernel *k = NULL;
    sluice_stream *s = NULL;
    uint32_t v = 99;
    sluice_status st =
        sluice_program_create_source(ctx, "probe.cl", bench_block_probe_cl_, NULL, &p);
    if (st == SLUICE_OK)
        st = sluice_program_build(p);
    if (st == SLUICE_OK)
        st = sluice_kernel_create(p, "probe", &k);
    if (st == SLUICE_OK)
        st = sluice_stream_create(ctx, sizeof v, 1, &s);
    if (st == SLUICE_OK)
        st = sluice_stream_upload(s, &v, 1); /* a length of 1 to download */
    if (st == SLUICE_OK)
        st = sluice_kernel_set_stream(k, 0, s, 0);
    if (st == SLUICE_OK)
        st = sluice_kernel_launch_count(k, 1);
    if (st == SLUICE_OK)
        st = sluice_stream_download(s, &v, 1, NULL);
    sluice_stream_destroy(s);
    sluice_kernel_destroy(k);
    sluice_program_destroy(p);
    return st != SLUICE_OK ? "unknown"
           : v == 2        ? "avx512"
           : v == 1        ? "avx2"
           : v == 0        ? "portable"
                           : "unknown";
}

/* Fills `m` for the device of `ctx` (NULL: CPU fields only). */
static inline void bench_machine_probe(sluice_context *ctx, bench_machine *m)
{
    snprintf(m->cpu, sizeof m->cpu, "unknown");
    m->isa = "unknown";
    m->block = ctx ? bench_block_path_(ctx) : "unknown";
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (!f)
        return;
    char line[4096];
    int have_model = 0, have_flags = 0, family = -1, model = -1;
    while ((!have_model || !have_flags) && fgets(line, sizeof line, f)) {
        char *c = strchr(line, ':');
        if (!c)
            continue;
        /* The model name alone can be generic ("Intel(R) Xeon(R)
         * Processor", "AMD EPYC" in virtual machines): family and model
         * tell the generations apart. They come before it. */
        if (strncmp(line, "cpu family", 10) == 0)
            sscanf(c + 1, "%d", &family);
        else if (strncmp(line, "model", 5) == 0 &&
                 strspn(line + 5, " \t") == (size_t)(c - line - 5))
            sscanf(c + 1, "%d", &model); /* "model : N", not "model name" */
        else if (!have_model && strncmp(line, "model name", 10) == 0) {
            c += 1 + (c[1] == ' ');
            c[strcspn(c, "\n")] = '\0';
            if (family >= 0 && model >= 0)
                snprintf(m->cpu, sizeof m->cpu, "%.200s (family %d, model %d)", c, family, model);
            else
                snprintf(m->cpu, sizeof m->cpu, "%s", c);
            have_model = 1;
        } else if (!have_flags && strncmp(line, "flags", 5) == 0) {
            m->isa = strstr(c, " avx512f") ? "AVX-512" : strstr(c, " avx2") ? "AVX2" : "SSE";
            have_flags = 1;
        }
    }
    fclose(f);
}

#endif /* SLUICE_BENCH_MACHINE_H */
