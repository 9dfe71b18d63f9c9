#include "ops/covfit.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* f(x) = min_s 1/2 ||R - M(x) - s I||^2 from <x, C>, <x, A^T A x> and
 * <x, n>; *s the minimising s */
static double objective(const struct c0_covfit *c, double xc, double xax, double xn, double *s)
{
	*s = fmax(0, (c->trR - xn) / c->HW);
	return 0.5 * c->R2 - xc - *s * c->trR + 0.5 * xax + *s * xn + 0.5 * *s * *s * c->HW;
}

/* <x, C>, <x, A^T A x>, <x, n> and sum x over the grid (A^T A x in c->Ax),
 * in blocks (C0_SUM_BLOCK): s, from <x, n>, moves the iterates. A pixel at
 * 0 adds a zero to each sum, which leaves it as it was: the sums skip it
 * and read C, A^T A x and n only where x is not 0 (x is sparse) */
static void grid_sums(struct c0_covfit *c, const double *x, double out[4])
{
	const double *n = c->op->n, *C = c->C, *Ax = c->Ax;
	const size_t L = (size_t)c->op->Ly * c->op->Lx, nb = (L + C0_SUM_BLOCK - 1) / C0_SUM_BLOCK;
#pragma omp parallel for schedule(static) if (L > 100000)
	for (size_t b = 0; b < nb; b++) {
		const size_t i0 = b * C0_SUM_BLOCK, i1 = L - i0 < C0_SUM_BLOCK ? L : i0 + C0_SUM_BLOCK;
		double xc = 0, xax = 0, xn = 0, x1 = 0;
		for (size_t i = i0; i < i1; i++)
			if (x[i] != 0)
				xc += x[i] * C[i], xax += x[i] * Ax[i], xn += x[i] * n[i], x1 += x[i];
		c->part[4 * b] = xc, c->part[4 * b + 1] = xax, c->part[4 * b + 2] = xn, c->part[4 * b + 3] = x1;
	}
	out[0] = out[1] = out[2] = out[3] = 0;
	for (size_t b = 0; b < nb; b++)
		for (int k = 0; k < 4; k++)
			out[k] += c->part[4 * b + k];
}

/* f(x) on the whole grid: A^T A x in c->Ax, the sums (grid_sums), s */
static double grid_objective(struct c0_covfit *c, const double *x, double sum[4], double *s)
{
	c0_covop_normal(c->op, x, c->Ax);
	grid_sums(c, x, sum);
	return objective(c, sum[0], sum[1], sum[2], s);
}

double c0_covfit_smooth(void *vctx, const double *x, double *g)
{
	struct c0_covfit *c = vctx;
	const struct c0_covop *op = c->op;
	const size_t L = (size_t)op->Ly * op->Lx;
	double sum[4], s;
	const double f = grid_objective(c, x, sum, &s);
#pragma omp parallel for if (L > 100000)
	for (size_t i = 0; i < L; i++)
		g[i] = c->Ax[i] + s * op->n[i] - c->C[i];
	return f;
}

int c0_covfit_ws_init(struct c0_covfit_ws *w, struct c0_covfit *c)
{
	*w = (struct c0_covfit_ws){ c, { 0 }, NULL, NULL };
	return c0_covnormal_init(&w->N, c->op);
}

void c0_covfit_ws_free(struct c0_covfit_ws *w)
{
	c0_covnormal_free(&w->N);
	free(w->cw), free(w->nw);
}

/* cw and nw: C and the column norms on the set */
int c0_covfit_ws_set(struct c0_covfit_ws *w, const uint8_t *in, const double *x, double *xw)
{
	c0_covnormal_set(&w->N, in);
	const size_t nws = w->N.nws, *ws = w->N.ws;
	for (size_t k = 0; k < nws; k++)
		xw[k] = x[ws[k]];
	free(w->cw), free(w->nw);
	w->cw = c0_alloc(nws, sizeof *w->cw), w->nw = c0_alloc(nws, sizeof *w->nw);
	if (!w->cw || !w->nw)
		return C0_ENOMEM;
	for (size_t k = 0; k < nws; k++)
		w->cw[k] = w->f->C[ws[k]], w->nw[k] = w->f->op->n[ws[k]];
	return C0_OK;
}

void c0_covfit_ws_scatter(const struct c0_covfit_ws *w, const double *vw, double *v)
{
	memset(v, 0, (size_t)w->f->op->Ly * w->f->op->Lx * sizeof *v);
	for (size_t k = 0; k < w->N.nws; k++)
		v[w->N.ws[k]] = vw[k];
}

double c0_covfit_ws_smooth(void *vctx, const double *xw, double *gw)
{
	struct c0_covfit_ws *w = vctx;
	c0_covnormal_apply(&w->N, xw, gw);
	double xc = 0, xax = 0, xn = 0, s;
	for (size_t k = 0; k < w->N.nws; k++)
		xc += xw[k] * w->cw[k], xax += xw[k] * gw[k], xn += xw[k] * w->nw[k];
	const double f = objective(w->f, xc, xax, xn, &s);
	for (size_t k = 0; k < w->N.nws; k++)
		gw[k] += s * w->nw[k] - w->cw[k];
	return f;
}

double c0_covfit_ws_lip(struct c0_covfit_ws *w, double lip, double *one, double *g)
{
	for (size_t k = 0; k < w->N.nws; k++)
		one[k] = 1;
	c0_covnormal_apply(&w->N, one, g);
	double rs = 0;
	for (size_t k = 0; k < w->N.nws; k++)
		rs = fmax(rs, g[k]);
	return fmin(lip, rs);
}

/* Relative duality gap of the l1 problem at x >= 0 (with s in closed form):
 * the residual rho = R - A x - s I scaled into the dual feasible set,
 * theta = rho / max(1, max_a (A^T rho)_a / lam), gives
 *   D = <R, theta> - ||theta||^2 / 2 <= P* <= P = ||rho||^2 / 2 + lam sum x,
 * and every term is one of the sums the objective needs already. */
double c0_covfit_gap(void *vctx, const double *x)
{
	struct c0_covfit *c = vctx;
	const struct c0_covop *op = c->op;
	const size_t L = (size_t)op->Ly * op->Lx;
	double sum[4], s;
	const double f = grid_objective(c, x, sum, &s);
	const double xc = sum[0], x1 = sum[3];
	double worst = 0;      /* max_a (A^T rho)_a = max_a -g_a */
#pragma omp parallel for reduction(max : worst) if (L > 100000)
	for (size_t i = 0; i < L; i++)
		worst = fmax(worst, c->C[i] - c->Ax[i] - s * op->n[i]);
	const double P = f + c->lam * x1, k = fmax(1, worst / c->lam);
	const double D = (c->R2 - xc - s * c->trR) / k - f / (k * k);
	return (P - D) / fmax(P, 1e-300);
}
