#include "stages/support.h"
#include "ops/covop.h"
#include "optics/psf.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int c0_support_lag(const struct c0_support_conf *c)
{
	return c->lag > 0 ? c->lag : (int)ceil(6 * c0_psf_sigma_px(c->fwhm_nm, c->pixel_nm));
}

double c0_support_default_lambda(enum c0_penalty p)
{
	return p == C0_PENALTY_CEL0 ? 3e-5 : 1e-2;
}

static double lambda_rel(const struct c0_support_conf *c)
{
	return c->lambda_rel > 0 ? c->lambda_rel : c0_support_default_lambda(c->penalty);
}

int c0_support_check(const struct c0_support_conf *c, int W, int H, int64_t frames, const char *name)
{
	if (!(c->pixel_nm > 0))
		return c0_fail(C0_EINVAL, "pixel_nm %g: must be positive (nm; not found in %s's calibration)", c->pixel_nm, name);
	int st = c0_psf_check(c->pixel_nm, c->fwhm_nm, c->srf);
	if (st)
		return st;
	if (!(c->lambda_rel >= 0 && c->lambda_rel < 1))
		return c0_fail(C0_EINVAL, "lambda %g: must be in (0, 1) (relative to lambda_max)", c->lambda_rel);
	if (c->fista.maxit < 1 || !(c->fista.tol > 0 && isfinite(c->fista.tol)))
		return c0_fail(C0_EINVAL, "iterations %d / tol %g: must be positive", c->fista.maxit, c->fista.tol);
	if (c->penalty == C0_PENALTY_CEL0 && c->cel0_outer < 1)
		return c0_fail(C0_EINVAL, "reweightings %d: must be at least 1", c->cel0_outer);
	if (c->lag < 0 || c->lag > 1000)
		return c0_fail(C0_EINVAL, "lag %d: must be 0 (from the PSF) to 1000 pixels", c->lag);
	int d = c0_support_lag(c);
	if (W < 2 * d + 1 || H < 2 * d + 1)
		return c0_fail(C0_EINVAL, "%s: %dx%d pixels is smaller than the PSF band (%d x %d pixels for lag %d)",
			       name, W, H, 2 * d + 1, 2 * d + 1, d);
	if (frames < 3)
		return c0_fail(C0_EINVAL, "%s: %lld frames; the covariance needs at least 3", name, (long long)frames);
	return C0_OK;
}

void c0_support_result_free(struct c0_support_result *r)
{
	free(r->mask), free(r->rx), free(r->mean), free(r->hist);
	memset(r, 0, sizeof *r);
}

struct ctx {
	struct c0_covop *op;
	const double *C;
	double trR, R2, HW;
	double *Ax;
	const uint8_t *mask;     /* if set, x is free only here */
};

/* f(x) = min_s 1/2 ||R - M(x) - s I||^2 (s in closed form) and its gradient */
static double smooth(void *vctx, const double *x, double *g)
{
	struct ctx *c = vctx;
	const struct c0_covop *op = c->op;
	const size_t L = (size_t)op->Ly * op->Lx;
	c0_covop_normal(c->op, x, c->Ax);
	double xc = 0, xax = 0, xn = 0;
#pragma omp parallel for reduction(+ : xc, xax, xn) if (L > 100000)
	for (size_t i = 0; i < L; i++)
		xc += x[i] * c->C[i], xax += x[i] * c->Ax[i], xn += x[i] * op->n[i];
	double s = fmax(0, (c->trR - xn) / c->HW);
#pragma omp parallel for if (L > 100000)
	for (size_t i = 0; i < L; i++)
		g[i] = c->mask && !c->mask[i] ? 0 : c->Ax[i] + s * op->n[i] - c->C[i];
	return 0.5 * c->R2 - xc - s * c->trR + 0.5 * xax + s * xn + 0.5 * s * s * c->HW;
}

static int solve(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask,
		 struct c0_support_result *res);

