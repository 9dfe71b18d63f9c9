#include "stages/matirf_ctx.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdlib.h>

/* The warm start from a coarser grid: the images binned 2x2 (mean), the same
 * problem in physical units there (per area, lateral TV weighs kappa / 2 and
 * its axial weight doubles; the data scale is the fine level's), solved, and
 * its volume and TV dual brought back bilinearly (the dual doubled,
 * the dual's bound being kappa there). u0, y0: nz np and 2 nz np floats. */
int matirf_coarse_start(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
			const float *const *x, int ny, int nx, int nz, double mx, int levels, const double *col,
			float *u0, float *y0, int *iters)
{
	const int cy = (ny + 1) / 2, cx = (nx + 1) / 2;
	const size_t np = (size_t)ny * nx, cp = (size_t)cy * cx;
	float *buf = c0_alloc((size_t)nq * cp, sizeof *buf), *yc = c0_alloc(2 * cp * nz, sizeof *yc);
	const float *xc[MAXQ];
	int st = C0_ENOMEM;
	if (!buf || !yc)
		goto out;
	for (int q = 0; q < nq; q++) {
		float *o = buf + q * cp;
		xc[q] = o;
		for (int y = 0; y < cy; y++)
			for (int xx = 0; xx < cx; xx++) {
				double s = 0;
				int n = 0;
				for (int dy = 0; dy < 2; dy++)
					for (int dx = 0; dx < 2; dx++)
						if (2 * y + dy < ny && 2 * xx + dx < nx)
							s += x[q][(size_t)(2 * y + dy) * nx + 2 * xx + dx], n++;
				o[(size_t)y * cx + xx] = (float)(s / n);
			}
	}
	struct c0_matirf_conf cc = *c;
	cc.kappa = c->kappa / 2, cc.wz = c->wz * 2;
	cc.psf_sigma_px = c->psf_sigma_px / 2;   /* the PSF binned with the images */
	struct c0_matirf_result r;
	if ((st = matirf_level(&cc, nq, angles, gain, xc, cy, cx, mx, levels - 1, yc, &r)))
		goto out;
	*iters = r.iters + r.coarse_iters;
	for (int j = 0; j < nz; j++)
		for (int y = 0; y < ny; y++)
			for (int xx = 0; xx < nx; xx++) {
				const size_t p = (size_t)y * nx + xx, pc = (size_t)(y / 2) * cx + xx / 2;
				/* bilinear, the fine pixel's centre between its block and the nearer
				 * neighbour block (nearest neighbour: 83 full-grid iterations
				 * instead of 71 on the 350x350 phantom) */
				const int y1 = y % 2 ? (y / 2 + 1 < cy ? y / 2 + 1 : y / 2) : (y > 0 ? y / 2 - 1 : 0);
				const int x1 = xx % 2 ? (xx / 2 + 1 < cx ? xx / 2 + 1 : xx / 2) : (xx > 0 ? xx / 2 - 1 : 0);
				const size_t q[4] = { pc, (size_t)(y / 2) * cx + x1, (size_t)y1 * cx + xx / 2, (size_t)y1 * cx + x1 };
				const float w[4] = { 0.5625f, 0.1875f, 0.1875f, 0.0625f };
				const float *fj = r.f + j * cp;
				const float v = w[0] * fj[q[0]] + w[1] * fj[q[1]] + w[2] * fj[q[2]] + w[3] * fj[q[3]];
				u0[j * np + p] = (float)(v * col[j] / mx);
				for (int e = 0; e < 2; e++) {
					const float *ye = yc + (e * nz + j) * cp;
					y0[(e * nz + j) * np + p] = 2 * (w[0] * ye[q[0]] + w[1] * ye[q[1]] + w[2] * ye[q[2]] + w[3] * ye[q[3]]);
				}
			}
	c0_matirf_result_free(&r);
out:
	free(buf), free(yc);
	return st;
}
