#include "stages/intensity.h"
#include "core/tiles.h"
#include "stages/depthpool.h"
#include "ops/neumann.h"
#include "ops/psi_omega.h"
#include "optics/psf.h"
#include "solve/root.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int c0_intensity_check(const struct c0_intensity_conf *c)
{
	int st = c0_grid_check(&c->grid);
	if (st)
		return st;
	if (!(c->beta >= 0 && isfinite(c->beta)) || !(c->nu >= 0 && isfinite(c->nu)) || !(c->mu >= 0 && isfinite(c->mu)))
		return c0_fail(C0_EINVAL, "beta %g, nu %g, mu %g: must be finite and >= 0", c->beta, c->nu, c->mu);
	if (!(c->tol > 0 && c->tol < 1) || c->maxit < 1)
		return c0_fail(C0_EINVAL, "cg_tol %g / cg_iterations %d: need a tolerance in (0, 1) and at least one step", c->tol, c->maxit);
	if (!(c->graph_radius >= 1 && c->graph_radius <= 8))
		return c0_fail(C0_EINVAL, "graph_radius %g: must be in [1, 8] fine pixels", c->graph_radius);
	if (!(c->graph_orient >= 0 && c->graph_orient <= 100))
		return c0_fail(C0_EINVAL, "graph_orient %g: must be in [0, 100] (0: every direction alike)", c->graph_orient);
	if (c->tile < 0)
		return c0_fail(C0_EINVAL, "tile %d: must be >= 0 camera pixels (0: the whole image)", c->tile);
	return C0_OK;
}

void c0_intensity_result_free(struct c0_intensity_result *r)
{
	free(r->x), free(r->b);
	memset(r, 0, sizeof *r);
}

/* Unknowns v = [x (n), b (nb)], nb = HW (smooth), 1 (constant, scaled to a
 * unit column) or 0. Variables fixed at zero by the active set are masked. */
struct prob {
	const struct c0_intensity_conf *c;
	struct c0_psi_omega P;
	int n, nb, NN;
	double bscale;            /* constant mode: b = bscale * v_b */
	double mu;
	const double *ybar;
	const double *yw;         /* w ybar (ybar without weights) */
	uint8_t *fixed;           /* n + nb */
	int bfixed;               /* some of the background's fixed[] are set (else its masks are skipped) */
	double *dinv;             /* Jacobi preconditioner */
	double *psi2;             /* ||psi_k||^2 on the support */
	double *deg;              /* weighted graph degree of each support pixel */
	double *y, *g, *v, *rhs;  /* workspaces */
	double level;             /* the data's mean: where b starts */
	double *lb;               /* NN: L b */
	double *s0;               /* n + nb: the start, x = 0 and b = level */
	struct c0_neumann *nm;    /* smooth: the background block's preconditioner */
	int cg_iters, solves, rounds;
};

/* the normal operator of the quadratic, on the free variables; the
 * background's part is masked only when some of it is fixed (b >= 0 is
 * rarely active: the camera offset is in it) */
static void normal(void *ctx, const double *in, double *out)
{
	struct prob *p = ctx;
	const int n = p->n, nb = p->nb, NN = p->NN;
	double *v = p->v;
	const double *vb = p->bfixed ? v + n : in + n;   /* the free background */
	for (int i = 0; i < (p->bfixed ? n + nb : n); i++)
		v[i] = p->fixed[i] ? 0 : in[i];
	c0_psi_omega_forward(&p->P, v, p->y);
	if (nb == NN)
		for (int i = 0; i < NN; i++)
			p->y[i] += vb[i];
	else if (nb == 1)
		for (int i = 0; i < NN; i++)
			p->y[i] += p->bscale * vb[0];
	if (p->c->weight)
		for (int i = 0; i < NN; i++)
			p->y[i] *= p->c->weight[i];
	c0_psi_omega_adjoint(&p->P, p->y, out);
	c0_grad_omega(&p->P, v, p->g);
	double *gx = p->rhs + n + nb;      /* spare room after rhs */
	c0_grad_omega_adjoint(&p->P, p->g, gx);
	for (int i = 0; i < n; i++)
		out[i] += p->mu * gx[i];
	if (nb == NN) {   /* beta L^2 b */
		c0_neumann_laplacian(p->P.Ny, p->P.Nx, vb, p->lb);
		c0_neumann_laplacian(p->P.Ny, p->P.Nx, p->lb, out + n);
		for (int i = 0; i < NN; i++)
			out[n + i] = p->y[i] + p->c->beta * out[n + i];
	} else if (nb == 1) {
		double s = 0;
		for (int i = 0; i < NN; i++)
			s += p->y[i];
		out[n] = p->bscale * s;
	}
	for (int i = 0; i < (p->bfixed ? n + nb : n); i++)
		if (p->fixed[i])
			out[i] = 0;
}

