#include "stages/intensity.h"
#include "stages/tiles.h"
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
	if (!(c->graph_radius >= 1 && c->graph_radius <= 4))
		return c0_fail(C0_EINVAL, "graph_radius %g: must be in [1, 4] fine pixels", c->graph_radius);
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
	double *dinv;             /* Jacobi preconditioner */
	double *psi2;             /* ||psi_k||^2 on the support */
	double *deg;              /* weighted graph degree of each support pixel */
	double *y, *g, *v, *rhs;  /* workspaces */
	int cg_iters, solves, rounds;
};

/* background smoothness: Neumann Laplacian on the coarse grid */
static void lap_b(const struct prob *p, const double *b, double *out)
{
	const int Ny = p->P.Ny, Nx = p->P.Nx;
	for (int y = 0; y < Ny; y++)
		for (int x = 0; x < Nx; x++) {
			double c = b[y * Nx + x], s = 0;
			if (x > 0) s += c - b[y * Nx + x - 1];
			if (x < Nx - 1) s += c - b[y * Nx + x + 1];
			if (y > 0) s += c - b[(y - 1) * Nx + x];
			if (y < Ny - 1) s += c - b[(y + 1) * Nx + x];
			out[y * Nx + x] = s;
		}
}

/* the normal operator of the quadratic, on the free variables */
static void normal(void *ctx, const double *in, double *out)
{
	struct prob *p = ctx;
	const int n = p->n, nb = p->nb, NN = p->NN;
	double *v = p->v;
	for (int i = 0; i < n + nb; i++)
		v[i] = p->fixed[i] ? 0 : in[i];
	c0_psi_omega_forward(&p->P, v, p->y);
	if (nb == NN)
		for (int i = 0; i < NN; i++)
			p->y[i] += v[n + i];
	else if (nb == 1)
		for (int i = 0; i < NN; i++)
			p->y[i] += p->bscale * v[n];
	if (p->c->weight)
		for (int i = 0; i < NN; i++)
			p->y[i] *= p->c->weight[i];
	c0_psi_omega_adjoint(&p->P, p->y, out);
	c0_grad_omega(&p->P, v, p->g);
	double *gx = p->rhs + n + nb;      /* spare room after rhs */
	c0_grad_omega_adjoint(&p->P, p->g, gx);
	for (int i = 0; i < n; i++)
		out[i] += p->mu * gx[i];
	if (nb == NN) {
		lap_b(p, v + n, out + n);
		for (int i = 0; i < NN; i++)
			out[n + i] = p->y[i] + p->c->beta * out[n + i];
	} else if (nb == 1) {
		double s = 0;
		for (int i = 0; i < NN; i++)
			s += p->y[i];
		out[n] = p->bscale * s;
	}
	for (int i = 0; i < n + nb; i++)
		if (p->fixed[i])
			out[i] = 0;
}

/* Solve for the current mu: CG on the free set, then fix negative variables
 * at zero and solve again until none is negative (an active-set projection). */
