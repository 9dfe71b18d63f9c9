/* The Airy (in-focus Bessel) PSF for the simulator, integrated over camera
 * pixels: I(v) = (2 J1(v) / v)^2, v = k r, k set so that its FWHM is the
 * configured one. It has the same FWHM as the Gaussian the methods assume,
 * but a narrower core's shoulders and rings with a heavy tail (about 3 % of
 * the light beyond 6 FWHM, dropped): a model mismatch real PSFs have.
 * Emitters are rendered from a bank of kernels, one per 1/32 camera pixel of
 * sub-pixel position (positions within 1/64 pixel), so the memory does not
 * grow with the number of emitters. */
#define _XOPEN_SOURCE 700   /* j1 */
#include "sim/sim.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define AIRY_V_HALF 1.616339948  /* (2 J1(v)/v)^2 = 1/2 */
#define SUB 8                    /* samples per pixel and axis */
#define TAB_DV 0.005             /* radial table step in v */

static const char *const PSFS[] = { "gauss", "airy" };

int c0_sim_psf_parse(const char *name, int *psf)
{
	for (int k = 0; k < 2; k++)
		if (!strcmp(name, PSFS[k]))
			return *psf = k, C0_OK;
	return c0_fail(C0_EINVAL, "psf %s: expected gauss or airy", name);
}

const char *c0_sim_psf_name(int psf)
{
	return psf >= 0 && psf < 2 ? PSFS[psf] : "?";
}

int c0_sim_airy_half(double fwhm_px)
{
	return (int)ceil(6 * fwhm_px);
}

static double airy(double v)
{
	if (v < 1e-6)
		return 1;
	const double a = 2 * j1(v) / v;
	return a * a;
}

int c0_sim_airy_bank(double fwhm_px, int K, double **bank)
{
	const int half = c0_sim_airy_half(fwhm_px), nb = C0_AIRY_BANK;
	const double k = 2 * AIRY_V_HALF / fwhm_px;
	const double rmax = (half + 2) * M_SQRT2;
	const int nt = (int)(k * rmax / TAB_DV) + 2;
	double *tab = c0_alloc((size_t)nt, sizeof *tab);
	double *b = c0_alloc((size_t)nb * nb * K * K, sizeof *b);
	if (!tab || !b) {
		free(tab), free(b);
		return C0_ENOMEM;
	}
	for (int i = 0; i < nt; i++)
		tab[i] = airy(i * TAB_DV);
	/* the whole plane's integral of I over pixel units is 4 pi / k^2 */
	const double norm = k * k / (4 * M_PI) / (SUB * SUB);
#pragma omp parallel for schedule(dynamic, 8)
	for (int q = 0; q < nb * nb; q++) {
		/* the emitter at (half + fx, half + fy) in window pixels */
		const double cx = half + (q % nb + 0.5) / nb, cy = half + (q / nb + 0.5) / nb;
		double *w = b + (size_t)q * K * K;
		for (int j = 0; j < K; j++)
			for (int i = 0; i < K; i++) {
				double s = 0;
				for (int sj = 0; sj < SUB; sj++)
					for (int si = 0; si < SUB; si++) {
						double dx = i + (si + 0.5) / SUB - cx, dy = j + (sj + 0.5) / SUB - cy;
						double u = k * sqrt(dx * dx + dy * dy) / TAB_DV;
						int t = (int)u;
						s += t + 1 < nt ? tab[t] + (u - t) * (tab[t + 1] - tab[t]) : 0;
					}
				w[j * K + i] = s * norm;
			}
	}
	free(tab);
	*bank = b;
	return C0_OK;
}