/* The preconditioner: Jacobi on x; on a smooth background an inverse of its
 * own block, I + beta L^2 (weights taken as 1), by FFTs on a padded grid
 * (ops/neumann.h): Jacobi leaves the curvature penalty's condition number,
 * 1 + 64 beta, to CG. */
static void precond(void *ctx, const double *in, double *out)
{
	struct prob *p = ctx;
	const int n = p->n, nb = p->nb, smooth = nb == p->NN;
	for (int i = 0; i < n + (smooth ? 0 : nb); i++)
		out[i] = p->dinv[i] * in[i];
	if (!smooth)
		return;
	for (int i = 0; p->bfixed && i < nb; i++)
		p->lb[i] = p->fixed[n + i] ? 0 : in[n + i];
	c0_neumann_solve(p->nm, 1, p->c->beta, 2, p->bfixed ? p->lb : in + n, out + n);
	for (int i = 0; p->bfixed && i < nb; i++)
		if (p->fixed[n + i])
			out[n + i] = 0;
}

static void start(const struct prob *p, double *sol)
{
	memset(sol, 0, sizeof *sol * (size_t)p->n);
	for (int i = 0; i < p->nb; i++)
		sol[p->n + i] = p->nb == 1 ? p->level / p->bscale : p->level;
}

static double norm(const double *v, size_t n)
{
	double s = 0;
	for (size_t i = 0; i < n; i++)
		s += v[i] * v[i];
	return sqrt(s);
}

/* Solve for the current mu: CG on the free set, then fix negative variables
 * at zero and solve again until none is negative (an active-set projection).
 * CG's tolerance is relative to the residual at x = 0, b = the data's mean,
 * not at zero: the camera offset and the mean background are nearly all of
 * ||A^T ybar|| (100-140 of a few ADU of signal), and a tolerance on that
 * stopped with the background still off by 0.1-1 ADU in its smooth modes. */
static int solve(struct prob *p, double *sol)
{
	const int n = p->n, nb = p->nb, NN = p->NN;
	double *b = p->rhs;
	memset(p->fixed, 0, (size_t)(n + nb));
	p->bfixed = 0;
	for (int round = 0; round < 20; round++) {
		/* rhs = A^T ybar on the free set */
		c0_psi_omega_adjoint(&p->P, p->yw, b);
		if (nb == NN)
			memcpy(b + n, p->yw, sizeof *b * NN);
		else if (nb == 1) {
			double s = 0;
			for (int i = 0; i < NN; i++)
				s += p->yw[i];
			b[n] = p->bscale * s;
		}
		for (int i = 0; i < n + nb; i++)
			if (p->fixed[i])
				b[i] = 0, sol[i] = 0;
		for (int i = 0; i < n; i++)
			p->dinv[i] = p->fixed[i] ? 1 : 1 / (p->psi2[i] + p->mu * p->deg[i]);
		for (int i = 0; i < nb; i++)
			p->dinv[n + i] = 1;
		start(p, p->s0);
		normal(p, p->s0, p->s0 + n + nb);
		for (int i = 0; i < n + nb; i++)
			p->s0[n + nb + i] = b[i] - p->s0[n + nb + i];
		const double bn = norm(b, (size_t)(n + nb));
		const double tol = bn > 0 ? p->c->tol * norm(p->s0 + n + nb, (size_t)(n + nb)) / bn : p->c->tol;
		struct c0_cg_info info;
		int st = c0_pcg(normal, p, (size_t)(n + nb), b, precond, p, sol, tol, p->c->maxit, &info);
		if (st)
			return st;
		p->cg_iters += info.iters;
		p->rounds++;
		if (p->c->linear)
			break;
		int neg = 0;
		for (int i = 0; i < n + nb; i++)
			if (!p->fixed[i] && sol[i] < 0)
				p->fixed[i] = 1, sol[i] = 0, neg++, p->bfixed |= i >= n;
		if (!neg)
			break;
	}
	p->solves++;
	return C0_OK;
}

