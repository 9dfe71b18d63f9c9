/* The automatic l1 lambda by symmetric covariance cross-validation
 * (stages/lambda.h, c0_lambda_cv; measured in docs/defaults.md#lambda_rule). */
#include "stages/lambda.h"
#include "stages/support_parts.h"
#include "ops/covfit.h"
#include "core/c0math.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* One half on the path: its fit (normalised by the common norm) and iterate. */
struct half {
	struct c0_covfit fit;
	double *C, *x, *Ax, *part, *xr;
};

static int half_open(struct c0_covop *op, const struct c0_cov *cov, double norm, struct half *h)
{
	const size_t n = (size_t)cov->W * cov->H, L = (size_t)op->Ly * op->Lx;
	memset(h, 0, sizeof *h);
	h->xr = c0_alloc(L, sizeof *h->xr), h->C = c0_alloc(L, sizeof *h->C), h->x = c0_alloc(L, sizeof *h->x), h->Ax = c0_alloc(L, sizeof *h->Ax);
	h->part = c0_alloc(4 * ((L + C0_SUM_BLOCK - 1) / C0_SUM_BLOCK), sizeof *h->part);
	if (!h->xr || !h->C || !h->x || !h->Ax || !h->part)
		return C0_ENOMEM;
	struct c0_covfit f = { op, h->C, 0, 0, (double)n, h->Ax, 0, h->part };
	for (int l = 0; l < cov->nlag; l++)
		for (size_t i = 0; i < n; i++) {
			const double v = cov->r[(size_t)l * n + i] / norm;
			f.R2 += c0_cov_weight(cov, l) * v * v;
			if (l == 0)
				f.trR += v;
		}
	c0_covop_adjoint(op, cov, cov->r, h->C);
	for (size_t i = 0; i < L; i++)
		h->C[i] /= norm;
	h->fit = f;
	return C0_OK;
}

static void half_close(struct half *h)
{
	free(h->C), free(h->x), free(h->Ax), free(h->part), free(h->xr);
}

/* The weighted squared error of the model m (forward of a half's x) against
 * the other half's covariance over the lags != 0 (normalised), on the
 * pixels of the interior in (y, x, h, w), added to eb per block of B x B of
 * them (nbx across); m NULL: of x = 0. */
static void off_error(const struct c0_cov *other, double norm, const double *m, const int in[4], int B, int nbx,
		      double *eb)
{
	const size_t n = (size_t)other->W * other->H;
	for (int l = 0; l < other->nlag; l++) {
		if (other->dy[l] == 0 && other->dx[l] == 0)
			continue;
		const double w = c0_cov_weight(other, l);
		for (int y = 0; y < in[2]; y++)
			for (int x = 0; x < in[3]; x++) {
				const size_t i = (size_t)(y + in[0]) * other->W + x + in[1];
				const double d = other->r[(size_t)l * n + i] / norm - (m ? m[(size_t)l * n + i] : 0);
				eb[(y / B) * nbx + x / B] += w * d * d;
			}
	}
}

/* lambda_max of the halves' mean (as c0_lambda_auto reads it) and the norm */
static int path_scale(const struct c0_covop *op, const struct c0_cov *a, const struct half h[2], double *lmax)
{
	const size_t n = (size_t)a->W * a->H, L = (size_t)op->Ly * op->Lx;
	double *m = c0_alloc(L, sizeof *m), lm[2];
	if (!m)
		return C0_ENOMEM;
	for (size_t i = 0; i < L; i++)
		m[i] = 0.5 * (h[0].C[i] + h[1].C[i]);
	c0_lambda_max(m, 1, fmax(0, 0.5 * (h[0].fit.trR + h[1].fit.trR) / (double)n), op->n, L, lm);
	free(m);
	*lmax = lm[0];
	return lm[0] > 0 ? C0_OK
			 : c0_fail(C0_EINVAL, "the stack's covariance correlates with no emitter position (lambda_max = 0)");
}

double c0_lambda_cv_rel(int k)
{
	return C0_LAMBDA_CV_TOP * pow(2, -0.5 * k);
}

int c0_lambda_cv_first(double rule_rel)
{
	int k = 0;
	while (k < C0_LAMBDA_CV_MAX - C0_LAMBDA_CV_PATIENCE - 1 && c0_lambda_cv_rel(k) > C0_LAMBDA_CV_START * rule_rel)
		k++;
	return k;
}

/* The path, point by point to C0_LAMBDA_CV_PATIENCE after its least: the
 * errors per block into eb (npts rows of nb), the sums into v */