static int solve(struct prob *p, double *sol)
{
	const int n = p->n, nb = p->nb, NN = p->NN;
	double *b = p->rhs;
	memset(p->fixed, 0, (size_t)(n + nb));
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
		for (int i = 0; i < nb; i++) {
			int y = i / p->P.Nx, x = i % p->P.Nx;
			int d = (y > 0) + (y < p->P.Ny - 1) + (x > 0) + (x < p->P.Nx - 1);
			p->dinv[n + i] = p->fixed[n + i] ? 1 : nb == NN ? 1 / (1 + p->c->beta * d) : 1;
		}
		struct c0_cg_info info;
		int st = c0_cg(normal, p, (size_t)(n + nb), b, p->dinv, sol, p->c->tol, p->c->maxit, &info);
		if (st)
			return st;
		p->cg_iters += info.iters;
		p->rounds++;
		int neg = 0;
		for (int i = 0; i < n + nb; i++)
			if (!p->fixed[i] && sol[i] < 0)
				p->fixed[i] = 1, sol[i] = 0, neg++;
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

struct dp { struct prob *p; double *sol, target, tprev, tmin, lo, hi; int fail; const double *floor; };

static double discrepancy(void *ctx, double t)
{
	struct dp *d = ctx;
	d->p->mu = exp(t);
	/* Warm start from the last mu only when it is far (a factor e or more):
	 * from a near one the start may already meet the CG tolerance and not
	 * move, and the residual would step instead of rising with mu. */
	const size_t nv = (size_t)(d->p->n + d->p->nb);
	if (t <= d->tmin && d->floor)   /* the smallest mu: the floor's solve */
		memcpy(d->sol, d->floor, sizeof *d->sol * nv);
	else {
		if (!(fabs(t - d->tprev) >= 1) || t <= d->tmin)
			memset(d->sol, 0, sizeof *d->sol * nv);
		if (solve(d->p, d->sol))
			d->fail = 1;
	}
	d->tprev = t;
	const double f = residual2(d->p, d->sol) - d->target;
	if (f < 0)
		d->lo = fmax(d->lo, t);
	else
		d->hi = fmin(d->hi, t);
	return d->hi - d->lo <= DP_LOGMU_TOL ? 0 : f;   /* the crossing is known to 1 % in mu: done */
}

/* No support pixel (a tile off the sample): x = 0 and the background alone,
 * min 1/2 ||b - ybar||^2 + beta/2 ||grad b||^2 (b >= 0 holds: ybar >= 0
 * smoothed stays so, and a negative b is clipped). */
struct bgonly { int Ny, Nx; double beta; };

static void bg_normal(void *ctx, const double *in, double *out)
{
	const struct bgonly *g = ctx;
	struct prob p = { .P = { .Ny = g->Ny, .Nx = g->Nx } };
	lap_b(&p, in, out);
	for (int i = 0; i < g->Ny * g->Nx; i++)
		out[i] = in[i] + g->beta * out[i];
}

static int background_only(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx,
			   struct c0_intensity_result *res)
{
	const int NN = Ny * Nx, r = c->grid.srf;
	res->Ly = Ny * r, res->Lx = Nx * r, res->Ny = Ny, res->Nx = Nx, res->dp_status = -1;
	res->x = c0_alloc((size_t)NN * r * r, sizeof *res->x);
	res->b = c0_alloc((size_t)NN, sizeof *res->b);
	double *b = c0_alloc((size_t)NN, sizeof *b), *dinv = c0_alloc((size_t)NN, sizeof *dinv);
	int st = !res->x || !res->b || !b || !dinv ? C0_ENOMEM : C0_OK;
	double m = 0;
	for (int i = 0; !st && i < NN; i++)
		m += ybar[i];
	m /= NN;
	if (!st && c->background == C0_BG_SMOOTH) {
		struct bgonly g = { Ny, Nx, c->beta };
		for (int i = 0; i < NN; i++) {
			int y = i / Nx, x = i % Nx, d = (y > 0) + (y < Ny - 1) + (x > 0) + (x < Nx - 1);
			dinv[i] = 1 / (1 + c->beta * d), b[i] = m;
		}
		struct c0_cg_info info;
		st = c0_cg(bg_normal, &g, (size_t)NN, ybar, dinv, b, c->tol, c->maxit, &info);
		res->cg_iters = info.iters, res->solves = 1;
	} else
		for (int i = 0; !st && i < NN; i++)
			b[i] = c->background == C0_BG_CONSTANT ? m : 0;
	for (int i = 0; !st && i < NN; i++)
		res->b[i] = (float)fmax(0, b[i]);
	free(b), free(dinv);
	return st;
}

static int solve_whole(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T,
		       const uint8_t *mask, double sigma2, struct c0_intensity_result *res);
static int solve_tiled(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T,
		       const uint8_t *mask, double sigma2, struct c0_intensity_result *res);

int c0_intensity_solve(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T,
		       const uint8_t *mask, double sigma2, struct c0_intensity_result *res)
{
	memset(res, 0, sizeof *res);
	double t0 = c0_now();
	int st = c0_intensity_check(c);
	if (st)
		return st;
	if (c->mu == 0 && !(sigma2 > 0))
		return c0_fail(C0_EINVAL, "noise variance %g: the discrepancy principle needs a positive noise variance (or give mu)", sigma2);
	st = c->tile > 0 && c->tile < (Ny > Nx ? Ny : Nx) ? solve_tiled(c, ybar, Ny, Nx, T, mask, sigma2, res)
							    : solve_whole(c, ybar, Ny, Nx, T, mask, sigma2, res);
	res->seconds = c0_now() - t0;
	if (st)
		c0_intensity_result_free(res);
	return st;
}

/* The tiles' windows overlap by two PSF lags (6 sigma each): the PSF and
 * the background's smoothing length (sqrt(beta) ~ 4.5 coarse pixels) fit. */
static int solve_tiled(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T,
		       const uint8_t *mask, double sigma2, struct c0_intensity_result *res)
{
	const int r = c->grid.srf, Lx = Nx * r, halo = 2 * c0_grid_lag(&c->grid, 0);
	struct c0_tiling tl;
	int st = c0_tiling_make(Ny, Nx, c->tile, halo, &tl);
	if (st)
		return st;
	res->Ly = Ny * r, res->Lx = Lx, res->Ny = Ny, res->Nx = Nx, res->sigma2 = sigma2, res->tiles = tl.n;
	res->x = c0_alloc((size_t)Ny * Nx * r * r, sizeof *res->x);
	res->b = c0_alloc((size_t)Ny * Nx, sizeof *res->b);
	double *ts = c0_alloc(8 * (size_t)tl.n, sizeof *ts);   /* per tile: weight, mu, residual2, target2, floor2, status, solves, cg */
	if (!res->x || !res->b || !ts) {
		free(ts);
		c0_tiling_free(&tl);
		return C0_ENOMEM;
	}
	struct c0_intensity_conf cc = *c;
	cc.tile = 0;
	struct c0_first_fail fail = { 0 };
	/* one tile per thread: each solve then runs serially, so a tile's
	 * numbers do not depend on the thread count */
#pragma omp parallel for schedule(dynamic, 1)
	for (int k = 0; k < tl.n; k++) {
		const struct c0_tile *t = &tl.t[k];
		const size_t nw = (size_t)t->h * t->w, Lw = nw * r * r;
		double *y = malloc(nw * sizeof *y);
		uint8_t *m = malloc(Lw);
		float *wt = c->weight ? malloc(nw * sizeof *wt) : NULL;
		struct c0_intensity_result tr;
		memset(&tr, 0, sizeof tr);
		int tst = y && m && (wt || !c->weight) ? C0_OK : C0_ENOMEM, any = 0;
		for (int a = 0; !tst && a < t->h; a++)
			memcpy(y + (size_t)a * t->w, ybar + (size_t)(t->y0 + a) * Nx + t->x0, (size_t)t->w * sizeof *y);
		for (int a = 0; !tst && wt && a < t->h; a++)
			memcpy(wt + (size_t)a * t->w, c->weight + (size_t)(t->y0 + a) * Nx + t->x0, (size_t)t->w * sizeof *wt);
		struct c0_intensity_conf tc = cc;   /* this tile's weights */
		tc.weight = wt;
		for (int a = 0; !tst && a < t->h * r; a++) {
			memcpy(m + (size_t)a * t->w * r, mask + (size_t)(t->y0 * r + a) * Lx + (size_t)t->x0 * r, (size_t)t->w * r);
			for (int b = 0; b < t->w * r && !any; b++)
				any = m[(size_t)a * t->w * r + b];
		}
		if (!tst)
			tst = any ? solve_whole(&tc, y, t->h, t->w, T, m, sigma2, &tr) : background_only(&tc, y, t->h, t->w, &tr);
		if (!tst) {
			const int oy = t->iy0 - t->y0, ox = t->ix0 - t->x0;
			for (int a = 0; a < t->ih * r; a++)
				memcpy(res->x + (size_t)(t->iy0 * r + a) * Lx + (size_t)t->ix0 * r,
				       tr.x + (size_t)(oy * r + a) * tr.Lx + (size_t)ox * r, (size_t)t->iw * r * sizeof *res->x);
			for (int a = 0; a < t->ih; a++)
				memcpy(res->b + (size_t)(t->iy0 + a) * Nx + t->ix0, tr.b + (size_t)(oy + a) * t->w + ox,
				       (size_t)t->iw * sizeof *res->b);
			double *s = ts + 8 * (size_t)k;
			s[0] = any ? (double)t->ih * t->iw / (double)nw : 0;   /* the interior's share of the window */
			s[1] = tr.mu, s[2] = tr.residual2, s[3] = tr.target2, s[4] = tr.floor2;
			s[5] = tr.dp_status, s[6] = tr.solves, s[7] = tr.cg_iters;
		}
		c0_first_fail_note(&fail, tst);
		c0_intensity_result_free(&tr);
		free(y), free(m), free(wt);
	}
	st = c0_first_fail_raise(&fail);
	/* in tile order: the same sums whatever the schedule */
	double lmu = 0, wmu = 0;
	res->dp_status = c->mu > 0 ? -1 : 0;
	for (int k = 0; !st && k < tl.n; k++) {
		const double *s = ts + 8 * (size_t)k;
		const struct c0_tile *t = &tl.t[k];
		res->solves += (int)s[6], res->cg_iters += (int)s[7];
		if (!(s[0] > 0))
			continue;   /* background only: no mu */
		lmu += t->ih * t->iw * log(s[1]), wmu += t->ih * t->iw;
		res->residual2 += s[0] * s[2], res->target2 += s[0] * s[3], res->floor2 += s[0] * s[4];
		res->tiles_met += s[5] <= 0;
		if (res->dp_status == 0 && s[5] > 0)
			res->dp_status = (int)s[5];   /* the first tile whose principle failed says how */
	}
	res->mu = wmu > 0 ? exp(lmu / wmu) : 0;
	free(ts);
	c0_tiling_free(&tl);
	return st;
}

static int solve_whole(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T,
		       const uint8_t *mask, double sigma2, struct c0_intensity_result *res)
{
	int st;
	struct prob p = { .c = c, .ybar = ybar, .yw = ybar, .NN = Ny * Nx };
	if ((st = c0_psi_omega_init(&p.P, Ny, Nx, c->grid.srf, c0_grid_sigma_px(&c->grid), mask, c->graph_radius)))
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
	double *yw = c->weight ? c0_alloc((size_t)p.NN, sizeof *yw) : NULL;
	for (int i = 0; yw && i < p.NN; i++)
		yw[i] = c->weight[i] * ybar[i];
	if (yw)
		p.yw = yw;
	res->x = c0_alloc((size_t)p.P.Ly * p.P.Lx, sizeof *res->x);
	res->b = c0_alloc((size_t)p.NN, sizeof *res->b);
	if (!sol || !p.fixed || !p.y || !p.g || !p.v || !p.rhs || !res->x || !res->b || !p.dinv || !p.psi2 || !p.deg ||
	    (c->weight && !yw)) {
		st = C0_ENOMEM;
		goto out;
	}
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
			if (!st && !(st = solve(&p, fsol)))
				res->floor2 = residual2(&p, fsol);
			if (st)
				goto out;
		}
		struct dp d = { &p, sol, res->floor2 + res->target2, NAN, tmin + 1e-9, -INFINITY, INFINITY, 0, fsol };
		double t;
		int evals;
		res->dp_status = c0_root_increasing(discrepancy, &d, log(1e-1), tmin, log(1e8), 0.01 * res->target2, 40, &t, &evals);
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
	free(yw);
	c0_psi_omega_free(&p.P);
	return st;
}
