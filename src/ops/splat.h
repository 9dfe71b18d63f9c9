/* The super-resolved image to look at: each fine pixel's intensity spread by
 * a normalised Gaussian of the localisation precision (sum preserved). */
#pragma once

/* Rows y0..y1 of it alone into out ((y1 - y0) x W), the same values bit for
 * bit: a band of the fine grid in memory instead of the whole. x holds the
 * rows from xrow0 on, at least those within the radius of the band. */
int c0_splat_rows(const float *x, int xrow0, int H, int W, double sigma_px, int y0, int y1, float *out);
/* The radius: ceil(3 sigma_px) */
int c0_splat_radius(double sigma_px);
