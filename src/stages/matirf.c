#include "stages/matirf.h"
#include "ops/diff3.h"
#include "ops/grad3m.h"
#include "ops/tirfop.h"
#include "solve/pdhg.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdlib.h>
#include <stdint.h>
#include <string.h>

#define MAXQ 64

int c0_matirf_check(const struct c0_matirf_conf *c, int nq, const double *angles)
{
	int st = c0_tirf_check(&c->tirf);
	if (st)
		return st;
	if (nq < 2 || nq > MAXQ)
		return c0_fail(C0_EINVAL, "--angles: MA-TIRF needs 2..%d angles (got %d)", MAXQ, nq);
	for (int q = 0; q < nq; q++) {
		double p;
		if (c0_tirf_p(&c->tirf, angles[q], &p))
			return c0_fail(C0_EINVAL, "--angles: %s", c0_errmsg());
	}
	if (!(c->dz_nm > 0) || !(c->z1_nm > c->z0_nm) || c->z0_nm < 0)
		return c0_fail(C0_EINVAL, "--z-range %g,%g,%g: need 0 <= min < max and a positive step (nm)", c->z0_nm, c->z1_nm, c->dz_nm);
	if ((c->z1_nm - c->z0_nm) / c->dz_nm > 512)
		return c0_fail(C0_EINVAL, "--z-range: more than 512 depth bins");
	if (!(c->kappa >= 0) || !(c->wz >= 0) || !(c->sparsity >= 0))
		return c0_fail(C0_EINVAL, "--kappa, --axial-weight and --sparsity must be >= 0");
	return C0_OK;
}

void c0_matirf_result_free(struct c0_matirf_result *r)
{
	free(r->f), free(r->z_nm), free(r->depth), free(r->total);
	memset(r, 0, sizeof *r);
}

struct ctx {
	int nq, nz, M;            /* columns: the lateral pixels solved for */
	size_t N;                 /* M * nz voxels */
	const double *W;          /* nq x nz, column-normalised */
	const double *b;          /* nq x M, scaled data */
	enum c0_reg reg;
	struct c0_grad3m g;       /* TV: gradient over the columns */
	struct c0_diff3 d;        /* Hessian: full grid (M = all pixels) */
	double kappa, l1;
	struct c0_progress *pr;
};

/* K u = [W u per column; R's operator u] */
static void K(void *vc, const double *u, double *y)
{
	struct ctx *c = vc;
	const struct c0_tirfop w = { c->nq, c->nz, (size_t)c->M, c->W };
	c0_tirfop_forward(&w, u, y);
	if (c->reg == C0_REG_TV)
		c0_grad3m_forward(&c->g, u, y + c->nq * w.M);
	else
		c0_hess3(&c->d, u, y + c->nq * w.M);
}

static void KT(void *vc, const double *y, double *u)
{
	struct ctx *c = vc;
	const struct c0_tirfop w = { c->nq, c->nz, (size_t)c->M, c->W };
	if (c->reg == C0_REG_TV)
		c0_grad3m_adjoint(&c->g, y + c->nq * w.M, u);
	else
		c0_hess3_adjoint(&c->d, y + c->nq * w.M, u);
	c0_tirfop_adjoint_add(&w, y, u);
}

static void iter(void *vc, int it)
{
	struct ctx *c = vc;
	c0_progress_update(c->pr, it);
}

static void prox_g(void *vc, double *u, const double *tau)
{
	struct ctx *c = vc;
	for (size_t i = 0; i < c->N; i++)
		u[i] = fmax(u[i] - tau[i] * c->l1, 0);
}

/* eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi */
static void eig3(double a[3][3], double v[3][3])
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			v[i][j] = i == j;
	for (int sweep = 0; sweep < 12; sweep++) {
		double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
		if (off < 1e-15 * (fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2])) || off == 0)
			break;
		for (int p = 0; p < 2; p++)
			for (int q = p + 1; q < 3; q++) {
				if (a[p][q] == 0)
					continue;
				double th = (a[q][q] - a[p][p]) / (2 * a[p][q]);
				double t = (th >= 0 ? 1 : -1) / (fabs(th) + sqrt(th * th + 1));
				double cs = 1 / sqrt(t * t + 1), sn = t * cs;
				for (int k = 0; k < 3; k++) {      /* A <- J^T A J */
					double akp = a[k][p], akq = a[k][q];
					a[k][p] = cs * akp - sn * akq;
					a[k][q] = sn * akp + cs * akq;
				}
				for (int k = 0; k < 3; k++) {
					double apk = a[p][k], aqk = a[q][k];
					a[p][k] = cs * apk - sn * aqk;
					a[q][k] = sn * apk + cs * aqk;
				}
				for (int k = 0; k < 3; k++) {
					double vkp = v[k][p], vkq = v[k][q];
					v[k][p] = cs * vkp - sn * vkq;
					v[k][q] = sn * vkp + cs * vkq;
				}
			}
	}
}

