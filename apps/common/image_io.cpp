/* The OpenImageIO shim: the only C++ in the tree, built as a module of its
 * own (libsluice-image-oiio.so) that image_io_module.c loads on first use;
 * it exports nothing but sr_image_io_module_get() (image.h). It opens, reads
 * and writes files and nothing more; colour handling, channel mapping, size
 * limits and atomic replacement live in image.c. No exception may cross into
 * C, so every entry point catches everything. */
#include "image.h"
#include "app_error.h"

#include <OpenImageIO/imageio.h>

#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <string>

struct sr_image_io_reader {
    std::unique_ptr<OIIO::ImageInput> in;
};

/* The status and message for the exception being handled (called inside a
 * catch block): no exception may cross into C. */
static sluice_status caught(char *err, size_t err_size)
{
    try {
        throw;
    } catch (const std::bad_alloc &) {
        sr_set_error(err, err_size, "out of memory");
        return SLUICE_ERROR_OUT_OF_MEMORY;
    } catch (const std::exception &e) {
        sr_set_error(err, err_size, "OpenImageIO: %s", e.what());
        return SLUICE_ERROR_IO;
    } catch (...) {
        sr_set_error(err, err_size, "OpenImageIO raised an unknown exception");
        return SLUICE_ERROR_IO;
    }
}

/* OpenImageIO messages can span lines; the callers print one line. */
static std::string one_line(std::string s, const char *fallback)
{
    for (char &c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    while (!s.empty() && s.back() == ' ')
        s.pop_back();
    return s.empty() ? std::string(fallback) : s;
}

static sluice_status io_open(const char *path, sr_image_io_reader **out, sr_image_io_info *info,
                             char *err, size_t err_size)
{
    if (out)
        *out = nullptr;
    if (!path || !out || !info) {
        sr_set_error(err, err_size, "NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    try {
        /* PNG and TIFF readers premultiply alpha unless asked not to; the
         * images here keep alpha straight. */
        OIIO::ImageSpec config;
        config.attribute("oiio:UnassociatedAlpha", 1);
        auto in = OIIO::ImageInput::open(path, &config);
        if (!in) {
            sr_set_error(err, err_size, "%s",
                         one_line(OIIO::geterror(), "OpenImageIO cannot open it").c_str());
            return SLUICE_ERROR_IO;
        }
        const OIIO::ImageSpec &spec = in->spec();
        std::memset(info, 0, sizeof *info);
        info->width = spec.width;
        info->height = spec.height;
        info->depth = spec.depth;
        info->channels = spec.nchannels;
        info->alpha_channel = spec.alpha_channel;
        info->is_float = spec.format.is_floating_point();
        info->bits = (int)(spec.format.size() * 8);
        info->gamma = spec.get_float_attribute("oiio:Gamma", 0.0f);
        std::string cs = spec.get_string_attribute("oiio:ColorSpace");
        std::snprintf(info->colorspace, sizeof info->colorspace, "%s", cs.c_str());
        auto *r = new sr_image_io_reader;
        r->in = std::move(in);
        *out = r;
        return SLUICE_OK;
    } catch (...) {
        return caught(err, err_size);
    }
}

static sluice_status io_read(sr_image_io_reader *r, int chbegin, int chend, float *pixels,
                             char *err, size_t err_size)
{
    if (!r || !pixels || chbegin < 0 || chend <= chbegin || chend > r->in->spec().nchannels) {
        sr_set_error(err, err_size, "bad arguments to sr_image_io_read");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    try {
        if (!r->in->read_image(0, 0, chbegin, chend, OIIO::TypeDesc::FLOAT, pixels)) {
            sr_set_error(err, err_size, "%s",
                         one_line(r->in->geterror(), "OpenImageIO cannot read the pixels").c_str());
            return SLUICE_ERROR_IO;
        }
        return SLUICE_OK;
    } catch (...) {
        return caught(err, err_size);
    }
}

static void io_close(sr_image_io_reader *r)
{
    if (!r)
        return;
    try {
        r->in->close();
    } catch (...) {
        /* Nothing to report from a destructor-like call; the handle is
         * freed regardless. */
    }
    delete r;
}

static sluice_status io_write(const char *path, unsigned width, unsigned height, unsigned channels,
                              sr_image_io_type type, const void *pixels, char *err, size_t err_size)
{
    if (!path || !pixels || !width || !height || !channels || channels > 4 ||
        width > SR_IMAGE_MAX_SIDE || height > SR_IMAGE_MAX_SIDE) {
        sr_set_error(err, err_size, "bad arguments to sr_image_io_write");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    try {
        auto out = OIIO::ImageOutput::create(path);
        if (!out) {
            sr_set_error(err, err_size, "%s",
                         one_line(OIIO::geterror(), "OpenImageIO has no writer for it").c_str());
            return SLUICE_ERROR_IO;
        }
        OIIO::TypeDesc td =
            type == SR_IMAGE_IO_UINT8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT;
        /* The spec names the channels R, G, B, A and sets alpha_channel. */
        OIIO::ImageSpec spec((int)width, (int)height, (int)channels, td);
        spec.attribute("oiio:ColorSpace", type == SR_IMAGE_IO_UINT8 ? "sRGB" : "linear");
        /* Our alpha is straight: stop writers from un-premultiplying it. */
        spec.attribute("oiio:UnassociatedAlpha", 1);
        bool ok = out->open(path, spec) && out->write_image(td, pixels);
        /* close() flushes: its failure (a full disk) is a failed write. */
        ok = out->close() && ok;
        if (!ok) {
            sr_set_error(err, err_size, "%s",
                         one_line(out->geterror(), "OpenImageIO cannot write it").c_str());
            return SLUICE_ERROR_IO;
        }
        return SLUICE_OK;
    } catch (...) {
        return caught(err, err_size);
    }
}

extern "C" __attribute__((visibility("default"))) const sr_image_io_module *
sr_image_io_module_get(void)
{
    static const sr_image_io_module table = {SR_IMAGE_IO_ABI, io_open, io_read, io_close, io_write};
    return &table;
}
