/* The tiled support's loops over one process's tiles (support_parts.h):
 * the automatic lambda's statistics (lambda_max, correlation and noise
 * histograms, the second step's peaks), the localisation precision from the
 * halves, and the tiles' solves with their interiors kept. */
#include "stages/support_parts.h"
#include "core/clock.h"
#include "core/comm.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int c0_support_even_window(const struct c0_support_share *s, int k, struct c0_cov *out)
{
	const struct c0_tile *t = &s->tl.t[k];
	if (s->even)
		return c0_cov_acc_window(s->even[k - s->k0], 0, 0, t->h, t->w, out);
	return c0_cov_acc_window_even(s->acc, s->odd[k - s->k0], t->y0 - s->ya, t->x0, out);
}

/* One tile: its window's covariance from the accumulator (rows from ya),
 * solved with the image's scale. */
static int tile_solve(const struct c0_support_conf *c, struct c0_cov_acc *acc, int ya, const struct c0_tile *t,
		      const struct c0_support_scale *g, struct c0_support_result *tr)
{
	struct c0_cov cov;
	memset(tr, 0, sizeof *tr);
	int st = c0_cov_acc_window(acc, t->y0 - ya, t->x0, t->h, t->w, &cov);
	if (!st)
		st = c0_support_window_solve(c, &cov, NULL, &cov.r, g, tr);
	if (!st)
		tr->mean = cov.mean, cov.mean = NULL;
	c0_cov_free(&cov);
	return st;
}

/* Tile t's solve tr kept: its interior (fine rows and columns inside the
 * window) into res (an image W camera pixels wide), its numbers into s2
 * and stats (4), its objective into obj (res->nhist). */
static void tile_keep(const struct c0_tile *t, int r, int W, const struct c0_support_result *tr,
		      struct c0_support_result *res, double *s2, double *stats, double *obj)
{
	const int oy = t->iy0 - t->y0, ox = t->ix0 - t->x0;
	const size_t src = (size_t)(oy * r) * tr->Lx + (size_t)ox * r, ld = (size_t)W * r;
	const size_t dst = (size_t)(t->iy0 * r) * ld + (size_t)t->ix0 * r, iw = (size_t)t->iw * r;
	c0_tile_copy(res->mask + dst, ld, tr->mask + src, (size_t)tr->Lx, t->ih * r, iw);
	c0_tile_copy(res->rx + dst, ld * sizeof(float), tr->rx + src, (size_t)tr->Lx * sizeof(float), t->ih * r,
		     iw * sizeof(float));
	c0_tile_copy(res->mean + (size_t)t->iy0 * W + t->ix0, (size_t)W * sizeof(double),
		     tr->mean + (size_t)oy * t->w + ox, (size_t)t->w * sizeof(double), t->ih, (size_t)t->iw * sizeof(double));
	*s2 = tr->sigma2;
	stats[0] = tr->iters, stats[1] = tr->converged, stats[2] = tr->gap, stats[3] = tr->lambda_max;
	for (int i = 0; i < res->nhist; i++)      /* a finished tile keeps its last value */
		obj[i] = tr->nhist ? tr->hist[i < tr->nhist ? i : tr->nhist - 1] : 0;
}

int c0_support_tiles_solve(const struct c0_support_conf *c, struct c0_support_share *s,
			   const struct c0_support_scale *g, struct c0_support_result *res, double *s2, double *stats,
			   double *obj)
{
	const struct c0_tiling *tl = &s->tl;
	const int k0 = s->k0, k1 = s->k1, ya = s->ya, W = tl->t[tl->n - 1].x0 + tl->t[tl->n - 1].w;
	struct c0_first_fail fail = { 0 };
	struct c0_progress pr;
	int done = 0, lo = k0;       /* the tiles before lo are done */
	uint8_t *fin = c0_alloc((size_t)(k1 - k0) + 1, 1);
	if (!fin)
		return C0_ENOMEM;
	c0_progress_begin(&pr, "support (tiles)", k1 - k0);
#pragma omp parallel for schedule(dynamic, 1) if (tl->n > 1)
	for (int k = k0; k < k1; k++) {
		struct c0_support_result tr;
		int st = tile_solve(c, s->acc, ya, &tl->t[k], g, &tr);
		if (!st)
			tile_keep(&tl->t[k], c->grid.srf, W, &tr, res, &s2[k], stats + 4 * (size_t)k, obj + (size_t)k * res->nhist);
		c0_first_fail_note(&fail, st);
		c0_support_result_free(&tr);
#pragma omp critical(c0_support_progress)
		{
			c0_progress_update(&pr, ++done);
			/* tiles start in tile order, so every tile from lo on cuts its
			 * window from row t[lo].y0 down: the band above goes back (it
			 * shrinks faster than rx and the mask grow) */
			for (fin[k - k0] = 1; lo < k1 && fin[lo - k0]; lo++)
				;
			if (lo < k1)
				c0_cov_acc_drop_rows(s->acc, tl->t[lo].y0 - ya);
		}
	}
	c0_progress_end(&pr);
	free(fin);
	return c0_first_fail_raise(&fail);
}

