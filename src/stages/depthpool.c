#include "stages/depthpool.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/c0math.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>

void c0_depth_single(const double *W, int nq, int nz, double z0, double dz, const float *const *x, const uint8_t *mask,
		     size_t np, float *out)
{
#pragma omp parallel for schedule(static)
	for (size_t p = 0; p < np; p++) {
		out[p] = 0;
		if (mask && !mask[p])
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

int c0_pixlist_from_mask(const uint8_t *mask, int ny, int nx, struct c0_pixlist *pl)
{
	const size_t L = (size_t)ny * nx;
	*pl = (struct c0_pixlist){ ny, nx, 0, NULL, NULL };
	for (size_t p = 0; p < L; p++)
		pl->M += mask[p] != 0;
	if (pl->M > INT_MAX)
		return c0_fail(C0_EINVAL, "support: %zu pixels, at most %d", pl->M, INT_MAX);
	pl->pix = c0_alloc(pl->M ? pl->M : 1, sizeof *pl->pix);
	pl->row = c0_alloc((size_t)ny + 1, sizeof *pl->row);
	if (!pl->pix || !pl->row) {
		c0_pixlist_free(pl);
		return C0_ENOMEM;
	}
	size_t k = 0;
	for (int y = 0; y < ny; y++) {
		pl->row[y] = k;
		for (size_t p = (size_t)y * nx; p < (size_t)(y + 1) * nx; p++)
			if (mask[p])
				pl->pix[k++] = (int)p;
	}
	pl->row[ny] = k;
	return C0_OK;
}

void c0_pixlist_free(struct c0_pixlist *pl)
{
	free(pl->pix), free(pl->row);
	*pl = (struct c0_pixlist){ 0 };
}

long c0_pixlist_find(const struct c0_pixlist *pl, size_t p)
{
	const size_t y = p / (size_t)pl->nx, hi = pl->row[y + 1], k = c0_lower_bound(pl->pix, pl->row[y], hi, p);
	return k < hi && (size_t)pl->pix[k] == p ? (long)k : -1;
}

int c0_pool_window_at(const float *x, const struct c0_pixlist *pl, int h, float *out)
{
	const int ny = pl->ny, nx = pl->nx, R = 2 * h + 2;
	/* rows y of the table S ((ny + 1) x (nx + 1), row 0 zero) at S[y % R] */
	double *S = c0_alloc((size_t)R * (nx + 1), sizeof *S);
	float *v = c0_alloc((size_t)nx, sizeof *v);
	if (!S || !v) {
		free(S), free(v);
		return C0_ENOMEM;
	}
#define SROW(y) (S + (size_t)((y) % R) * (nx + 1))
	int made = 0;   /* rows 0..made of S are in the band */
	for (int y = 0; y < ny; y++) {
		const int y0 = y - h < 0 ? 0 : y - h, y1 = y + h + 1 > ny ? ny : y + h + 1;
		for (; made < y1; made++) {   /* row made + 1 from row made and the image's row made */
			double *a = SROW(made), *b = SROW(made + 1);
			for (int i = 0; i < nx; i++)
				v[i] = 0;
			for (size_t k = pl->row[made]; k < pl->row[made + 1]; k++)
				v[pl->pix[k] - (size_t)made * nx] = x[k];
			b[0] = 0;
			for (int xx = 0; xx < nx; xx++)
				b[xx + 1] = v[xx] + a[xx + 1] + b[xx] - a[xx];
		}
		const double *s0 = SROW(y0), *s1 = SROW(y1);
		for (size_t k = pl->row[y]; k < pl->row[y + 1]; k++) {
			const int xx = (int)(pl->pix[k] - (size_t)y * nx);
			const int x0 = xx - h < 0 ? 0 : xx - h, x1 = xx + h + 1 > nx ? nx : xx + h + 1;
			out[k] = (float)(s1[x1] - s0[x1] - s1[x0] + s0[x0]);
		}
	}
#undef SROW
	free(S), free(v);
	return C0_OK;
}

void c0_pixlist_normals(const struct c0_pixlist *pl, int r, float *nrm)
{
	const int ny = pl->ny, nx = pl->nx;
#pragma omp parallel for schedule(static)
	for (size_t k = 0; k < pl->M; k++) {
		const int y = pl->pix[k] / nx, xx = pl->pix[k] % nx;
		const int x0 = xx - r < 0 ? 0 : xx - r, x1 = xx + r < nx ? xx + r : nx - 1;
		double sxx = 0, syy = 0, sxy = 0;
		for (int j = y - r < 0 ? 0 : y - r; j <= y + r && j < ny; j++) {
			const size_t end = pl->row[j + 1];
			for (size_t o = c0_lower_bound(pl->pix, pl->row[j], end, (size_t)j * nx + x0);
			     o < end && (size_t)pl->pix[o] <= (size_t)j * nx + x1; o++) {
				const int dx = pl->pix[o] - j * nx - xx, dy = j - y;
				if (dx * dx + dy * dy <= r * r)
					sxx += dx * dx, syy += dy * dy, sxy += dx * dy;
			}
		}
		/* the major axis runs along the structure; the normal is at a right angle */
		const double along = 0.5 * atan2(2 * sxy, sxx - syy);
		nrm[2 * k] = (float)-sin(along), nrm[2 * k + 1] = (float)cos(along);
	}
}

int c0_pool_guided_at(const float *const *x, int nq, const struct c0_pixlist *pl, const float *guide, double range,
		      const float *nrm, double width, int h, float *const *out)
{
	enum { QMAX = 64 };
	if (nq > QMAX)
		return c0_fail(C0_EINVAL, "depth pooling: %d angles (at most %d)", nq, QMAX);
	const int ny = pl->ny, nx = pl->nx;
#pragma omp parallel for schedule(static)
	for (size_t k = 0; k < pl->M; k++) {
		const int y = pl->pix[k] / nx, xx = pl->pix[k] % nx;
		const int x0 = xx - h < 0 ? 0 : xx - h, x1 = xx + h < nx ? xx + h : nx - 1;
		double acc[QMAX] = { 0 };
		/* the window's pixels on the list, row by row, in raster order as c0_pool_guided */
		for (int j = y - h < 0 ? 0 : y - h; j <= y + h && j < ny; j++) {
			const size_t end = pl->row[j + 1];
			for (size_t o = c0_lower_bound(pl->pix, pl->row[j], end, (size_t)j * nx + x0);
			     o < end && (size_t)pl->pix[o] <= (size_t)j * nx + x1; o++)
				if (fabs(guide[o] - guide[k]) <= range &&
				    (!nrm || fabs(nrm[2 * k] * (pl->pix[o] - j * nx - xx) + nrm[2 * k + 1] * (j - y)) <= width))
					for (int q = 0; q < nq; q++)
						acc[q] += x[q][o];
		}
		for (int q = 0; q < nq; q++)
			out[q][k] = (float)acc[q];
	}
	return C0_OK;
}

void c0_pool_rescale_at(float *f, int nz, const int *pixel, size_t M, int nq, const struct c0_pixlist *pl,
			const float *const *x, const float *const *pooled)
{
	size_t i = 0;   /* pixel[] and pl->pix both increase */
	for (size_t k = 0; k < M; k++) {
		while (i < pl->M && pl->pix[i] < pixel[k])
			i++;
		double a = 0, b = 0;
		for (int q = 0; i < pl->M && pl->pix[i] == pixel[k] && q < nq; q++)
			a += x[q][i], b += pooled[q][i];
		double s = b > 0 ? a / b : 0;
		for (int j = 0; j < nz; j++)
			f[j * M + k] = (float)(f[j * M + k] * s);
	}
}