static double residual2(struct prob *p, const double *sol)
{
	const int n = p->n, NN = p->NN;
	c0_psi_omega_forward(&p->P, sol, p->y);
	double s = 0;
	for (int i = 0; i < NN; i++) {
		double bi = p->nb == NN ? sol[n + i] : p->nb == 1 ? p->bscale * sol[n] : 0;
		double r = p->y[i] + bi - p->ybar[i];
		s += (p->c->weight ? p->c->weight[i] : 1) * r * r;
	}
	return s;
}

/* mu is wanted to 1 %: the residual, from CG to a tolerance and an active
 * set, is not smooth enough in mu for the root finder's residual test when
 * the floor is large, and it would try mu after mu */
#define DP_LOGMU_TOL 0.01
/* The root search runs on log((residual^2 - floor^2) / target^2), met
 * within 1 % (as |residual^2 - floor^2 - target^2| <= 1 % of target^2 was):
 * nearly straight in log mu, its slope 0.5-0.9 at the crossing (26 tiles of
 * two 1024^2 x 500 stacks), so that the first step (by that slope) and the
 * secants land near the root, and a tile whose residual never rises that
 * far (x smooth at no cost) reaches the largest mu in two steps, not one a
 * decade (docs/speed.md, "The intensity step's root search") */
#define DP_RES_TOL 0.01
#define DP_SLOPE 0.7

struct dp { struct prob *p; double *sol, floor2, target2, tprev, tmin, lo, hi; int fail; const double *floor; };

static double discrepancy(void *ctx, double t)
{
	struct dp *d = ctx;
	d->p->mu = exp(t);
	/* Warm start from the last mu only when it is far (a factor e or more):
	 * from a near one the start may already meet the CG tolerance and not
	 * move, and the residual would step instead of rising with mu. Near
	 * trials started from the nearest one's solution with CG run on until
	 * the start's residual fell 10x (docs/speed.md) met the principle 2-6 %
	 * off in mu when they kept its fixed variables (the active set only
	 * grows), and took more steps than from cold when they freed them. */
	const size_t nv = (size_t)(d->p->n + d->p->nb);
	if (t <= d->tmin && d->floor)   /* the smallest mu: the floor's solve */
		memcpy(d->sol, d->floor, sizeof *d->sol * nv);
	else {
		if (!(fabs(t - d->tprev) >= 1) || t <= d->tmin)
			start(d->p, d->sol);
		if (solve(d->p, d->sol))
			d->fail = 1;
	}
	d->tprev = t;
	/* at the floor's own mu the excess is 0 (-inf): any large negative will do */
	const double f = log(fmax(residual2(d->p, d->sol) - d->floor2, 1e-12 * d->target2) / d->target2);
	if (f < 0)
		d->lo = fmax(d->lo, t);
	else
		d->hi = fmin(d->hi, t);
	return d->hi - d->lo <= DP_LOGMU_TOL ? 0 : f;   /* the crossing is known to 1 % in mu: done */
}

/* No support pixel (a tile off the sample): x = 0 and the background alone,
 * min 1/2 ||b - ybar||^2 + beta/2 ||L b||^2, solved exactly (b >= 0 is not
 * held: a negative b is clipped). */
static int background_only(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx,
			   struct c0_intensity_result *res)
{
	const int NN = Ny * Nx, r = c->grid.srf;
	res->Ly = Ny * r, res->Lx = Nx * r, res->Ny = Ny, res->Nx = Nx, res->dp_status = -1;
	res->x = c0_alloc((size_t)NN * r * r, sizeof *res->x);
	res->b = c0_alloc((size_t)NN, sizeof *res->b);
	double *b = c0_alloc((size_t)NN, sizeof *b);
	int st = !res->x || !res->b || !b ? C0_ENOMEM : C0_OK;
	double m = 0;
	for (int i = 0; !st && i < NN; i++)
		m += ybar[i];
	m /= NN;
	struct c0_neumann *nm = NULL;
	if (!st && c->background == C0_BG_SMOOTH && !(st = c0_neumann_new(Ny, Nx, 0, &nm))) {
		c0_neumann_solve(nm, 1, c->beta, 2, ybar, b);
		res->solves = 1;
	} else
		for (int i = 0; !st && i < NN; i++)
			b[i] = c->background == C0_BG_CONSTANT ? m : 0;
	for (int i = 0; !st && i < NN; i++)
		res->b[i] = (float)fmax(0, b[i]);
	c0_neumann_free(nm);
	free(b);
	return st;
}