/* The end of one tile of the automatic lambda's loops, from its thread: its
 * histogram h (n counts, or NULL) added to hist when its work succeeded and
 * freed, its status noted, the progress advanced. */
static void tile_hist_done(double *hist, double *h, int n, int st, struct c0_first_fail *fail, struct c0_progress *pr,
			   int *done)
{
	if (!st && h) {
		/* counts: the sum is exact in any order */
#pragma omp critical(c0_support_hist_sum)
		for (int i = 0; i < n; i++)
			hist[i] += h[i];
	}
	free(h);
	c0_first_fail_note(fail, st);
#pragma omp critical(c0_support_progress)
	c0_progress_update(pr, ++*done);
}

int c0_support_tiles_second(const struct c0_support_conf *c, struct c0_support_share *s,
			    const struct c0_support_scale *g, double lmax, struct c0_support_result *res)
{
	const struct c0_tiling *tl = &s->tl;
	struct c0_first_fail fail = { 0 };
	struct c0_progress pr;
	int done = 0, nsub = 0;
	double *hist = c0_alloc(C0_LAMBDA_BINS, sizeof *hist);
	if (!hist)
		c0_first_fail_note(&fail, C0_ENOMEM);
	for (int k = s->k0; k < s->k1; k++)
		nsub += s->sub[k];
	c0_progress_begin(&pr, "support (lambda, first solve)", nsub);
#pragma omp parallel for schedule(dynamic, 1) if (tl->n > 1)
	for (int k = s->k0; k < s->k1; k++) {
		if (!s->sub[k] || !hist)
			continue;
		const struct c0_tile *t = &tl->t[k];
		struct c0_support_result tr = { 0 };
		double *h = c0_alloc(C0_LAMBDA_BINS, sizeof *h);
		int st = h ? tile_solve(c, s->acc, s->ya, t, g, &tr) : C0_ENOMEM;
		if (!st)
			st = c0_lambda_peaks(c, tr.rx, g->norm, t->h, t->w, t->iy0 - t->y0, t->ix0 - t->x0, t->ih, t->iw, h);
		c0_support_result_free(&tr);
		tile_hist_done(hist, h, C0_LAMBDA_BINS, st, &fail, &pr, &done);
	}
	c0_progress_end(&pr);
	int st = c0_comm_status(c0_first_fail_raise(&fail));
	if (!st) {
		c0_comm_sum(hist, C0_LAMBDA_BINS);
		c0_lambda_second(hist, lmax, &res->cv);
	}
	free(hist);
	return st;
}

/* One subset tile's cross-validation path (stages/lambda.h) at the image's
 * scale, the errors over its interior: its sums into v */
static int tile_cv(const struct c0_support_conf *c, struct c0_support_share *s, int k, double norm, double lmax,
		   int k0, struct c0_lambda_cv_sums *v)
{
	const struct c0_tile *t = &s->tl.t[k];
	struct c0_cov_acc *o = s->odd[k - s->k0];
	struct c0_cov ev, od;
	int st = c0_support_even_window(s, k, &ev);
	if (st)
		return st;
	if (!(st = c0_cov_acc_window(o, 0, 0, t->h, t->w, &od))) {
		const int in[4] = { t->iy0 - t->y0, t->ix0 - t->x0, t->ih, t->iw };
		st = c0_lambda_cv_window(c, &ev, &od, norm, lmax, k0, in, v);
		c0_cov_free(&od);
	}
	c0_cov_free(&ev);
	return st;
}

