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
