/* The camera and fine-grid geometry every stage shares: camera pixel size,
 * PSF FWHM and super-resolution factor, and what follows from them. */
#pragma once

struct c0_grid {
	double pixel_nm;           /* camera pixel size (required) */
	double fwhm_nm;            /* PSF FWHM (required) */
	int srf;                   /* fine grid factor r (4 in the stage defaults) */
};

/* Pixel size and FWHM positive (nm), FWHM C0_PSF_MIN_PX..C0_PSF_MAX_PX
 * camera pixels, srf 1..16; errors name the option. */
int c0_grid_check(const struct c0_grid *g);
/* The PSF's sigma in camera pixels. */
double c0_grid_sigma_px(const struct c0_grid *g);
/* The fine pixel's side in nm: pixel_nm / srf. */
double c0_grid_fine_nm(const struct c0_grid *g);
/* A covariance lag radius in camera pixels: lag when positive, else
 * ceil(6 sigma) (ops/covariance.h). */
int c0_grid_lag(const struct c0_grid *g, int lag);
