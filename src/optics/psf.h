/* Gaussian PSF integrated over camera pixels, in separable form.
 * Lengths are in coarse (camera) pixel units: pixel i covers [i, i+1). */
#pragma once
#include "core/band.h"

/* The FWHM range c0_grid_check (optics/grid.h) accepts, in camera pixels. */
#define C0_PSF_MIN_PX 0.1
#define C0_PSF_MAX_PX 100.0
/* FWHM 0.51 lambda / NA (emission in nm), with 0 < NA < n_glass. */
int c0_fwhm_from_na(double emission_nm, double na, double n_glass, double *fwhm_nm);

/* sigma of the Gaussian in camera pixels from FWHM and pixel size (nm) */
double c0_psf_sigma_px(double fwhm_nm, double pixel_nm);

/* Half-width in pixels beyond which the Gaussian is treated as zero. */
#define C0_PSF_CUTOFF 5.0

/* out[k] = integral over pixel (first+k) of a unit Gaussian centred at c. */
void c0_psf_pixel_weights(double c, double sigma, int first, int n, double *out);

/* G (N x rN): G[i][a] = integral over coarse pixel i of the Gaussian centred
 * on fine pixel a (centre (a+1/2)/r). Zero outside the field (no wrap). */
int c0_psf_factor(int N, int r, double sigma, struct c0_band *G);