static int path(const struct c0_support_conf *c, struct c0_covop *op, const struct c0_cov *hv[2], double norm,
		double lmax, int k0, int min_pts, const int in[4], struct half h[2], double *m, double *eb,
		struct c0_lambda_cv_sums *v)
{
	const int B = hv[0]->d > 0 ? hv[0]->d : 1, nbx = (in[3] + B - 1) / B;
	const size_t nb = (size_t)nbx * ((in[2] + B - 1) / B);
	int st = C0_OK, best = -1;
	memset(eb, 0, nb * sizeof *eb);
	for (int j = 0; j < 2; j++)
		off_error(hv[1 - j], norm, NULL, in, B, nbx, eb);
	for (size_t b = 0; b < nb; b++)
		v->e0 += eb[b];
	for (int k = k0; k < C0_LAMBDA_CV_MAX && !st; k++) {
		double *e = eb + k * nb;
		memset(e, 0, nb * sizeof *e);
		for (int j = 0; j < 2 && !st; j++) {
			int it;
			h[j].fit.lam = c0_lambda_cv_rel(k) * lmax;
			/* the first point starts from x = 0: twice the budget */
			st = c0_support_l1_warm(c, &h[j].fit, (k == k0 ? 2 : 1) * C0_LAMBDA_CV_ITERS, h[j].x, &it);
			/* the prediction from the support alone, refitted without
			 * shrinkage: the l1 shrinkage would favour the lowest lambda */
			memcpy(h[j].xr, h[j].x, (size_t)op->Ly * op->Lx * sizeof *h[j].xr);
			if (!st)
				st = c0_support_refit(&h[j].fit, C0_LAMBDA_CV_REFIT, h[j].xr);
			c0_covop_forward(op, hv[1 - j], h[j].xr, m);
			off_error(hv[1 - j], norm, m, in, B, nbx, e);
		}
		for (size_t b = 0; b < nb; b++)
			v->err[k] += e[b];
		v->npts = k + 1;
		if (best < 0 || v->err[k] < v->err[best])
			best = k;
		/* a tile's path (min_pts) runs on to min_pts: the tiles' sums
		 * hold the points all of them reached */
		if (k - best >= C0_LAMBDA_CV_PATIENCE && k + 1 - k0 >= min_pts)
			break;
	}
	/* the paired differences' sums, for the standard errors */
	for (int k = k0; k < (int)v->npts; k++)
		for (int q = k0; q < (int)v->npts; q++)
			for (size_t b = 0; b < nb; b++) {
				const double d = eb[k * nb + b] - eb[q * nb + b];
				v->s1[k][q] += d, v->s2[k][q] += d * d;
			}
	v->nb = (double)nb;
	return st;
}

int c0_lambda_cv_window(const struct c0_support_conf *c, const struct c0_cov *a, const struct c0_cov *b, double norm,
			double lmax, int k0, const int *interior, struct c0_lambda_cv_sums *v)
{
	memset(v, 0, sizeof *v);
	const int whole[4] = { 0, 0, a->H, a->W }, *in = interior ? interior : whole;
	if (a->W != b->W || a->H != b->H || a->nlag != b->nlag)
		return c0_fail(C0_EINVAL, "lambda: the two halves differ in size");
	const size_t n = (size_t)a->W * a->H;
	struct c0_covop op;
	int st = c0_support_covop(c, a, &op);
	if (st)
		return st;
	struct half h[2];
	memset(h, 0, sizeof h);
	const struct c0_cov *hv[2] = { a, b };
	const int B = a->d > 0 ? a->d : 1;
	const size_t nb = (size_t)((in[3] + B - 1) / B) * ((in[2] + B - 1) / B);
	double *m = c0_alloc((size_t)a->nlag * n, sizeof *m), *eb = c0_alloc(C0_LAMBDA_CV_MAX * nb, sizeof *eb);
	for (size_t i = 0; norm <= 0 && i < n; i++)
		norm = fmax(norm, 0.5 * (a->r[i] + b->r[i]));
	if (!(norm > 0))
		st = c0_support_fail_flat();
	for (int j = 0; j < 2 && !st; j++)
		st = half_open(&op, hv[j], norm, &h[j]);
	if (!st && (!m || !eb))
		st = C0_ENOMEM;
	if (!st && !(lmax > 0))
		st = path_scale(&op, a, h, &lmax);
	if (!st)
		st = path(c, &op, hv, norm, lmax, k0, interior ? C0_LAMBDA_CV_TILE_POINTS : 0, in, h, m, eb, v);
	half_close(&h[0]), half_close(&h[1]);
	free(m), free(eb);
	c0_covop_free(&op);
	return st;
}

void c0_lambda_cv_choose(const struct c0_lambda_cv_sums *v, int k0, struct c0_lambda_result *out)
{
	const int n = (int)v->npts;
	int best = k0, pick;
	for (int k = k0; k < n; k++) {
		out->cv_rel[k - k0] = c0_lambda_cv_rel(k), out->cv_err[k - k0] = v->e0 > 0 ? v->err[k] / v->e0 : v->err[k];
		if (v->err[k] < v->err[best])
			best = k;
	}
	/* the largest lambda within one standard error of the least (the
	 * error's difference to it over the blocks, paired) */
	for (pick = k0; pick < best; pick++) {
		const double d = v->err[pick] - v->err[best];
		const double se = sqrt(fmax(0, v->s2[pick][best] - v->s1[pick][best] * v->s1[pick][best] / v->nb));
		out->cv_se[pick - k0] = se / (v->e0 > 0 ? v->e0 : 1);
		if (d <= se)
			break;
	}
	out->cv = n > k0, out->cv_points = n - k0, out->cv_min = best - k0, out->cv_pick = pick - k0;
	out->cv_iters = C0_LAMBDA_CV_ITERS;
	/* each half's covariance has twice the noise variance of the whole's:
	 * lambda follows the noise sd, so the whole's is the halves' over sqrt 2 */
	if (n > k0)
		out->chosen_rel = C0_LAMBDA_CV_WHOLE * c0_lambda_cv_rel(pick);
}

int c0_lambda_cv(const struct c0_support_conf *c, const struct c0_cov *a, const struct c0_cov *b,
		 struct c0_lambda_result *out)
{
	const double t0 = c0_now();
	struct c0_lambda_cv_sums *v = c0_alloc(1, sizeof *v);
	const int k0 = c0_lambda_cv_first(out->chosen_rel);
	int st = v ? c0_lambda_cv_window(c, a, b, 0, 0, k0, NULL, v) : C0_ENOMEM;
	if (!st)
		c0_lambda_cv_choose(v, k0, out);
	free(v);
	out->cv_seconds = c0_now() - t0;
	out->seconds += out->cv_seconds;
	return st;
}
