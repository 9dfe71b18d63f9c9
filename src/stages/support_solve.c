/* One window's support solve (support.h's model) on the covariance fit
 * (ops/covfit.h): l1 by FISTA on shrinking working sets, CEL0 by
 * reweighting, the masked fit for the noise variance. */
#include "stages/support_parts.h"
#include "ops/covfit.h"
#include "ops/finevar.h"
#include "ops/ridge.h"
#include "optics/psf.h"
#include "core/c0math.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* join: a gradient g that would move the pixel by more than rounding
 * (1e-3 lambda); leave: at 0 and not pushed up. 1 when a pixel joined. */
static int ws_update(const struct c0_covfit *ctx, const double *x, const double *g, uint8_t *in)
{
	const size_t L = (size_t)ctx->op->Ly * ctx->op->Lx;
	int grew = 0;
	for (size_t i = 0; i < L; i++) {
		const double m = g[i] + ctx->lam;
		if (!in[i] && (x[i] > 0 || m < -1e-3 * ctx->lam))
			in[i] = 1, grew = 1;
		else if (in[i] && x[i] == 0 && m > 0)
			in[i] = 0;
	}
	return grew;
}

/* l1 by FISTA: a short run on the whole grid finds where the support can
 * be; then FISTA on the working set (pixels that are non-zero or whose
 * gradient would make them so), re-made every PIECE iterations and checked
 * on the whole grid whenever FISTA converges on it: pixels that would move
 * join, every pixel at 0 that is not pushed up leaves, and FISTA's momentum
 * is carried across. The set shrinks from the warm-up's blur (~5x the
 * support) towards the support, so the iterations get cheaper: at 512x512
 * the capped iterate's duality gap is 25x smaller, in 35 % less time, than
 * with a set kept until FISTA converged on it (docs/defaults.md#support_solver).
 * fista (the default) takes the whole grid's step; pruned, on each piece,
 * the longest step safe on its set (longer, as the set shrinks). */
#define WARMUP 30
#define PIECE 100
/* The working sets' part, after the warm-up (its momentum in xp; pw: L
 * doubles of workspace). */
static int solve_l1_sets(struct c0_covfit *ctx, const struct c0_fista_conf *fc, double lip, int pruned, double *x,
			 double *xp, double *pw, struct c0_fista_info *info)
{
	const size_t L = (size_t)ctx->op->Ly * ctx->op->Lx;
	int used = info->iters;
	struct c0_covfit_ws w;
	int st = c0_covfit_ws_init(&w, ctx);
	double *xw = c0_alloc(L, sizeof *xw), *one = pruned ? c0_alloc(L, sizeof *one) : NULL, *g = ctx->Ax;
	uint8_t *in = c0_alloc(L, 1);
	if (st || !xw || (pruned && !one) || !in) {
		st = C0_ENOMEM;
		goto out;
	}
	struct c0_fista_info part = *info;
	for (;;) {
		/* the gradient on the whole grid: who would move? */
		c0_covfit_smooth(ctx, x, g);
		if (!ws_update(ctx, x, g, in) && part.converged)
			break;
		if ((st = c0_covfit_ws_set(&w, in, x, xw)))
			break;
		for (size_t k = 0; k < w.N.nws; k++)
			pw[k] = xp[w.N.ws[k]];
		part.prev = pw;
		struct c0_fista_conf fw = *fc;
		fw.maxit = fc->maxit - used < PIECE ? fc->maxit - used : PIECE;
		part.hist = info->hist ? info->hist + used : NULL;
		part.nhist = info->hist && info->nhist > used ? info->nhist - used : 0;
		const double lw = pruned ? c0_covfit_ws_lip(&w, lip, one, g) : lip;
		if ((st = c0_fista_nn(c0_covfit_ws_smooth, &w, w.N.nws, lw, NULL, ctx->lam, xw, &fw, &part)))
			break;
		used += part.iters;
		c0_covfit_ws_scatter(&w, xw, x);
		c0_covfit_ws_scatter(&w, pw, xp);
		if (used >= fc->maxit) {
			part.converged = 0;
			break;
		}
	}
	info->iters = used, info->converged = part.converged, info->obj = part.obj;
	info->restarts += part.restarts;
out:
	c0_covfit_ws_free(&w);
	free(xw), free(one), free(in);
	return st;
}

