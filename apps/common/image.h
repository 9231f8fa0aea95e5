/*
 * Images for the apps: an opaque handle on linear float RGB or RGBA pixels,
 * and reading and writing files through OpenImageIO.
 *
 * Pixels are 32-bit floats, row-major, top row first, channels interleaved
 * (R, G, B[, A]). Colour values are linear; alpha is straight (not
 * premultiplied) and never goes through a transfer function.
 *
 * Conventions are those of <sluice/sluice.h>: fallible functions return a
 * sluice_status, nothing aborts, exits or prints, destroy accepts NULL. A
 * failing function writes a NUL-terminated message of at most `err_size`
 * bytes into `err` (which may be NULL) and, when a file is involved, names
 * it.
 */
#ifndef SR_APPS_IMAGE_H
#define SR_APPS_IMAGE_H

#include "sluice/sluice.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Largest width or height sr_image_create() accepts. */
#define SR_IMAGE_MAX_SIDE 65536u
/** Largest width * height sr_image_create() accepts (2^28 pixels, 4 GiB
 *  of RGBA floats): beyond it a request is a bug, not an image. */
#define SR_IMAGE_MAX_PIXELS (1u << 28)

typedef struct sr_image sr_image;

/**
 * Creates a width x height image of `channels` (3: RGB, 4: RGBA) floats per
 * pixel, all zero. Fails with SLUICE_ERROR_INVALID_ARGUMENT for a zero size,
 * a side above SR_IMAGE_MAX_SIDE, more than SR_IMAGE_MAX_PIXELS pixels
 * or another channel count, before allocating anything, and with
 * SLUICE_ERROR_OUT_OF_MEMORY when the pixels cannot be allocated. On failure
 * `*out` is NULL.
 */
sluice_status sr_image_create(unsigned width, unsigned height, unsigned channels, sr_image **out,
                              char *err, size_t err_size);

/** Frees the image and its pixels. NULL is allowed. */
void sr_image_destroy(sr_image *img);

/** Width in pixels (0 for NULL). */
unsigned sr_image_width(const sr_image *img);

/** Height in pixels (0 for NULL). */
unsigned sr_image_height(const sr_image *img);

/** Floats per pixel: 3 or 4 (0 for NULL). */
unsigned sr_image_channels(const sr_image *img);

/** The pixels: width * height * channels floats, row-major, top row first;
 *  pixel (x, y) starts at index (y * width + x) * channels. NULL for NULL. */
float *sr_image_pixels(sr_image *img);

/** Read-only view of the same pixels as sr_image_pixels(). */
const float *sr_image_pixels_const(const sr_image *img);

/**
 * Writes the image to `path`, in the format its extension names (any case):
 *   .exr  32-bit float (not half), every channel: reads back bit-exactly.
 *   .png  8-bit, colour sRGB-encoded, alpha as is; values are clamped to
 *         [0, 1] and NaN becomes 0.
 *   .hdr  Radiance RGBE, linear; alpha is dropped.
 * Any other extension fails with SLUICE_ERROR_INVALID_ARGUMENT (.pfm too:
 * OpenImageIO 2.4 reads it but has no writer for it).
 *
 * The write is atomic: the file is written under a hidden temporary name in
 * the same directory (".NAME.tmpPID-N.EXT", NAME the whole file name),
 * flushed to disk, then renamed over `path`. On failure the temporary file
 * is removed and a file already at `path` is left untouched, so a crash or
 * error never leaves a truncated image there. Errors: SLUICE_ERROR_IO
 * (OpenImageIO, fsync or rename failed; a missing directory),
 * SLUICE_ERROR_OUT_OF_MEMORY.
 */
sluice_status sr_image_write(const sr_image *img, const char *path, char *err, size_t err_size);

/** Flags of sr_image_read_ex(). */
enum {
    /** Skip the transfer function: integer files come back as their stored
     *  values scaled to [0, 1] (an 8-bit 128 reads 128/255). For data that
     *  is not colour (normal maps), and to inspect what a file holds. */
    SR_IMAGE_READ_RAW = 1u
};

/**
 * Reads the first subimage of any file OpenImageIO can read into a new RGB
 * or RGBA image of linear floats. Integer files (8- and 16-bit PNG, JPEG,
 * TIFF, ...) are decoded from sRGB, or with the file's gamma when it states
 * one, unless the file says it is linear; floating-point files (EXR, HDR,
 * PFM, float TIFF) are taken as linear. One grey channel becomes RGB, grey
 * and alpha become RGBA; of more channels, the first three that are not
 * alpha become RGB and the alpha channel, if the file has one, A.
 * Errors: SLUICE_ERROR_NOT_FOUND (no such file), SLUICE_ERROR_IO (not
 * readable as an image; the message quotes OpenImageIO),
 * SLUICE_ERROR_INVALID_ARGUMENT (too large for sr_image_create, a
 * volume), SLUICE_ERROR_OUT_OF_MEMORY. On failure `*out` is NULL.
 */
sluice_status sr_image_read(const char *path, sr_image **out, char *err, size_t err_size);

/** sr_image_read() with flags (SR_IMAGE_READ_RAW); flags 0 is the
 *  same as sr_image_read(). */
