/* The image handle, the sRGB transfer function, and the policy around the
 * OpenImageIO shim (image_io.cpp): which formats are written and how, atomic
 * replacement of the target file, and turning whatever a file holds into
 * linear RGB or RGBA floats. */
#include "image.h"
#include "app_error.h"
#include "data_path.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

struct sr_image {
    unsigned width, height, channels;
    float *pixels;
};

/* One place for the size limits, so that create and read agree. Sizes come
 * in as long long because files report signed ints of any value. */
static sluice_status check_size(long long width, long long height, char *msg, size_t msg_size)
{
    if (width <= 0 || height <= 0) {
        sr_set_error(msg, msg_size, "image size %lldx%lld is empty", width, height);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (width > SR_IMAGE_MAX_SIDE || height > SR_IMAGE_MAX_SIDE ||
        width * height > (long long)SR_IMAGE_MAX_PIXELS) {
        sr_set_error(msg, msg_size,
                     "image size %lldx%lld is too large (at most %u pixels a side and %u pixels)",
                     width, height, SR_IMAGE_MAX_SIDE, SR_IMAGE_MAX_PIXELS);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    return SLUICE_OK;
}

sluice_status sr_image_create(unsigned width, unsigned height, unsigned channels, sr_image **out,
                              char *err, size_t err_size)
{
    if (!out) {
        sr_set_error(err, err_size, "sr_image_create: out is NULL");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    *out = NULL;
    sluice_status st = check_size(width, height, err, err_size);
    if (st != SLUICE_OK)
        return st;
    if (channels != 3 && channels != 4) {
        sr_set_error(err, err_size, "images have 3 (RGB) or 4 (RGBA) channels, not %u", channels);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    sr_image *img = malloc(sizeof *img);
    /* At most 2^28 * 4 floats: the product fits a 64-bit size_t. */
    size_t count = (size_t)width * height * channels;
    float *px = calloc(count, sizeof *px);
    if (!img || !px) {
        free(img);
        free(px);
        sr_set_error(err, err_size, "out of memory for a %ux%u image of %u channels", width, height,
                     channels);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    img->width = width;
    img->height = height;
    img->channels = channels;
    img->pixels = px;
    *out = img;
    return SLUICE_OK;
}

void sr_image_destroy(sr_image *img)
{
    if (!img)
        return;
    free(img->pixels);
    free(img);
}

unsigned sr_image_width(const sr_image *img)
{
    return img ? img->width : 0;
}

unsigned sr_image_height(const sr_image *img)
{
    return img ? img->height : 0;
}

unsigned sr_image_channels(const sr_image *img)
{
    return img ? img->channels : 0;
}

float *sr_image_pixels(sr_image *img)
{
    return img ? img->pixels : NULL;
}

const float *sr_image_pixels_const(const sr_image *img)
{
    return img ? img->pixels : NULL;
}

/* `!(v > 0)` also catches NaN. */
static double clamp01(double v)
{
    return !(v > 0.0) ? 0.0 : v > 1.0 ? 1.0 : v;
}

float sr_srgb_encode(float linear)
{
    double l = clamp01(linear);
    return (float)(l <= 0.0031308 ? 12.92 * l : 1.055 * pow(l, 1.0 / 2.4) - 0.055);
}

float sr_srgb_decode(float encoded)
{
    double e = clamp01(encoded);
    return (float)(e <= 0.04045 ? e / 12.92 : pow((e + 0.055) / 1.055, 2.4));
}

/* ------------------------------------------------------------------ */
/* Writing                                                             */
/* ------------------------------------------------------------------ */

enum file_kind { KIND_EXR, KIND_PNG, KIND_HDR };

static const struct {
    const char *ext;
    enum file_kind kind;
} write_formats[] = {
    {".exr", KIND_EXR},
    {".png", KIND_PNG},
    {".hdr", KIND_HDR},
};

/* Temporary names differ between processes by the pid and between threads
 * of one process by this counter. */
static atomic_uint temp_counter;

/* "dir/name.ext" -> "dir/.name.ext.tmpPID-N.ext": hidden, in the same
 * directory (so rename() cannot cross file systems), and ending in the real
 * extension, because OpenImageIO picks the format from it. */
static char *temp_path(const char *path, const char *base, const char *ext)
{
    unsigned n = atomic_fetch_add(&temp_counter, 1u);
    long pid = (long)getpid();
    int dir_len = (int)(base - path);
    int len = snprintf(NULL, 0, "%.*s.%s.tmp%ld-%u%s", dir_len, path, base, pid, n, ext);
    if (len < 0)
        return NULL;
    char *tmp = malloc((size_t)len + 1);
    if (tmp)
        snprintf(tmp, (size_t)len + 1, "%.*s.%s.tmp%ld-%u%s", dir_len, path, base, pid, n, ext);
    return tmp;
}

/* Makes the temporary file's data durable before it replaces the target:
 * without this, a crash shortly after rename() could leave an empty file at
 * the target on some file systems. */
static int sync_file(const char *path)
{
    int fd = open(path, O_RDONLY);
    if (fd < 0)
        return -1;
    int rc = fsync(fd);
    int saved = errno;
    close(fd);
    errno = saved;
    return rc;
}

sluice_status sr_image_write(const sr_image *img, const char *path, char *err, size_t err_size)
{
    if (!path || !*path) {
        sr_set_error(err, err_size, "sr_image_write: no path given");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    if (!img || !img->pixels) {
        sr_set_error(err, err_size, "cannot write '%s': no image (NULL)", path);
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *ext = strrchr(base, '.');
    int kind = -1;
    for (size_t i = 0; ext && i < sizeof write_formats / sizeof write_formats[0]; ++i)
        if (strcasecmp(ext, write_formats[i].ext) == 0)
            kind = (int)write_formats[i].kind;
    if (kind < 0) {
        sr_set_error(err, err_size,
                     "cannot write '%s': unsupported extension '%s' (use .exr, .png or .hdr)", path,
                     ext ? ext : "");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }

    const size_t npix = (size_t)img->width * img->height;
    const unsigned c = img->channels;
    unsigned out_c = c;
    sr_image_io_type type = SR_IMAGE_IO_FLOAT;
    const void *data = img->pixels;
    void *converted = NULL;
    if (kind == KIND_PNG) {
        uint8_t *q = malloc(npix * c);
        if (q) {
            for (size_t i = 0; i < npix * c; ++i) {
                float v = img->pixels[i];
                /* Alpha (the fourth channel) is coverage, not colour. */
                double e = (c == 4 && i % 4 == 3) ? clamp01(v) : sr_srgb_encode(v);
                q[i] = (uint8_t)(e * 255.0 + 0.5);
            }
        }
        converted = q;
        type = SR_IMAGE_IO_UINT8;
    } else if (kind == KIND_HDR && c == 4) {
        /* RGBE holds RGB only. */
        float *rgb = malloc(npix * 3 * sizeof *rgb);
        if (rgb)
            for (size_t i = 0; i < npix; ++i)
                memcpy(rgb + i * 3, img->pixels + i * 4, 3 * sizeof *rgb);
        converted = rgb;
        out_c = 3;
    }
    if (type == SR_IMAGE_IO_UINT8 || out_c != c) {
        if (!converted) {
            sr_set_error(err, err_size, "cannot write '%s': out of memory", path);
            return SLUICE_ERROR_OUT_OF_MEMORY;
        }
        data = converted;
    }

    char *tmp = temp_path(path, base, ext);
    if (!tmp) {
        free(converted);
        sr_set_error(err, err_size, "cannot write '%s': out of memory", path);
        return SLUICE_ERROR_OUT_OF_MEMORY;
    }
    char msg[512] = "";
    sluice_status st =
        sr_image_io_write(tmp, img->width, img->height, out_c, type, data, msg, sizeof msg);
    free(converted);
    if (st != SLUICE_OK) {
        /* OpenImageIO's message names the temporary file and often not the
         * reason; a missing directory is the common one, so say so. */
        char parent[512];
        struct stat sb;
        if (sr_path_dir(path, parent, sizeof parent) == 0 && stat(parent, &sb) != 0)
            sr_set_error(err, err_size, "cannot write '%s': directory '%s': %s", path, parent,
                         strerror(errno));
        else
            sr_set_error(err, err_size, "cannot write '%s': %s", path, msg);
    } else if (sync_file(tmp) != 0) {
        sr_set_error(err, err_size, "cannot write '%s': flushing '%s' failed: %s", path, tmp,
                     strerror(errno));
        st = SLUICE_ERROR_IO;
    } else if (rename(tmp, path) != 0) {
        sr_set_error(err, err_size, "cannot write '%s': renaming '%s' over it failed: %s", path,
                     tmp, strerror(errno));
        st = SLUICE_ERROR_IO;
    }
    /* Whatever failed, OpenImageIO may have created the file: never leave
     * it behind. */
    if (st != SLUICE_OK)
        remove(tmp);
    free(tmp);
    return st;
}

/* ------------------------------------------------------------------ */
/* Reading                                                             */
/* ------------------------------------------------------------------ */

enum transfer { TRANSFER_LINEAR, TRANSFER_SRGB, TRANSFER_GAMMA };

/* Whether an "oiio:ColorSpace" value names linear data ("linear",
 * "Linear", "scene_linear", "lin_srgb", "ACEScg", ...). */
static int colorspace_is_linear(const char *cs)
{
    char low[64];
    size_t i = 0;
    for (; cs[i] && i + 1 < sizeof low; ++i)
        low[i] = (char)(cs[i] >= 'A' && cs[i] <= 'Z' ? cs[i] - 'A' + 'a' : cs[i]);
    low[i] = 0;
    return strstr(low, "linear") || strncmp(low, "lin_", 4) == 0 || strcmp(low, "acescg") == 0;
}

static enum transfer pick_transfer(const sr_image_io_info *info, unsigned flags)
{
    if ((flags & SR_IMAGE_READ_RAW) || info->is_float || colorspace_is_linear(info->colorspace))
        return TRANSFER_LINEAR;
    /* OpenImageIO reports a PNG gAMA chunk (and similar) as "GammaX.Y". */
    if (info->gamma > 0.0f && strncasecmp(info->colorspace, "gamma", 5) == 0)
        return TRANSFER_GAMMA;
    return TRANSFER_SRGB;
}

/* Which file channels feed R, G, B and A (-1: none; for B, none means 0).
 * Colour comes from the first three channels that are not alpha; one grey
 * channel feeds all three. Returns the channel count of the image. */
static unsigned map_channels(const sr_image_io_info *info, int src[4])
{
    int alpha =
        info->alpha_channel >= 0 && info->alpha_channel < info->channels ? info->alpha_channel : -1;
    int colour[3], ncolour = 0;
    for (int ch = 0; ch < info->channels && ncolour < 3; ++ch)
        if (ch != alpha)
            colour[ncolour++] = ch;
    if (ncolour == 0) { /* a lone alpha channel: show it as grey */
        colour[ncolour++] = alpha;
        alpha = -1;
    }
    src[0] = colour[0];
    src[1] = ncolour == 1 ? colour[0] : colour[1];
    src[2] = ncolour == 1 ? colour[0] : ncolour == 2 ? -1 : colour[2];
    src[3] = alpha;
    return alpha >= 0 ? 4u : 3u;
}

sluice_status sr_image_read_ex(const char *path, unsigned flags, sr_image **out, char *err,
                               size_t err_size)
{
    if (out)
        *out = NULL;
    if (!path || !*path || !out) {
        sr_set_error(err, err_size, "sr_image_read: %s", !out ? "out is NULL" : "no path given");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    /* OpenImageIO says "could not open" for every reason; tell a missing
     * file apart, as callers may want to. */
    struct stat sb;
    if (stat(path, &sb) != 0) {
        int e = errno;
        sr_set_error(err, err_size, "cannot read '%s': %s", path, strerror(e));
        return e == ENOENT || e == ENOTDIR ? SLUICE_ERROR_NOT_FOUND : SLUICE_ERROR_IO;
    }
    if (S_ISDIR(sb.st_mode)) {
        sr_set_error(err, err_size, "cannot read '%s': it is a directory", path);
        return SLUICE_ERROR_IO;
    }

    char msg[512] = "";
    sr_image_io_info info;
    sr_image_io_reader *r = NULL;
    sluice_status st = sr_image_io_open(path, &r, &info, msg, sizeof msg);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "cannot read '%s': %s", path, msg);
        return st;
    }
    sr_image *img = NULL;
    float *buf = NULL;
    if (info.depth != 1) {
        sr_set_error(err, err_size,
                     "cannot read '%s': volume images (depth %lld) are not supported", path,
                     info.depth);
        st = SLUICE_ERROR_INVALID_ARGUMENT;
        goto done;
    }
    if (info.channels < 1) {
        sr_set_error(err, err_size, "cannot read '%s': it has no channels", path);
        st = SLUICE_ERROR_IO;
        goto done;
    }
    st = check_size(info.width, info.height, msg, sizeof msg);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "cannot read '%s': %s", path, msg);
        goto done;
    }
    int src[4];
    unsigned c = map_channels(&info, src);
    int chend = 0; /* read only the channels used: an EXR may hold dozens */
    for (int i = 0; i < 4; ++i)
        if (src[i] + 1 > chend)
            chend = src[i] + 1;
    const size_t npix = (size_t)info.width * (size_t)info.height;
    buf = malloc(npix * (size_t)chend * sizeof *buf);
    st =
        buf ? sr_image_create((unsigned)info.width, (unsigned)info.height, c, &img, msg, sizeof msg)
            : SLUICE_ERROR_OUT_OF_MEMORY;
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "cannot read '%s': out of memory for %lldx%lld pixels", path,
                     info.width, info.height);
        goto done;
    }
    st = sr_image_io_read(r, 0, chend, buf, msg, sizeof msg);
    if (st != SLUICE_OK) {
        sr_set_error(err, err_size, "cannot read '%s': %s", path, msg);
        goto done;
    }

    enum transfer tf = pick_transfer(&info, flags);
    /* 8-bit files: 256 possible values, so decode through a table instead
     * of a pow() per value. */
    float lut[256];
    int use_lut = tf != TRANSFER_LINEAR && info.bits == 8;
    if (use_lut)
        for (int i = 0; i < 256; ++i)
            lut[i] = tf == TRANSFER_SRGB ? sr_srgb_decode((float)i / 255.0f)
                                         : (float)pow(i / 255.0, info.gamma);
    float *px = img->pixels;
    for (size_t p = 0; p < npix; ++p) {
        const float *s = buf + p * (size_t)chend;
        float *d = px + p * c;
        for (int k = 0; k < 3; ++k) {
            float v = src[k] >= 0 ? s[src[k]] : 0.0f;
            if (use_lut)
                v = lut[(int)(clamp01(v) * 255.0 + 0.5)];
            else if (tf == TRANSFER_SRGB)
                v = sr_srgb_decode(v);
            else if (tf == TRANSFER_GAMMA)
                v = (float)pow(clamp01(v), info.gamma);
            d[k] = v;
        }
        if (c == 4)
            d[3] = s[src[3]];
    }

done:
    free(buf);
    sr_image_io_close(r);
    if (st != SLUICE_OK) {
        sr_image_destroy(img);
        return st;
    }
    *out = img;
    return SLUICE_OK;
}

sluice_status sr_image_read(const char *path, sr_image **out, char *err, size_t err_size)
{
    return sr_image_read_ex(path, 0, out, err, err_size);
}
