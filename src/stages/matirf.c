#include "stages/matirf.h"
#include "ops/diff3.h"
#include "ops/grad3m.h"
#include "ops/tirfop.h"
#include "ops/blur2.h"
#include "solve/cg.h"
#include "optics/psf.h"
#include "solve/pdhg.h"
#include "solve/nnqp.h"
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
	if (!(c->bg_smooth >= 0))
		return c0_fail(C0_EINVAL, "matirf_background_smooth %g: must be >= 0", c->bg_smooth);
	if (!(c->psf_sigma_px >= 0) || c->psf_sigma_px > 12)
		return c0_fail(C0_EINVAL, "psf_fwhm_nm: %g pixels sigma, must be in [0, 12]", c->psf_sigma_px);
	if (!(c->gamma > 0))
		return c0_fail(C0_EINVAL, "matirf: gamma %g must be > 0", c->gamma);
	if (!(c->kappa >= 0 && isfinite(c->kappa)) || !(c->wz >= 0 && isfinite(c->wz)) || !(c->sparsity >= 0 && isfinite(c->sparsity)))
		return c0_fail(C0_EINVAL, "kappa %g, axial_weight %g, sparsity %g: must be finite and >= 0", c->kappa, c->wz,
			       c->sparsity);
	if (c->coarse < 0 || c->coarse > 8)
		return c0_fail(C0_EINVAL, "matirf_coarse %d: must be 0..8", c->coarse);
	if (c->pdhg.maxit < 1)
		return c0_fail(C0_EINVAL, "matirf_iterations %d: must be at least 1", c->pdhg.maxit);
	if (!(c->pdhg.tol >= 0 && isfinite(c->pdhg.tol)) || !(c->pdhg.relax > 0 && c->pdhg.relax < 2))
		return c0_fail(C0_EINVAL, "matirf_tol %g: must be >= 0 (relaxation %g in (0, 2))", c->pdhg.tol, c->pdhg.relax);
	return C0_OK;
}

int c0_matirf_subtract(float *const *x, int nq, size_t np, double v, const char *what)
{
	if (!(v == v) || v < 0)
		return c0_fail(C0_EINVAL, "%s %g: must be >= 0", what, v);
	for (int q = 0; q < nq && v > 0; q++) {
		double s = 0;
		for (size_t p = 0; p < np; p++)
			s += x[q][p];
		if (!(v < s / np))
			return c0_fail(C0_EINVAL, "%s %g: not below the mean of image %d (%g): nothing would be left of it", what,
				       v, q + 1, s / np);
	}
	for (int q = 0; q < nq && v > 0; q++)
		for (size_t p = 0; p < np; p++)
			x[q][p] -= (float)v;
	return C0_OK;
}

void c0_matirf_result_free(struct c0_matirf_result *r)
{
	free(r->f), free(r->z_nm), free(r->depth), free(r->total), free(r->background);
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
	/* the exact solver (C0_MATIRF_EXACT): K = R's operator, one primal step
	 * tau1, H = W^T W + I / tau1 and c = W^T b - l1 per voxel */
	int exact;
	/* joint deconvolution: the data rows are B W u, B a Gaussian blur of
	 * each angle's image (full grid); work: nq M floats */
	struct c0_blur2 blur;
	float *dwork;
	/* background estimation: b = b0 - bg, bg updated from the residual every
	 * BG_EVERY iterations; u is the solver's primal iterate */
	const float *b0, *u;
	float *bg, *b_mut;
	double *bgd, *bgr;
	double bg_smooth;
	int ny, nx;
	double tau1, hcol, H[C0_NNQP_MAX * C0_NNQP_MAX], Hi[C0_NNQP_MAX * C0_NNQP_MAX];
	float *c;
	/* the apg solver: the same prox by APG_ITS accelerated projected
	 * gradient steps (step 1/L, momentum beta from L and mu = 1/tau1) */
	int apg;
	float Hf[C0_NNQP_MAX * C0_NNQP_MAX], apg_step, apg_beta;
	struct c0_progress *pr;
};

