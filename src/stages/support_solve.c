/* One window's support solve (support.h's model): the objective on the
 * whole grid and on a working set, l1 by FISTA on shrinking working sets,
 * CEL0 by reweighting, the masked fit for the noise variance, and the
 * duality gap. */
#include "stages/support_parts.h"
#include "ops/covnormal.h"
#include "optics/psf.h"
#include "core/c0math.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct ctx {
	struct c0_covop *op;
	const double *C;
	double trR, R2, HW;
	double *Ax;
	double lam;
	double *part;        /* 4 per C0_SUM_BLOCK of the grid: the sums' blocks */
};

/* f(x) = min_s 1/2 ||R - M(x) - s I||^2 from <x, C>, <x, A^T A x> and
 * <x, n>; *s the minimising s */
static double objective(const struct ctx *c, double xc, double xax, double xn, double *s)
{
	*s = fmax(0, (c->trR - xn) / c->HW);
	return 0.5 * c->R2 - xc - *s * c->trR + 0.5 * xax + *s * xn + 0.5 * *s * *s * c->HW;
}

/* <x, C>, <x, A^T A x>, <x, n> and sum x over the grid (A^T A x in c->Ax),
 * in blocks (C0_SUM_BLOCK): s, from <x, n>, moves the iterates */
static void grid_sums(struct ctx *c, const double *x, double out[4])
{
	const double *n = c->op->n, *C = c->C, *Ax = c->Ax;
	const size_t L = (size_t)c->op->Ly * c->op->Lx, nb = (L + C0_SUM_BLOCK - 1) / C0_SUM_BLOCK;
#pragma omp parallel for schedule(static) if (L > 100000)
	for (size_t b = 0; b < nb; b++) {
		const size_t i0 = b * C0_SUM_BLOCK, i1 = L - i0 < C0_SUM_BLOCK ? L : i0 + C0_SUM_BLOCK;
		double xc = 0, xax = 0, xn = 0, x1 = 0;
		for (size_t i = i0; i < i1; i++)
			xc += x[i] * C[i], xax += x[i] * Ax[i], xn += x[i] * n[i], x1 += x[i];
		c->part[4 * b] = xc, c->part[4 * b + 1] = xax, c->part[4 * b + 2] = xn, c->part[4 * b + 3] = x1;
	}
	out[0] = out[1] = out[2] = out[3] = 0;
	for (size_t b = 0; b < nb; b++)
		for (int k = 0; k < 4; k++)
			out[k] += c->part[4 * b + k];
}

/* f(x) on the whole grid: A^T A x in c->Ax, the sums (grid_sums), s */
static double grid_objective(struct ctx *c, const double *x, double sum[4], double *s)
{
	c0_covop_normal(c->op, x, c->Ax);
	grid_sums(c, x, sum);
	return objective(c, sum[0], sum[1], sum[2], s);
}

/* f(x) and its gradient */
static double smooth(void *vctx, const double *x, double *g)
{
	struct ctx *c = vctx;
	const struct c0_covop *op = c->op;
	const size_t L = (size_t)op->Ly * op->Lx;
	double sum[4], s;
	const double f = grid_objective(c, x, sum, &s);
#pragma omp parallel for if (L > 100000)
	for (size_t i = 0; i < L; i++)
		g[i] = c->Ax[i] + s * op->n[i] - c->C[i];
	return f;
}

/* The same on a working set: x and g hold only the set's pixels
 * (ops/covnormal.h), the others are 0. */
struct wctx {
	struct ctx *c;
	struct c0_covnormal N;
	double *cw, *nw;     /* C and the column norms at the set's pixels */
};

static int ws_alloc(struct wctx *w, struct ctx *c)
{
	*w = (struct wctx){ c, { 0 }, NULL, NULL };
	return c0_covnormal_init(&w->N, c->op);
}

static void ws_free(struct wctx *w)
{
	c0_covnormal_free(&w->N);
	free(w->cw), free(w->nw);
}

/* The set := the pixels with in[i], in grid order; xw their values in x,
 * cw and nw those of C and the column norms */
static int ws_set(struct wctx *w, const uint8_t *in, const double *x, double *xw)
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
		w->cw[k] = w->c->C[ws[k]], w->nw[k] = w->c->op->n[ws[k]];
	return C0_OK;
}

/* v := the set's values vw on the grid, 0 elsewhere */
static void ws_scatter(const struct wctx *w, const double *vw, double *v)
{
	memset(v, 0, (size_t)w->c->op->Ly * w->c->op->Lx * sizeof *v);
	for (size_t k = 0; k < w->N.nws; k++)
		v[w->N.ws[k]] = vw[k];
}

