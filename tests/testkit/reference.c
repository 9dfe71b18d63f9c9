/* The tests' references (reference.h), moved from the library files whose
 * fast forms they check. */
#include "testkit/reference.h"
#include "ops/splat.h"
#include "core/err.h"
#include "core/mem.h"
#include "io/tiff.h"
#include "sim/sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void c0_band_to_dense(const struct c0_band *b, double *d)
{
	memset(d, 0, sizeof *d * (size_t)b->m * b->n);
	for (int i = 0; i < b->m; i++)
		for (int k = 0; k < b->w; k++)
			d[(size_t)i * b->n + b->start[i] + k] = b->v[(size_t)i * b->w + k];
}

void c0_covop_psi(struct c0_covop *op, const double *x, double *y)
{
	c0_band_apply_x(&op->Gx, op->Ly, x, op->tmp);          /* Ly x Nx */
	c0_band_apply_y(&op->Gy, op->Nx, op->tmp, y);
}

void c0_covop_psit(struct c0_covop *op, const double *y, double *x)
{
	c0_band_apply_x(&op->GxT, op->Ny, y, op->tmp);         /* Ny x Lx */
	c0_band_apply_y(&op->GyT, op->Lx, op->tmp, x);
}

int c0_splat(const float *x, int H, int W, double sigma_px, float *out)
{
	return c0_splat_rows(x, 0, H, W, sigma_px, 0, H, out);
}

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

uint8_t *c0_truth_mask(const char *path, int *w, int *h)
{
	struct c0_tiff_info in;
	float *t;
	if (c0_tiff_load_f32(path, &in, &t))
		return NULL;
	const size_t n = (size_t)in.width * in.height;
	uint8_t *m = malloc(n ? n : 1);
	for (size_t i = 0; m && i < n; i++)
		m[i] = t[i] > 0;
	free(t);
	*w = in.width, *h = in.height;
	return m;
}

void c0_sim_lines(struct c0_sim_conf *s)
{
	s->density_per_um = 60, s->label_radius_nm = 0;
}
