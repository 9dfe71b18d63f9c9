#include "stages/splat.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>

int c0_splat(const float *x, int H, int W, double sigma_px, float *out)
{
	if (!(sigma_px > 0))
		return c0_fail(C0_EINVAL, "render: Gaussian sd %g pixels must be positive", sigma_px);
	const int r = (int)ceil(3 * sigma_px);
	double *k = c0_alloc((size_t)(2 * r + 1), sizeof *k), *tmp = c0_alloc((size_t)H * W, sizeof *tmp);
	if (!k || !tmp) {
		free(k), free(tmp);
		return C0_ENOMEM;
	}
	double s = 0;
	for (int i = -r; i <= r; i++)
		s += k[i + r] = exp(-0.5 * i * i / (sigma_px * sigma_px));
	for (int i = 0; i <= 2 * r; i++)
		k[i] /= s;
#pragma omp parallel for if ((size_t)H * W > 100000)
	for (int y = 0; y < H; y++)
		for (int xx = 0; xx < W; xx++) {
			double v = 0;
			for (int i = -r; i <= r; i++)
				if (xx + i >= 0 && xx + i < W)
					v += k[i + r] * x[(size_t)y * W + xx + i];
			tmp[(size_t)y * W + xx] = v;
		}
#pragma omp parallel for if ((size_t)H * W > 100000)
	for (int y = 0; y < H; y++)
		for (int xx = 0; xx < W; xx++) {
			double v = 0;
			for (int i = -r; i <= r; i++)
				if (y + i >= 0 && y + i < H)
					v += k[i + r] * tmp[(size_t)(y + i) * W + xx];
			out[(size_t)y * W + xx] = (float)v;
		}
	free(k), free(tmp);
	return C0_OK;
}
