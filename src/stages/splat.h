/* The super-resolved image to look at: each fine pixel's intensity spread by
 * a normalised Gaussian of the localisation precision (sum preserved). */
#pragma once

/* out (H x W) = x (H x W) convolved with a sampled, normalised Gaussian of
 * sd sigma_px (separable, radius ceil(3 sigma), zero outside the field). */
int c0_splat(const float *x, int H, int W, double sigma_px, float *out);