int c0_support_solve(const struct c0_support_conf *c, const struct c0_cov *cov, struct c0_support_result *res)
{
	return solve(c, cov, NULL, res);
}

int c0_support_noise(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask, double *sigma2)
{
	struct c0_support_conf cc = *c;
	cc.penalty = C0_PENALTY_L1;
	cc.fista.maxit = 100;   /* sigma2 within 0.1 % of 1000 iterations (docs/parameters.md) */
	struct c0_support_result r;
	memset(&r, 0, sizeof r);
	int st = solve(&cc, cov, mask, &r);
	*sigma2 = r.sigma2;
	c0_support_result_free(&r);
	return st;
}

static int solve(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask,
		 struct c0_support_result *res)
{
	double t0 = c0_now();
	const int W = cov->W, H = cov->H, r = c->srf;
	const size_t n = (size_t)W * H, L = n * r * r;
	struct c0_covop op;
	int st = c0_covop_init(&op, H, W, r, c0_psf_sigma_px(c->fwhm_nm, c->pixel_nm), cov->d);
	if (st)
		return st;
	double *R = c0_alloc((size_t)cov->nlag * n, sizeof *R), *C = c0_alloc(L, sizeof *C);
	double *x = c0_alloc(L, sizeof *x), *Ax = c0_alloc(L, sizeof *Ax);
	res->Ly = H * r, res->Lx = W * r, res->lag = cov->d, res->nlag = cov->nlag, res->frames = cov->frames;
	res->mask = c0_alloc(L, 1);
	res->rx = c0_alloc(L, sizeof *res->rx);
	res->nhist = c->fista.maxit * (c->penalty == C0_PENALTY_CEL0 ? c->cel0_outer : 1);
	res->hist = c0_alloc((size_t)res->nhist, sizeof *res->hist);
	if (!R || !C || !x || !Ax || !res->mask || !res->rx || !res->hist) {
		st = C0_ENOMEM;
		goto out;
	}
	/* normalise by the largest pixel variance, as the reference does, so that
	 * lambda and tolerances do not depend on the camera's units */
	double mx = 0;
	for (size_t i = 0; i < n; i++)
		mx = fmax(mx, cov->r[i]);
	if (!(mx > 0)) {
		st = c0_fail(C0_EINVAL, "the stack does not fluctuate (zero temporal variance everywhere)");
		goto out;
	}
	res->norm = mx;
	struct ctx ctx = { &op, C, 0, 0, (double)n, Ax, mask };
	for (int l = 0; l < cov->nlag; l++) {
		double w = c0_cov_weight(cov, l);
		for (size_t i = 0; i < n; i++) {
			double v = cov->r[(size_t)l * n + i] / mx;
			R[(size_t)l * n + i] = v;
			ctx.R2 += w * v * v;
			if (l == 0)
				ctx.trR += v;
		}
	}
	c0_covop_adjoint(&op, cov, R, C);
	/* lambda_max: the smallest lambda for which x = 0 (with s = tr R / HW) is optimal */
	double s0 = fmax(0, ctx.trR / ctx.HW), lmax = 0;
	for (size_t i = 0; i < L; i++) {
		double gi = C[i] - s0 * op.n[i];
		if (c->penalty == C0_PENALTY_L1)
			lmax = fmax(lmax, gi);
		else if (gi > 0)
			lmax = fmax(lmax, gi * gi / (2 * op.n[i] * op.n[i]));
	}
	res->lambda_max = lmax;
	res->lambda = mask ? 0 : lambda_rel(c) * lmax;
	struct c0_fista_info info = { .hist = res->hist, .nhist = res->nhist };
	if (lmax > 0 || mask) {
		if (c->penalty == C0_PENALTY_L1 || mask)
			st = c0_fista_nn(smooth, &ctx, L, op.lip, NULL, res->lambda, x, &c->fista, &info);
		else
			st = c0_irl1_cel0(smooth, &ctx, L, op.lip, op.n, res->lambda, x, &c->fista, c->cel0_outer, c->fista.tol, &info);
	}
	if (st)
		goto out;
	res->iters = info.iters;
	res->converged = lmax > 0 ? info.converged : 1;
	res->nhist = info.iters < res->nhist ? info.iters : res->nhist;
	double xn = 0;
	for (size_t i = 0; i < L; i++) {
		res->mask[i] = x[i] > 0;
		res->support_pixels += res->mask[i];
		res->rx[i] = (float)(x[i] * mx);
		xn += x[i] * op.n[i];
	}
	res->sigma2 = fmax(0, (ctx.trR - xn) / ctx.HW) * mx;
out:
	free(R), free(C), free(x), free(Ax);
	c0_covop_free(&op);
	res->t_solve = c0_now() - t0;
	return st;
}

