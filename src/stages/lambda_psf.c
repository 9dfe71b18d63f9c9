/* The PSF width the data's covariance says, to check the stated one
 * (docs/defaults.md#fwhm_rule). Summed over all
 * pixels, the covariance at lag d is sum_e v_e (psi * psi)(d): every
 * emitter's PSF autocorrelation, whatever the emitters' places. For a
 * Gaussian of sd sigma integrated over the pixels it is h(dy) h(dx) with
 * h(d) = E_u sum_i w_i(u) w_{i+d}(u) (u the emitter's place in its pixel),
 * so the ratio of lag 2 to lag 1 (both free of the noise variance, which
 * only lag 0 holds) gives sigma without knowing the structure. */
#include "stages/lambda.h"
#include "optics/psf.h"
#include "core/err.h"

#include <math.h>
#include <stdlib.h>

#define SUBPOS 64

/* h(2) / h(1) of a Gaussian of sd s pixels */
static double lag_ratio(double s)
{
	const int half = (int)ceil(C0_PSF_CUTOFF * s) + 3, n = 2 * half + 2;
	double w[2 * 64 + 8], h1 = 0, h2 = 0;
	if (n > (int)(sizeof w / sizeof *w))
		return NAN;
	for (int k = 0; k < SUBPOS; k++) {
		c0_psf_pixel_weights(half + (k + 0.5) / SUBPOS, s, 0, n, w);
		for (int i = 0; i + 2 < n; i++)
			h1 += w[i] * w[i + 1], h2 += w[i] * w[i + 2];
	}
	return h2 / h1;
}

/* adds cov's sums of lag 1 and lag 2 (x and y) to s */
static void lag_sums(const struct c0_cov *cov, double s[2])
{
	const size_t n = (size_t)cov->W * cov->H;
	for (int l = 0; l < cov->nlag; l++) {
		const int ay = abs(cov->dy[l]), ax = abs(cov->dx[l]);
		if (!((ay == 0) ^ (ax == 0)) || ay + ax > 2)
			continue;
		for (size_t i = 0; i < n; i++)
			s[ay + ax - 1] += cov->r[(size_t)l * n + i];
	}
}

void c0_lambda_psf_row_sums(const struct c0_cov *cov, int y, double s[2])
{
	const size_t n = (size_t)cov->W * cov->H;
	for (int l = 0; cov->d >= 2 && l < cov->nlag; l++) {
		const int ay = abs(cov->dy[l]), ax = abs(cov->dx[l]);
		if (!((ay == 0) ^ (ax == 0)) || ay + ax > 2)
			continue;
		for (int x = 0; x < cov->W; x++)
			s[ay + ax - 1] += cov->r[(size_t)l * n + (size_t)y * cov->W + x];
	}
}

int c0_lambda_psf_fwhm(const struct c0_cov *cov, const struct c0_cov *more, double pixel_nm, double *fwhm_nm)
{
	double s[2] = { 0, 0 };   /* lag 1 and lag 2, x and y summed */
	lag_sums(cov, s);
	if (more)
		lag_sums(more, s);
	if (cov->d < 2)
		s[0] = s[1] = 0;
	return c0_lambda_psf_fwhm_sums(s, pixel_nm, fwhm_nm);
}

int c0_lambda_psf_fwhm_sums(const double s[2], double pixel_nm, double *fwhm_nm)
{
	*fwhm_nm = NAN;
	if (!(s[0] > 0) || !(s[1] > 0))
		return c0_fail(C0_EINVAL, "the covariance gives no PSF width (lags 1 and 2: %g, %g)", s[0], s[1]);
	const double r = s[1] / s[0];
	/* h(2)/h(1) grows with sigma: bisect on log sigma over 0.2 .. 12 pixels */
	double lo = log(0.2), hi = log(12);
	if (!(r > lag_ratio(exp(lo)) && r < lag_ratio(exp(hi))))
		return c0_fail(C0_EINVAL, "the covariance's lag 2 / lag 1 ratio %g fits no Gaussian PSF of 0.2-12 pixels", r);
	for (int it = 0; it < 50; it++) {
		const double mid = 0.5 * (lo + hi);
		if (lag_ratio(exp(mid)) < r)
			lo = mid;
		else
			hi = mid;
	}
	*fwhm_nm = exp(0.5 * (lo + hi)) * 2 * sqrt(2 * log(2)) * pixel_nm;
	return C0_OK;
}
