/* The PSF width from a measured PSF image on disk (optics/psffit.h). */
#pragma once
#include "optics/psffit.h"

/* Loads a TIFF, averages its planes and fits a Gaussian; *pixel_nm: the
 * file's calibration (0 when it has none). */
int c0_psf_fit_file(const char *path, struct c0_psf_fit *out, double *pixel_nm);
