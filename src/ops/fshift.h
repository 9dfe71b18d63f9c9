/* Sub-pixel translation of an image by Fourier phase ramps on its mirrored
 * extension: rows, then columns, each extended symmetrically to twice its
 * length so that the shift sees no edge jump (no wrap-around ringing). A
 * phase ramp is unitary, so white noise stays white and keeps its variance
 * (interpolating kernels would smooth it and correlate neighbours, which the
 * covariance model would read as signal). */
#pragma once

struct c0_fshift;

int c0_fshift_new(int H, int W, struct c0_fshift **out);
void c0_fshift_free(struct c0_fshift *s);
/* img (H x W) <- img sampled at (x + dx, y + dy): content moves by (-dx, -dy).
 * Thread-safe for one c0_fshift: each call takes its own work buffers from
 * the object's pool (and returns them). */
int c0_fshift_apply(struct c0_fshift *s, float *img, double dx, double dy);
/* The variances of c0_fshift_apply's output for an input of independent
 * pixels with variances var (H x W), times w added to out: each pixel's sum of the
 * shift kernel's squared weights times var (the kernel truncated at 16
 * pixels and its squares summed to 1). A Fourier shift moves a noisy pixel's
 * variance and spreads it over its neighbours, where its value would not. */
int c0_fshift_variance(int H, int W, const float *var, double dx, double dy, double w, double *out);
