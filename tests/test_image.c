/* Tests of the apps' image code (apps/common): creation limits, EXR, PNG,
 * HDR files, PFM reads, atomic writes, read errors, and the error metrics
 * against values worked out by hand. Given "--imgdiff PATH" it tests the
 * sluice-imgdiff program at PATH instead, running it as a child process.
 * Files go to a fresh directory under the working directory (the tests'
 * build directory), removed at the end. */
#include "check.h"
#include "image.h"
#include "image_metrics.h"

#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <spawn.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

static char dir[64];

/* dir/name, in one of a few rotating buffers so that a call can use two. */
static const char *in_dir(const char *name)
{
    static char bufs[4][512];
    static int next;
    char *b = bufs[next++ % 4];
    snprintf(b, sizeof bufs[0], "%s/%s", dir, name);
    return b;
}

/* Entries of a directory other than "." and ".."; with `tmp`, only those
 * that look like leftover temporary files. */
static int count_entries(const char *path, int tmp)
{
    DIR *d = opendir(path);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") &&
            (!tmp || strstr(e->d_name, ".tmp")))
            n++;
    closedir(d);
    return n;
}

static void remove_tree(const char *path)
{
    DIR *d = opendir(path);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d))) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            char sub[1024];
            snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
            struct stat sb;
            if (lstat(sub, &sb) == 0 && S_ISDIR(sb.st_mode))
                remove_tree(sub);
            else
                remove(sub);
        }
        closedir(d);
    }
    rmdir(path);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

/* The whole of a small file, NUL-terminated, in a static buffer. */
static const char *read_text(const char *path)
{
    static char buf[8192];
    buf[0] = 0;
    FILE *f = fopen(path, "r");
    if (f) {
        size_t n = fread(buf, 1, sizeof buf - 1, f);
        buf[n] = 0;
        fclose(f);
    }
    return buf;
}

static int exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}

/* An image filled with one value in every colour channel (alpha 1). */
static sr_image *uniform(unsigned w, unsigned h, unsigned c, float v)
{
    sr_image *img = NULL;
    char err[256];
    if (sr_image_create(w, h, c, &img, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "cannot create an image: %s\n", err);
        exit(2);
    }
    float *p = sr_image_pixels(img);
    for (size_t i = 0; i < (size_t)w * h * c; ++i)
        p[i] = (c == 4 && i % 4 == 3) ? 1.0f : v;
    return img;
}

