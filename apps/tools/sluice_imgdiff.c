/* sluice-imgdiff: compares an image with a reference and prints the error
 * metrics of image_metrics.h; with --fail it is a pass/fail check for
 * scripts and regression tests. Exit status: 0 ok, 1 over the threshold (or
 * NaN/Inf pixels), 2 bad usage or unreadable input. */
#include "image.h"
#include "image_metrics.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum metric { METRIC_RMSE, METRIC_RELMSE, METRIC_MAX, METRIC_PSNR };
static const char *const metric_names[] = {"rmse", "relmse", "max", "psnr"};

static void usage(FILE *f)
{
    fprintf(f, "usage: sluice-imgdiff IMAGE REFERENCE [--fail X] [--metric NAME] [--json]\n"
               "Compares IMAGE with REFERENCE (any format OpenImageIO reads; 8- and 16-bit\n"
               "files are decoded from sRGB to linear) and prints, over the RGB channels:\n"
               "  rmse    root mean square error\n"
               "  relmse  mean of (a - b)^2 / (b^2 + 0.01), b the reference\n"
               "  psnr    20 log10(1 / rmse) in dB (\"inf\" for identical images)\n"
               "  max     largest absolute difference\n"
               "and the pixels with a NaN or an Inf in either image, which the figures\n"
               "leave out.\n"
               "options:\n"
               "  --fail X       exit 1 when the metric is above X (psnr: below X), or when\n"
               "                 any pixel is NaN or Inf\n"
               "  --metric NAME  the metric --fail tests: rmse (default), relmse, max, psnr\n"
               "  --json         print one JSON object instead (psnr is null when infinite)\n"
               "  --help         this text\n"
               "exit status: 0 passed (or no --fail), 1 failed, 2 bad usage, unreadable\n"
               "input or different sizes.\n"
               "examples:\n"
               "  sluice-imgdiff render.exr reference.exr\n"
               "  sluice-imgdiff render.png reference.png --fail 0.01\n"
               "  sluice-imgdiff out.exr ref.exr --metric psnr --fail 40 --json\n");
}

static double metric_value(const sr_image_metrics *m, enum metric which)
{
    switch (which) {
    case METRIC_RELMSE:
        return m->rel_mse;
    case METRIC_MAX:
        return m->max_error;
    case METRIC_PSNR:
        return m->psnr;
    default:
        return m->rmse;
    }
}

/* Writes s as a JSON string: paths may hold quotes, backslashes or control
 * characters. */
static void json_string(const char *s)
{
    putchar('"');
    for (const unsigned char *p = (const unsigned char *)s; *p; ++p) {
        if (*p == '"' || *p == '\\')
            printf("\\%c", *p);
        else if (*p < 0x20)
            printf("\\u%04x", *p);
        else
            putchar(*p);
    }
    putchar('"');
}

/* A JSON number, or null for a value JSON cannot hold (infinite PSNR). */
static void json_number(double v)
{
    if (isfinite(v))
        printf("%.9g", v);
    else
        printf("null");
}

/* Reads the value of an option given as "--name VALUE" or "--name=VALUE";
 * returns NULL when it is missing. */
static const char *option_value(int argc, char **argv, int *i, const char *name)
{
    size_t n = strlen(name);
    if (argv[*i][n] == '=')
        return argv[*i] + n + 1;
    if (*i + 1 >= argc)
        return NULL;
    return argv[++*i];
}

static int matches(const char *arg, const char *name)
{
    size_t n = strlen(name);
    return strncmp(arg, name, n) == 0 && (arg[n] == 0 || arg[n] == '=');
}

