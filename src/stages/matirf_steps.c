/* The MA-TIRF problem's operator K and the diag solver's steps (data rows
 * in the dual), their fused forms for lateral TV, and the background
 * update between iterations. */
#include "stages/matirf_ctx.h"
#include "ops/tirfop.h"
#include "solve/cg.h"
#include "solve/prox_schatten.h"
#include "core/progress.h"

#include <string.h>

/* K u = [W u per column; R's operator u], or R's operator alone for the
 * exact solver */
void matirf_K(void *vc, const float *u, float *y)
{
	struct matirf_ctx *c = vc;
	const struct c0_tirfop w = { c->nq, c->nz, (size_t)c->M, c->W };
	float *yr = c->exact ? y : y + c->nq * w.M;
	if (!c->exact)
		c0_tirfop_forward(&w, u, y);
	if (!c->exact && c->blur.k)
		c0_blur2_apply(&c->blur, y, c->nq);
	if (c->reg == C0_REG_TV)
		c0_grad3m_forward(&c->g, u, yr);
	else
		c0_hess3(&c->d, u, yr);
}

void matirf_KT(void *vc, const float *y, float *u)
{
	struct matirf_ctx *c = vc;
	const struct c0_tirfop w = { c->nq, c->nz, (size_t)c->M, c->W };
	const float *yr = c->exact ? y : y + c->nq * w.M;
	if (c->reg == C0_REG_TV)
		c0_grad3m_adjoint(&c->g, yr, u);
	else
		c0_hess3_adjoint(&c->d, yr, u);
	if (!c->exact && c->blur.k) {
		memcpy(c->dwork, y, sizeof(float) * c->nq * w.M);
		c0_blur2_apply(&c->blur, c->dwork, c->nq);
		c0_tirfop_adjoint_add(&w, c->dwork, u);
	} else if (!c->exact)
		c0_tirfop_adjoint_add(&w, y, u);
}

/* (I + lambda grad^T grad) on the ny x nx grid, Neumann borders */
static void smooth_op(void *vc, const double *in, double *out)
{
	const struct matirf_ctx *c = vc;
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
void matirf_background_update(struct matirf_ctx *c, const double *W)
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
		matirf_exact_rhs(c);
}

#define BG_EVERY 10

void matirf_iter(void *vc, int it)
{
	struct matirf_ctx *c = vc;
	c0_progress_update(c->pr, it);
	if (c->bg && it % BG_EVERY == 0)
		matirf_background_update(c, c->W);
}

/* G = l1 sum u + indicator(u >= 0) */
void matirf_primal_step(void *vc, float *x, float *t, float rho, double sums[2])
{
	struct matirf_ctx *c = vc;
	const float l1 = (float)c->l1, *tau = c->tau;
	const size_t N = c->N;
	float d2 = 0, n2 = 0;   /* per thread; sums is double */
	/* firstprivate: private copies of the pointers let the loop vectorise */
#pragma omp parallel for simd schedule(static) reduction(+ : d2, n2) firstprivate(x, t, tau) if (N > 50000)
	for (size_t i = 0; i < N; i++)
		prox_g_entry(&x[i], &t[i], tau[i], t[i], l1, rho, &d2, &n2);
	sums[0] += d2, sums[1] += n2;
}

/* F = 1/2 ||. - b||^2 on the data rows and kappa R on the regulariser rows.
 * prox of sigma F*: the data part shrinks towards -b, the regulariser part
 * projects on the kappa ball of the dual norm (group l2 for TV, spectral for
 * Schatten-1; the sum of |entries| bounds the spectral norm, so most voxels
 * skip the eigen-decomposition). */
static void dual_reg(struct matirf_ctx *c, float *y, const float *s, float rho, double sums[2]);