/* The tiles' sums in tile order, on the points every tile reached (each
 * went C0_LAMBDA_CV_PATIENCE past its own least) */
static void cv_add(const struct c0_tiling *tl, const uint8_t *sub, const struct c0_lambda_cv_sums *v,
		   struct c0_lambda_cv_sums *all)
{
	const int M = C0_LAMBDA_CV_MAX;
	memset(all, 0, sizeof *all);
	all->npts = M;
	for (int k = 0; k < tl->n; k++) {
		if (!sub[k])
			continue;
		all->npts = fmin(all->npts, v[k].npts), all->e0 += v[k].e0, all->nb += v[k].nb;
		for (int j = 0; j < M; j++) {
			all->err[j] += v[k].err[j];
			for (int q = 0; q < M; q++)
				all->s1[j][q] += v[k].s1[j][q], all->s2[j][q] += v[k].s2[j][q];
		}
	}
}

int c0_support_tiles_cv(const struct c0_support_conf *c, struct c0_support_share *s, double norm, double lmax,
			struct c0_support_result *res)
{
	const struct c0_tiling *tl = &s->tl;
	struct c0_first_fail fail = { 0 };
	struct c0_progress pr;
	int done = 0, nsub = 0;
	const int k0 = c0_lambda_cv_first(res->cv.chosen_rel);
	struct c0_lambda_cv_sums *v = c0_alloc((size_t)tl->n + 1, sizeof *v), *all = v ? v + tl->n : NULL;
	if (!v)
		c0_first_fail_note(&fail, C0_ENOMEM);
	for (int k = s->k0; k < s->k1; k++)
		nsub += s->sub[k];
	c0_progress_begin(&pr, "support (lambda, cross-validation)", nsub);
#pragma omp parallel for schedule(dynamic, 1) if (tl->n > 1)
	for (int k = s->k0; k < s->k1; k++) {
		if (!s->sub[k] || !v)
			continue;
		c0_first_fail_note(&fail, tile_cv(c, s, k, norm, lmax, k0, &v[k]));
#pragma omp critical(c0_support_progress)
		c0_progress_update(&pr, ++done);
	}
	c0_progress_end(&pr);
	int st = c0_comm_status(c0_first_fail_raise(&fail));
	if (!st) {
		/* each tile's from one rank: the sums over ranks are exact */
		c0_comm_sum((double *)v, (int)(tl->n * (sizeof *v / sizeof(double))));
		cv_add(tl, s->sub, v, all);
		c0_lambda_cv_choose(all, k0, &res->cv);
	}
	free(v);
	return st;
}

/* The automatic lambda on tiles needs the odd frames' covariance too; it is
 * kept for a subset of the tiles only, spread evenly over the grid in tile
 * order, whose interiors hold at most SUBSET_PX camera pixels (every tile up
 * to 512x512 images; its band costs about a quarter of a 1024x1024 frame's).
 * The subset depends on the tile grid only. */
#define SUBSET_PX (512 * 512)
/* in[k] = 1 for m of the candidates cand[0..nc) (tile indices in tile order;
 * cand NULL: tiles 0..nc), spread evenly, with the largest m whose interiors
 * hold at most px pixels */
static void spread(const struct c0_tiling *tl, const int *cand, int nc, double px_max, uint8_t *in)
{
	for (int m = nc; m >= 1; m--) {
		double px = 0;
		memset(in, 0, (size_t)tl->n);
		for (int j = 0; j < m; j++) {
			const int c = (int)(((2LL * j + 1) * nc) / (2 * m));
			const struct c0_tile *t = &tl->t[cand ? cand[c] : c];
			in[t - tl->t] = 1, px += (double)t->ih * t->iw;
		}
		if (px <= px_max || m == 1)
			return;
	}
}

void c0_support_subset(const struct c0_tiling *tl, uint8_t *sub)
{
	spread(tl, NULL, tl->n, SUBSET_PX, sub);
}

/* Tile k's halves (the even frames and the odd ones in o), one band at a
 * time: each gives its correlation image; their noise into h */