int main(int argc, char **argv)
{
    const char *paths[2] = {NULL, NULL};
    int npaths = 0, json = 0, have_fail = 0;
    double threshold = 0.0;
    enum metric which = METRIC_RMSE;

    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        if (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(arg, "--json") == 0) {
            json = 1;
        } else if (matches(arg, "--fail")) {
            const char *v = option_value(argc, argv, &i, "--fail");
            char *end = NULL;
            threshold = v ? strtod(v, &end) : NAN;
            if (!v || end == v || *end || isnan(threshold)) {
                fprintf(stderr, "sluice-imgdiff: --fail needs a number, got '%s'\n",
                        v ? v : "nothing");
                return 2;
            }
            have_fail = 1;
        } else if (matches(arg, "--metric")) {
            const char *v = option_value(argc, argv, &i, "--metric");
            int found = 0;
            for (int k = 0; v && k < 4; ++k)
                if (strcmp(v, metric_names[k]) == 0) {
                    which = (enum metric)k;
                    found = 1;
                }
            if (!found) {
                fprintf(stderr,
                        "sluice-imgdiff: --metric is one of rmse, relmse, max, psnr, not '%s'\n",
                        v ? v : "nothing");
                return 2;
            }
        } else if (arg[0] == '-' && arg[1] != 0) {
            fprintf(stderr, "sluice-imgdiff: unknown option '%s' (see --help)\n", arg);
            return 2;
        } else if (npaths < 2) {
            paths[npaths++] = arg;
        } else {
            fprintf(stderr, "sluice-imgdiff: too many images: '%s' (see --help)\n", arg);
            return 2;
        }
    }
    if (npaths != 2) {
        usage(stderr);
        return 2;
    }

    char err[1024];
    sr_image *img[2] = {NULL, NULL};
    int rc = 2;
    for (int k = 0; k < 2; ++k) {
        if (sr_image_read(paths[k], &img[k], err, sizeof err) != SLUICE_OK) {
            fprintf(stderr, "sluice-imgdiff: %s\n", err);
            goto done;
        }
    }
    sr_image_metrics m;
    if (sr_image_compare(img[0], img[1], &m, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "sluice-imgdiff: '%s' and '%s': %s\n", paths[0], paths[1], err);
        goto done;
    }

    double value = metric_value(&m, which);
    int over = which == METRIC_PSNR ? value < threshold : value > threshold;
    int failed = have_fail && (over || m.nan_count || m.inf_count);
    unsigned w = sr_image_width(img[0]), h = sr_image_height(img[0]);
    if (json) {
        printf("{\"image\": ");
        json_string(paths[0]);
        printf(", \"reference\": ");
        json_string(paths[1]);
        printf(", \"width\": %u, \"height\": %u, \"channels\": %u, \"pixels\": %zu", w, h,
               m.channels, m.pixels);
        printf(", \"rmse\": ");
        json_number(m.rmse);
        printf(", \"relmse\": ");
        json_number(m.rel_mse);
        printf(", \"psnr\": ");
        json_number(m.psnr);
        printf(", \"max\": ");
        json_number(m.max_error);
        printf(", \"nan_pixels\": %zu, \"inf_pixels\": %zu", m.nan_count, m.inf_count);
        if (have_fail) {
            printf(", \"metric\": \"%s\", \"threshold\": ", metric_names[which]);
            json_number(threshold);
            printf(", \"pass\": %s", failed ? "false" : "true");
        }
        printf("}\n");
    } else {
        printf("image       %s\n", paths[0]);
        printf("reference   %s\n", paths[1]);
        printf("size        %ux%u, %u channels compared\n", w, h, m.channels);
        printf("rmse        %.6g\n", m.rmse);
        printf("relmse      %.6g\n", m.rel_mse);
        if (isinf(m.psnr))
            printf("psnr        inf\n");
        else
            printf("psnr        %.3f dB\n", m.psnr);
        printf("max         %.6g\n", m.max_error);
        printf("nan pixels  %zu\n", m.nan_count);
        printf("inf pixels  %zu\n", m.inf_count);
        if (have_fail) {
            const char *op = which == METRIC_PSNR ? (over ? "<" : ">=") : (over ? ">" : "<=");
            printf("result      %s: %s %.6g %s %.6g", failed ? "FAIL" : "pass", metric_names[which],
                   value, op, threshold);
            if (m.nan_count || m.inf_count)
                printf(", %zu NaN and %zu Inf pixels", m.nan_count, m.inf_count);
            printf("\n");
        }
    }
    rc = failed ? 1 : 0;

done:
    sr_image_destroy(img[0]);
    sr_image_destroy(img[1]);
    return rc;
}
