#include "ops/covop.h"
#include "optics/psf.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* K_d(i, a) = G(i, a) G(i + d, a), same band layout as G */
static int lag_factor(const struct c0_band *G, int d, struct c0_band *K)
{
	int st = c0_band_alloc(K, G->m, G->n, G->w);
	if (st)
		return st;
	for (int i = 0; i < G->m; i++) {
		K->start[i] = G->start[i];
		for (int k = 0; k < G->w; k++) {
			int a = G->start[i] + k;
			double g2 = i + d >= 0 && i + d < G->m ? c0_band_get(G, i + d, a) : 0;
			K->v[(size_t)i * K->w + k] = G->v[(size_t)i * G->w + k] * g2;
		}
	}
	return C0_OK;
}

/* H = (G^T G) o (G^T G), stored as a band without the tails below
 * C0_COVOP_TRIM of its largest entry (covop.h). */
static int hadamard_gram(const struct c0_band *G, struct c0_band *H)
{
	const int L = G->n;
	struct c0_band GT;
	int st = c0_band_transpose(G, &GT);
	if (st)
		return st;
	int w = 2 * G->w + 1;     /* G^T G (a, b) = 0 unless a row of G holds both: |a - b| < G->w */
	if (w > L)
		w = L;
	if ((st = c0_band_alloc(H, L, L, w))) {
		c0_band_free(&GT);
		return st;
	}
	for (int a = 0; a < L; a++) {
		int s = a - w / 2;
		if (s < 0) s = 0;
		if (s > L - w) s = L - w;
		H->start[a] = s;
		for (int k = 0; k < w; k++) {
			int b = s + k;
			double g = 0;
			for (int t = 0; t < GT.w; t++) {
				int i = GT.start[a] + t;
				g += GT.v[(size_t)a * GT.w + t] * c0_band_get(G, i, b);
			}
			H->v[(size_t)a * w + k] = g * g;
		}
	}
	c0_band_free(&GT);
	return c0_band_trim(H, C0_COVOP_TRIM);
}

static int axis(int N, int r, double sigma, int d, struct c0_band *G, struct c0_band *H,
		struct c0_band **K, struct c0_band **KT, double **norm)
{
	int st = c0_psf_factor(N, r, sigma, G);
	if (!st)
		st = hadamard_gram(G, H);
	*K = c0_alloc((size_t)(2 * d + 1), sizeof **K);
	*KT = c0_alloc((size_t)(2 * d + 1), sizeof **KT);
	*norm = c0_alloc((size_t)N * r, sizeof **norm);
	if (!*K || !*KT || !*norm)
		return C0_ENOMEM;
	for (int l = -d; l <= d && !st; l++) {
		st = lag_factor(G, l, &(*K)[d + l]);
		if (!st)
			st = c0_band_transpose(&(*K)[d + l], &(*KT)[d + l]);
	}
	if (st)
		return st;
	/* ||g_a||^2 = sum_i G(i, a)^2 = K_0^T 1 */
	c0_band_col_sumsq(G, *norm);
	return C0_OK;
}

/* lambda_max of an axis's H, which depends on (N, r, sigma) alone: the
 * power iteration (most of an operator's set-up) once per run for each
 * size, not for every tile of every stack. The same number either way. */
#define LIP_CACHE 16
static double axis_lambda(const struct c0_band *H, int N, int r, double sigma)
{
	static struct { int N, r; double sigma, lam; } cache[LIP_CACHE];
	static int used;
	double lam = NAN;
#pragma omp critical(c0_covop_lip)
	for (int k = 0; k < used; k++)
		if (cache[k].N == N && cache[k].r == r && cache[k].sigma == sigma)
			lam = cache[k].lam;
	if (!isnan(lam))
		return lam;
	lam = c0_band_lambda_max(H, 500);
#pragma omp critical(c0_covop_lip)
	{
		const int k = used < LIP_CACHE ? used++ : (int)(((unsigned)N * 31u + (unsigned)r) % LIP_CACHE);
		cache[k].N = N, cache[k].r = r, cache[k].sigma = sigma, cache[k].lam = lam;
	}
	return lam;
}