/* K u = [W u per column; R's operator u] */
/* K u = [W u per column; R's operator u], or R's operator alone for the
 * exact solver */
static void K(void *vc, const float *u, float *y)
{
	struct ctx *c = vc;
	const struct c0_tirfop w = { c->nq, c->nz, (size_t)c->M, c->W };
	float *yr = c->exact ? y : y + c->nq * w.M;
	if (!c->exact)
		c0_tirfop_forward(&w, u, y);
	if (c->blur.k)
		c0_blur2_apply(&c->blur, y, c->nq);
	if (c->reg == C0_REG_TV)
		c0_grad3m_forward(&c->g, u, yr);
	else
		c0_hess3(&c->d, u, yr);
}

static void KT(void *vc, const float *y, float *u)
{
	struct ctx *c = vc;
	const struct c0_tirfop w = { c->nq, c->nz, (size_t)c->M, c->W };
	const float *yr = c->exact ? y : y + c->nq * w.M;
	if (c->reg == C0_REG_TV)
		c0_grad3m_adjoint(&c->g, yr, u);
	else
		c0_hess3_adjoint(&c->d, yr, u);
	if (c->blur.k) {
		memcpy(c->dwork, y, sizeof(float) * c->nq * w.M);
		c0_blur2_apply(&c->blur, c->dwork, c->nq);
		c0_tirfop_adjoint_add(&w, c->dwork, u);
	} else if (!c->exact)
		c0_tirfop_adjoint_add(&w, y, u);
}

/* (I + lambda grad^T grad) on the ny x nx grid, Neumann borders */
static void smooth_op(void *vc, const double *in, double *out)
{
	const struct ctx *c = vc;
	const int ny = c->ny, nx = c->nx;
	const double l = c->bg_smooth;
	for (int y = 0; y < ny; y++)
		for (int x = 0; x < nx; x++) {
			const size_t i = (size_t)y * nx + x;
			double v = in[i], s = 0;
			if (x > 0) s += v - in[i - 1];
			if (x < nx - 1) s += v - in[i + 1];
			if (y > 0) s += v - in[i - nx];
			if (y < ny - 1) s += v - in[i + nx];
			out[i] = v + l * s;
		}
}

/* bg = max((I + lambda grad^T grad)^-1 mean_q (b0_q - (B W u)_q), 0): the
 * background common to all angles that minimises the data term given u,
 * smoothed (Soubies et al., ISBI 2019); then the data the solver sees. */
static void background_update(struct ctx *c, const double *W)
{
	const size_t M = c->M;
	const struct c0_tirfop w = { c->nq, c->nz, M, W };
	c0_tirfop_forward(&w, c->u, c->dwork);
	if (c->blur.k)
		c0_blur2_apply(&c->blur, c->dwork, c->nq);
	for (size_t k = 0; k < M; k++) {
		double s = 0;
		for (int q = 0; q < c->nq; q++)
			s += c->b0[q * M + k] - c->dwork[q * M + k];
		c->bgr[k] = s / c->nq;
	}
	struct c0_cg_info ci;
	c0_cg(smooth_op, c, M, c->bgr, NULL, c->bgd, 1e-6, 500, &ci);
	for (size_t k = 0; k < M; k++) {
		c->bg[k] = c->bgd[k] > 0 ? (float)c->bgd[k] : 0;
		for (int q = 0; q < c->nq; q++)
			c->b_mut[q * M + k] = c->b0[q * M + k] - c->bg[k];
	}
	if (c->exact)
		for (int j = 0; j < c->nz; j++)
			for (size_t k = 0; k < M; k++) {
				double s = -c->l1;
				for (int q = 0; q < c->nq; q++)
					s += W[q * c->nz + j] * c->b_mut[q * M + k];
				c->c[j * M + k] = (float)s;
			}
}

#define BG_EVERY 10

