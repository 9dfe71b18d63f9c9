#include "ops/splat.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>

int c0_splat_radius(double sigma_px)
{
	return (int)ceil(3 * sigma_px);
}

/* the normalised kernel of radius ceil(3 sigma) */
static double *kernel(double sigma_px, int *r)
{
	*r = c0_splat_radius(sigma_px);
	double *k = c0_alloc((size_t)(2 * *r + 1), sizeof *k), s = 0;
	for (int i = -*r; k && i <= *r; i++)
		s += k[i + *r] = exp(-0.5 * i * i / (sigma_px * sigma_px));
	for (int i = 0; k && i <= 2 * *r; i++)
		k[i] /= s;
	return k;
}

int c0_splat_rows(const float *x, int xrow0, int H, int W, double sigma_px, int y0, int y1, float *out)
{
	if (!(sigma_px > 0))
		return c0_fail(C0_EINVAL, "render: Gaussian sd %g pixels must be positive", sigma_px);
	int r;
	double *k = kernel(sigma_px, &r);
	/* the horizontal pass on the rows the band's vertical pass reads */
	const int t0 = y0 - r < 0 ? 0 : y0 - r, t1 = y1 + r > H ? H : y1 + r;
	double *tmp = c0_alloc((size_t)(t1 - t0) * W, sizeof *tmp);
	if (!k || !tmp) {
		free(k), free(tmp);
		return C0_ENOMEM;
	}
#pragma omp parallel for if ((size_t)(t1 - t0) * W > 100000)
	for (int y = t0; y < t1; y++)
		for (int xx = 0; xx < W; xx++) {
			double v = 0;
			for (int i = -r; i <= r; i++)
				if (xx + i >= 0 && xx + i < W)
					v += k[i + r] * x[(size_t)(y - xrow0) * W + xx + i];
			tmp[(size_t)(y - t0) * W + xx] = v;
		}
#pragma omp parallel for if ((size_t)(y1 - y0) * W > 100000)
	for (int y = y0; y < y1; y++)
		for (int xx = 0; xx < W; xx++) {
			double v = 0;
			for (int i = -r; i <= r; i++)
				if (y + i >= 0 && y + i < H)
					v += k[i + r] * tmp[(size_t)(y + i - t0) * W + xx];
			out[(size_t)(y - y0) * W + xx] = (float)v;
		}
	free(k), free(tmp);
	return C0_OK;
}