static void test_create(void)
{
    char err[256];
    sr_image *img = (sr_image *)&err; /* must be reset to NULL */
    CHECK(sr_image_create(0, 0, 3, &img, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "0x0 accepted");
    CHECK(img == NULL, "out not NULL after a failure");
    CHECK(sr_image_create(5, 0, 3, &img, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "5x0 accepted");
    err[0] = 0;
    CHECK(sr_image_create(1000000, 1000000, 3, &img, err, sizeof err) ==
              SLUICE_ERROR_INVALID_ARGUMENT,
          "10^6 x 10^6 accepted");
    CHECK(strstr(err, "1000000x1000000") && strstr(err, "too large"), "message: %s", err);
    CHECK(sr_image_create(65537, 1, 3, &img, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "65537 wide accepted");
    CHECK(sr_image_create(65536, 65536, 3, &img, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "2^32 pixels accepted");
    CHECK(sr_image_create(4, 4, 2, &img, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "2 channels accepted");
    CHECK(sr_image_create(4, 4, 3, NULL, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL out accepted");
    /* NULL or empty error buffers are allowed. */
    CHECK(sr_image_create(0, 1, 3, &img, NULL, 0) == SLUICE_ERROR_INVALID_ARGUMENT, "no err");

    CHECK(sr_image_create(7, 5, 4, &img, err, sizeof err) == SLUICE_OK, "7x5x4: %s", err);
    CHECK(sr_image_width(img) == 7 && sr_image_height(img) == 5 && sr_image_channels(img) == 4,
          "accessors");
    int zero = 1;
    for (size_t i = 0; i < 7 * 5 * 4; ++i)
        zero &= sr_image_pixels_const(img)[i] == 0.0f;
    CHECK(zero, "not zero-filled");
    CHECK(sr_image_pixels(img) == sr_image_pixels_const(img), "two pixel views");
    sr_image_destroy(img);
    sr_image_destroy(NULL);
    CHECK(sr_image_width(NULL) == 0 && sr_image_pixels(NULL) == NULL, "NULL accessors");
}

static void test_srgb(void)
{
    CHECK(sr_srgb_encode(0.0f) == 0.0f && sr_srgb_encode(1.0f) == 1.0f, "encode ends");
    CHECK(sr_srgb_encode(NAN) == 0.0f && sr_srgb_encode(-1.0f) == 0.0f &&
              sr_srgb_encode(7.0f) == 1.0f,
          "encode clamps");
    CHECK(fabsf(sr_srgb_encode(0.002f) - 0.002f * 12.92f) < 1e-7f, "linear segment");
    /* 18% grey encodes to about 0.4614 (46% of the scale). */
    CHECK(fabsf(sr_srgb_encode(0.18f) - 0.4614f) < 1e-3f, "18%% grey: %g", sr_srgb_encode(0.18f));
    float worst = 0.0f;
    for (int i = 0; i <= 1000; ++i) {
        float x = (float)i / 1000.0f;
        float e = fabsf(sr_srgb_decode(sr_srgb_encode(x)) - x);
        worst = e > worst ? e : worst;
    }
    CHECK(worst < 1e-6f, "decode(encode(x)) off by %g", worst);
}

/* Finite floats of every kind: mixed signs, tiny, subnormal, huge. */
static float awkward_float(uint32_t *seed, size_t i)
{
    static const float specials[] = {0.0f,    -0.0f,  1e-30f,  -1e-38f,  1.4e-45f, 3e-41f,
                                     1e30f,   -3e38f, 65504.f, 65520.f,  1.0f / 3, -1.0f,
                                     3.4e38f, 1e-8f,  0.1f,    123456.7f};
    if (i % 3 == 0)
        return specials[(i / 3) % (sizeof specials / sizeof specials[0])];
    float u = (float)((double)check_rand(seed) / 4294967296.0);
    float scale = powf(10.0f, (float)((int)(check_rand(seed) % 61) - 30));
    return (check_rand(seed) & 1 ? -u : u) * scale;
}

static void test_exr(void)
{
    char err[512];
    uint32_t seed = 2024u;
    for (unsigned c = 3; c <= 4; ++c) {
        sr_image *img = uniform(7, 5, c, 0.0f), *back = NULL;
        float *p = sr_image_pixels(img);
        for (size_t i = 0; i < 7 * 5 * c; ++i)
            p[i] = awkward_float(&seed, i);
        const char *path = in_dir(c == 3 ? "rgb.exr" : "RGBA.EXR");
        CHECK(sr_image_write(img, path, err, sizeof err) == SLUICE_OK, "write: %s", err);
        CHECK(sr_image_read(path, &back, err, sizeof err) == SLUICE_OK, "read: %s", err);
        if (back) {
            CHECK(sr_image_width(back) == 7 && sr_image_height(back) == 5 &&
                      sr_image_channels(back) == c,
                  "exr %u channels: read back %ux%ux%u", c, sr_image_width(back),
                  sr_image_height(back), sr_image_channels(back));
            if (sr_image_channels(back) == c) {
                size_t bad = 0, first = 0;
                for (size_t i = 0; i < 7 * 5 * c; ++i)
                    if (memcmp(&p[i], &sr_image_pixels_const(back)[i], 4) && bad++ == 0)
                        first = i;
                CHECK(bad == 0, "exr %u channels: %zu values differ, first [%zu] %a vs %a", c, bad,
                      first, p[first], sr_image_pixels_const(back)[first]);
            }
        }
        sr_image_destroy(back);
        sr_image_destroy(img);
    }
}

static void test_png(void)
{
    char err[512];
    /* 0.214 linear is 0.49995 encoded: 127.49 of 255. */
    sr_image *img = uniform(4, 3, 4, 0.214f), *raw = NULL, *back = NULL;
    float *p = sr_image_pixels(img);
    p[3] = 0.5f;  /* alpha is not encoded: 128 */
    p[4] = -1.0f; /* clamped to 0 */
    p[5] = 2.0f;  /* clamped to 255 */
    p[6] = NAN;   /* 0 */
    const char *path = in_dir("grey.png");
    CHECK(sr_image_write(img, path, err, sizeof err) == SLUICE_OK, "write png: %s", err);
    CHECK(sr_image_read_ex(path, SR_IMAGE_READ_RAW, &raw, err, sizeof err) == SLUICE_OK,
          "read raw: %s", err);
    CHECK(sr_image_read(path, &back, err, sizeof err) == SLUICE_OK, "read png: %s", err);
    if (!raw || !back || sr_image_channels(raw) != 4 || sr_image_channels(back) != 4) {
        CHECK(0, "png read back with %u channels", sr_image_channels(raw));
        goto done;
    }
    const float *r = sr_image_pixels_const(raw), *b = sr_image_pixels_const(back);
    /* Raw reads give stored / 255 as OpenImageIO computes it: round. */
    long stored = lrintf(r[0] * 255.0f);
    CHECK(fabsf(r[0] * 255.0f - (float)stored) < 1e-3f && (stored == 127 || stored == 128),
          "stored %g / 255, want 127 or 128", r[0] * 255.0f);
    CHECK(lrintf(r[3] * 255.0f) == 128, "alpha stored as %g / 255", r[3] * 255.0f);
    CHECK(r[4] == 0.0f && r[5] == 1.0f && r[6] == 0.0f, "clamps: %g %g %g", r[4], r[5], r[6]);
    /* One 8-bit step around 127.5, in linear terms. */
    float step = sr_srgb_decode(128.0f / 255.0f) - sr_srgb_decode(127.0f / 255.0f);
    size_t bad = 0;
    for (size_t i = 8; i < 4 * 3 * 4; ++i)
        if (i % 4 != 3 && !(fabsf(b[i] - 0.214f) <= step))
            bad++;
    CHECK(bad == 0, "%zu colour values not within %g of 0.214 (first %g)", bad, step, b[8]);
    CHECK(fabsf(b[3] - 0.5f) <= 0.5f / 255.0f + 1e-6f, "alpha read back as %g", b[3]);
    CHECK(fabsf(b[11] - 1.0f) == 0.0f, "opaque alpha read back as %g", b[11]);
done:
    sr_image_destroy(raw);
    sr_image_destroy(back);
    sr_image_destroy(img);
}

static void test_hdr(void)
{
    char err[512];
    static const float values[] = {0.214f, 1.0f, 5.5f, 100.0f, 0.001f, 0.5f};
    sr_image *img = uniform(6, 2, 4, 0.0f), *back = NULL;
    float *p = sr_image_pixels(img);
    for (size_t i = 0; i < 12; ++i) {
        p[i * 4 + 0] = values[i % 6];
        p[i * 4 + 1] = values[(i + 1) % 6];
        p[i * 4 + 2] = values[(i + 2) % 6];
    }
    /* RGBE: 8-bit mantissas sharing an exponent, so every value of a pixel
     * is good to about 1/256 of the pixel's largest; allow twice that. Were
     * the file decoded as sRGB, 0.214 would come back as 0.037. */
    const char *path = in_dir("light.hdr");
    CHECK(sr_image_write(img, path, err, sizeof err) == SLUICE_OK, "write hdr: %s", err);
    CHECK(sr_image_read(path, &back, err, sizeof err) == SLUICE_OK, "read hdr: %s", err);
    if (back && sr_image_channels(back) == 3 && sr_image_width(back) == 6) {
        const float *b = sr_image_pixels_const(back);
        size_t bad = 0;
        for (size_t i = 0; i < 12; ++i) {
            float mx = fmaxf(p[i * 4], fmaxf(p[i * 4 + 1], p[i * 4 + 2]));
            for (int k = 0; k < 3; ++k)
                if (!(fabsf(b[i * 3 + k] - p[i * 4 + k]) <= mx / 128.0f))
                    bad++;
        }
        CHECK(bad == 0, "hdr: %zu values off (first pixel %g %g %g)", bad, b[0], b[1], b[2]);
    } else {
        CHECK(0, "hdr read back as %ux%ux%u", sr_image_width(back), sr_image_height(back),
              sr_image_channels(back));
    }
    sr_image_destroy(back);
    sr_image_destroy(img);
}

/* Writes a PFM file by hand (OpenImageIO 2.4 cannot): "PF" (RGB) or "Pf"
 * (grey), the size, a negative scale for little-endian floats, then the
 * rows from the bottom up. */
static void write_pfm(const char *path, unsigned w, unsigned h, unsigned c, const float *top_first)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return;
    fprintf(f, "%s\n%u %u\n-1.0\n", c == 3 ? "PF" : "Pf", w, h);
    for (unsigned y = h; y-- > 0;)
        fwrite(top_first + (size_t)y * w * c, sizeof(float), (size_t)w * c, f);
    fclose(f);
}

static void test_pfm_read(void)
{
    char err[512];
    float rgb[4 * 3 * 3], grey[4 * 3];
    for (int i = 0; i < 36; ++i)
        rgb[i] = (float)i * 0.25f - 3.0f;
    for (int i = 0; i < 12; ++i)
        grey[i] = (float)i * 1.5f;
    const char *path = in_dir("hand.pfm");
    write_pfm(path, 4, 3, 3, rgb);
    sr_image *back = NULL;
    CHECK(sr_image_read(path, &back, err, sizeof err) == SLUICE_OK, "read pfm: %s", err);
    if (back && sr_image_channels(back) == 3 && sr_image_width(back) == 4 &&
        sr_image_height(back) == 3)
        CHECK(memcmp(sr_image_pixels_const(back), rgb, sizeof rgb) == 0,
              "pfm pixels differ (rows flipped?): %g %g", sr_image_pixels_const(back)[0], rgb[0]);
    else
        CHECK(0, "pfm read back as %ux%ux%u", sr_image_width(back), sr_image_height(back),
              sr_image_channels(back));
    sr_image_destroy(back);
    back = NULL;

    /* One grey channel becomes RGB. */
    path = in_dir("grey.pfm");
    write_pfm(path, 4, 3, 1, grey);
    CHECK(sr_image_read(path, &back, err, sizeof err) == SLUICE_OK, "read grey pfm: %s", err);
    if (back && sr_image_channels(back) == 3 && sr_image_width(back) == 4) {
        const float *b = sr_image_pixels_const(back);
        size_t bad = 0;
        for (int i = 0; i < 12; ++i)
            bad += b[i * 3] != grey[i] || b[i * 3 + 1] != grey[i] || b[i * 3 + 2] != grey[i];
        CHECK(bad == 0, "grey pfm: %zu pixels not expanded to RGB", bad);
    } else {
        CHECK(0, "grey pfm read back with %u channels", sr_image_channels(back));
    }
    sr_image_destroy(back);

    /* Writing .pfm is refused up front, not half done. */
    sr_image *img = uniform(2, 2, 3, 1.0f);
    CHECK(sr_image_write(img, in_dir("out.pfm"), err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "pfm write: %s", err);
    CHECK(!exists(in_dir("out.pfm")), "out.pfm exists");
    sr_image_destroy(img);
}

static void test_atomic(void)
{
    char err[512];
    char sub[128];
    snprintf(sub, sizeof sub, "%s/atomic", dir);
    mkdir(sub, 0755);
    sr_image *img = uniform(3, 2, 3, 0.25f), *back = NULL;

    /* Success: the target and nothing else. */
    char target[256];
    snprintf(target, sizeof target, "%s/out.png", sub);
    CHECK(sr_image_write(img, target, err, sizeof err) == SLUICE_OK, "write: %s", err);
    CHECK(count_entries(sub, 0) == 1 && exists(target), "after a write: %d entries",
          count_entries(sub, 0));
    snprintf(target, sizeof target, "%s/out.exr", sub);
    CHECK(sr_image_write(img, target, err, sizeof err) == SLUICE_OK, "write: %s", err);
    CHECK(count_entries(sub, 0) == 2 && count_entries(sub, 1) == 0, "temporary files left");

    /* A directory that does not exist. */
    char missing[256];
    snprintf(missing, sizeof missing, "%s/no-such-dir/out.png", sub);
    err[0] = 0;
    CHECK(sr_image_write(img, missing, err, sizeof err) == SLUICE_ERROR_IO,
          "write into a missing directory");
    CHECK(strstr(err, missing) != NULL, "message does not name the path: %s", err);
    CHECK(count_entries(sub, 0) == 2, "something was left: %d entries", count_entries(sub, 0));

    /* An unsupported extension. */
    snprintf(target, sizeof target, "%s/out.xyz", sub);
    err[0] = 0;
    CHECK(sr_image_write(img, target, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          ".xyz accepted");
    CHECK(strstr(err, target) && strstr(err, "'.xyz'"), "message: %s", err);
    snprintf(target, sizeof target, "%s/noext", sub);
    CHECK(sr_image_write(img, target, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "no extension accepted");
    CHECK(count_entries(sub, 0) == 2, "something was left: %d entries", count_entries(sub, 0));

    /* A failing write leaves the old file as it was ... */
    snprintf(target, sizeof target, "%s/old.png", sub);
    write_text(target, "the old contents");
    CHECK(sr_image_write(NULL, target, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "NULL image accepted");
    CHECK(strstr(err, target) != NULL, "message does not name the path: %s", err);
    CHECK(strcmp(read_text(target), "the old contents") == 0, "old file changed");

    /* ... also when it fails after writing the temporary file: rename()
     * cannot replace a non-empty directory. */
    char blocker[256], inside[300];
    snprintf(blocker, sizeof blocker, "%s/blocked.exr", sub);
    snprintf(inside, sizeof inside, "%s/keep", blocker);
    mkdir(blocker, 0755);
    write_text(inside, "kept");
    err[0] = 0;
    CHECK(sr_image_write(img, blocker, err, sizeof err) == SLUICE_ERROR_IO,
          "rename over a directory succeeded");
    CHECK(strstr(err, blocker) != NULL, "message does not name the path: %s", err);
    CHECK(count_entries(sub, 1) == 0, "temporary file left after a failed rename");
    CHECK(strcmp(read_text(inside), "kept") == 0, "directory contents changed");

    /* ... and a successful one replaces it. */
    CHECK(sr_image_write(img, target, err, sizeof err) == SLUICE_OK, "replace: %s", err);
    CHECK(sr_image_read(target, &back, err, sizeof err) == SLUICE_OK, "read: %s", err);
    CHECK(back && sr_image_width(back) == 3, "replaced file is not the image");
    CHECK(count_entries(sub, 1) == 0, "temporary files left");
    sr_image_destroy(back);
    sr_image_destroy(img);
}

static void test_read_errors(void)
{
    char err[512];
    sr_image *img = (sr_image *)&err;
    const char *missing = in_dir("missing.exr");
    err[0] = 0;
    CHECK(sr_image_read(missing, &img, err, sizeof err) == SLUICE_ERROR_NOT_FOUND, "missing file");
    CHECK(img == NULL, "out not NULL after a failure");
    CHECK(strstr(err, missing) != NULL, "message does not name the path: %s", err);

    const char *garbage = in_dir("garbage.png");
    write_text(garbage, "this is text, not a PNG file\n");
    err[0] = 0;
    CHECK(sr_image_read(garbage, &img, err, sizeof err) == SLUICE_ERROR_IO, "garbage read");
    CHECK(strstr(err, garbage) != NULL, "message does not name the path: %s", err);
    printf("garbage file: %s\n", err);

    err[0] = 0;
    CHECK(sr_image_read(dir, &img, err, sizeof err) == SLUICE_ERROR_IO, "directory read");
    CHECK(strstr(err, dir) != NULL, "message does not name the path: %s", err);
    CHECK(sr_image_read(NULL, &img, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL");
}

static int near(double got, double want)
{
    return fabs(got - want) <= 1e-6 * fabs(want) + 1e-9;
}

static void test_metrics(void)
{
    char err[512];
    sr_image_metrics m;
    /* Reference: 2x2, every channel 0.5. Image: R of pixel 0 is 0.6 (off by
     * 0.1), B of pixel 3 is 0.2 (off by 0.3). Over 12 values:
     *   sum of squares 0.01 + 0.09 = 0.1, rmse = sqrt(0.1 / 12) = 0.0912871
     *   rel_mse = (0.01 + 0.09) / (0.25 + 0.01) / 12 = 0.0320513
     *   psnr = 20 log10(1 / 0.0912871) = 20.7918 dB, max = 0.3 */
    sr_image *b = uniform(2, 2, 3, 0.5f), *a = uniform(2, 2, 4, 0.5f);
    float *pa = sr_image_pixels(a);
    pa[0] = 0.6f;
    pa[3 * 4 + 2] = 0.2f;
    pa[1 * 4 + 3] = 0.0f; /* alpha differs: not compared */
    CHECK(sr_image_compare(a, b, &m, err, sizeof err) == SLUICE_OK, "compare: %s", err);
    CHECK(near(m.rmse, 0.0912871), "rmse %.9g", m.rmse);
    CHECK(near(m.rel_mse, 0.0320513) || fabs(m.rel_mse - 0.0320513) < 1e-7, "rel_mse %.9g",
          m.rel_mse);
    CHECK(fabs(m.psnr - 20.7918) < 1e-4, "psnr %.9g", m.psnr);
    CHECK(fabs(m.max_error - 0.3) < 1e-7, "max %.9g", m.max_error);
    CHECK(m.pixels == 4 && m.channels == 3 && m.nan_count == 0 && m.inf_count == 0,
          "counts %zu %u %zu %zu", m.pixels, m.channels, m.nan_count, m.inf_count);

    /* Identical: zero error, infinite PSNR. */
    CHECK(sr_image_compare(b, b, &m, err, sizeof err) == SLUICE_OK, "compare: %s", err);
    CHECK(m.rmse == 0 && m.rel_mse == 0 && m.max_error == 0 && isinf(m.psnr) && m.psnr > 0,
          "identical: rmse %g psnr %g", m.rmse, m.psnr);

    /* NaN and Inf pixels are counted once each and left out: pixel 1 has a
     * NaN in a, pixel 2 an Inf in b, pixel 3 a NaN in a and an Inf in b (a
     * NaN pixel). Only pixel 0 remains: one error of 0.1 in 3 values. */
    sr_image *c = uniform(2, 2, 3, 0.5f);
    float *pc = sr_image_pixels(c);
    pa[1 * 4 + 1] = NAN;
    pa[3 * 4 + 0] = NAN;
    pc[2 * 3 + 2] = INFINITY;
    pc[3 * 3 + 1] = -INFINITY;
    CHECK(sr_image_compare(a, c, &m, err, sizeof err) == SLUICE_OK, "compare: %s", err);
    CHECK(m.nan_count == 2 && m.inf_count == 1, "nan %zu inf %zu", m.nan_count, m.inf_count);
    CHECK(near(m.rmse, sqrt(0.01 / 3.0)), "rmse with NaN pixels %.9g", m.rmse);
    CHECK(fabs(m.max_error - 0.1) < 1e-7, "max with NaN pixels %.9g", m.max_error);
    /* A NaN in alpha also makes the pixel invalid. */
    pa[1 * 4 + 1] = 0.5f;
    pa[1 * 4 + 3] = NAN;
    CHECK(sr_image_compare(a, c, &m, err, sizeof err) == SLUICE_OK, "compare: %s", err);
    CHECK(m.nan_count == 2 && m.inf_count == 1, "alpha NaN: nan %zu inf %zu", m.nan_count,
          m.inf_count);

    /* Different sizes. */
    sr_image *d = uniform(3, 2, 3, 0.5f);
    err[0] = 0;
    CHECK(sr_image_compare(a, d, &m, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT,
          "sizes differ");
    CHECK(strstr(err, "2x2") && strstr(err, "3x2"), "message: %s", err);
    CHECK(sr_image_compare(a, NULL, &m, err, sizeof err) == SLUICE_ERROR_INVALID_ARGUMENT, "NULL");
    sr_image_destroy(a);
    sr_image_destroy(b);
    sr_image_destroy(c);
    sr_image_destroy(d);
}

/* ------------------------------------------------------------------ */
/* sluice-imgdiff                                                      */
/* ------------------------------------------------------------------ */

static const char *imgdiff;
static char out_text[8192], err_text[8192];

/* Runs sluice-imgdiff with up to 6 arguments; returns its exit status (or
 * -1) and leaves its stdout and stderr in out_text and err_text. */
static int run_imgdiff(const char *a1, const char *a2, const char *a3, const char *a4,
                       const char *a5, const char *a6)
{
    char out_path[256], err_path[256];
    snprintf(out_path, sizeof out_path, "%s/stdout.txt", dir);
    snprintf(err_path, sizeof err_path, "%s/stderr.txt", dir);
    char *argv[] = {(char *)imgdiff, (char *)a1, (char *)a2, (char *)a3,
                    (char *)a4,      (char *)a5, (char *)a6, NULL};
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid;
    int rc = -1, status;
    if (posix_spawn(&pid, imgdiff, &fa, NULL, argv, environ) == 0 &&
        waitpid(pid, &status, 0) == pid && WIFEXITED(status))
        rc = WEXITSTATUS(status);
    posix_spawn_file_actions_destroy(&fa);
    snprintf(out_text, sizeof out_text, "%s", read_text(out_path));
    snprintf(err_text, sizeof err_text, "%s", read_text(err_path));
    return rc;
}

static void write_or_die(sr_image *img, const char *path)
{
    char err[512];
    if (sr_image_write(img, path, err, sizeof err) != SLUICE_OK) {
        fprintf(stderr, "%s\n", err);
        exit(2);
    }
    sr_image_destroy(img);
}

static void test_imgdiff(void)
{
    char a[256], b[256], c[256], n[256], s[256], missing[256];
    snprintf(a, sizeof a, "%s", in_dir("a.exr"));
    snprintf(b, sizeof b, "%s", in_dir("b.exr"));
    snprintf(c, sizeof c, "%s", in_dir("c.exr"));
    snprintf(n, sizeof n, "%s", in_dir("nan.exr"));
    snprintf(s, sizeof s, "%s", in_dir("small.exr"));
    snprintf(missing, sizeof missing, "%s", in_dir("missing.exr"));
    write_or_die(uniform(8, 4, 3, 0.5f), a);
    write_or_die(uniform(8, 4, 3, 0.5f), b);
    write_or_die(uniform(8, 4, 3, 0.6f), c); /* rmse 0.1, psnr 20 dB */
    write_or_die(uniform(4, 4, 3, 0.5f), s);
    sr_image *img = uniform(8, 4, 3, 0.5f);
    sr_image_pixels(img)[5] = NAN;
    write_or_die(img, n);

    int rc = run_imgdiff(a, b, NULL, NULL, NULL, NULL);
    CHECK(rc == 0, "identical: exit %d (%s)", rc, err_text);
    CHECK(strstr(out_text, "rmse") && strstr(out_text, "inf"), "identical output:\n%s", out_text);
    rc = run_imgdiff(a, b, "--fail", "0", NULL, NULL);
    CHECK(rc == 0, "identical --fail 0: exit %d", rc);

    rc = run_imgdiff(c, a, "--fail", "0.05", NULL, NULL);
    CHECK(rc == 1, "rmse 0.1 --fail 0.05: exit %d\n%s", rc, out_text);
    CHECK(strstr(out_text, "FAIL") != NULL, "no FAIL line:\n%s", out_text);
    rc = run_imgdiff(c, a, "--fail=0.2", NULL, NULL, NULL);
    CHECK(rc == 0, "rmse 0.1 --fail 0.2: exit %d", rc);
    rc = run_imgdiff(c, a, "--metric", "psnr", "--fail", "30");
    CHECK(rc == 1, "psnr 20 --fail 30: exit %d", rc);
    rc = run_imgdiff("--metric=psnr", c, a, "--fail", "10", NULL);
    CHECK(rc == 0, "psnr 20 --fail 10: exit %d", rc);
    rc = run_imgdiff(c, a, "--metric", "max", "--fail", "0.09");
    CHECK(rc == 1, "max 0.1 --fail 0.09: exit %d", rc);
    rc = run_imgdiff(c, a, "--json", NULL, NULL, NULL);
    CHECK(rc == 0 && out_text[0] == '{' && strstr(out_text, "\"rmse\": 0.1"), "json: %d\n%s", rc,
          out_text);
    rc = run_imgdiff(a, b, "--json", "--fail", "1", NULL);
    CHECK(rc == 0 && strstr(out_text, "\"psnr\": null") && strstr(out_text, "\"pass\": true"),
          "json identical: %d\n%s", rc, out_text);

    rc = run_imgdiff(n, a, "--fail", "1", NULL, NULL);
    CHECK(rc == 1, "NaN pixel --fail 1: exit %d", rc);
    CHECK(strstr(out_text, "nan pixels  1") != NULL, "NaN count:\n%s", out_text);
    rc = run_imgdiff(n, a, NULL, NULL, NULL, NULL);
    CHECK(rc == 0, "NaN pixel without --fail: exit %d", rc);

    rc = run_imgdiff(a, missing, NULL, NULL, NULL, NULL);
    CHECK(rc == 2, "missing file: exit %d", rc);
    CHECK(strstr(err_text, missing) != NULL, "stderr does not name the path: %s", err_text);
    rc = run_imgdiff(a, s, NULL, NULL, NULL, NULL);
    CHECK(rc == 2 && strstr(err_text, "8x4") && strstr(err_text, "4x4"), "sizes differ: %d %s", rc,
          err_text);

    rc = run_imgdiff("--help", NULL, NULL, NULL, NULL, NULL);
    CHECK(rc == 0 && strstr(out_text, "usage") && strstr(out_text, "--fail"), "--help: %d", rc);
    rc = run_imgdiff(NULL, NULL, NULL, NULL, NULL, NULL);
    CHECK(rc == 2 && strstr(err_text, "usage"), "no arguments: exit %d", rc);
    rc = run_imgdiff(a, b, "--bogus", NULL, NULL, NULL);
    CHECK(rc == 2, "unknown option: exit %d", rc);
    rc = run_imgdiff(a, b, "--fail", "lots", NULL, NULL);
    CHECK(rc == 2, "--fail lots: exit %d", rc);
    rc = run_imgdiff(a, b, "--metric", "ssim", NULL, NULL);
    CHECK(rc == 2, "--metric ssim: exit %d", rc);
    rc = run_imgdiff(a, b, c, NULL, NULL, NULL);
    CHECK(rc == 2, "three images: exit %d", rc);

    /* The image module (OpenImageIO) loaded on first use: a missing one and
     * a file that is no module are clear errors naming the path, not a
     * crash; --help needs no module. */
    char bogus[256];
    snprintf(bogus, sizeof bogus, "%s/no-such-module.so", dir);
    setenv("SLUICE_IMAGE_MODULE", bogus, 1);
    rc = run_imgdiff(a, b, NULL, NULL, NULL, NULL);
    CHECK(rc == 2 && strstr(err_text, bogus) && strstr(err_text, "image module"),
          "missing module: exit %d: %s", rc, err_text);
    rc = run_imgdiff("--help", NULL, NULL, NULL, NULL, NULL);
    CHECK(rc == 0 && strstr(out_text, "usage"), "--help without the module: %d", rc);
    setenv("SLUICE_IMAGE_MODULE", a, 1); /* an EXR file, not a library */
    rc = run_imgdiff(a, b, NULL, NULL, NULL, NULL);
    CHECK(rc == 2 && strstr(err_text, a) && strstr(err_text, "image module"),
          "a file that is no module: exit %d: %s", rc, err_text);
    unsetenv("SLUICE_IMAGE_MODULE");
    rc = run_imgdiff(a, b, NULL, NULL, NULL, NULL);
    CHECK(rc == 0, "module found again: exit %d (%s)", rc, err_text);
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--imgdiff") == 0) {
        imgdiff = argv[2];
    } else if (argc != 1) {
        fprintf(stderr, "usage: test_image [--imgdiff PATH-OF-sluice-imgdiff]\n");
        return 2;
    }
    snprintf(dir, sizeof dir, "%s", imgdiff ? "imgdiff-test-XXXXXX" : "image-test-XXXXXX");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 2;
    }
    if (imgdiff) {
        test_imgdiff();
    } else {
        test_create();
        test_srgb();
        test_exr();
        test_png();
        test_hdr();
        test_pfm_read();
        test_atomic();
        test_read_errors();
        test_metrics();
    }
    remove_tree(dir);
    return check_summary();
}
