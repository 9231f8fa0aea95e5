/* Image error metrics in plain C (definitions in image_metrics.h), summed
 * in double so that 2^28 pixels lose nothing that matters. */
#include "image_metrics.h"
#include "app_error.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* 0: finite, 1: Inf somewhere, 2: NaN somewhere. */
static int pixel_class(const float *p, unsigned channels)
{
    int cls = 0;
    for (unsigned k = 0; k < channels; ++k) {
        if (isnan(p[k]))
            return 2;
        if (isinf(p[k]))
            cls = 1;
    }
    return cls;
}

sluice_status sr_image_compare(const sr_image *a, const sr_image *b, sr_image_metrics *m, char *err,
                               size_t err_size)
{
    if (m)
        memset(m, 0, sizeof *m);
    if (!a || !b || !m) {
        sr_set_error(err, err_size, "sr_image_compare: NULL argument");
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    unsigned w = sr_image_width(a), h = sr_image_height(a);
    if (w != sr_image_width(b) || h != sr_image_height(b)) {
        sr_set_error(err, err_size, "image sizes differ: %ux%u vs %ux%u", w, h, sr_image_width(b),
                     sr_image_height(b));
        return SLUICE_ERROR_INVALID_ARGUMENT;
    }
    unsigned ca = sr_image_channels(a), cb = sr_image_channels(b);
    unsigned nc = ca < cb ? ca : cb;
    if (nc > 3)
        nc = 3;
    const float *pa = sr_image_pixels_const(a), *pb = sr_image_pixels_const(b);
    const size_t npix = (size_t)w * h;

    double sum_sq = 0.0, sum_rel = 0.0, max_err = 0.0;
    size_t valid = 0;
    for (size_t p = 0; p < npix; ++p) {
        const float *x = pa + p * ca, *y = pb + p * cb;
        int cls = pixel_class(x, ca), cls_b = pixel_class(y, cb);
        if (cls_b > cls)
            cls = cls_b;
        if (cls == 2) {
            m->nan_count++;
            continue;
        }
        if (cls == 1) {
            m->inf_count++;
            continue;
        }
        valid++;
        for (unsigned k = 0; k < nc; ++k) {
            double d = (double)x[k] - (double)y[k];
            double ref = y[k];
            sum_sq += d * d;
            sum_rel += d * d / (ref * ref + SR_IMAGE_REL_MSE_EPSILON);
            if (fabs(d) > max_err)
                max_err = fabs(d);
        }
    }
    double n = (double)valid * nc;
    m->rmse = n > 0 ? sqrt(sum_sq / n) : 0.0;
    m->rel_mse = n > 0 ? sum_rel / n : 0.0;
    m->max_error = max_err;
    m->psnr = m->rmse > 0 ? 20.0 * log10(1.0 / m->rmse) : INFINITY;
    m->pixels = npix;
    m->channels = nc;
    return SLUICE_OK;
}
