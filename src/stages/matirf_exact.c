/* The exact and apg solvers' primal step: the data + l1 + positivity prox
 * per lateral pixel, a small non-negative quadratic program (the dual holds
 * only the regulariser's rows), and the steps and matrices it needs. */
#include "stages/matirf_ctx.h"
#include "ops/tirfop.h"
#include "core/c0math.h"

#include <string.h>

void matirf_exact_rhs(struct matirf_ctx *x)
{
	const int nz = x->nz, nq = x->nq;
	const size_t M = x->M;
	const double *W = x->W;
	const float *b = x->b;
	if (x->blur.k) {          /* B b, B being its own adjoint */
		memcpy(x->dwork, b, sizeof(float) * nq * M);
		c0_blur2_apply(&x->blur, x->dwork, nq);
		b = x->dwork;
	}
	for (int j = 0; j < nz; j++)
		for (size_t k = 0; k < M; k++) {
			double s = -x->l1;
			for (int q = 0; q < nq; q++)
				s += W[q * nz + j] * b[q * M + k];
			x->c[j * M + k] = (float)s;
		}
}

/* With a blur the data term 1/2 ||B W u - b||^2 couples the pixels, but B is
 * a normalised non-negative kernel (||B|| <= 1), so 1/2 (u - x)^T W^T W (u - x)
 * majorises its curvature: the per-pixel step keeps H and takes the
 * gradient's remainder corr = W^T (I - B^2) W x as a forward step (Condat-Vu
 * in the metric H). Without a blur corr is 0 and the step is exact's. */
static void blur_correction(struct matirf_ctx *c, const float *x, int adjoint)
{
	const struct c0_tirfop w = { c->nq, c->nz, (size_t)c->M, c->W };
	const size_t nd = (size_t)c->nq * c->M;
	float *r = c->dwork, *s = c->dwork2;
	c0_tirfop_forward(&w, x, r);
	memcpy(s, r, sizeof(float) * nd);
	c0_blur2_apply(&c->blur, s, c->nq);
	c0_blur2_apply(&c->blur, s, c->nq);
	for (size_t i = 0; i < nd; i++)
		r[i] -= s[i];
	if (!adjoint)    /* apg applies W^T to r chunk by chunk (corr_chunk) */
		return;
	memset(c->corr, 0, sizeof(float) * c->N);
	c0_tirfop_adjoint_add(&w, r, c->corr);
}

/* corr at depth l of the n columns from k0: W^T r as c0_tirfop_adjoint_add
 * sums it (from 0, the angles in turn), without storing it */
C0_HOT_SAME static void corr_chunk(const struct matirf_ctx *c, int l, size_t k0, size_t n, float *out)
{
	const size_t M = c->M;
	for (size_t i = 0; i < n; i++)
		out[i] = 0;
	for (int q = 0; q < c->nq; q++) {
		const float w = (float)c->W[q * c->nz + l], *rq = c->dwork + q * M + k0;
		for (size_t i = 0; i < n; i++)
			out[i] += w * rq[i];
	}
}

/* The exact solver's primal step: G = data + l1 + positivity, whose prox is
 * a small non-negative quadratic program per column,
 *   min_{u >= 0} 1/2 u^T H u - (c + v / tau)^T u,  v = x - tau K^T y,
 * warm-started from the column's current values. */