/* projection onto the radius-k ball of the dual norm (group l2 for TV,
 * spectral for Schatten-1) */
static void project_dual(const struct ctx *c, double *y, double k)
{
	const size_t N = c->N;
	if (c->reg == C0_REG_TV) {
#pragma omp parallel for schedule(static) if (N > 50000)
		for (size_t i = 0; i < N; i++) {
			double n = sqrt(y[i] * y[i] + y[N + i] * y[N + i] + y[2 * N + i] * y[2 * N + i]);
			if (n > k) {
				double s = k / n;
				y[i] *= s, y[N + i] *= s, y[2 * N + i] *= s;
			}
		}
		return;
	}
	/* Schatten-1's dual is the spectral norm: clip the eigenvalues to [-kappa, kappa] */
	const double r2 = sqrt(2.0);
#pragma omp parallel for if (N > 20000)
	for (size_t i = 0; i < N; i++) {
		double a[3][3] = { { y[i], y[3 * N + i] / r2, y[4 * N + i] / r2 },
				   { y[3 * N + i] / r2, y[N + i], y[5 * N + i] / r2 },
				   { y[4 * N + i] / r2, y[5 * N + i] / r2, y[2 * N + i] } };
		if (fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]) + fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]) <= k)
			continue;   /* spectral norm <= sum of |entries| <= kappa: already inside */
		double v[3][3], e[3];
		eig3(a, v);
		int clip = 0;
		for (int j = 0; j < 3; j++) {
			e[j] = a[j][j];
			if (e[j] > k) e[j] = k, clip = 1;
			if (e[j] < -k) e[j] = -k, clip = 1;
		}
		if (!clip)
			continue;
		double m[3][3];
		for (int p = 0; p < 3; p++)
			for (int q = 0; q < 3; q++)
				m[p][q] = v[p][0] * e[0] * v[q][0] + v[p][1] * e[1] * v[q][1] + v[p][2] * e[2] * v[q][2];
		y[i] = m[0][0], y[N + i] = m[1][1], y[2 * N + i] = m[2][2];
		y[3 * N + i] = r2 * m[0][1], y[4 * N + i] = r2 * m[0][2], y[5 * N + i] = r2 * m[1][2];
	}
}

/* F*(y) for F = 1/2 ||. - b||^2 (data rows) + kappa R (regulariser rows):
 * the data part shrinks, the regulariser part projects on the kappa ball */
static void prox_fstar(void *vc, double *y, const double *sigma)
{
	struct ctx *c = vc;
	const size_t nd = (size_t)c->nq * c->M;
	for (size_t i = 0; i < nd; i++)
		y[i] = (y[i] - sigma[i] * c->b[i]) / (1 + sigma[i]);
	project_dual(c, y + nd, c->kappa);
}