static double smooth_ws(void *vctx, const double *xw, double *gw)
{
	struct wctx *w = vctx;
	c0_covnormal_apply(&w->N, xw, gw);
	double xc = 0, xax = 0, xn = 0, s;
	for (size_t k = 0; k < w->N.nws; k++)
		xc += xw[k] * w->cw[k], xax += xw[k] * gw[k], xn += xw[k] * w->nw[k];
	const double f = objective(w->c, xc, xax, xn, &s);
	for (size_t k = 0; k < w->N.nws; k++)
		gw[k] += s * w->nw[k] - w->cw[k];
	return f;
}

/* join: a gradient g that would move the pixel by more than rounding
 * (1e-3 lambda); leave: at 0 and not pushed up. 1 when a pixel joined. */
static int ws_update(const struct ctx *ctx, const double *x, const double *g, uint8_t *in)
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

/* pruned's step on the set: A^T A >= 0 entrywise, so its largest row sum
 * on the set bounds its largest eigenvalue there (Gershgorin); one and g
 * are workspaces */
static double ws_lip(struct wctx *w, double lip, double *one, double *g)
{
	for (size_t k = 0; k < w->N.nws; k++)
		one[k] = 1;
	c0_covnormal_apply(&w->N, one, g);
	double rs = 0;
	for (size_t k = 0; k < w->N.nws; k++)
		rs = fmax(rs, g[k]);
	return fmin(lip, rs);
}

/* l1 by FISTA: a short run on the whole grid finds where the support can
 * be; then FISTA on the working set (pixels that are non-zero or whose
 * gradient would make them so), re-made every PIECE iterations and checked
 * on the whole grid whenever FISTA converges on it: pixels that would move
 * join, every pixel at 0 that is not pushed up leaves, and FISTA's momentum
 * is carried across. The set shrinks from the warm-up's blur (~5x the
 * support) towards the support, so the iterations get cheaper: at 512x512
 * the capped iterate's duality gap is 25x smaller, in 35 % less time, than
 * with a set kept until FISTA converged on it (docs/parameters.md).
 * fista (the default) takes the whole grid's step; pruned, on each piece,
 * the longest step safe on its set (longer, as the set shrinks). */
#define WARMUP 30
#define PIECE 100
/* The working sets' part, after the warm-up (its momentum in xp; pw: L
 * doubles of workspace). */
static int solve_l1_sets(struct ctx *ctx, const struct c0_fista_conf *fc, double lip, int pruned, double *x,
			 double *xp, double *pw, struct c0_fista_info *info)
{
	const size_t L = (size_t)ctx->op->Ly * ctx->op->Lx;
	int used = info->iters;
	struct wctx w;
	int st = ws_alloc(&w, ctx);
	double *xw = c0_alloc(L, sizeof *xw), *one = pruned ? c0_alloc(L, sizeof *one) : NULL, *g = ctx->Ax;
	uint8_t *in = c0_alloc(L, 1);
	if (st || !xw || (pruned && !one) || !in) {
		st = C0_ENOMEM;
		goto out;
	}
	struct c0_fista_info part = *info;
	for (;;) {
		/* the gradient on the whole grid: who would move? */
		smooth(ctx, x, g);
		if (!ws_update(ctx, x, g, in) && part.converged)
			break;
		if ((st = ws_set(&w, in, x, xw)))
			break;
		for (size_t k = 0; k < w.N.nws; k++)
			pw[k] = xp[w.N.ws[k]];
		part.prev = pw;
		struct c0_fista_conf fw = *fc;
		fw.maxit = fc->maxit - used < PIECE ? fc->maxit - used : PIECE;
		part.hist = info->hist ? info->hist + used : NULL;
		part.nhist = info->hist && info->nhist > used ? info->nhist - used : 0;
		const double lw = pruned ? ws_lip(&w, lip, one, g) : lip;
		if ((st = c0_fista_nn(smooth_ws, &w, w.N.nws, lw, NULL, ctx->lam, xw, &fw, &part)))
			break;
		used += part.iters;
		ws_scatter(&w, xw, x);
		ws_scatter(&w, pw, xp);
		if (used >= fc->maxit) {
			part.converged = 0;
			break;
		}
	}
	info->iters = used, info->converged = part.converged, info->obj = part.obj;
	info->restarts += part.restarts;
out:
	ws_free(&w);
	free(xw), free(one), free(in);
	return st;
}