int c0_covop_init(struct c0_covop *op, int Ny, int Nx, int r, double sigma, int d)
{
	memset(op, 0, sizeof *op);
	if (Ny < 2 || Nx < 2 || r < 1 || !(sigma > 0) || d < 0)
		return c0_fail(C0_EINVAL, "covariance operator: invalid grid %dx%d, r=%d, sigma=%g, lag=%d", Ny, Nx, r, sigma, d);
	op->Ny = Ny, op->Nx = Nx, op->r = r, op->Ly = Ny * r, op->Lx = Nx * r, op->d = d;
	double *ny = NULL, *nx = NULL;
	int st = axis(Ny, r, sigma, d, &op->Gy, &op->Hy, &op->Ky, &op->KyT, &ny);
	if (!st)
		st = axis(Nx, r, sigma, d, &op->Gx, &op->Hx, &op->Kx, &op->KxT, &nx);
	op->n = c0_alloc((size_t)op->Ly * op->Lx, sizeof *op->n);
	op->tmp = c0_alloc((size_t)op->Ly * op->Lx, sizeof *op->tmp);
	op->tmp2 = c0_alloc((size_t)op->Ly * op->Lx, sizeof *op->tmp2);
	op->occ = c0_alloc((size_t)op->Ly * C0_BAND_STRIPS(op->Lx), 1);
	if (!st && (!op->n || !op->tmp || !op->tmp2 || !op->occ))
		st = C0_ENOMEM;
	if (!st)
		st = c0_band_transpose(&op->Gy, &op->GyT);
	if (!st)
		st = c0_band_transpose(&op->Gx, &op->GxT);
	if (!st) {
		for (int a = 0; a < op->Ly; a++)
			for (int b = 0; b < op->Lx; b++)
				op->n[(size_t)a * op->Lx + b] = ny[a] * nx[b];
		op->lip = axis_lambda(&op->Hy, Ny, r, sigma) * axis_lambda(&op->Hx, Nx, r, sigma);
	}
	free(ny), free(nx);
	if (st)
		c0_covop_free(op);
	return st;
}

void c0_covop_free(struct c0_covop *op)
{
	c0_band_free(&op->Gy), c0_band_free(&op->Gx), c0_band_free(&op->Hy), c0_band_free(&op->Hx);
	c0_band_free(&op->GyT), c0_band_free(&op->GxT);
	for (int l = 0; l <= 2 * op->d; l++) {
		if (op->Ky) c0_band_free(&op->Ky[l]), c0_band_free(&op->KyT[l]);
		if (op->Kx) c0_band_free(&op->Kx[l]), c0_band_free(&op->KxT[l]);
	}
	free(op->Ky), free(op->Kx), free(op->KyT), free(op->KxT), free(op->n), free(op->tmp), free(op->tmp2), free(op->occ);
	memset(op, 0, sizeof *op);
}

void c0_covop_forward(struct c0_covop *op, const struct c0_cov *cov, const double *x, double *m)
{
	const size_t n = (size_t)op->Ny * op->Nx;
	for (int l = 0; l < cov->nlag; l++) {
		c0_band_apply_x(&op->Kx[op->d + cov->dx[l]], op->Ly, x, op->tmp);       /* Ly x Nx */
		c0_band_apply_y(&op->Ky[op->d + cov->dy[l]], op->Nx, op->tmp, m + l * n);
	}
}