int c0_stack_covariance(const struct c0_support_conf *c, struct c0_frames *in, struct c0_cov *cov, double *seconds)
{
	int st = c0_support_check(c, in->width, in->height, in->count, in->name);
	if (st)
		return st;
	double t0 = c0_now();
	struct c0_cov_acc *acc;
	if ((st = c0_cov_acc_new(in->width, in->height, c0_support_lag(c), &acc)))
		return st;
	float *frame = c0_alloc((size_t)in->width * in->height, sizeof *frame);
	if (!frame) {
		c0_cov_acc_free(acc);
		return C0_ENOMEM;
	}
	struct c0_progress pr;
	c0_progress_begin(&pr, "covariance", (double)in->count);
	for (int64_t t = 0; t < in->count && !st; t++) {
		st = c0_frames_read(in, t, frame);
		if (!st)
			st = c0_cov_acc_add(acc, frame);
		c0_progress_update(&pr, (double)t + 1);
	}
	c0_progress_end(&pr);
	free(frame);
	if (st) {
		c0_cov_acc_free(acc);
		return st;
	}
	st = c0_cov_acc_finish(acc, cov);
	*seconds = c0_now() - t0;
	return st;
}

int c0_stack_mean(const struct c0_support_conf *c, struct c0_frames *in, double **mean, int64_t *frames,
		  double *seconds)
{
	int st = c0_support_check(c, in->width, in->height, in->count, in->name);
	if (st)
		return st;
	double t0 = c0_now();
	const size_t n = (size_t)in->width * in->height;
	float *frame = c0_alloc(n, sizeof *frame);
	*mean = c0_alloc(n, sizeof **mean);
	if (!frame || !*mean) {
		free(frame), free(*mean), *mean = NULL;
		return C0_ENOMEM;
	}
	struct c0_progress pr;
	c0_progress_begin(&pr, "mean", (double)in->count);
	for (int64_t t = 0; t < in->count && !st; t++) {
		st = c0_frames_read(in, t, frame);
		for (size_t i = 0; !st && i < n; i++)
			(*mean)[i] += frame[i];
		c0_progress_update(&pr, (double)t + 1);
	}
	c0_progress_end(&pr);
	free(frame);
	for (size_t i = 0; !st && i < n; i++)
		(*mean)[i] /= (double)in->count;
	if (st)
		free(*mean), *mean = NULL;
	*frames = in->count;
	*seconds = c0_now() - t0;
	return st;
}

int c0_support_stack(const struct c0_support_conf *c, struct c0_frames *in, struct c0_support_result *res)
{
	memset(res, 0, sizeof *res);
	struct c0_cov cov;
	double tc;
	int st = c0_stack_covariance(c, in, &cov, &tc);
	if (st)
		return st;
	struct c0_progress ps;
	c0_progress_begin(&ps, "support", 1);
	st = c0_support_solve(c, &cov, res);
	c0_progress_end(&ps);
	res->t_cov = tc;
	if (!st) {
		res->mean = cov.mean;
		cov.mean = NULL;
	}
	c0_cov_free(&cov);
	return st;
}