void matirf_primal_step_exact(void *vc, float *x, float *t, float rho, double sums[2])
{
	struct matirf_ctx *c = vc;
	const size_t M = c->M;
	const int nz = c->nz;
	const double tau = c->tau1;
	float d2 = 0, n2 = 0;
	if (c->blur.k)
		blur_correction(c, x, 1);
#pragma omp parallel for schedule(dynamic, 512) reduction(+ : d2, n2) if (c->N > 50000)
	for (size_t k = 0; k < M; k++) {
		double g[C0_NNQP_MAX], u[C0_NNQP_MAX];
		for (int l = 0; l < nz; l++) {
			const size_t i = l * M + k;
			g[l] = c->c[i] + (x[i] - tau * t[i]) / tau;
			if (c->blur.k)
				g[l] += c->corr[i];
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
 * solved only approximately by c0_nnqp_batch: APG_ITS projected gradient
 * steps with constant momentum (H's eigenvalues lie in [1/tau, L], well
 * conditioned), warm-started from the column's current values, branch-free
 * and vectorised across a chunk of columns (the active-set NNQP branches
 * per pixel and was 2/3 of the exact solver's time). x moves little per
 * iteration, so a few steps keep up with it, and at a fixed point of PDHG
 * the warm start is already the prox: the solution is the exact solver's.
 * 6 steps: 4 left the depths 1.4 nm from diag's on the 350x350 phantom, 6
 * and 8 0.7 nm (docs/defaults.md#matirf_solver). */
#define APG_CHUNK C0_NNQP_BATCH
#define APG_ITS 6

/* The n columns from k0 into a chunk: u = x and the NNQP's linear term
 * g = c + x / tau - K^T y (+ the blur's correction), zero past n */
C0_HOT_SAME static void apg_gather(const struct matirf_ctx *c, const float *y, const float *x, const float *t, size_t k0,
				   size_t n, float *g, float *u)
{
	const size_t M = c->M, N = c->N;
	const float it1 = (float)(1 / c->tau1), wl = (float)c->g.wl;
	float a[APG_CHUNK], cr[APG_CHUNK];
	for (int l = 0; l < c->nz; l++) {
		float *gl = g + l * APG_CHUNK, *ul = u + l * APG_CHUNK;
		const float *xl = x + l * M + k0, *cl = c->c + l * M + k0, *al = t + l * M + k0;
		if (y) {
			c0_grad3m_lateral_adjoint(&c->g, y + l * M, y + N + l * M, k0, n, a);
			for (size_t i = 0; i < n; i++)
				a[i] *= wl;
			al = a;
		}
		for (size_t i = 0; i < n; i++) {
			gl[i] = cl[i] + xl[i] * it1 - al[i];
			ul[i] = xl[i];
		}
		if (c->blur.k) {
			corr_chunk(c, l, k0, n, cr);
			for (size_t i = 0; i < n; i++)
				gl[i] += cr[i];
		}
		for (size_t i = n; i < APG_CHUNK; i++)   /* the last chunk's tail: c0_nnqp_batch takes whole chunks */
			gl[i] = ul[i] = 0;
	}
}

/* y: the dual iterate when fused with lateral TV's K^T (then t is only
 * written), else NULL and t holds K^T y */
static void apg_step(struct matirf_ctx *c, const float *y, float *x, float *t, float rho, double sums[2])
{
	const size_t M = c->M;
	const int nz = c->nz;
	float d2 = 0, n2 = 0;
	if (c->blur.k)
		blur_correction(c, x, 0);
#pragma omp parallel for schedule(static) reduction(+ : d2, n2) if (c->N > 50000)
	for (size_t k0 = 0; k0 < M; k0 += APG_CHUNK) {
		const size_t n = k0 + APG_CHUNK < M ? APG_CHUNK : M - k0;
		float g[C0_NNQP_MAX * APG_CHUNK], u[C0_NNQP_MAX * APG_CHUNK];
		apg_gather(c, y, x, t, k0, n, g, u);
		c0_nnqp_batch(nz, c->Hf, c->apg_step, c->apg_beta, APG_ITS, g, u);
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

void matirf_primal_step_apg(void *vc, float *x, float *t, float rho, double sums[2])
{
	apg_step(vc, NULL, x, t, rho, sums);
}

void matirf_primal_fused_apg(void *vc, const float *y, float *x, float *t, float rho, double sums[2])
{
	apg_step(vc, y, x, t, rho, sums);
}

/* Steps of the exact solver: the diagonal (Pock-Chambolle) steps of K = R's
 * operator with one tau for all voxels (their largest column sum), traded
 * against sigma by gamma; H = W^T W + I / tau and c = W^T b - l1. */
void matirf_exact_setup(struct matirf_ctx *x, const struct c0_matirf_conf *c, const double *W)
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
	matirf_exact_rhs(x);
}