static int solve_whole(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T,
		       const uint8_t *mask, double sigma2, struct c0_intensity_result *res);

static int solve_check(const struct c0_intensity_conf *c, double sigma2)
{
	int st = c0_intensity_check(c);
	if (st)
		return st;
	if (c->linear && !(c->mu > 0))
		return c0_fail(C0_EINVAL, "linear intensity solve: needs a given mu (got %g)", c->mu);
	if (c->mu == 0 && !(sigma2 > 0))
		return c0_fail(C0_EINVAL, "noise variance %g: the discrepancy principle needs a positive noise variance (or give mu)", sigma2);
	return C0_OK;
}

static int tiled(const struct c0_intensity_conf *c, int Ny, int Nx)
{
	return c->tile > 0 && c->tile < (Ny > Nx ? Ny : Nx);
}

/* One image's tiles, solved one at a time (by any thread) and put together
 * in tile order */
struct c0_intensity_tiles {
	struct c0_intensity_conf c;   /* tile 0: a tile is one solve */
	const double *ybar;
	const uint8_t *mask;
	int Ny, Nx;
	int64_t T;
	double sigma2;
	struct c0_tiling tl;
	double *ts;   /* per tile: weight, mu, residual2, target2, floor2, status, solves, cg, seconds */
	struct c0_intensity_result res;
	struct c0_first_fail fail;
};
#define TILE_NUMBERS 9

/* The tiles' windows overlap by two PSF lags (6 sigma each): the PSF and
 * the background's smoothing length (beta^(1/4) ~ 3.2 coarse pixels) fit. */
static int tiles_new(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T, const uint8_t *mask,
		     double sigma2, struct c0_intensity_tiles **out)
{
	struct c0_intensity_tiles *s = c0_alloc(1, sizeof *s);
	*out = NULL;
	if (!s)
		return C0_ENOMEM;
	const int r = c->grid.srf;
	int st = c0_tiling_make(Ny, Nx, c->tile, 2 * c0_grid_lag(&c->grid, 0), &s->tl);
	if (st) {
		free(s);
		return st;
	}
	s->c = *c, s->c.tile = 0, s->ybar = ybar, s->mask = mask, s->Ny = Ny, s->Nx = Nx, s->T = T, s->sigma2 = sigma2;
	struct c0_intensity_result *res = &s->res;
	res->Ly = Ny * r, res->Lx = Nx * r, res->Ny = Ny, res->Nx = Nx, res->sigma2 = sigma2, res->tiles = s->tl.n;
	res->x = c0_alloc((size_t)Ny * Nx * r * r, sizeof *res->x);
	res->b = c0_alloc((size_t)Ny * Nx, sizeof *res->b);
	s->ts = c0_alloc(TILE_NUMBERS * (size_t)s->tl.n, sizeof *s->ts);
	*out = s;
	return res->x && res->b && s->ts ? C0_OK : C0_ENOMEM;
}

/* tile k of s: each solve runs serially, so a tile's numbers do not depend
 * on the thread count or on which thread solves it */
