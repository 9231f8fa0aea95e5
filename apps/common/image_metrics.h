/*
 * Error metrics between two images of the same size: the figures that
 * regression tests of the renderers and sluice-imgdiff report.
 *
 * Definitions (a: the test image, b: the reference; sums run over the valid
 * pixels and the compared channels, N = valid pixels * channels):
 *   rmse       sqrt( sum (a - b)^2 / N )
 *   rel_mse    sum ( (a - b)^2 / (b^2 + 0.01) ) / N
 *              The 0.01 (SR_IMAGE_REL_MSE_EPSILON) keeps dark reference
 *              values from dominating: below b = 0.1 the error counts
 *              roughly as absolute, above it as relative.
 *   psnr       20 log10(1 / rmse) dB, with a peak of 1.0 (linear white).
 *              +infinity when rmse is 0 (identical images).
 *   max_error  max |a - b|
 * Compared channels are the colour channels both images have (R, G, B);
 * alpha is not compared.
 *
 * Invalid pixels: a pixel where either image has a NaN in any channel
 * (alpha included) counts in nan_count; one with an Inf but no NaN counts in
 * inf_count. Those pixels are left out of every figure above, so one NaN
 * does not turn them all into NaN; a caller deciding pass or fail should
 * treat nan_count or inf_count > 0 as a failure. When no pixel is valid,
 * rmse, rel_mse and max_error are 0 and psnr is +infinity.
 */
#ifndef SR_APPS_IMAGE_METRICS_H
#define SR_APPS_IMAGE_METRICS_H

#include "image.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The epsilon in the denominator of rel_mse. */
#define SR_IMAGE_REL_MSE_EPSILON 1e-2

/** What sr_image_compare() measures; see the definitions above. */
typedef struct sr_image_metrics {
    double rmse;       /**< root mean square error */
    double rel_mse;    /**< relative mean square error */
    double psnr;       /**< peak signal-to-noise ratio in dB, peak 1.0 */
    double max_error;  /**< largest absolute difference */
    size_t nan_count;  /**< pixels with a NaN in either image */
    size_t inf_count;  /**< pixels with an Inf (and no NaN) in either image */
    size_t pixels;     /**< all pixels of one image (width * height) */
    unsigned channels; /**< channels compared per pixel (3) */
} sr_image_metrics;

/**
 * Compares image `a` with the reference `b` and fills `*m`. Fails with
 * SLUICE_ERROR_INVALID_ARGUMENT for NULL arguments or images of different
 * sizes (the message gives both sizes); `*m` is then zeroed.
 */
sluice_status sr_image_compare(const sr_image *a, const sr_image *b, sr_image_metrics *m, char *err,
                               size_t err_size);

#ifdef __cplusplus
}
#endif

#endif
