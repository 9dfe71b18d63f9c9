#include "optics/psf.h"
#include "core/c0math.h"
#include "core/err.h"

#include <math.h>
#include <stddef.h>

int c0_fwhm_from_na(double emission_nm, double na, double n_glass, double *fwhm_nm)
{
	if (!(emission_nm > 0 && isfinite(emission_nm)))
		return c0_fail(C0_EINVAL, "emission_nm %g: must be a positive wavelength in nm", emission_nm);
	if (!(na > 0 && na < n_glass))
		return c0_fail(C0_EINVAL, "na %g: must be positive and below the immersion index n_glass %g", na, n_glass);
	*fwhm_nm = 0.51 * emission_nm / na;
	return C0_OK;
}

double c0_psf_sigma_px(double fwhm_nm, double pixel_nm)
{
	return fwhm_nm * C0_FWHM_TO_SIGMA / pixel_nm;
}

static double phi(double x)
{
	return 0.5 * erfc(-x / sqrt(2.0));
}

void c0_psf_pixel_weights(double c, double sigma, int first, int n, double *out)
{
	double prev = phi((first - c) / sigma);
	for (int k = 0; k < n; k++) {
		double next = phi((first + k + 1 - c) / sigma);
		/* the difference of complementary tails keeps precision far out */
		out[k] = next - prev;
		prev = next;
	}
}

int c0_psf_factor(int N, int r, double sigma, struct c0_band *G)
{
	if (N <= 0 || r < 1 || !(sigma > 0))
		return c0_fail(C0_EINVAL, "psf: invalid grid N=%d r=%d sigma=%g", N, r, sigma);
	int L = N * r;
	/* row i: fine centres within [i - K s, i + 1 + K s] */
	int w = (int)ceil(r * (1 + 2 * C0_PSF_CUTOFF * sigma)) + 2;
	int st = c0_band_alloc(G, N, L, w);
	if (st)
		return st;
	w = G->w;
	for (int i = 0; i < N; i++) {
		int s = (int)floor(r * (i - C0_PSF_CUTOFF * sigma) - 0.5);
		if (s < 0) s = 0;
		if (s > L - w) s = L - w;
		G->start[i] = s;
		for (int k = 0; k < w; k++) {
			double c = (s + k + 0.5) / r, v;
			if (fabs(c - (i + 0.5)) > C0_PSF_CUTOFF * sigma + 0.5)
				v = 0;
			else
				c0_psf_pixel_weights(c, sigma, i, 1, &v);
			G->v[(size_t)i * w + k] = v;
		}
	}
	return C0_OK;
}
