/* The pixel variance a fit predicts on the fine grid (ops/finevar.h). */
#include "ops/finevar.h"
#include "optics/psf.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int c0_finevar(const double *x, int Ly, int Lx, int r, double sigma_px, double *v)
{
	/* (e^{-8})^2 ~ 1e-7; no offset beyond the field is ever used */
	const double reach = ceil(4 * sigma_px * r), field = Ly > Lx ? Ly : Lx;
	const int K = (int)(reach < field ? reach : field);
	double *k = c0_alloc(2 * (size_t)K + 1, sizeof *k);
	if (!k)
		return C0_ENOMEM;
	for (int d = -K; d <= K; d++) {
		c0_psf_pixel_weights(0.5 + (double)d / r, sigma_px, 0, 1, &k[d + K]);
		k[d + K] *= k[d + K];
	}
	memset(v, 0, (size_t)Ly * Lx * sizeof *v);
	/* x is sparse (the support): each nonzero adds its kernel */
	for (int y = 0; y < Ly; y++)
		for (int xx = 0; xx < Lx; xx++) {
			const double a = x[(size_t)y * Lx + xx];
			if (a == 0)
				continue;
			const int y0 = y - K < 0 ? 0 : y - K, y1 = y + K >= Ly ? Ly - 1 : y + K;
			const int x0 = xx - K < 0 ? 0 : xx - K, x1 = xx + K >= Lx ? Lx - 1 : xx + K;
			for (int u = y0; u <= y1; u++) {
				const double ay = a * k[u - y + K];
				double *row = v + (size_t)u * Lx;
				for (int w = x0; w <= x1; w++)
					row[w] += ay * k[w - xx + K];
			}
		}
	free(k);
	return C0_OK;
}