void matirf_dual_step(void *vc, float *y, const float *s, float rho, double sums[2])
{
	struct matirf_ctx *c = vc;
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

/* TV's rows: the (a, b[, z]) of each voxel projected on the radius-kappa
 * ball (group l2) */
static void dual_tv(struct matirf_ctx *c, float *y, const float *s, float rho, double sums[2])
{
	const size_t N = c->N;
	const float k = (float)c->kappa;
	float d2 = 0, n2 = 0;
	const float s0 = (float)c->sig_r[0], s1 = (float)c->sig_r[1], s2 = (float)c->sig_r[2];
	if (!(k > 0)) {   /* no regulariser: its dual goes to 0 */
		for (size_t i = 0; i < c->ncomp * N; i++)
			c0_pdhg_dual_entry(&y[i], 0, rho, &d2, &n2);
	} else if (c->ncomp == 2) {
#pragma omp parallel for simd schedule(static) reduction(+ : d2, n2) if (N > 50000)
		for (size_t i = 0; i < N; i++)
			prox_tv2_entry(&y[i], &y[N + i], y[i] + s0 * s[i], y[N + i] + s1 * s[N + i], k, rho, &d2, &n2);
	} else {
#pragma omp parallel for simd schedule(static) reduction(+ : d2, n2) if (N > 50000)
		for (size_t i = 0; i < N; i++) {
			float a = y[i] + s0 * s[i], b = y[N + i] + s1 * s[N + i], z = y[2 * N + i] + s2 * s[2 * N + i];
			float n = sqrtf(a * a + b * b + z * z), f = k / (n > k ? n : k);
			c0_pdhg_dual_entry(&y[i], f * a, rho, &d2, &n2);
			c0_pdhg_dual_entry(&y[N + i], f * b, rho, &d2, &n2);
			c0_pdhg_dual_entry(&y[2 * N + i], f * z, rho, &d2, &n2);
		}
	}
	sums[0] += d2, sums[1] += n2;
}

/* The lateral Hessian's rows (wz = 0): the z rows stay 0 and the matrix is
 * 2x2, whose eigenvalues m +- r have a closed form; clipped ones rebuild it
 * as c2 I + (c1 - c2) (A - e2 I) / (2 r). */
static void dual_hess2(struct matirf_ctx *c, float *y, const float *s, float rho, double sums[2])
{
	const size_t N = c->N;
	const float k = (float)c->kappa;
	float d2 = 0, n2 = 0;
	const double r2 = sqrt(2.0);
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
	sums[0] += d2, sums[1] += n2;
}

/* The 3D Hessian's rows: the spectral clip of each voxel's 3x3 matrix */
static void dual_hess3(struct matirf_ctx *c, float *y, const float *s, float rho, double sums[2])
{
	const size_t N = c->N;
	const float k = (float)c->kappa;
	float d2 = 0, n2 = 0;
	const double r2 = sqrt(2.0);
#pragma omp parallel for schedule(static) reduction(+ : d2, n2) if (N > 20000)
	for (size_t i = 0; i < N; i++) {
		double h[6];
		for (int e = 0; e < 6; e++)
			h[e] = y[e * N + i] + (float)c->sig_r[e] * s[e * N + i];
		if (fabs(h[0]) + fabs(h[1]) + fabs(h[2]) + (fabs(h[3]) + fabs(h[4]) + fabs(h[5])) / r2 > k)
			c0_spectral_clip(h, k);
		for (int e = 0; e < 6; e++)
			c0_pdhg_dual_entry(&y[e * N + i], (float)h[e], rho, &d2, &n2);
	}
	sums[0] += d2, sums[1] += n2;
}

/* the regulariser's rows of the dual step; Schatten-1's dual is the
 * spectral norm: its eigenvalues clipped to [-kappa, kappa] */
static void dual_reg(struct matirf_ctx *c, float *y, const float *s, float rho, double sums[2])
{
	if (c->reg == C0_REG_TV)
		dual_tv(c, y, s, rho, sums);
	else if (c->d.wz == 0)
		dual_hess2(c, y, s, rho, sums);
	else
		dual_hess3(c, y, s, rho, sums);
}

void matirf_dual_step_exact(void *vc, float *y, const float *s, float rho, double sums[2])
{
	dual_reg(vc, y, s, rho, sums);
}

/* TV without axial weight (the default) has its two steps fused with the
 * operator into one pass over memory each: KT then primal_step, and K then
 * dual_step, written out per chunk of columns (tests/test_matirf.c checks
 * them against that sequence). All depths of a chunk go in turn, so that
 * the chunk's per-column tables and data rows stay in cache; the gathers
 * from the lower and upper neighbours have loops of their own so that the
 * rest vectorises. */
#define FCHUNK 256

void matirf_primal_fused(void *vc, const float *y, float *x, float *t, float rho, double sums[2])
{
	struct matirf_ctx *c = vc;
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

void matirf_dual_fused(void *vc, const float *t, float *y, float rho, double sums[2])
{
	struct matirf_ctx *c = vc;
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