static int solve_l1(struct c0_covfit *ctx, const struct c0_fista_conf *fc, double lip, int pruned, double *x,
		    struct c0_fista_info *info)
{
	const size_t L = (size_t)ctx->op->Ly * ctx->op->Lx;
	struct c0_fista_conf f0 = *fc;
	f0.maxit = fc->maxit < WARMUP ? fc->maxit : WARMUP;
	double *xp = c0_alloc(L, sizeof *xp), *pw = c0_alloc(L, sizeof *pw);
	if (!xp || !pw) {
		free(xp), free(pw);
		return C0_ENOMEM;
	}
	info->prev = xp, info->theta = 1;
	int st = c0_fista_nn(c0_covfit_smooth, ctx, L, lip, NULL, ctx->lam, x, &f0, info);
	info->prev = NULL;
	if (!st && !info->converged && info->iters < fc->maxit)
		st = solve_l1_sets(ctx, fc, lip, pruned, x, xp, pw, info);
	free(xp), free(pw);
	return st;
}

int c0_support_l1_warm(const struct c0_support_conf *c, struct c0_covfit *ctx, int maxit, double *x, int *iters)
{
	struct c0_fista_conf fc = { maxit, c0_support_tol(c) };
	struct c0_fista_info info = { 0 };
	int st = solve_l1(ctx, &fc, ctx->op->lip, c->solver == C0_SUPPORT_PRUNED, x, &info);
	*iters = info.iters;
	return st;
}

static int solve_masked(struct c0_covfit *ctx, const struct c0_fista_conf *fc, double lip, const uint8_t *mask, double *x,
			struct c0_fista_info *info);

int c0_support_refit(struct c0_covfit *ctx, int maxit, double *x)
{
	const size_t L = (size_t)ctx->op->Ly * ctx->op->Lx;
	uint8_t *mask = c0_alloc(L, 1);
	if (!mask)
		return C0_ENOMEM;
	for (size_t i = 0; i < L; i++)
		mask[i] = x[i] > 0;
	struct c0_fista_conf fc = { maxit, C0_SUPPORT_TOL };
	struct c0_fista_info info = { 0 };
	const double lam = ctx->lam;
	ctx->lam = 0;
	int st = solve_masked(ctx, &fc, ctx->op->lip, mask, x, &info);
	ctx->lam = lam;
	free(mask);
	return st;
}

/* lambda = 0 with x free only on the mask (the noise variance on a given
 * support): FISTA on the mask's pixels alone, the whole grid's step */
static int solve_masked(struct c0_covfit *ctx, const struct c0_fista_conf *fc, double lip, const uint8_t *mask, double *x,
			struct c0_fista_info *info)
{
	const size_t L = (size_t)ctx->op->Ly * ctx->op->Lx;
	struct c0_covfit_ws w;
	int st = c0_covfit_ws_init(&w, ctx);
	double *xw = c0_alloc(L, sizeof *xw);
	if (!st && xw && !(st = c0_covfit_ws_set(&w, mask, x, xw))) {
		st = c0_fista_nn(c0_covfit_ws_smooth, &w, w.N.nws, lip, NULL, 0, xw, fc, info);
		for (size_t k = 0; !st && k < w.N.nws; k++)
			x[w.N.ws[k]] = xw[k];
	} else if (!st)
		st = C0_ENOMEM;
	c0_covfit_ws_free(&w);
	free(xw);
	return st;
}

int c0_support_covop(const struct c0_support_conf *c, const struct c0_cov *cov, struct c0_covop *op)
{
	return c0_covop_init(op, cov->H, cov->W, c->grid.srf, c0_grid_sigma_px(&c->grid), cov->d);
}

void c0_support_correlate(struct c0_covop *op, const struct c0_cov *cov, double norm, double *C, double *trR,
			  double lm[2])
{
	const size_t n = (size_t)cov->W * cov->H;
	*trR = 0;
	for (size_t i = 0; i < n; i++)
		*trR += cov->r[i] / norm;
	c0_covop_adjoint(op, cov, cov->r, C);
	/* lambda_max: the smallest lambda for which x = 0 (with s = tr R / HW) is optimal */
	c0_lambda_max(C, norm, fmax(0, *trR / (double)n), op->n, (size_t)op->Ly * op->Lx, lm);
}