static int tile_halves(const struct c0_support_conf *c, const struct c0_support_share *s, int k, double norm, double *h)
{
	const struct c0_tile *t = &s->tl.t[k];
	struct c0_cov_acc *o = s->odd[k - s->k0];
	struct c0_cov ev, od;
	double *ca = NULL, *cb = NULL, *cn = NULL;
	int st = c0_support_even_window(s, k, &ev);
	if (!st) {
		st = c0_lambda_tile_corr(c, &ev, &ca, &cn);
		c0_cov_free(&ev);
		if (!st && !(st = c0_cov_acc_window(o, 0, 0, t->h, t->w, &od))) {
			st = c0_lambda_tile_corr(c, &od, &cb, NULL);
			c0_cov_free(&od);
		}
		if (!st)
			c0_lambda_tile_noise(c, ca, cb, cn, t->w, norm, t->iy0 - t->y0, t->ix0 - t->x0, t->ih, t->iw, h);
	}
	free(ca), free(cb), free(cn);
	return st;
}

int c0_support_tiles_lambda(const struct c0_support_conf *c, struct c0_support_share *s, double norm, double *lm,
			    double *hist)
{
	const struct c0_tiling *tl = &s->tl;
	struct c0_first_fail fail = { 0 };
	struct c0_progress pr;
	int done = 0;
	c0_progress_begin(&pr, "support (lambda)", s->k1 - s->k0);
#pragma omp parallel for schedule(dynamic, 1) if (tl->n > 1)
	for (int k = s->k0; k < s->k1; k++) {
		const struct c0_tile *t = &tl->t[k];
		struct c0_cov all;
		const int halves = hist && s->odd[k - s->k0];
		double *h = hist ? c0_alloc(C0_LAMBDA_HIST, sizeof *h) : NULL;
		int st = hist && !h ? C0_ENOMEM : c0_cov_acc_window(s->acc, t->y0 - s->ya, t->x0, t->h, t->w, &all);
		if (!st) {
			st = c0_lambda_tile_max(c, &all, norm, t->iy0 - t->y0, t->ix0 - t->x0, t->ih, t->iw, lm + 2 * (size_t)k, h);
			c0_cov_free(&all);
		}
		if (!st && halves)
			st = tile_halves(c, s, k, norm, h);
		tile_hist_done(hist, h, C0_LAMBDA_HIST, st, &fail, &pr, &done);
	}
	c0_progress_end(&pr);
	return c0_first_fail_raise(&fail);
}

/* The localisation precision on tiles: each subset tile's halves solved on
 * their own (at most C0_SUPPORT_FRC_MAXIT iterations, the image's scale and
 * lambda), their interiors' matched distances added in tile order (the
 * halves' FRC on one tile), on part of the noise subset (PRECISION_PX). The
 * halves are solved side by side, one per thread, as the tiles are. No FRC:
 * its ring sums added over Hann-windowed tiles disagreed with the one-tile
 * value (docs/defaults.md#tile). */
#define PRECISION_PX (256 * 256)
/* which of the noise subset: spread evenly, interiors up to PRECISION_PX
 * (all of them up to 256x256 images; each half solve costs as much as a
 * tile's whole solve) */
static uint8_t *precision_subset(const struct c0_tiling *tl, const uint8_t *sub)
{
	int nc = 0, *cand = c0_alloc((size_t)tl->n, sizeof *cand);
	uint8_t *use = c0_alloc((size_t)tl->n, 1);
	if (!cand || !use) {
		free(cand), free(use);
		return NULL;
	}
	for (int k = 0; k < tl->n; k++)
		if (sub[k])
			cand[nc++] = k;
	if (nc)
		spread(tl, cand, nc, PRECISION_PX, use);
	free(cand);
	return use;
}

/* One half (j: 0 even, 1 odd frames) of subset tile k solved; its
 * interior's mask into m (both halves' interiors, one after the other) */
