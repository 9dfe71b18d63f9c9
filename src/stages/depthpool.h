/* Depth pooling for 3D-COL0RME. Each angle's intensity estimate is accurate
 * in total over a PSF-sized patch, but how it splits among neighbouring
 * fine pixels is noisy and independent from angle to angle, and depth lives
 * in the ratios between angles. So the depth profile of a support pixel is
 * reconstructed from the intensities summed over a window around it (on the
 * support only), and the volume is then rescaled pixel by pixel to the
 * pixel's own intensity. On the default simulation this halves the median
 * depth error (docs/parameters.md). */
#pragma once
#include <stdint.h>

/* out = sum of x over the (2h+1)^2 window, on the mask (0 elsewhere). */
int c0_pool_window(const float *x, const uint8_t *mask, int ny, int nx, int h, float *out);
/* f (nz x ny x nx) reconstructed from pooled images: scale each pixel's
 * column by sum_q x_q / sum_q pooled_q, so the volume keeps the pixel's own
 * intensity (the depth profile, hence the depth map, is unchanged). */
void c0_pool_rescale(float *f, int nz, int ny, int nx, int nq, const float *const *x, const float *const *pooled);

/* Default window of run's depth pooling, as a fraction of the PSF FWHM:
 * wide enough to average the per-angle splitting noise, narrower than two
 * filaments 120 nm apart at different depths (docs/parameters.md). */
#define C0_DEPTH_POOL_FWHM 0.75