int c0_matirf_solve(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
		    const float *const *x, int ny, int nx, struct c0_matirf_result *res)
{
	memset(res, 0, sizeof *res);
	double t0 = c0_now();
	int st = c0_matirf_check(c, nq, angles);
	if (st)
		return st;
	const int nz = (int)ceil((c->z1_nm - c->z0_nm) / c->dz_nm - 1e-9);
	const size_t np = (size_t)ny * nx;
	double W[MAXQ * 512], col[512];
	if ((st = c0_tirf_weights(&c->tirf, nq, angles, gain, nz, c->z0_nm, c->dz_nm, W)))
		return st;
	for (int j = 0; j < nz; j++) {
		double s = 0;
		for (int q = 0; q < nq; q++)
			s += W[q * nz + j] * W[q * nz + j];
		col[j] = sqrt(s);
		for (int q = 0; q < nq; q++)
			W[q * nz + j] /= col[j];
	}
	double mx = 0;
	for (int q = 0; q < nq; q++)
		for (size_t p = 0; p < np; p++)
			mx = fmax(mx, x[q][p]);
	if (!(mx > 0))
		return c0_fail(C0_EINVAL, "the angle images are empty (no positive value)");
	res->scale = mx;
	/* TV solves only for the pixels with signal in some image (a pixel that
	 * is zero at every angle has f = 0); the Hessian works on the full grid */
	uint8_t *mask = c0_alloc(np, 1);
	struct ctx ctx = { .nq = nq, .nz = nz, .W = W, .reg = c->reg, .kappa = c->kappa, .l1 = c->sparsity,
			   .d = { nx, ny, nz, 1, c->wz, NULL } };
	if (!mask)
		return C0_ENOMEM;
	for (size_t p = 0; p < np; p++)
		for (int q = 0; q < nq; q++)
			mask[p] |= c->reg == C0_REG_HESSIAN || x[q][p] > 0;
	st = c0_grad3m_init(&ctx.g, mask, ny, nx, nz, 1, c->wz);
	free(mask);
	if (st)
		return st;
	const size_t M = (size_t)ctx.g.M, N = M * nz, nd = (size_t)nq * M;
	const int ncomp = c->reg == C0_REG_TV ? 3 : 6;
	ctx.M = (int)M, ctx.N = N;
	const size_t m = nd + ncomp * N;
	double *b = c0_alloc(nd, sizeof *b), *u = c0_alloc(N, sizeof *u), *y = c0_alloc(m, sizeof *y);
	double *tau = c0_alloc(N, sizeof *tau), *sigma = c0_alloc(m, sizeof *sigma);
	if (c->reg == C0_REG_HESSIAN && !(ctx.d.work = c0_alloc(2 * N, sizeof *ctx.d.work)))
		st = C0_ENOMEM;
	res->f = c0_alloc(np * nz, sizeof *res->f);
	res->z_nm = c0_alloc((size_t)nz, sizeof *res->z_nm);
	res->depth = c0_alloc(np, sizeof *res->depth);
	res->total = c0_alloc(np, sizeof *res->total);
	if (st || !b || !u || !y || !tau || !sigma || !res->f || !res->z_nm || !res->depth || !res->total) {
		st = C0_ENOMEM;
		goto out;
	}
	ctx.b = b;
	for (int q = 0; q < nq; q++)
		for (size_t k = 0; k < M; k++)
			b[q * M + k] = x[q][ctx.g.pixel[k]] / mx;
	/* diagonal steps: 1 / (absolute row or column sums of K) */
	const double wa[3] = { 1, 1, c->wz };
	double hcol = 0;
	for (int a = 0; a < 3; a++)
		for (int e = a; e < 3; e++)
			hcol += (a == e ? 4 : 4 * sqrt(2.0)) * wa[a] * wa[e];
	for (int j = 0; j < nz; j++) {
		double sw = 0;
		for (int q = 0; q < nq; q++)
			sw += W[q * nz + j];
		for (size_t k = 0; k < M; k++) {
			double r = c->reg == C0_REG_TV ? c0_grad3m_colsum(&ctx.g, (int)k, j) : hcol;
			tau[j * M + k] = 1 / (sw + r);
		}
	}
	for (int q = 0; q < nq; q++) {
		double sw = 0;
		for (int j = 0; j < nz; j++)
			sw += W[q * nz + j];
		for (size_t k = 0; k < M; k++)
			sigma[q * M + k] = 1 / sw;
	}
	for (int comp = 0; comp < ncomp; comp++) {
		static const int HA[6] = { 0, 1, 2, 0, 0, 1 }, HB[6] = { 0, 1, 2, 1, 2, 2 };
		double rs = c->reg == C0_REG_TV ? 2 * wa[comp]
			  : (comp < 3 ? 4 : 4 * sqrt(2.0)) * wa[HA[comp]] * wa[HB[comp]];
		double v = rs > 0 ? 1 / rs : 1;
		for (size_t i = 0; i < N; i++)
			sigma[nd + comp * N + i] = v;
	}
	struct c0_pdhg_problem pb = { N, m, &ctx, K, KT, prox_g, prox_fstar, tau, sigma, iter };
	struct c0_pdhg_info info;
	struct c0_progress pr;
	c0_progress_begin(&pr, "matirf (iterations, at most)", c->pdhg.maxit);
	ctx.pr = &pr;
	st = c0_pdhg_solve(&pb, &c->pdhg, u, y, &info);
	c0_progress_end(&pr);
	if (st)
		goto out;
	res->nz = nz, res->ny = ny, res->nx = nx, res->iters = info.iters, res->converged = info.converged;
	for (int j = 0; j < nz; j++) {
		res->z_nm[j] = c->z0_nm + (j + 0.5) * c->dz_nm;
		for (size_t k = 0; k < M; k++)
			res->f[j * np + ctx.g.pixel[k]] = (float)(u[j * M + k] / col[j] * mx);
	}
	for (size_t p = 0; p < np; p++) {
		double s = 0, sz = 0;
		for (int j = 0; j < nz; j++)
			s += res->f[j * np + p], sz += res->f[j * np + p] * res->z_nm[j];
		res->total[p] = (float)s;
		res->depth[p] = s > 0 ? (float)(sz / s) : 0;
	}
out:
	c0_grad3m_free(&ctx.g);
	free(b), free(u), free(y), free(tau), free(sigma), free(ctx.d.work);
	if (st)
		c0_matirf_result_free(res);
	res->seconds = c0_now() - t0;
	return st;
}