static int half_solve(const struct c0_support_conf *c, struct c0_support_share *s, int k, int j,
		      const struct c0_support_scale *g, uint8_t *m)
{
	const int r = c->grid.srf;
	const struct c0_tile *t = &s->tl.t[k];
	struct c0_cov h;
	struct c0_support_result hr;
	memset(&hr, 0, sizeof hr);
	const int ih = t->ih * r, iw = t->iw * r, oy = (t->iy0 - t->y0) * r, ox = (t->ix0 - t->x0) * r;
	struct c0_cov_acc *o = s->odd[k - s->k0];
	int st = j ? c0_cov_acc_window(o, 0, 0, t->h, t->w, &h) : c0_support_even_window(s, k, &h);
	if (!st) {
		st = c0_support_window_solve(c, &h, NULL, &h.r, g, &hr);
		c0_cov_free(&h);
	}
	if (!st)
		c0_tile_copy(m + (size_t)j * ih * iw, (size_t)iw, hr.mask + (size_t)oy * hr.Lx + ox, (size_t)hr.Lx, ih,
			     (size_t)iw);
	c0_support_result_free(&hr);
	return st;
}

/* over ranks, then over tiles in tile order: the same sums for any split */
static void precision_sum(const struct c0_support_conf *c, const struct c0_tiling *tl, double *sums,
			  struct c0_support_result *res)
{
	const double fine = c0_grid_fine_nm(&c->grid);
	c0_comm_sum(sums, 2 * tl->n);
	double s = 0, n = 0;
	for (int k = 0; k < tl->n; k++)
		s += sums[2 * k], n += sums[2 * k + 1];
	res->precision_nm = n > 0 ? sqrt(s / n / 4) * fine / sqrt(2) : -1;
}

int c0_support_tiles_precision(const struct c0_support_conf *c, struct c0_support_share *s,
			       const struct c0_support_scale *g, struct c0_support_result *res)
{
	const struct c0_tiling *tl = &s->tl;
	const int k0 = s->k0, k1 = s->k1, r = c->grid.srf;
	uint8_t *use = precision_subset(tl, s->sub);
	if (!use)
		return C0_ENOMEM;
	double t0 = c0_now();
	const int rad = (int)ceil(0.5 * c->grid.fwhm_nm / c0_grid_fine_nm(&c->grid));
	double *sums = c0_alloc(2 * (size_t)tl->n, sizeof *sums);   /* distance^2, matches */
	const struct c0_support_conf cc = c0_support_halves_conf(c);
	/* work items: the two halves of each subset tile of this process */
	int nw = 0;
	int *item = c0_alloc(2 * (size_t)(k1 - k0) + 1, sizeof *item);
	uint8_t **m = c0_alloc((size_t)(k1 - k0) + 1, sizeof *m);     /* both halves' interior masks */
	int fail = sums && item && m ? C0_OK : C0_ENOMEM;
	struct c0_first_fail ff = { 0 };
	for (int k = k0; k < k1 && !fail; k++) {
		const struct c0_tile *t = &tl->t[k];
		if (!s->odd[k - k0] || !use[k])
			continue;
		if (!(m[k - k0] = c0_alloc(2 * (size_t)t->ih * r * t->iw * r, 1)))
			fail = C0_ENOMEM;
		item[nw++] = 2 * k, item[nw++] = 2 * k + 1;
	}
	/* side by side, one solve per thread (the solver's own loops then run
	 * serially, as in the tiles' solves): two solves at a time, as there */
#pragma omp parallel for schedule(dynamic, 1) if (nw > 1 && !fail)
	for (int w = 0; w < nw; w++)
		if (!fail)
			c0_first_fail_note(&ff, half_solve(&cc, s, item[w] / 2, item[w] % 2, g, m[item[w] / 2 - k0]));
	if (!fail)
		fail = c0_first_fail_raise(&ff);
	for (int k = k0; k < k1 && !fail; k++) {
		const struct c0_tile *t = &tl->t[k];
		const size_t n1 = (size_t)t->ih * r * t->iw * r;
		if (m[k - k0])
			c0_pair_sums(m[k - k0], m[k - k0] + n1, t->ih * r, t->iw * r, rad, &sums[2 * k], &sums[2 * k + 1]);
	}
	for (int k = 0; m && k < k1 - k0; k++)
		free(m[k]);
	free(m), free(item), free(use);
	/* every rank sums, or none: a rank that failed must not leave the
	 * others waiting in the sum */
	if (!(fail = c0_comm_status(fail)))
		precision_sum(c, tl, sums, res);
	free(sums);
	if (!fail)
		res->t_frc = c0_now() - t0;
	return fail;
}
