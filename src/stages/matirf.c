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
		return c0_fail(C0_EINVAL, "angles: MA-TIRF needs 2..%d angles (got %d)", MAXQ, nq);
	for (int q = 0; q < nq; q++) {
		double p;
		if (c0_tirf_p(&c->tirf, angles[q], &p))
			return c0_fail_prefix(C0_EINVAL, "angles");
	}
	if (!(c->dz_nm > 0) || !(c->z1_nm > c->z0_nm) || !(c->z0_nm >= 0) || !isfinite(c->z1_nm))
		return c0_fail(C0_EINVAL, "z_range_nm %g,%g,%g: need 0 <= min < max and a positive step (nm)", c->z0_nm, c->z1_nm, c->dz_nm);
	if ((c->z1_nm - c->z0_nm) / c->dz_nm > 512)
		return c0_fail(C0_EINVAL, "z_range_nm: more than 512 depth bins");
	if (!(c->kappa >= 0 && isfinite(c->kappa)) || !(c->wz >= 0 && isfinite(c->wz)) || !(c->sparsity >= 0 && isfinite(c->sparsity)))
		return c0_fail(C0_EINVAL, "kappa %g, axial_weight %g, sparsity %g: must be finite and >= 0", c->kappa, c->wz,
			       c->sparsity);
	if (c->pdhg.maxit < 1)
		return c0_fail(C0_EINVAL, "matirf_iterations %d: must be at least 1", c->pdhg.maxit);
	if (!(c->pdhg.tol >= 0 && isfinite(c->pdhg.tol)) || !(c->pdhg.relax > 0 && c->pdhg.relax < 2))
		return c0_fail(C0_EINVAL, "matirf_tol %g: must be >= 0 (relaxation %g in (0, 2))", c->pdhg.tol, c->pdhg.relax);
	return C0_OK;
}

void c0_matirf_result_free(struct c0_matirf_result *r)
{
	free(r->f), free(r->z_nm), free(r->depth), free(r->total);
	memset(r, 0, sizeof *r);
}

struct ctx {
	int nq, nz, M;            /* columns: the lateral pixels solved for */
	int ncomp;                /* components of the regulariser's operator */
	size_t N;                 /* M * nz voxels */
	const double *W;          /* nq x nz, column-normalised */
	const float *b;           /* nq x M, scaled data */
	const float *tau;         /* N primal steps */
	double sig_d[MAXQ], sig_r[6];  /* dual steps: per angle, per regulariser component */
	enum c0_reg reg;
	struct c0_grad3m g;       /* TV: gradient over the columns */
	struct c0_diff3 d;        /* Hessian: full grid (M = all pixels) */
	double kappa, l1;
	struct c0_progress *pr;
};

/* K u = [W u per column; R's operator u] */
static void K(void *vc, const float *u, float *y)
{
	struct ctx *c = vc;
	const struct c0_tirfop w = { c->nq, c->nz, (size_t)c->M, c->W };
	c0_tirfop_forward(&w, u, y);
	if (c->reg == C0_REG_TV)
		c0_grad3m_forward(&c->g, u, y + c->nq * w.M);
	else
		c0_hess3(&c->d, u, y + c->nq * w.M);
}

static void KT(void *vc, const float *y, float *u)
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

/* The proximal maps per entry, shared by the plain and the fused steps.
 * Primal, G = l1 sum u + indicator(u >= 0): from x and (K^T y)_i = a. */
static inline void prox_g_entry(float *x, float *t, float tau, float a, float l1, float rho, float *d2, float *n2)
{
	float v = *x - tau * (a + l1);
	c0_pdhg_primal_entry(x, t, 0.5f * (v + fabsf(v)), rho, d2, n2);   /* max(v, 0) without a branch */
}

/* Dual of a data row, F = 1/2 (. - b)^2: from y and (K xbar)_i = s. */
static inline void prox_data_entry(float *y, float s, float b, float sg, float rho, float *d2, float *n2)
{
	c0_pdhg_dual_entry(y, (*y + sg * (s - b)) / (1 + sg), rho, d2, n2);
}

/* Dual of lateral TV (k > 0): (a, b) = y + sigma K xbar, projected on the
 * radius-k disc. */