static int solve_l1(struct ctx *ctx, const struct c0_fista_conf *fc, double lip, int pruned, double *x,
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
	int st = c0_fista_nn(smooth, ctx, L, lip, NULL, ctx->lam, x, &f0, info);
	info->prev = NULL;
	if (!st && !info->converged && info->iters < fc->maxit)
		st = solve_l1_sets(ctx, fc, lip, pruned, x, xp, pw, info);
	free(xp), free(pw);
	return st;
}

/* lambda = 0 with x free only on the mask (the noise variance on a given
 * support): FISTA on the mask's pixels alone, the whole grid's step */
static int solve_masked(struct ctx *ctx, const struct c0_fista_conf *fc, double lip, const uint8_t *mask, double *x,
			struct c0_fista_info *info)
{
	const size_t L = (size_t)ctx->op->Ly * ctx->op->Lx;
	struct wctx w;
	int st = ws_alloc(&w, ctx);
	double *xw = c0_alloc(L, sizeof *xw);
	if (!st && xw && !(st = ws_set(&w, mask, x, xw))) {
		st = c0_fista_nn(smooth_ws, &w, w.N.nws, lip, NULL, 0, xw, fc, info);
		for (size_t k = 0; !st && k < w.N.nws; k++)
			x[w.N.ws[k]] = xw[k];
	} else if (!st)
		st = C0_ENOMEM;
	ws_free(&w);
	free(xw);
	return st;
}

/* Relative duality gap of the l1 problem at x >= 0 (with s in closed form):
 * the residual rho = R - A x - s I scaled into the dual feasible set,
 * theta = rho / max(1, max_a (A^T rho)_a / lam), gives
 *   D = <R, theta> - ||theta||^2 / 2 <= P* <= P = ||rho||^2 / 2 + lam sum x,
 * and every term is one of the sums the objective needs already. */
static double gap(void *vctx, const double *x)
{
	struct ctx *c = vctx;
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

int c0_support_covop(const struct c0_support_conf *c, const struct c0_cov *cov, struct c0_covop *op)
{
	return c0_covop_init(op, cov->H, cov->W, c->srf, c0_psf_sigma_px(c->fwhm_nm, c->pixel_nm), cov->d);
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
		     const struct c0_support_scale *g, struct ctx *ctx, double *C, struct c0_support_result *res)
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
	/* C without a normalised copy of the band */
	double lm[2];
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
static int run(const struct c0_support_conf *c, const uint8_t *mask, struct ctx *ctx, double *x,
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
			st = c0_irl1_cel0(smooth, ctx, L, op->lip, op->n, res->lambda, x, &fc, c->cel0_outer, fc.tol, &info);
	}
	if (st)
		return st;
	res->iters = info.iters;
	res->converged = lmax > res->lambda || mask ? info.converged : 1;
	res->gap = c->penalty == C0_PENALTY_L1 && !mask && lmax > res->lambda ? gap(ctx, x) : 0;
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

int c0_support_window_solve(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask,
			    double **band, const struct c0_support_scale *g, struct c0_support_result *res)
{
	double t0 = c0_now();
	const int W = cov->W, H = cov->H, r = c->srf;
	const size_t n = (size_t)W * H, L = n * r * r;
	struct c0_covop op;
	int st = c0_support_covop(c, cov, &op);
	if (st)
		return st;
	double *C = c0_alloc(L, sizeof *C);
	double *x = c0_alloc(L, sizeof *x), *Ax = c0_alloc(L, sizeof *Ax);
	double *part = c0_alloc(4 * ((L + C0_SUM_BLOCK - 1) / C0_SUM_BLOCK), sizeof *part);
	res->Ly = H * r, res->Lx = W * r, res->lag = cov->d, res->nlag = cov->nlag, res->frames = cov->frames;
	res->mask = c0_alloc(L, 1);
	res->rx = c0_alloc(L, sizeof *res->rx);
	res->nhist = c->fista.maxit * (c->penalty == C0_PENALTY_CEL0 ? c->cel0_outer : 1);
	res->hist = c0_alloc((size_t)res->nhist, sizeof *res->hist);
	struct ctx ctx = { &op, C, 0, 0, (double)n, Ax, 0, part };
	if (!C || !x || !Ax || !part || !res->mask || !res->rx || !res->hist)
		st = C0_ENOMEM;
	if (!st)
		st = normalise(c, cov, mask, band, g, &ctx, C, res);
	if (!st)
		st = run(c, mask, &ctx, x, res);
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
