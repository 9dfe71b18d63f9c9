#include "stages/support.h"
#include "ops/covop.h"
#include "ops/covpool.h"
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
	c0_frc_free(&r->frc);
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

static int solve(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask, const float *x0,
		 struct c0_support_result *res);

int c0_support_solve(const struct c0_support_conf *c, const struct c0_cov *cov, struct c0_support_result *res)
{
	return solve(c, cov, NULL, NULL, res);
}

int c0_support_noise(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask, double *sigma2)
{
	struct c0_support_conf cc = *c;
	cc.penalty = C0_PENALTY_L1;
	cc.fista.maxit = 100;   /* sigma2 within 0.1 % of 1000 iterations (docs/parameters.md) */
	struct c0_support_result r;
	memset(&r, 0, sizeof r);
	int st = solve(&cc, cov, mask, NULL, &r);
	*sigma2 = r.sigma2;
	c0_support_result_free(&r);
	return st;
}

/* x0 (or NULL): a start in camera units (rx of another solve) */
static int solve(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask, const float *x0,
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
	for (size_t i = 0; x0 && i < L; i++)
		x[i] = x0[i] / mx;
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

/* One pass; frames alternate between the nacc accumulators (1 or 2). */
static int stream_cov(const struct c0_support_conf *c, struct c0_frames *in, int nacc, struct c0_cov *cov,
		      double *seconds)
{
	int st = c0_support_check(c, in->width, in->height, in->count, in->name);
	if (!st && nacc == 2 && in->count < 6)
		st = c0_fail(C0_EINVAL, "%s: %lld frames is too short to choose lambda from two halves (needs >= 6; "
			     "give lambda)", in->name, (long long)in->count);
	if (st)
		return st;
	double t0 = c0_now();
	struct c0_cov_acc *acc[2] = { NULL, NULL };
	for (int k = 0; k < nacc && !st; k++)
		st = c0_cov_acc_new(in->width, in->height, c0_support_lag(c), &acc[k]);
	float *frame = st ? NULL : c0_alloc((size_t)in->width * in->height, sizeof *frame);
	if (!st && !frame)
		st = C0_ENOMEM;
	struct c0_progress pr;
	c0_progress_begin(&pr, "covariance", (double)in->count);
	for (int64_t t = 0; t < in->count && !st; t++) {
		st = c0_frames_read(in, t, frame);
		if (!st && c->frame_fn)
			st = c->frame_fn(c->frame_ctx, t, frame, in->height, in->width);
		if (!st)
			st = c0_cov_acc_add(acc[t % nacc], frame);
		c0_progress_update(&pr, (double)t + 1);
	}
	c0_progress_end(&pr);
	free(frame);
	for (int k = 0; k < nacc; k++) {
		if (st)
			c0_cov_acc_free(acc[k]);
		else if ((st = c0_cov_acc_finish(acc[k], &cov[k])))
			for (int j = k + 1; j < nacc; j++)
				c0_cov_acc_free(acc[j]);
	}
	*seconds = c0_now() - t0;
	return st;
}

int c0_stack_covariance(const struct c0_support_conf *c, struct c0_frames *in, struct c0_cov *cov, double *seconds)
{
	return stream_cov(c, in, 1, cov, seconds);
}

int c0_stack_covariance_halves(const struct c0_support_conf *c, struct c0_frames *in, struct c0_cov half[2],
			       double *seconds)
{
	return stream_cov(c, in, 2, half, seconds);
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
		if (!st && c->frame_fn)
			st = c->frame_fn(c->frame_ctx, t, frame, in->height, in->width);
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

/* Each half solved on its own (a warm start from the full solution would
 * make them agree) at the same relative lambda, with at most FRC_MAXIT
 * iterations; the FRC of their emitter variances, and the localisation
 * precision from how far their supports lie apart. */
#define FRC_MAXIT 300
static int half_frc(const struct c0_support_conf *c, const struct c0_cov half[2], struct c0_support_result *res)
{
	double t0 = c0_now();
	struct c0_support_result h[2];
	memset(h, 0, sizeof h);
	struct c0_support_conf cc = *c;
	cc.lambda_rel = res->lambda_max > 0 ? res->lambda / res->lambda_max : c0_support_default_lambda(c->penalty);
	if (cc.fista.maxit > FRC_MAXIT)
		cc.fista.maxit = FRC_MAXIT;
	int st = C0_OK;
	for (int k = 0; k < 2 && !st; k++)
		st = solve(&cc, &half[k], NULL, NULL, &h[k]);
	if (!st)
		st = c0_frc_compute(h[0].rx, h[1].rx, res->Ly, res->Lx, &res->frc);
	if (!st) {
		const double fine = c->pixel_nm / c->srf;
		res->frc_nm = res->frc.resolution_px * fine;
		/* match within the PSF's half width at half maximum */
		double p = c0_pair_precision(h[0].mask, h[1].mask, res->Ly, res->Lx, (int)ceil(0.5 * c->fwhm_nm / fine));
		res->precision_nm = p < 0 ? -1 : p * fine / sqrt(2);
	}
	c0_support_result_free(&h[0]), c0_support_result_free(&h[1]);
	res->t_frc = c0_now() - t0;
	return st;
}

int c0_support_stack(const struct c0_support_conf *c, struct c0_frames *in, struct c0_support_result *res)
{
	memset(res, 0, sizeof *res);
	struct c0_cov cov = { 0 }, half[2] = { { 0 } };
	struct c0_support_conf cc = *c;
	const int automatic = !(c->lambda_rel > 0), halves = automatic || c->frc;
	double tc;
	int st = halves ? c0_stack_covariance_halves(c, in, half, &tc) : c0_stack_covariance(c, in, &cov, &tc);
	if (!st && halves) {
		double t0 = c0_now();
		st = c0_cov_pool(&half[0], &half[1], &cov);
		tc += c0_now() - t0;
	}
	struct c0_progress ps;
	c0_progress_begin(&ps, "support", 1);
	if (!st && automatic && !(st = c0_lambda_auto(c, &half[0], &half[1], &res->cv)))
		cc.lambda_rel = res->cv.chosen_rel, res->lambda_auto = 1;
	if (!st)
		st = c0_support_solve(&cc, &cov, res);
	if (!st && c->frc)
		st = half_frc(&cc, half, res);
	c0_cov_free(&half[0]), c0_cov_free(&half[1]);
	c0_progress_end(&ps);
	res->t_cov = tc;
	if (!st) {
		res->mean = cov.mean;
		cov.mean = NULL;
	}
	c0_cov_free(&cov);
	return st;
}
