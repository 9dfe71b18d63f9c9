#include "stages/matirf_ctx.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/c0math.h"

#include <stdlib.h>

/* the column of raster index p among the coarse level's (increasing), -1 when none */
static long find_col(const int *pixel, size_t M, size_t p)
{
	const size_t k = c0_lower_bound(pixel, 0, M, p);
	return k < M && (size_t)pixel[k] == p ? (long)k : -1;
}

/* The warm start from a coarser grid (matirf.c's level_warm): the images
 * binned 2x2 (mean), the same problem in physical units there (per area,
 * lateral TV weighs kappa / 2 and its axial weight doubles; the data scale
 * is the fine level's), solved, and its volume and TV dual brought back
 * bilinearly (the dual doubled, the dual's bound being kappa there), at the
 * fine level's columns only: the coarse level's are looked up by bisection
 * (a coarse pixel off them is 0). */
float *matirf_coarse_bin(const struct c0_matirf_conf *c, int nq, const float *const *x, int ny, int nx,
			 const float *xc[], struct c0_matirf_conf *cc)
{
	const int cy = (ny + 1) / 2, cx = (nx + 1) / 2;
	const size_t cp = (size_t)cy * cx;
	float *buf = c0_alloc((size_t)nq * cp, sizeof *buf);
	if (!buf)
		return NULL;
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
	*cc = *c;
	cc->kappa = c->kappa / 2, cc->wz = c->wz * 2;
	cc->psf_sigma_px = c->psf_sigma_px / 2;   /* the PSF binned with the images */
	if (c->coarse_tol > 0)
		cc->pdhg.tol = c->coarse_tol;
	return buf;
}

void matirf_coarse_lift(const struct c0_matirf_result *r, const float *yc, int ny, int nx, int nz, double mx,
			const double *col, const struct matirf_cols *cols, float *u0, float *y0)
{
	const int cy = (ny + 1) / 2, cx = (nx + 1) / 2;
	const size_t M = cols->M;
	const size_t Mc = r->M, Nc = Mc * nz, N = M * nz;
	for (size_t k = 0; k < M; k++) {
		const int y = cols->pixel[k] / nx, xx = cols->pixel[k] % nx;
		const size_t pc = (size_t)(y / 2) * cx + xx / 2;
		/* bilinear, the fine pixel's centre between its block and the nearer
		 * neighbour block (nearest neighbour: 83 full-grid iterations
		 * instead of 71 on the 350x350 phantom) */
		const int y1 = y % 2 ? (y / 2 + 1 < cy ? y / 2 + 1 : y / 2) : (y > 0 ? y / 2 - 1 : 0);
		const int x1 = xx % 2 ? (xx / 2 + 1 < cx ? xx / 2 + 1 : xx / 2) : (xx > 0 ? xx / 2 - 1 : 0);
		const size_t q[4] = { pc, (size_t)(y / 2) * cx + x1, (size_t)y1 * cx + xx / 2, (size_t)y1 * cx + x1 };
		const float w[4] = { 0.5625f, 0.1875f, 0.1875f, 0.0625f };
		long i[4];
		for (int a = 0; a < 4; a++)
			i[a] = find_col(r->pixel, Mc, q[a]);
		for (int j = 0; j < nz; j++) {
			float v[4], e2[2][4];
			for (int a = 0; a < 4; a++) {
				v[a] = i[a] < 0 ? 0 : r->f[j * Mc + i[a]];
				for (int e = 0; e < 2; e++)
					e2[e][a] = i[a] < 0 || !yc ? 0 : yc[e * Nc + j * Mc + i[a]];
			}
			const float f = w[0] * v[0] + w[1] * v[1] + w[2] * v[2] + w[3] * v[3];
			u0[j * M + k] = (float)(f * col[j] / mx);
			for (int e = 0; e < 2; e++)
				y0[e * N + j * M + k] = 2 * (w[0] * e2[e][0] + w[1] * e2[e][1] + w[2] * e2[e][2] + w[3] * e2[e][3]);
		}
	}
}