static void tiles_solve(struct c0_intensity_tiles *s, int k)
{
	const struct c0_intensity_conf *c = &s->c;
	const int r = c->grid.srf, Nx = s->Nx, Lx = Nx * r;
	const struct c0_tile *t = &s->tl.t[k];
	const size_t nw = (size_t)t->h * t->w, Lw = nw * r * r;
	const double t0 = c0_now();
	double *y = malloc(nw * sizeof *y);
	uint8_t *m = malloc(Lw);
	float *wt = c->weight ? malloc(nw * sizeof *wt) : NULL;
	struct c0_intensity_result tr;
	memset(&tr, 0, sizeof tr);
	int tst = y && m && (wt || !c->weight) ? C0_OK : C0_ENOMEM, any = 0;
	for (int a = 0; !tst && a < t->h; a++)
		memcpy(y + (size_t)a * t->w, s->ybar + (size_t)(t->y0 + a) * Nx + t->x0, (size_t)t->w * sizeof *y);
	for (int a = 0; !tst && wt && a < t->h; a++)
		memcpy(wt + (size_t)a * t->w, c->weight + (size_t)(t->y0 + a) * Nx + t->x0, (size_t)t->w * sizeof *wt);
	struct c0_intensity_conf tc = *c;   /* this tile's weights */
	tc.weight = wt;
	for (int a = 0; !tst && a < t->h * r; a++) {
		memcpy(m + (size_t)a * t->w * r, s->mask + (size_t)(t->y0 * r + a) * Lx + (size_t)t->x0 * r, (size_t)t->w * r);
		for (int b = 0; b < t->w * r && !any; b++)
			any = m[(size_t)a * t->w * r + b];
	}
	if (!tst)
		tst = any ? solve_whole(&tc, y, t->h, t->w, s->T, m, s->sigma2, &tr) : background_only(&tc, y, t->h, t->w, &tr);
	if (!tst) {
		struct c0_intensity_result *res = &s->res;
		const int oy = t->iy0 - t->y0, ox = t->ix0 - t->x0;
		for (int a = 0; a < t->ih * r; a++)
			memcpy(res->x + (size_t)(t->iy0 * r + a) * Lx + (size_t)t->ix0 * r,
			       tr.x + (size_t)(oy * r + a) * tr.Lx + (size_t)ox * r, (size_t)t->iw * r * sizeof *res->x);
		for (int a = 0; a < t->ih; a++)
			memcpy(res->b + (size_t)(t->iy0 + a) * Nx + t->ix0, tr.b + (size_t)(oy + a) * t->w + ox,
			       (size_t)t->iw * sizeof *res->b);
		double *n = s->ts + TILE_NUMBERS * (size_t)k;
		n[0] = any ? (double)t->ih * t->iw / (double)nw : 0;   /* the interior's share of the window */
		n[1] = tr.mu, n[2] = tr.residual2, n[3] = tr.target2, n[4] = tr.floor2;
		n[5] = tr.dp_status, n[6] = tr.solves, n[7] = tr.cg_iters, n[8] = c0_now() - t0;
	}
	c0_first_fail_note(&s->fail, tst);
	c0_intensity_result_free(&tr);
	free(y), free(m), free(wt);
}

/* s's tiles put together (in tile order: the same sums whatever the
 * schedule) into *res, and s freed; seconds: the tiles' own, summed */
static int tiles_finish(struct c0_intensity_tiles *s, struct c0_intensity_result *res)
{
	int st = c0_first_fail_raise(&s->fail);
	double lmu = 0, wmu = 0;
	*res = s->res;
	res->dp_status = s->c.mu > 0 ? -1 : 0;
	for (int k = 0; !st && k < s->tl.n; k++) {
		const double *n = s->ts + TILE_NUMBERS * (size_t)k;
		const struct c0_tile *t = &s->tl.t[k];
		res->solves += (int)n[6], res->cg_iters += (int)n[7], res->seconds += n[8];
		if (!(n[0] > 0))
			continue;   /* background only: no mu */
		lmu += t->ih * t->iw * log(n[1]), wmu += t->ih * t->iw;
		res->residual2 += n[0] * n[2], res->target2 += n[0] * n[3], res->floor2 += n[0] * n[4];
		res->tiles_met += n[5] <= 0;
		if (res->dp_status == 0 && n[5] > 0)
			res->dp_status = (int)n[5];   /* the first tile whose principle failed says how */
	}
	res->mu = wmu > 0 ? exp(lmu / wmu) : 0;
	free(s->ts);
	c0_tiling_free(&s->tl);
	free(s);
	if (st)
		c0_intensity_result_free(res);
	return st;
}

static void tiles_free(struct c0_intensity_tiles *s)
{
	if (s) {
		c0_intensity_result_free(&s->res);
		free(s->ts);
		c0_tiling_free(&s->tl);
		free(s);
	}
}

int c0_intensity_solve(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T,
		       const uint8_t *mask, double sigma2, struct c0_intensity_result *res)
{
	memset(res, 0, sizeof *res);
	double t0 = c0_now();
	int st = solve_check(c, sigma2);
	if (st)
		return st;
	if (!tiled(c, Ny, Nx))
		st = solve_whole(c, ybar, Ny, Nx, T, mask, sigma2, res);
	else {
		struct c0_intensity_tiles *s;
		if ((st = tiles_new(c, ybar, Ny, Nx, T, mask, sigma2, &s))) {
			tiles_free(s);
			return st;
		}
#pragma omp parallel for schedule(dynamic, 1)
		for (int k = 0; k < s->tl.n; k++)
			tiles_solve(s, k);
		st = tiles_finish(s, res);
	}
	res->seconds = c0_now() - t0;
	if (st)
		c0_intensity_result_free(res);
	return st;
}

