#include "stages/depthpool.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>

int c0_pool_window(const float *x, const uint8_t *mask, int ny, int nx, int h, float *out)
{
	/* summed-area table: O(1) per pixel whatever the window */
	double *S = c0_alloc((size_t)(ny + 1) * (nx + 1), sizeof *S);
	if (!S)
		return C0_ENOMEM;
	for (int y = 0; y < ny; y++)
		for (int xx = 0; xx < nx; xx++)
			S[(size_t)(y + 1) * (nx + 1) + xx + 1] = (mask[(size_t)y * nx + xx] ? x[(size_t)y * nx + xx] : 0)
				+ S[(size_t)y * (nx + 1) + xx + 1] + S[(size_t)(y + 1) * (nx + 1) + xx] - S[(size_t)y * (nx + 1) + xx];
	for (int y = 0; y < ny; y++)
		for (int xx = 0; xx < nx; xx++) {
			size_t p = (size_t)y * nx + xx;
			if (!mask[p]) {
				out[p] = 0;
				continue;
			}
			int y0 = y - h < 0 ? 0 : y - h, y1 = y + h + 1 > ny ? ny : y + h + 1;
			int x0 = xx - h < 0 ? 0 : xx - h, x1 = xx + h + 1 > nx ? nx : xx + h + 1;
			out[p] = (float)(S[(size_t)y1 * (nx + 1) + x1] - S[(size_t)y0 * (nx + 1) + x1] - S[(size_t)y1 * (nx + 1) + x0]
					 + S[(size_t)y0 * (nx + 1) + x0]);
		}
	free(S);
	return C0_OK;
}

void c0_pool_rescale(float *f, int nz, const int *pixel, size_t M, int nq, const float *const *x, const float *const *pooled)
{
	for (size_t k = 0; k < M; k++) {
		const size_t p = (size_t)pixel[k];
		double a = 0, b = 0;
		for (int q = 0; q < nq; q++)
			a += x[q][p], b += pooled[q][p];
		double s = b > 0 ? a / b : 0;
		for (int j = 0; j < nz; j++)
			f[j * M + k] = (float)(f[j * M + k] * s);
	}
}

int c0_pool_guided(const float *const *x, int nq, const uint8_t *mask, const float *guide, double range, int ny,
		   int nx, int h, float *const *out)
{
	enum { QMAX = 64 };
	if (nq > QMAX)
		return c0_fail(C0_EINVAL, "depth pooling: %d angles (at most %d)", nq, QMAX);
#pragma omp parallel for schedule(static)
	for (int y = 0; y < ny; y++)
		for (int xx = 0; xx < nx; xx++) {
			const size_t p = (size_t)y * nx + xx;
			double acc[QMAX] = { 0 };
			if (!mask[p]) {
				for (int q = 0; q < nq; q++)
					out[q][p] = 0;
				continue;
			}
			for (int j = y - h < 0 ? 0 : y - h; j <= y + h && j < ny; j++)
				for (int i = xx - h < 0 ? 0 : xx - h; i <= xx + h && i < nx; i++) {
					const size_t o = (size_t)j * nx + i;
					if (mask[o] && fabs(guide[o] - guide[p]) <= range)
						for (int q = 0; q < nq; q++)
							acc[q] += x[q][o];
				}
			for (int q = 0; q < nq; q++)
				out[q][p] = (float)acc[q];
		}
	return C0_OK;
}

void c0_depth_single(const double *W, int nq, int nz, double z0, double dz, const float *const *x, const uint8_t *mask,
		     size_t np, float *out)
{
#pragma omp parallel for schedule(static)
	for (size_t p = 0; p < np; p++) {
		out[p] = 0;
		if (!mask[p])
			continue;
		/* ||x - a w_j||^2 at the best a >= 0 is ||x||^2 - (x.w_j)^2 / ||w_j||^2 when x.w_j > 0 */
		double best = 0;
		for (int j = 0; j < nz; j++) {
			double xw = 0, ww = 0;
			for (int q = 0; q < nq; q++)
				xw += x[q][p] * W[q * nz + j], ww += W[q * nz + j] * W[q * nz + j];
			const double gain = xw > 0 && ww > 0 ? xw * xw / ww : 0;
			if (gain > best)
				best = gain, out[p] = (float)(z0 + (j + 0.5) * dz);
		}
	}
}
