/* The PSF width from a measured image (a bead, or the average of several
 * centred ones): least-squares fit of a pixel-integrated Gaussian plus a
 * constant background, A gx(x) gy(y) + b, over the whole image. */
#pragma once

struct c0_psf_fit {
	double sigma_px, fwhm_px;   /* fitted width, camera pixels */
	double cx, cy;              /* centre, pixels from the top-left corner */
	double amplitude, background;
	double rel_rms;             /* rms residual / peak of the fitted Gaussian */
};

/* img: h x w (one plane, or the mean of a bead stack). Refuses an image
 * whose peak does not stand above its background. */
int c0_psf_fit_image(const float *img, int w, int h, const char *name, struct c0_psf_fit *out);