/* ctx's sums of R / mx and C = A^T (R / mx), mx the largest pixel variance
 * of the window or g's (as the reference does, so that lambda and
 * tolerances do not depend on the camera's units); res->norm, lambda_max
 * and lambda */
static int normalise(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask, double **band,
		     const struct c0_support_scale *g, struct c0_covfit *ctx, double *C, struct c0_support_result *res)
{
	const size_t n = (size_t)cov->W * cov->H, L = (size_t)ctx->op->Ly * ctx->op->Lx;
	double mx = 0;
	for (size_t i = 0; i < n; i++)
		mx = fmax(mx, cov->r[i]);
	if (g)
		mx = g->norm;
	if (!(mx > 0))
		return c0_support_fail_flat();
	res->norm = mx;
	for (int l = 0; l < cov->nlag; l++) {
		double w = c0_cov_weight(cov, l);
		for (size_t i = 0; i < n; i++) {
			double v = cov->r[(size_t)l * n + i] / mx;
			ctx->R2 += w * v * v;
		}
	}
	/* C without a normalised copy of the band; on a mask, the masked fit
	 * reads C only there (and needs no lambda_max) */
	double lm[2] = { 0, 0 };
	if (mask) {
		ctx->trR = 0;
		for (size_t i = 0; i < n; i++)
			ctx->trR += cov->r[i] / mx;
		c0_covop_adjoint_on(ctx->op, cov, cov->r, mask, C);
	} else
		c0_support_correlate(ctx->op, cov, mx, C, &ctx->trR, lm);
	for (size_t i = 0; i < L; i++)
		C[i] /= mx;
	if (band)
		free(*band), *band = NULL;
	res->lambda_max = lm[c->penalty != C0_PENALTY_L1];
	res->lambda = mask ? 0 : g ? g->lam : c0_support_lambda_rel(c) * res->lambda_max;
	ctx->lam = res->lambda;
	return C0_OK;
}

/* The solver for c (x = 0 when lambda >= lambda_max), and res from x */
static int run(const struct c0_support_conf *c, const uint8_t *mask, struct c0_covfit *ctx, double *x,
	       struct c0_support_result *res)
{
	struct c0_covop *op = ctx->op;
	const size_t L = (size_t)op->Ly * op->Lx;
	const double lmax = res->lambda_max;
	struct c0_fista_info info = { .hist = res->hist, .nhist = res->nhist };
	struct c0_fista_conf fc = { c->fista.maxit, c0_support_tol(c) };
	int st = C0_OK;
	if (lmax > res->lambda || mask) {      /* else x = 0 is the answer */
		if (mask)
			st = solve_masked(ctx, &fc, op->lip, mask, x, &info);
		else if (c->penalty == C0_PENALTY_L1)
			st = solve_l1(ctx, &fc, op->lip, c->solver == C0_SUPPORT_PRUNED, x, &info);
		else
			st = c0_irl1_cel0(c0_covfit_smooth, ctx, L, op->lip, op->n, res->lambda, x, &fc, c->cel0_outer, fc.tol, &info);
	}
	if (st)
		return st;
	res->iters = info.iters;
	res->converged = lmax > res->lambda || mask ? info.converged : 1;
	res->gap = c->penalty == C0_PENALTY_L1 && !mask && lmax > res->lambda ? c0_covfit_gap(ctx, x) : 0;
	res->nhist = info.iters < res->nhist ? info.iters : res->nhist;
	double xn = 0;
	for (size_t i = 0; i < L; i++) {
		res->mask[i] = x[i] > 0;
		res->support_pixels += res->mask[i];
		res->rx[i] = (float)(x[i] * res->norm);
		xn += x[i] * op->n[i];
	}
	res->sigma2 = fmax(0, (ctx->trR - xn) / ctx->HW) * res->norm;
	return C0_OK;
}