static void iter(void *vc, int it)
{
	struct ctx *c = vc;
	c0_progress_update(c->pr, it);
	if (c->bg && it % BG_EVERY == 0)
		background_update(c, c->W);
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
static void dual_reg(struct ctx *c, float *y, const float *s, float rho, double sums[2]);

static void dual_step(void *vc, float *y, const float *s, float rho, double sums[2])
{
	struct ctx *c = vc;
	const size_t M = c->M, nd = (size_t)c->nq * M;
	float d2 = 0, n2 = 0;   /* per thread; sums is double */
	for (int q = 0; q < c->nq; q++) {
		const float sg = (float)c->sig_d[q], *bq = c->b + q * M, *sq = s + q * M;
		float *yq = y + q * M;
#pragma omp simd reduction(+ : d2, n2)
		for (size_t i = 0; i < M; i++)
			prox_data_entry(&yq[i], sq[i], bq[i], sg, rho, &d2, &n2);
	}
	sums[0] += d2, sums[1] += n2;
	dual_reg(c, y + nd, s + nd, rho, sums);
}

/* the regulariser's rows of the dual step */
static void dual_reg(struct ctx *c, float *y, const float *s, float rho, double sums[2])
{
	const size_t N = c->N;
	const float k = (float)c->kappa;
	float d2 = 0, n2 = 0;
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
		if (c->d.wz == 0) {
			/* lateral Hessian: the z rows stay 0 and the matrix is 2x2, whose
			 * eigenvalues m +- r have a closed form; clipped ones rebuild it
			 * as c2 I + (c1 - c2) (A - e2 I) / (2 r) */
			const float s0 = (float)c->sig_r[0], s1 = (float)c->sig_r[1], s3 = (float)c->sig_r[3], ir2 = (float)(1 / r2);
			float *y0 = y, *y1 = y + N, *y3 = y + 3 * N;
			const float *t0 = s, *t1 = s + N, *t3 = s + 3 * N;
#pragma omp parallel for simd schedule(static) reduction(+ : d2, n2) if (N > 20000)
			for (size_t i = 0; i < N; i++) {
				float a = y0[i] + s0 * t0[i], b = y1[i] + s1 * t1[i], o = (y3[i] + s3 * t3[i]) * ir2;
				float m = 0.5f * (a + b), h = 0.5f * (a - b), r = sqrtf(h * h + o * o);
				float e1 = m + r, e2 = m - r;
				float c1 = fminf(fmaxf(e1, -k), k), c2 = fminf(fmaxf(e2, -k), k);
				float f = r > 0 ? (c1 - c2) / (2 * r) : 0;
				float na = r > 0 ? c2 + f * (a - e2) : c1, nb = r > 0 ? c2 + f * (b - e2) : c1, no = f * o;
				c0_pdhg_dual_entry(&y0[i], na, rho, &d2, &n2);
				c0_pdhg_dual_entry(&y1[i], nb, rho, &d2, &n2);
				c0_pdhg_dual_entry(&y3[i], no * (float)r2, rho, &d2, &n2);
			}
		} else
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

static void dual_step_exact(void *vc, float *y, const float *s, float rho, double sums[2])
{
	dual_reg(vc, y, s, rho, sums);
}

/* The exact solver's primal step: G = data + l1 + positivity, whose prox is
 * a small non-negative quadratic program per column,
 *   min_{u >= 0} 1/2 u^T H u - (c + v / tau)^T u,  v = x - tau K^T y,
 * warm-started from the column's current values. */
static void primal_step_exact(void *vc, float *x, float *t, float rho, double sums[2])
{
	struct ctx *c = vc;
	const size_t M = c->M;
	const int nz = c->nz;
	const double tau = c->tau1;
	float d2 = 0, n2 = 0;
#pragma omp parallel for schedule(dynamic, 512) reduction(+ : d2, n2) if (c->N > 50000)
	for (size_t k = 0; k < M; k++) {
		double g[C0_NNQP_MAX], u[C0_NNQP_MAX];
		for (int l = 0; l < nz; l++) {
			const size_t i = l * M + k;
			g[l] = c->c[i] + (x[i] - tau * t[i]) / tau;
			u[l] = x[i];
		}
		c0_nnqp(nz, c->H, c->Hi, g, u);   /* at its cap u is still feasible and no worse */
		for (int l = 0; l < nz; l++)
			c0_pdhg_primal_entry(&x[l * M + k], &t[l * M + k], (float)u[l], rho, &d2, &n2);
	}
	sums[0] += d2, sums[1] += n2;
}

/* The apg solver's primal step: the exact solver's per-pixel NNQP,
 *   min_{u >= 0} 1/2 u^T H u - g^T u,  g = c + (x - tau K^T y) / tau,
 * solved only approximately, by APG_ITS projected gradient steps with
 * constant momentum (H's eigenvalues lie in [1/tau, L], well conditioned),
 * warm-started from the column's current values: branch-free and
 * vectorised across a chunk of columns (the active-set NNQP branches per
 * pixel and was 2/3 of the exact solver's time). x moves little per
 * iteration, so a few steps keep up with it, and at a fixed point of PDHG
 * the warm start is already the prox: the solution is the exact solver's.
 * 6 steps: 4 left the depths 1.4 nm from diag's on the 350x350 phantom, 6
 * and 8 0.7 nm (docs/parameters.md). */
#define APG_CHUNK 256
#define APG_ITS 6

/* most of the step's time: built also for AVX2 (8 floats a vector) where
 * the CPU has it, chosen at load time; the default build targets plain x86-64 */
#if defined(__x86_64__) && defined(__GNUC__) && (!defined(__clang__) || __clang_major__ >= 14)
__attribute__((target_clones("avx2", "default")))
#endif
static void apg_chunk(const struct ctx *c, size_t n, const float *g, float *u)
{
	const int nz = c->nz;
	const float st = c->apg_step, be = c->apg_beta;
	float v[C0_NNQP_MAX * APG_CHUNK], w[C0_NNQP_MAX * APG_CHUNK], acc[APG_CHUNK];
	memcpy(v, u, sizeof(float) * nz * APG_CHUNK);
	for (int it = 0; it < APG_ITS; it++) {
		for (int l = 0; l < nz; l++) {
			const float *gl = g + l * APG_CHUNK, *vl = v + l * APG_CHUNK;
			for (size_t i = 0; i < n; i++)
				acc[i] = -gl[i];
			for (int m = 0; m < nz; m++) {
				const float h = c->Hf[l * nz + m], *vm = v + m * APG_CHUNK;
				for (size_t i = 0; i < n; i++)
					acc[i] += h * vm[i];
			}
			float *wl = w + l * APG_CHUNK;
			for (size_t i = 0; i < n; i++) {
				float p = vl[i] - st * acc[i];
				wl[i] = 0.5f * (p + fabsf(p));
			}
		}
		for (int l = 0; l < nz; l++) {
			float *ul = u + l * APG_CHUNK, *vl = v + l * APG_CHUNK;
			const float *wl = w + l * APG_CHUNK;
			for (size_t i = 0; i < n; i++) {
				vl[i] = wl[i] + be * (wl[i] - ul[i]);
				ul[i] = wl[i];
			}
		}
	}
}

/* y: the dual iterate when fused with lateral TV's K^T (then t is only
 * written), else NULL and t holds K^T y */
static void apg_step(struct ctx *c, const float *y, float *x, float *t, float rho, double sums[2])
{
	const size_t M = c->M, N = c->N;
	const int nz = c->nz;
	const float it1 = (float)(1 / c->tau1), wl = (float)c->g.wl;
	float d2 = 0, n2 = 0;
#pragma omp parallel for schedule(static) reduction(+ : d2, n2) if (N > 50000)
	for (size_t k0 = 0; k0 < M; k0 += APG_CHUNK) {
		const size_t n = k0 + APG_CHUNK < M ? APG_CHUNK : M - k0;
		float g[C0_NNQP_MAX * APG_CHUNK], u[C0_NNQP_MAX * APG_CHUNK], a[APG_CHUNK];
		for (int l = 0; l < nz; l++) {
			const float *xl = x + l * M + k0, *cl = c->c + l * M + k0, *al = t + l * M + k0;
			if (y) {
				c0_grad3m_lateral_adjoint(&c->g, y + l * M, y + N + l * M, k0, n, a);
				for (size_t i = 0; i < n; i++)
					a[i] *= wl;
				al = a;
			}
			for (size_t i = 0; i < n; i++) {
				g[l * APG_CHUNK + i] = cl[i] + xl[i] * it1 - al[i];
				u[l * APG_CHUNK + i] = xl[i];
			}
		}
		apg_chunk(c, n, g, u);
		for (int l = 0; l < nz; l++) {
			float *xl = x + l * M + k0, *tl = t + l * M + k0;
			const float *ul = u + l * APG_CHUNK;
#pragma omp simd reduction(+ : d2, n2)
			for (size_t i = 0; i < n; i++)
				c0_pdhg_primal_entry(&xl[i], &tl[i], ul[i], rho, &d2, &n2);
		}
	}
	sums[0] += d2, sums[1] += n2;
}

static void primal_step_apg(void *vc, float *x, float *t, float rho, double sums[2])
{
	apg_step(vc, NULL, x, t, rho, sums);
}

static void primal_fused_apg(void *vc, const float *y, float *x, float *t, float rho, double sums[2])
{
	apg_step(vc, y, x, t, rho, sums);
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
	const int nq = c->exact ? 0 : c->nq, nz = c->nz;   /* the exact solver's dual has no data rows */
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

/* Steps of the exact solver: the diagonal (Pock-Chambolle) steps of K = R's
 * operator with one tau for all voxels (their largest column sum), traded
 * against sigma by gamma; H = W^T W + I / tau and c = W^T b - l1. */
static void exact_setup(struct ctx *x, const struct c0_matirf_conf *c, const double *W)
{
	const int nz = x->nz, nq = x->nq;
	const size_t M = x->M;
	double cmax = 0;
	if (x->reg == C0_REG_TV) {
		for (int j = 0; j < nz; j++)
			for (size_t k = 0; k < M; k++)
				cmax = fmax(cmax, c0_grad3m_colsum(&x->g, (int)k, j));
	} else
		cmax = x->hcol;
	const double gamma = c->gamma;
	x->tau1 = gamma / (cmax > 0 ? cmax : 1);
	for (int comp = 0; comp < x->ncomp; comp++)
		x->sig_r[comp] /= gamma;
	for (int i = 0; i < nz; i++)
		for (int j = 0; j < nz; j++) {
			double s = i == j ? 1 / x->tau1 : 0;
			for (int q = 0; q < nq; q++)
				s += W[q * nz + i] * W[q * nz + j];
			x->H[i * nz + j] = s;
		}
	c0_spd_inverse(nz, x->H, x->Hi);
	/* apg: L = H's largest eigenvalue (power iteration, then 1 % margin);
	 * the smallest is 1/tau1 (W^T W is singular when nq < nz, else >= it) */
	double v[C0_NNQP_MAX], L = 0;
	for (int i = 0; i < nz; i++)
		v[i] = 1;
	for (int it = 0; it < 200; it++) {
		double w[C0_NNQP_MAX], n2 = 0;
		for (int i = 0; i < nz; i++) {
			w[i] = 0;
			for (int j = 0; j < nz; j++)
				w[i] += x->H[i * nz + j] * v[j];
			n2 += w[i] * w[i];
		}
		L = sqrt(n2);
		for (int i = 0; i < nz; i++)
			v[i] = w[i] / L;
	}
	L *= 1.01;
	const double q = sqrt(1 / x->tau1 / L);
	x->apg_step = (float)(1 / L), x->apg_beta = (float)((1 - q) / (1 + q));
	for (int i = 0; i < nz * nz; i++)
		x->Hf[i] = (float)x->H[i];
	for (int j = 0; j < nz; j++)
		for (size_t k = 0; k < M; k++) {
			double s = -x->l1;
			for (int q = 0; q < nq; q++)
				s += W[q * nz + j] * x->b[q * M + k];
			x->c[j * M + k] = (float)s;
		}
}

/* The objective at u (scaled units): 1/2 ||W u - b||^2 + kappa R(u) + l1 sum u,
 * to compare solvers; work: ncomp N floats. */
static double objective(struct ctx *c, const float *u, float *work)
{
	const size_t M = c->M, N = c->N;
	double data = 0, reg = 0, l1 = 0;
	for (size_t k = 0; k < M; k++)
		for (int q = 0; q < c->nq; q++) {
			double s = -c->b[q * M + k];
			for (int j = 0; j < c->nz; j++)
				s += c->W[q * c->nz + j] * u[j * M + k];
			data += 0.5 * s * s;
		}
	for (size_t i = 0; i < N; i++)
		l1 += u[i];
	if (c->reg == C0_REG_TV) {
		c0_grad3m_forward(&c->g, u, work);
		for (size_t i = 0; i < N; i++) {
			double s = 0;
			for (int e = 0; e < c->ncomp; e++)
				s += (double)work[e * N + i] * work[e * N + i];
			reg += sqrt(s);
		}
	} else {
		c0_hess3(&c->d, u, work);
		const double r2 = sqrt(2.0);
		for (size_t i = 0; i < N; i++) {
			double h[6], v[3][3];
			for (int e = 0; e < 6; e++)
				h[e] = work[e * N + i];
			double a[3][3] = { { h[0], h[3] / r2, h[4] / r2 }, { h[3] / r2, h[1], h[5] / r2 }, { h[4] / r2, h[5] / r2, h[2] } };
			eig3(a, v);
			reg += fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
		}
	}
	return data + c->kappa * reg + c->l1 * l1;
}

/* One level: mx0 > 0 fixes the data scale (a coarse level solves in the
 * fine level's units); u0, y0 (full grid, u units; y0 the TV dual, ncomp x
 * nz x ny x nx) start the solver when not NULL; yout receives the final
 * dual on the full grid. */
static int solve(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
		 const float *const *x, int ny, int nx, double mx0, int coarse, float *yout, struct c0_matirf_result *res);

int c0_matirf_nz(const struct c0_matirf_conf *c)
{
	return (int)ceil((c->z1_nm - c->z0_nm) / c->dz_nm - 1e-9);
}

int c0_matirf_solve(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
		    const float *const *x, int ny, int nx, struct c0_matirf_result *res)
{
	return solve(c, nq, angles, gain, x, ny, nx, 0, c->coarse, NULL, res);
}

/* The warm start from a coarser grid: the images binned 2x2 (mean), the same
 * problem in physical units there (per area, lateral TV weighs kappa / 2 and
 * its axial weight doubles; the data scale is the fine level's), solved, and
 * its volume and TV dual brought back bilinearly (the dual doubled,
 * the dual's bound being kappa there). u0, y0: nz np and 2 nz np floats. */
static int coarse_start(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
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
	struct c0_matirf_result r;
	if ((st = solve(&cc, nq, angles, gain, xc, cy, cx, mx, levels - 1, yc, &r)))
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

static int solve(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
		 const float *const *x, int ny, int nx, double mx0, int coarse, float *yout, struct c0_matirf_result *res)
{
	memset(res, 0, sizeof *res);
	double t0 = c0_now();
	int st = c0_matirf_check(c, nq, angles);
	if (st)
		return st;
	const int nz = c0_matirf_nz(c);
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
	if (mx0 > 0)
		mx = mx0;
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
			mask[p] |= c->reg == C0_REG_HESSIAN || c->bg_smooth > 0 || c->psf_sigma_px > 0 || x[q][p] > 0;
	st = c0_grad3m_init(&ctx.g, mask, ny, nx, nz, 1, c->wz);
	free(mask);
	if (st)
		return st;
	const size_t M = (size_t)ctx.g.M, N = M * nz, nd = (size_t)nq * M;
	const int ncomp = c->reg == C0_REG_TV ? ctx.g.nc : 6;
	ctx.M = (int)M, ctx.N = N, ctx.ncomp = ncomp;
	/* the exact solver's per-pixel prox has no room for a lateral blur */
	ctx.exact = (c->solver == C0_MATIRF_EXACT || c->solver == C0_MATIRF_APG) && nz <= C0_NNQP_MAX && !(c->psf_sigma_px > 0);
	ctx.apg = ctx.exact && c->solver == C0_MATIRF_APG;
	ctx.ny = ny, ctx.nx = nx, ctx.bg_smooth = c->bg_smooth;
	float kern[2 * 64 + 1];
	if (c->psf_sigma_px > 0) {
		double kd[2 * 64 + 1];
		int r = (int)ceil(C0_PSF_CUTOFF * c->psf_sigma_px);
		r = r > 64 ? 64 : r;
		c0_psf_pixel_weights(0.5, c->psf_sigma_px, -r, 2 * r + 1, kd);
		for (int i = 0; i <= 2 * r; i++)
			kern[i] = (float)kd[i];
		ctx.blur = (struct c0_blur2){ ny, nx, r, kern, c0_alloc(np, sizeof(float)) };
		if (!ctx.blur.work)
			st = C0_ENOMEM;
	}
	if ((c->psf_sigma_px > 0 || c->bg_smooth > 0) && !(ctx.dwork = c0_alloc((size_t)nq * M, sizeof(float))))
		st = C0_ENOMEM;
	float *b0 = NULL;
	if (c->bg_smooth > 0) {
		ctx.bg = c0_alloc(M, sizeof *ctx.bg), ctx.bgd = c0_alloc(M, sizeof *ctx.bgd), ctx.bgr = c0_alloc(M, sizeof *ctx.bgr);
		b0 = c0_alloc(nd, sizeof *b0);
		res->background = c0_alloc(np, sizeof *res->background);
		if (!ctx.bg || !ctx.bgd || !ctx.bgr || !b0 || !res->background)
			st = C0_ENOMEM;
	}
	const size_t m = ctx.exact ? ncomp * N : nd + ncomp * N;
	float *b = c0_alloc(nd, sizeof *b), *u = c0_alloc(N, sizeof *u), *y = c0_alloc(m, sizeof *y);
	float *tau = c0_alloc(N, sizeof *tau);
	if (ctx.exact && !(ctx.c = c0_alloc(N, sizeof *ctx.c)))
		st = C0_ENOMEM;
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
	ctx.b = b, ctx.tau = tau, ctx.u = u;
	for (int q = 0; q < nq; q++)
		for (size_t k = 0; k < M; k++)
			b[q * M + k] = (float)(x[q][ctx.g.pixel[k]] / mx);
	if (b0) {
		memcpy(b0, b, sizeof *b0 * nd);
		ctx.b0 = b0, ctx.b_mut = b;
	}
	/* diagonal steps: 1 / (absolute row or column sums of K) */
	const double wa[3] = { 1, 1, c->wz };
	double hcol = 0;
	for (int a = 0; a < 3; a++)
		for (int e = a; e < 3; e++)
			hcol += (a == e ? 4 : 4 * sqrt(2.0)) * wa[a] * wa[e];
	ctx.hcol = hcol;
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
	if (ctx.exact) {
		pb.primal_step = ctx.apg ? primal_step_apg : primal_step_exact, pb.dual_step = dual_step_exact;
		exact_setup(&ctx, c, W);
		if (c->reg == C0_REG_TV && ctx.g.nc == 2 && c->kappa > 0 && c->fused) {
			pb.dual_fused = dual_fused;   /* its TV part alone */
			if (ctx.apg)
				pb.primal_fused = primal_fused_apg;
		}
	} else if (c->reg == C0_REG_TV && ctx.g.nc == 2 && c->kappa > 0 && c->fused && !ctx.blur.k)
		pb.primal_fused = primal_fused, pb.dual_fused = dual_fused;
	/* the coarse start: the apg and exact solvers with TV (no background, no
	 * blur), on grids large enough to bin */
	if (coarse > 0 && ctx.exact && c->reg == C0_REG_TV && !ctx.bg && ny >= 16 && nx >= 16 && ctx.g.nc <= 2) {
		float *u0 = c0_alloc(np * nz, sizeof *u0), *y0 = c0_alloc(2 * np * nz, sizeof *y0);
		if (!u0 || !y0 || (st = coarse_start(c, nq, angles, gain, x, ny, nx, nz, mx, coarse, col, u0, y0, &res->coarse_iters))) {
			free(u0), free(y0);
			st = st ? st : C0_ENOMEM;
			goto out;
		}
		for (int j = 0; j < nz; j++)
			for (size_t k = 0; k < M; k++) {
				u[j * M + k] = u0[j * np + ctx.g.pixel[k]];
				for (int e = 0; e < ctx.g.nc; e++)
					y[e * N + j * M + k] = y0[(e * nz + j) * np + ctx.g.pixel[k]];
			}
		free(u0), free(y0);
	}
	struct c0_pdhg_info info;
	struct c0_progress pr;
	c0_progress_begin(&pr, "matirf (iterations, at most)", c->pdhg.maxit);
	ctx.pr = &pr;
	struct c0_pdhg_conf pc = c->pdhg;
	/* each solver's default; apg with TV: at 1e-3 the pipeline's demo depths
	 * were 1.4 nm worse than diag's, at 5e-4 as good (docs/parameters.md) */
	if (pc.tol == 0)
		pc.tol = ctx.apg && c->reg == C0_REG_TV ? 5e-4 : ctx.exact ? 1e-3 : 1e-4;
	st = c0_pdhg_solve(&pb, &pc, u, y, &info);
	c0_progress_end(&pr);
	if (st)
		goto out;
	res->nz = nz, res->ny = ny, res->nx = nx, res->iters = info.iters, res->converged = info.converged;
	res->exact = ctx.exact, res->apg = ctx.apg, res->rel_change = fmax(info.dx, info.dy);
	if (yout && ctx.exact && c->reg == C0_REG_TV && ctx.g.nc <= 2) {
		memset(yout, 0, sizeof *yout * 2 * np * nz);
		for (int j = 0; j < nz; j++)
			for (size_t k = 0; k < M; k++)
				for (int e = 0; e < ctx.g.nc; e++)
					yout[(e * nz + j) * np + ctx.g.pixel[k]] = y[e * N + j * M + k];
	}
	if (ctx.bg) {
		background_update(&ctx, W);      /* the background of the final iterate */
		double sb = 0;
		for (size_t k = 0; k < M; k++)
			res->background[ctx.g.pixel[k]] = (float)(ctx.bg[k] * mx), sb += ctx.bg[k] * mx;
		res->background_mean = sb / (M ? M : 1);
	}
	{
		float *work = c0_alloc(ncomp * N, sizeof *work);
		res->objective = work ? objective(&ctx, u, work) : NAN;
		free(work);
	}
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
	free(b), free(u), free(y), free(tau), free(ctx.d.work), free(ctx.c);
	free(ctx.blur.work), free(ctx.dwork), free(ctx.bg), free(ctx.bgd), free(ctx.bgr), free(b0);
	if (st)
		c0_matirf_result_free(res);
	res->seconds = c0_now() - t0;
	return st;
}