int c0_intensity_solve_many(int n, const struct c0_intensity_conf *c, const double *const *ybar, int Ny, int Nx,
			    const int64_t *T, const uint8_t *mask, const double *sigma2, const int *skip,
			    struct c0_intensity_result *res, int *sts, char (*msg)[256])
{
	struct c0_intensity_tiles *s[C0_MAX_STACKS] = { 0 };
	int first[C0_MAX_STACKS + 1] = { 0 }, bad = 0;
	if (n > C0_MAX_STACKS)
		return c0_fail(C0_EINVAL, "%d images: at most %d", n, C0_MAX_STACKS);
	for (int i = 0; i < n; i++) {
		memset(&res[i], 0, sizeof res[i]);
		sts[i] = skip && skip[i] ? C0_OK : solve_check(&c[i], sigma2[i]);
		if (!sts[i] && !(skip && skip[i]) && !tiled(&c[i], Ny, Nx))
			sts[i] = c0_fail(C0_EINVAL, "tile %d: the image (%d x %d) is one tile", c[i].tile, Nx, Ny);
		if (!sts[i] && !(skip && skip[i]))
			sts[i] = tiles_new(&c[i], ybar[i], Ny, Nx, T[i], mask, sigma2[i], &s[i]);
		if (sts[i])
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
		bad |= sts[i];
		first[i + 1] = first[i] + (s[i] ? s[i]->tl.n : 0);
	}
	if (!bad) {
#pragma omp parallel for schedule(dynamic, 1)
		for (int j = 0; j < first[n]; j++) {
			int i = 0;
			while (j >= first[i + 1])
				i++;
			tiles_solve(s[i], j - first[i]);
		}
	}
	for (int i = 0; i < n; i++) {
		if (!s[i])
			continue;
		if (bad) {
			tiles_free(s[i]);
			continue;
		}
		if ((sts[i] = tiles_finish(s[i], &res[i])))
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
	}
	return C0_OK;
}

/* Psi_Omega and its graph; with graph_orient, the graph's differences along
 * each pixel's structure (its normal from the support's own shape, as the
 * depth pool's strip) weigh more than those across it, which would smooth
 * one filament into its neighbour. */
static int graph_init(const struct c0_intensity_conf *c, int Ny, int Nx, const uint8_t *mask, struct c0_psi_omega *P)
{
	const double sigma = c0_grid_sigma_px(&c->grid);
	if (c->graph_orient <= 0)
		return c0_psi_omega_init(P, Ny, Nx, c->grid.srf, sigma, mask, c->graph_radius);
	struct c0_pixlist pl;
	int st = c0_pixlist_from_mask(mask, Ny * c->grid.srf, Nx * c->grid.srf, &pl);
	float *nrm = st ? NULL : c0_alloc(2 * pl.M + 1, sizeof *nrm);
	if (!st && !nrm)
		st = C0_ENOMEM;
	if (!st) {
		c0_pixlist_normals(&pl, C0_DEPTH_NORMAL_PX, nrm);   /* in raster order, as Psi_Omega's unknowns */
		st = c0_psi_omega_init_dir(P, Ny, Nx, c->grid.srf, sigma, mask, c->graph_radius, nrm, c->graph_orient);
	}
	free(nrm);
	c0_pixlist_free(&pl);   /* c0_pixlist_from_mask sets pl, even when it fails */
	return st;
}