static inline void prox_tv2_entry(float *yx, float *yy, float a, float b, float k, float rho, float *d2, float *n2)
{
	float r = sqrtf(a * a + b * b), f = k / (r > k ? r : k);
	c0_pdhg_dual_entry(yx, f * a, rho, d2, n2);
	c0_pdhg_dual_entry(yy, f * b, rho, d2, n2);
}

/* G = l1 sum u + indicator(u >= 0) */
static void primal_step(void *vc, float *x, float *t, float rho, double sums[2])
{
	struct ctx *c = vc;
	const float l1 = (float)c->l1, *tau = c->tau;
	const size_t N = c->N;
	float d2 = 0, n2 = 0;   /* per thread; sums is double */
	/* firstprivate: private copies of the pointers let the loop vectorise */
#pragma omp parallel for simd schedule(static) reduction(+ : d2, n2) firstprivate(x, t, tau) if (N > 50000)
	for (size_t i = 0; i < N; i++)
		prox_g_entry(&x[i], &t[i], tau[i], t[i], l1, rho, &d2, &n2);
	sums[0] += d2, sums[1] += n2;
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

/* h (xx, yy, zz, sqrt2 xy, sqrt2 xz, sqrt2 yz) <- the symmetric matrix with
 * its eigenvalues clipped to [-k, k]: the projection on the spectral-norm
 * ball, Schatten-1's dual. */
static void spectral_clip(double h[6], double k)
{
	const double r2 = sqrt(2.0);
	double a[3][3] = { { h[0], h[3] / r2, h[4] / r2 }, { h[3] / r2, h[1], h[5] / r2 }, { h[4] / r2, h[5] / r2, h[2] } };
	double v[3][3], e[3];
	eig3(a, v);
	int clip = 0;
	for (int j = 0; j < 3; j++) {
		e[j] = a[j][j];
		if (e[j] > k) e[j] = k, clip = 1;
		if (e[j] < -k) e[j] = -k, clip = 1;
	}
	if (!clip)
		return;
	double m[3][3];
	for (int p = 0; p < 3; p++)
		for (int q = 0; q < 3; q++)
			m[p][q] = v[p][0] * e[0] * v[q][0] + v[p][1] * e[1] * v[q][1] + v[p][2] * e[2] * v[q][2];
	h[0] = m[0][0], h[1] = m[1][1], h[2] = m[2][2];
	h[3] = r2 * m[0][1], h[4] = r2 * m[0][2], h[5] = r2 * m[1][2];
}

/* F = 1/2 ||. - b||^2 on the data rows and kappa R on the regulariser rows.
 * prox of sigma F*: the data part shrinks towards -b, the regulariser part
 * projects on the kappa ball of the dual norm (group l2 for TV, spectral for
 * Schatten-1; the sum of |entries| bounds the spectral norm, so most voxels
 * skip the eigen-decomposition). */
static void dual_step(void *vc, float *y, const float *s, float rho, double sums[2])
{
	struct ctx *c = vc;
	const size_t M = c->M, N = c->N, nd = (size_t)c->nq * M;
	const float k = (float)c->kappa;
	float d2 = 0, n2 = 0;   /* per thread; sums is double */
	for (int q = 0; q < c->nq; q++) {
		const float sg = (float)c->sig_d[q], *bq = c->b + q * M, *sq = s + q * M;
		float *yq = y + q * M;
#pragma omp simd reduction(+ : d2, n2)
		for (size_t i = 0; i < M; i++)
			prox_data_entry(&yq[i], sq[i], bq[i], sg, rho, &d2, &n2);
	}
	y += nd, s += nd;
	const float s0 = (float)c->sig_r[0], s1 = (float)c->sig_r[1], s2 = (float)c->sig_r[2];
	if (c->reg == C0_REG_TV && !(k > 0)) {   /* no regulariser: its dual goes to 0 */
		for (size_t i = 0; i < c->ncomp * N; i++)
			c0_pdhg_dual_entry(&y[i], 0, rho, &d2, &n2);
	} else if (c->reg == C0_REG_TV && c->ncomp == 2) {
#pragma omp parallel for simd schedule(static) reduction(+ : d2, n2) if (N > 50000)
		for (size_t i = 0; i < N; i++)
			prox_tv2_entry(&y[i], &y[N + i], y[i] + s0 * s[i], y[N + i] + s1 * s[N + i], k, rho, &d2, &n2);
	} else if (c->reg == C0_REG_TV) {
#pragma omp parallel for simd schedule(static) reduction(+ : d2, n2) if (N > 50000)
		for (size_t i = 0; i < N; i++) {
			float a = y[i] + s0 * s[i], b = y[N + i] + s1 * s[N + i], z = y[2 * N + i] + s2 * s[2 * N + i];
			float n = sqrtf(a * a + b * b + z * z), f = k / (n > k ? n : k);
			c0_pdhg_dual_entry(&y[i], f * a, rho, &d2, &n2);
			c0_pdhg_dual_entry(&y[N + i], f * b, rho, &d2, &n2);
			c0_pdhg_dual_entry(&y[2 * N + i], f * z, rho, &d2, &n2);
		}
	} else {
		/* Schatten-1's dual is the spectral norm: clip the eigenvalues to [-kappa, kappa] */
		const double r2 = sqrt(2.0);
#pragma omp parallel for schedule(static) reduction(+ : d2, n2) if (N > 20000)
		for (size_t i = 0; i < N; i++) {
			double h[6];
			for (int e = 0; e < 6; e++)
				h[e] = y[e * N + i] + (float)c->sig_r[e] * s[e * N + i];
			if (fabs(h[0]) + fabs(h[1]) + fabs(h[2]) + (fabs(h[3]) + fabs(h[4]) + fabs(h[5])) / r2 > k)
				spectral_clip(h, k);
			for (int e = 0; e < 6; e++)
				c0_pdhg_dual_entry(&y[e * N + i], (float)h[e], rho, &d2, &n2);
		}
	}
	sums[0] += d2, sums[1] += n2;
}

/* TV without axial weight (the default) has its two steps fused with the
 * operator into one pass over memory each: KT then primal_step, and K then
 * dual_step, written out per chunk of columns (tests/test_matirf.c checks
 * them against that sequence). All depths of a chunk go in turn, so that
 * the chunk's per-column tables and data rows stay in cache; the gathers
 * from the lower and upper neighbours have loops of their own so that the
 * rest vectorises. */
#define FCHUNK 256

static void primal_fused(void *vc, const float *y, float *x, float *t, float rho, double sums[2])
{
	struct ctx *c = vc;
	const struct c0_grad3m *g = &c->g;
	const size_t M = c->M, N = c->N;
	const int nq = c->nq, nz = c->nz;
	const float wl = (float)g->wl, l1 = (float)c->l1;
	const float *yd = y, *dx = y + nq * M, *dy = dx + N;
	float d2 = 0, n2 = 0;   /* per thread; sums is double */
#pragma omp parallel for schedule(static) reduction(+ : d2, n2) if (N > 50000)
	for (size_t k0 = 0; k0 < M; k0 += FCHUNK) {
		const size_t k1 = k0 + FCHUNK < M ? k0 + FCHUNK : M, n = k1 - k0;
		float a[FCHUNK];                    /* K^T y of the chunk at one depth */
		for (int j = 0; j < nz; j++) {
			c0_grad3m_lateral_adjoint(g, dx + j * M, dy + j * M, k0, n, a);
			for (size_t i = 0; i < n; i++)
				a[i] *= wl;
			for (int q = 0; q < nq; q++) {
				const float w = (float)c->W[q * nz + j], *yq = yd + q * M + k0;
				for (size_t i = 0; i < n; i++)
					a[i] += w * yq[i];
			}
			float *xj = x + j * M + k0, *tj = t + j * M + k0;
			const float *tau = c->tau + j * M + k0;
#pragma omp simd reduction(+ : d2, n2)
			for (size_t i = 0; i < n; i++)
				prox_g_entry(&xj[i], &tj[i], tau[i], a[i], l1, rho, &d2, &n2);
		}
	}
	sums[0] += d2, sums[1] += n2;
}

static void dual_fused(void *vc, const float *t, float *y, float rho, double sums[2])
{
	struct ctx *c = vc;
	const struct c0_grad3m *g = &c->g;
	const size_t M = c->M, N = c->N;
	const int nq = c->nq, nz = c->nz;
	const float k = (float)c->kappa, s0 = (float)(c->sig_r[0] * g->wl), s1 = (float)(c->sig_r[1] * g->wl);
	float *yd = y, *gx = y + nq * M, *gy = gx + N;
	float d2 = 0, n2 = 0;   /* per thread; sums is double */
#pragma omp parallel for schedule(static) reduction(+ : d2, n2) if (N > 50000)
	for (size_t k0 = 0; k0 < M; k0 += FCHUNK) {
		const size_t k1 = k0 + FCHUNK < M ? k0 + FCHUNK : M, n = k1 - k0;
		float acc[MAXQ * FCHUNK], ex[FCHUNK], ey[FCHUNK];
		for (size_t i = 0; i < (size_t)nq * FCHUNK; i++)
			acc[i] = 0;
		for (int j = 0; j < nz; j++) {
			const float *tj = t + j * M;
			for (int q = 0; q < nq; q++) {      /* W t, summed over depth */
				const float w = (float)c->W[q * nz + j];
				for (size_t i = 0; i < n; i++)
					acc[q * FCHUNK + i] += w * tj[k0 + i];
			}
			c0_grad3m_lateral(g, tj, k0, n, ex, ey);
			float *gxj = gx + j * M + k0, *gyj = gy + j * M + k0;
#pragma omp simd reduction(+ : d2, n2)
			for (size_t i = 0; i < n; i++)
				prox_tv2_entry(&gxj[i], &gyj[i], gxj[i] + s0 * ex[i], gyj[i] + s1 * ey[i], k, rho, &d2, &n2);
		}
		for (int q = 0; q < nq; q++) {
			const float sg = (float)c->sig_d[q], *bq = c->b + q * M + k0, *aq = acc + q * FCHUNK;
			float *yq = yd + q * M + k0;
#pragma omp simd reduction(+ : d2, n2)
			for (size_t i = 0; i < n; i++)
				prox_data_entry(&yq[i], aq[i], bq[i], sg, rho, &d2, &n2);
		}
	}
	sums[0] += d2, sums[1] += n2;
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
	const int ncomp = c->reg == C0_REG_TV ? ctx.g.nc : 6;
	ctx.M = (int)M, ctx.N = N, ctx.ncomp = ncomp;
	const size_t m = nd + ncomp * N;
	float *b = c0_alloc(nd, sizeof *b), *u = c0_alloc(N, sizeof *u), *y = c0_alloc(m, sizeof *y);
	float *tau = c0_alloc(N, sizeof *tau);
	if (c->reg == C0_REG_HESSIAN && !(ctx.d.work = c0_alloc(2 * N, sizeof *ctx.d.work)))
		st = C0_ENOMEM;
	res->f = c0_alloc(np * nz, sizeof *res->f);
	res->z_nm = c0_alloc((size_t)nz, sizeof *res->z_nm);
	res->depth = c0_alloc(np, sizeof *res->depth);
	res->total = c0_alloc(np, sizeof *res->total);
	if (st || !b || !u || !y || !tau || !res->f || !res->z_nm || !res->depth || !res->total) {
		st = C0_ENOMEM;
		goto out;
	}
	ctx.b = b, ctx.tau = tau;
	for (int q = 0; q < nq; q++)
		for (size_t k = 0; k < M; k++)
			b[q * M + k] = (float)(x[q][ctx.g.pixel[k]] / mx);
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
			tau[j * M + k] = (float)(1 / (sw + r));
		}
	}
	for (int q = 0; q < nq; q++) {
		double sw = 0;
		for (int j = 0; j < nz; j++)
			sw += W[q * nz + j];
		ctx.sig_d[q] = 1 / sw;
	}
	for (int comp = 0; comp < ncomp; comp++) {
		static const int HA[6] = { 0, 1, 2, 0, 0, 1 }, HB[6] = { 0, 1, 2, 1, 2, 2 };
		double rs = c->reg == C0_REG_TV ? 2 * wa[comp]
			  : (comp < 3 ? 4 : 4 * sqrt(2.0)) * wa[HA[comp]] * wa[HB[comp]];
		ctx.sig_r[comp] = rs > 0 ? 1 / rs : 1;
	}
	struct c0_pdhg_problem pb = { N, m, &ctx, K, KT, primal_step, dual_step, iter, NULL, NULL };
	if (c->reg == C0_REG_TV && ctx.g.nc == 2 && c->kappa > 0 && c->fused)
		pb.primal_fused = primal_fused, pb.dual_fused = dual_fused;
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
	free(b), free(u), free(y), free(tau), free(ctx.d.work);
	if (st)
		c0_matirf_result_free(res);
	res->seconds = c0_now() - t0;
	return st;
}
