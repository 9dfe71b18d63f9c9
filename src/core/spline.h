/* Cubic B-spline interpolation onto a grid r times finer: the C2-smooth
 * interpolant through an image's samples (Unser's recursive prefilter, then
 * the cubic B-spline's weights), with half-sample symmetric edges. Its
 * second derivatives are continuous, which a Newton step on them needs
 * (cubic convolution's jump at every sample). */
#pragma once

/* in (H x W, row-major) -> out (H r x W r): fine pixel k of sample i sits
 * at i + (k + 0.5) / r - 0.5 (each sample's pixel cut into r x r). Returns
 * C0_OK or C0_ENOMEM. */
int c0_spline_upsample(const double *in, int H, int W, int r, double *out);
