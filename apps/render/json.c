/* JSON output shared by the renderers' statistics files; see json.h. */
#include "json.h"

void sr_json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; s && *s; ++s) {
        if (*s == '"' || *s == '\\')
            fprintf(f, "\\%c", *s);
        else if ((unsigned char)*s < 0x20)
            fprintf(f, "\\u%04x", (unsigned char)*s);
        else
            fputc(*s, f);
    }
    fputc('"', f);
}

void sr_json_kernels(FILE *f, sluice_context *ctx, int indent)
{
    fprintf(f, "%*s\"kernels\": [", indent, "");
    size_t nk = ctx && sluice_profile_enabled(ctx) ? sluice_profile_count(ctx) : 0;
    int first = 1;
    for (size_t i = 0; i < nk; ++i) {
        sluice_profile_entry e;
        if (sluice_profile_get(ctx, i, &e) != SLUICE_OK)
            continue;
        fprintf(f, "%s\n%*s{\"name\": ", first ? "" : ",", indent + 2, "");
        sr_json_string(f, e.name);
        fprintf(f,
                ", \"launches\": %llu, \"records_in\": %llu, \"records_out\": %llu, "
                "\"seconds\": %.6g}",
                (unsigned long long)e.launches, (unsigned long long)e.records_in,
                (unsigned long long)e.records_out, e.device_seconds);
        first = 0;
    }
    fprintf(f, "\n%*s]", indent, "");
}