static int solve_whole(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T,
		       const uint8_t *mask, double sigma2, struct c0_intensity_result *res)
{
	int st;
	struct prob p = { .c = c, .ybar = ybar, .yw = ybar, .NN = Ny * Nx };
	if ((st = graph_init(c, Ny, Nx, mask, &p.P)))
		return st;
	p.n = p.P.n;
	p.nb = c->background == C0_BG_SMOOTH ? p.NN : c->background == C0_BG_CONSTANT ? 1 : 0;
	p.bscale = 1 / sqrt((double)p.NN);
	size_t nv = (size_t)p.n + p.nb;
	double *sol = c0_alloc(nv, sizeof *sol), *fsol = NULL;
	p.fixed = c0_alloc(nv, 1);
	p.dinv = c0_alloc(nv, sizeof *p.dinv);
	p.psi2 = c0_alloc((size_t)p.n, sizeof *p.psi2);
	p.deg = c0_alloc((size_t)p.n, sizeof *p.deg);
	p.y = c0_alloc((size_t)p.NN, sizeof *p.y);
	p.g = c0_alloc((size_t)p.P.ne + 1, sizeof *p.g);
	p.v = c0_alloc(nv, sizeof *p.v);
	p.rhs = c0_alloc(nv + p.n, sizeof *p.rhs);
	p.lb = c0_alloc((size_t)p.NN, sizeof *p.lb);
	p.s0 = c0_alloc(2 * nv, sizeof *p.s0);
	double *yw = c->weight ? c0_alloc((size_t)p.NN, sizeof *yw) : NULL;
	for (int i = 0; yw && i < p.NN; i++)
		yw[i] = c->weight[i] * ybar[i];
	if (yw)
		p.yw = yw;
	res->x = c0_alloc((size_t)p.P.Ly * p.P.Lx, sizeof *res->x);
	res->b = c0_alloc((size_t)p.NN, sizeof *res->b);
	if (!sol || !p.fixed || !p.y || !p.g || !p.v || !p.rhs || !p.lb || !p.s0 || !res->x || !res->b || !p.dinv || !p.psi2 || !p.deg ||
	    (c->weight && !yw)) {
		st = C0_ENOMEM;
		goto out;
	}
	if (p.nb == p.NN && (st = c0_neumann_new(Ny, Nx, (int)ceil(4 * pow(c->beta, 0.25)), &p.nm)))
		goto out;
	for (int i = 0; p.nb && i < p.NN; i++)
		p.level += ybar[i] / p.NN;
	start(&p, sol);
	c0_psi_omega_diag(&p.P, p.psi2);
	c0_grad_omega_diag(&p.P, p.deg);
	res->Ly = p.P.Ly, res->Lx = p.P.Lx, res->Ny = Ny, res->Nx = Nx, res->sigma2 = sigma2;
	double nu = c->nu > 0 ? c->nu : sqrt((double)T);
	res->target2 = nu * nu * p.NN * sigma2 / (double)T;
	if (c->mu > 0) {
		p.mu = c->mu;
		st = solve(&p, sol);
		res->dp_status = -1;
	} else {
		/* the residual that the model reaches at all (the smallest mu): on real
		 * data and continuous positions it exceeds the noise level, and the
		 * plain principle is never met; the relative one lets the smoothness
		 * cost as much residual above that floor as the noise explains */
		const double tmin = log(C0_INTENSITY_MU_MIN);
		res->floor2 = 0;
		if (c->relative) {
			p.mu = C0_INTENSITY_MU_MIN;
			if (!(fsol = c0_alloc(nv, sizeof *fsol)))
				st = C0_ENOMEM;
			else
				start(&p, fsol);
			if (!st && !(st = solve(&p, fsol)))
				res->floor2 = residual2(&p, fsol);
			if (st)
				goto out;
		}
		struct dp d = { &p, sol, res->floor2, res->target2, NAN, tmin + 1e-9, -INFINITY, INFINITY, 0, fsol };
		double t;
		int evals;
		res->dp_status = c0_root_increasing(discrepancy, &d, log(1e-1), DP_SLOPE, tmin, log(1e8), DP_RES_TOL, 40, &t, &evals);
		st = d.fail ? C0_ENOMEM : C0_OK;
		if (!st && fabs(p.mu - exp(t)) > 1e-12 * p.mu) {   /* make sol belong to the returned mu */
			p.mu = exp(t);
			st = solve(&p, sol);
		}
	}
	if (st)
		goto out;
	res->mu = p.mu;
	res->residual2 = residual2(&p, sol);
	for (int k = 0; k < p.n; k++)
		res->x[c0_psi_omega_pixel(&p.P, k)] = (float)sol[k];
	for (int i = 0; i < p.NN; i++)
		res->b[i] = (float)(p.nb == p.NN ? sol[p.n + i] : p.nb == 1 ? p.bscale * sol[p.n] : 0);
	res->solves = p.solves, res->cg_iters = p.cg_iters, res->active_rounds = p.rounds;
	res->tiles = 1, res->tiles_met = res->dp_status <= 0;
out:
	free(sol), free(fsol), free(p.fixed), free(p.dinv), free(p.psi2), free(p.deg), free(p.y), free(p.g), free(p.v), free(p.rhs);
	free(p.lb), free(p.s0), free(yw);
	c0_neumann_free(p.nm);
	c0_psi_omega_free(&p.P);
	return st;
}