void c0_covop_adjoint(struct c0_covop *op, const struct c0_cov *cov, const double *R, double *c)
{
	const size_t n = (size_t)op->Ny * op->Nx, L = (size_t)op->Ly * op->Lx;
	double *t2 = op->tmp2;
	memset(c, 0, L * sizeof *c);
	/* group lags by dy: sum_dx Kx_dx^T applied along x, then one Ky_dy^T along y */
	for (int dy = 0; dy <= cov->d; dy++) {
		memset(op->tmp, 0, sizeof(double) * (size_t)op->Ny * op->Lx);
		int any = 0;
		for (int l = 0; l < cov->nlag; l++) {
			if (cov->dy[l] != dy)
				continue;
			any = 1;
			double w = c0_cov_weight(cov, l);
			c0_band_apply_x(&op->KxT[op->d + cov->dx[l]], op->Ny, R + l * n, t2);   /* Ny x Lx */
			for (size_t i = 0; i < (size_t)op->Ny * op->Lx; i++)
				op->tmp[i] += w * t2[i];
		}
		if (!any)
			continue;
		c0_band_apply_y(&op->KyT[op->d + dy], op->Lx, op->tmp, t2);                 /* Ly x Lx */
		for (size_t i = 0; i < L; i++)
			c[i] += t2[i];
	}
}

/* One fine pixel (a, b) of c0_covop_adjoint: the same products and sums
 * in the same order (each band product sums its terms in order from 0; the
 * lags of one dy weighted into a sum from 0; the dy's summed from 0). */
static double adjoint_at(const struct c0_covop *op, const struct c0_cov *cov, const double *R, int a, int b)
{
	const size_t n = (size_t)op->Ny * op->Nx;
	double c = 0;
	for (int dy = 0; dy <= cov->d; dy++) {
		const struct c0_band *ky = &op->KyT[op->d + dy];
		int any = 0;
		for (int l = 0; l < cov->nlag && !any; l++)
			any = cov->dy[l] == dy;
		if (!any)
			continue;
		double sy = 0;
		for (int k = 0; k < ky->w; k++) {
			const int i = ky->start[a] + k;
			double t = 0;
			for (int l = 0; l < cov->nlag; l++) {
				if (cov->dy[l] != dy)
					continue;
				const struct c0_band *kx = &op->KxT[op->d + cov->dx[l]];
				const double *g = kx->v + (size_t)b * kx->w, *row = R + l * n + (size_t)i * op->Nx + kx->start[b];
				double sx = 0;
				for (int q = 0; q < kx->w; q++)
					sx += g[q] * row[q];
				t += c0_cov_weight(cov, l) * sx;
			}
			sy += ky->v[(size_t)a * ky->w + k] * t;
		}
		c += sy;
	}
	return c;
}

void c0_covop_adjoint_on(const struct c0_covop *op, const struct c0_cov *cov, const double *R, const uint8_t *on, double *c)
{
	const size_t L = (size_t)op->Ly * op->Lx;
	for (size_t p = 0; p < L; p++)
		c[p] = on[p] ? adjoint_at(op, cov, R, (int)(p / op->Lx), (int)(p % op->Lx)) : 0;
}

/* x is sparse in the solvers (a few % of the grid after their first
 * iterations): the first product then goes through its non-zeros only */
void c0_covop_normal(struct c0_covop *op, const double *x, double *out)
{
	const size_t L = (size_t)op->Ly * op->Lx;
	size_t nz = 0;
#pragma omp parallel for reduction(+ : nz) if (L > 100000)
	for (size_t i = 0; i < L; i++)
		nz += x[i] != 0;
	/* a sparse x leaves most strips of X Hx zero (two thirds of the
	 * output's strips during the support's first iterations): skip them */
	if (nz < L / 4) {
		c0_band_apply_x_sym_sparse_occ(&op->Hx, op->Ly, x, op->tmp, op->occ);
		c0_band_apply_y_occ(&op->Hy, op->Lx, op->tmp, op->occ, out);
		return;
	}
	c0_band_apply_x(&op->Hx, op->Ly, x, op->tmp);
	c0_band_apply_y(&op->Hy, op->Lx, op->tmp, out);
}