sluice_status sr_image_read_ex(const char *path, unsigned flags, sr_image **out, char *err,
                               size_t err_size);

/** The sRGB transfer function (IEC 61966-2-1): linear [0, 1] to encoded
 *  [0, 1]. Values outside [0, 1] are clamped and NaN gives 0. */
float sr_srgb_encode(float linear);

/** The inverse of sr_srgb_encode(): encoded [0, 1] to linear [0, 1],
 *  clamped the same way. */
float sr_srgb_decode(float encoded);

/* ------------------------------------------------------------------ */
/* The image I/O module. Used by image.c; other code should call        */
/* sr_image_read/write. These functions take no file-naming             */
/* responsibility: their messages are OpenImageIO's, and the callers    */
/* above prefix the path.                                               */
/*                                                                      */
/* OpenImageIO and the ~250 libraries it links live in a module of      */
/* their own (image_io.cpp, libsluice-image-oiio.so), loaded on the     */
/* first call of one of these functions (image_io_module.c): linked     */
/* into every program, they made start-up slow (the dynamic linker's    */
/* relocations; bench/README.md has the figures) and every kernel       */
/* library PoCL loads later searched that scope too. A program that     */
/* reads or writes no image never loads them.                           */
/* ------------------------------------------------------------------ */

/** What sr_image_io_open() learned about a file. */
typedef struct sr_image_io_info {
    long long width, height, depth; /**< of the data window; depth 1 for 2D */
    int channels;                   /**< channels in the file */
    int alpha_channel;              /**< index of alpha, or -1 */
    int is_float;                   /**< stored as half, float or double */
    int bits;                       /**< bits per stored channel value */
    float gamma;                    /**< the file's stated gamma, or 0 */
    char colorspace[64];            /**< "oiio:ColorSpace", or "" */
} sr_image_io_info;

typedef struct sr_image_io_reader sr_image_io_reader;

/** Pixel types sr_image_io_write() takes. */
typedef enum sr_image_io_type {
    SR_IMAGE_IO_FLOAT, /**< float, stored as 32-bit float where possible */
    SR_IMAGE_IO_UINT8  /**< uint8_t, stored as is, tagged sRGB */
} sr_image_io_type;

/** Opens `path` for reading and fills `*info`. Returns SLUICE_ERROR_IO with
 *  OpenImageIO's message when it cannot (or when the module cannot be
 *  loaded: the message says where it was looked for),
 *  SLUICE_ERROR_OUT_OF_MEMORY. */
sluice_status sr_image_io_open(const char *path, sr_image_io_reader **out, sr_image_io_info *info,
                               char *err, size_t err_size);

/** Reads channels [chbegin, chend) of every pixel of the open file as
 *  floats (integer formats scaled to [0, 1]) into `pixels`, which holds
 *  width * height * (chend - chbegin) floats. */
sluice_status sr_image_io_read(sr_image_io_reader *r, int chbegin, int chend, float *pixels,
                               char *err, size_t err_size);

/** Closes a reader from sr_image_io_open(); NULL is allowed. */
void sr_image_io_close(sr_image_io_reader *r);

/** Writes width x height pixels of `channels` interleaved values of `type`
 *  to `path`, in the format OpenImageIO picks from its extension. Alpha,
 *  if any, is the fourth channel and is stored unassociated. Returns
 *  SLUICE_ERROR_IO as sr_image_io_open() does. */
sluice_status sr_image_io_write(const char *path, unsigned width, unsigned height,
                                unsigned channels, sr_image_io_type type, const void *pixels,
                                char *err, size_t err_size);

/** Loads the image module now, if not yet loaded. A program that will
 *  write an image calls it before long work, so that a missing module is an
 *  error at the start and not lost output at the end. Returns SLUICE_OK, or
 *  SLUICE_ERROR_IO with the reason (where the module was looked for) in
 *  `err`. */
sluice_status sr_image_io_load(char *err, size_t err_size);

/** Bumped whenever sr_image_io_module or the functions' meaning changes,
 *  so that a stale module is refused with a message instead of called. */
#define SR_IMAGE_IO_ABI 1u

/** The module's functions, which the ones above call. */
typedef struct sr_image_io_module {
    unsigned abi; /**< SR_IMAGE_IO_ABI of the module's build */
    sluice_status (*open)(const char *path, sr_image_io_reader **out, sr_image_io_info *info,
                          char *err, size_t err_size);
    sluice_status (*read)(sr_image_io_reader *r, int chbegin, int chend, float *pixels, char *err,
                          size_t err_size);
    void (*close)(sr_image_io_reader *r);
    sluice_status (*write)(const char *path, unsigned width, unsigned height, unsigned channels,
                           sr_image_io_type type, const void *pixels, char *err, size_t err_size);
} sr_image_io_module;

/** The module's one exported symbol (SR_IMAGE_IO_MODULE_SYMBOL): its
 *  function table, static, never NULL. */
const sr_image_io_module *sr_image_io_module_get(void);
#define SR_IMAGE_IO_MODULE_SYMBOL "sr_image_io_module_get"

#ifdef __cplusplus
}
#endif

#endif