/* A labelled structure's fluorophores lie up to label_radius_nm from its
 * axis, so every fine pixel whose centre is within that and half a fine
 * pixel of the axis holds some. The l1 support marks about one pixel across
 * a structure, near its axis; the axis is a crest of the pixel variance the
 * fit x predicts on the fine grid (ops/finevar.h): free of the measured
 * variances' noise and background, and its profile across a line is the
 * PSF's squared, narrower than C = A^T R's, so that a neighbouring structure
 * pulls it less (docs/defaults.md#label_radius_nm). The support's
 * 4-neighbours that close to a crest join it (their rx stays 0: the solve
 * put no variance there). */
static int grow_support(const struct c0_support_conf *c, const double *x, struct c0_support_result *res)
{
	const double fine = c->grid.pixel_nm / c->grid.srf;
	double *v = c0_alloc((size_t)res->Ly * res->Lx, sizeof *v);
	if (!v)
		return C0_ENOMEM;
	if (c0_finevar(x, res->Ly, res->Lx, c->grid.srf, c0_grid_sigma_px(&c->grid), v)) {
		free(v);
		return C0_ENOMEM;
	}
	const long n = c0_ridge_grow(v, res->Ly, res->Lx, c->label_radius_nm / fine + 0.5, res->mask);
	free(v);
	if (n < 0)
		return C0_ENOMEM;
	res->support_pixels += (int)n;
	return C0_OK;
}

struct c0_support_conf c0_support_halves_conf(const struct c0_support_conf *c)
{
	struct c0_support_conf cc = *c;
	if (cc.fista.maxit > C0_SUPPORT_FRC_MAXIT)
		cc.fista.maxit = C0_SUPPORT_FRC_MAXIT;
	cc.label_radius_nm = 0;
	return cc;
}

int c0_support_window_solve(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask,
			    double **band, const struct c0_support_scale *g, struct c0_support_result *res)
{
	double t0 = c0_now();
	const int W = cov->W, H = cov->H, r = c->grid.srf;
	const size_t n = (size_t)W * H, L = n * r * r;
	struct c0_covop op;
	int st = c0_support_covop(c, cov, &op);
	if (st)
		return st;
	double *C = c0_alloc(L, sizeof *C);
	double *x = c0_alloc(L, sizeof *x), *Ax = c0_alloc(L, sizeof *Ax);
	const int grow = !mask && c->label_radius_nm > 0;
	double *part = c0_alloc(4 * ((L + C0_SUM_BLOCK - 1) / C0_SUM_BLOCK), sizeof *part);
	res->Ly = H * r, res->Lx = W * r, res->lag = cov->d, res->nlag = cov->nlag, res->frames = cov->frames;
	res->mask = c0_alloc(L, 1);
	res->rx = c0_alloc(L, sizeof *res->rx);
	res->nhist = c->fista.maxit * (c->penalty == C0_PENALTY_CEL0 ? c->cel0_outer : 1);
	res->hist = c0_alloc((size_t)res->nhist, sizeof *res->hist);
	struct c0_covfit ctx = { &op, C, 0, 0, (double)n, Ax, 0, part };
	if (!C || !x || !Ax || !part || !res->mask || !res->rx || !res->hist)
		st = C0_ENOMEM;
	if (!st)
		st = normalise(c, cov, mask, band, g, &ctx, C, res);
	if (!st)
		st = run(c, mask, &ctx, x, res);
	if (!st && grow)
		st = grow_support(c, x, res);
	free(C), free(x), free(Ax), free(part);
	c0_covop_free(&op);
	res->t_solve = c0_now() - t0;
	return st;
}

int c0_support_solve(const struct c0_support_conf *c, const struct c0_cov *cov, struct c0_support_result *res)
{
	return c0_support_window_solve(c, cov, NULL, NULL, NULL, res);
}

int c0_support_noise_solve(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask,
			   struct c0_support_result *res)
{
	struct c0_support_conf cc = *c;
	cc.penalty = C0_PENALTY_L1;
	if (cc.fista.tol < 0)    /* lambda = 0 on a mask: it converges, as before */
		cc.fista.tol = C0_SUPPORT_TOL;
	return c0_support_window_solve(&cc, cov, mask, NULL, NULL, res);
}
