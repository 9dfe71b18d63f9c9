#include "stages/support_parts.h"
#include "ops/covpool.h"
#include "optics/psf.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"
#include "core/comm.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Each half solved on its own (a warm start from the full solution would
 * make them agree) at the same relative lambda, with at most
 * C0_SUPPORT_FRC_MAXIT iterations; the FRC curve of their emitter variances
 * (no resolution is read from it: docs/guide.md, section 5), and the
 * localisation precision from how far their supports lie apart. */
static int half_frc(const struct c0_support_conf *c, const struct c0_cov half[2], struct c0_support_result *res)
{
	double t0 = c0_now();
	struct c0_support_result h[2];
	memset(h, 0, sizeof h);
	struct c0_support_conf cc = c0_support_halves_conf(c);
	cc.lambda_rel = res->lambda_max > 0 ? res->lambda / res->lambda_max : c0_support_default_lambda(c->penalty);
	int st = C0_OK;
	for (int k = 0; k < 2 && !st; k++)
		st = c0_support_solve(&cc, &half[k], &h[k]);
	if (!st)
		st = c0_frc_compute(h[0].rx, h[1].rx, res->Ly, res->Lx, &res->frc);
	if (!st) {
		const double fine = c0_grid_fine_nm(&c->grid);
		/* match within the PSF's half width at half maximum */
		double p = c0_pair_precision(h[0].mask, h[1].mask, res->Ly, res->Lx, (int)ceil(0.5 * c->grid.fwhm_nm / fine));
		res->precision_nm = p < 0 ? -1 : p * fine / sqrt(2);
	}
	c0_support_result_free(&h[0]), c0_support_result_free(&h[1]);
	res->t_frc = c0_now() - t0;
	return st;
}

/* The normalisation (largest pixel variance) of a streamed stack. */
static int check_norm(const char *name, double norm)
{
	if (!isfinite(norm))
		return c0_fail(C0_EINVAL, "%s: the temporal variance is not finite (pixel values too large for the covariance sums)",
			       name);
	if (!(norm > 0))
		return c0_support_fail_flat();
	return C0_OK;
}

/* The automatic lambda's second step on one tile (stages/lambda.h): a
 * solve at the rule's lambda, its peaks, and the lambda of the solve that
 * counts in cc. */
static int second_step(struct c0_support_conf *cc, const struct c0_cov *cov, struct c0_support_result *res)
{
	const double t0 = c0_now();
	struct c0_support_result first;
	memset(&first, 0, sizeof first);
	double *h = c0_alloc(C0_LAMBDA_BINS, sizeof *h);
	int st = h ? c0_support_solve(cc, cov, &first) : C0_ENOMEM;
	if (!st)
		st = c0_lambda_peaks(cc, first.rx, first.norm, cov->H, cov->W, 0, 0, cov->H, cov->W, h);
	if (!st) {
		c0_lambda_second(h, first.lambda_max, &res->cv);
		cc->lambda_rel = res->cv.chosen_rel;
	}
	free(h);
	c0_support_result_free(&first);
	res->cv.seconds += c0_now() - t0;
	return st;
}

/* With fwhm_data: the PSF width the data say (before any operator is
 * built) replaces the stated one where they differ by more than the
 * estimator's measured error allows
 * (docs/defaults.md#fwhm_rule); 1 when it did. The covariance's lag stays the stated width's. */
static int adopt_width(struct c0_support_conf *cc, double fw)
{
	if (!(fabs(fw / cc->grid.fwhm_nm - 1) > C0_LAMBDA_PSF_WARN))
		return 0;
	c0_support_set_width(cc, fw);
	return 1;
}

/* the halves' covariance's width (0: none), adopted or not */
static double data_width(struct c0_support_conf *cc, const struct c0_cov half[2])
{
	double fw;
	if (c0_lambda_psf_fwhm(&half[0], &half[1], cc->grid.pixel_nm, &fw)) {
		c0_clear_error();
		return 0;
	}
	adopt_width(cc, fw);
	return fw;
}

/* The covariance (halves: and its two interleaved halves) of the n stacks
 * pooled (ops/covpool.h), one pass of whole frames each. */
static int pooled_covariance(const struct c0_support_conf *c, struct c0_frames *in, int n, int halves,
			     struct c0_cov *cov, struct c0_cov half[2], double *tc)
{
	int st = C0_OK;
	*tc = 0;
	for (int q = 0; q < n && !st; q++) {
		struct c0_cov one = { 0 }, h[2] = { { 0 } };
		double t;
		st = halves ? c0_stack_covariance_halves(&c[q], &in[q], h, &t) : c0_stack_covariance(&c[q], &in[q], &one, &t);
		*tc += t;
		for (int k = 0; k < 2 && !st && halves; k++)
			st = c0_cov_pool_add(&half[k], &h[k]);
		if (!st && !halves)
			st = c0_cov_pool_add(cov, &one);
		c0_cov_free(&one), c0_cov_free(&h[0]), c0_cov_free(&h[1]);
	}
	return st;
}

/* One tile and one process: the covariance with its two interleaved halves
 * (automatic lambda, FRC) in one pass of whole frames, of each stack. */
static int stack_whole(const struct c0_support_conf *c, struct c0_frames *in, int n, struct c0_support_result *res)
{
	memset(res, 0, sizeof *res);
	struct c0_cov cov = { 0 }, half[2] = { { 0 } };
	struct c0_support_conf cc = *c;
	const int automatic = !(c->lambda_rel > 0), halves = automatic || c->frc;
	double tc;
	int st = pooled_covariance(c, in, n, halves, &cov, half, &tc);
	if (!st && halves) {
		double t0 = c0_now();
		st = c0_cov_pool(&half[0], &half[1], &cov);
		tc += c0_now() - t0;
	}
	double norm = 0;
	for (size_t i = 0; !st && i < (size_t)cov.W * cov.H; i++)
		norm = isfinite(cov.r[i]) ? fmax(norm, cov.r[i]) : INFINITY;
	if (!st)
		st = check_norm(in->name, norm);
	const double fwd = !st && halves && c->fwhm_data ? data_width(&cc, half) : 0;
	res->fwhm_nm = cc.grid.fwhm_nm;
	struct c0_progress ps;
	c0_progress_begin(&ps, "support", 1);
	if (!st && automatic && !(st = c0_lambda_auto(&cc, &half[0], &half[1], &res->cv)))
		cc.lambda_rel = res->cv.chosen_rel, res->lambda_auto = 1;
	if (!st && automatic && c->penalty == C0_PENALTY_L1 && c->lambda_cv &&
	    !(st = c0_lambda_cv(&cc, &half[0], &half[1], &res->cv)))
		cc.lambda_rel = res->cv.chosen_rel;
	else if (!st && automatic && c->penalty == C0_PENALTY_L1 && !c->lambda_noise)
		st = second_step(&cc, &cov, res);
	if (fwd > 0)
		res->cv.fwhm_data_nm = fwd;   /* the lambda rules clear their result */
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
	res->tiles = 1, res->tile = c0_support_tile_size(c, in->width, in->height);
	res->frames = cov.frames;
	c0_cov_free(&cov);
	return st;
}


/* A stack on several tiles or processes (c0_support_stack), phase by
 * phase: its share and accumulators, the image's scale, lambda, the tiles'
 * solves, and rank 0's gathering. */
struct stack {
	const struct c0_support_conf *c;
	struct c0_support_conf cc;  /* c with the data's PSF width (stack_width) */
	double fwd;                 /* that width (nm; 0: not measured) */
	struct c0_frames *in;      /* n stacks pooled (in[0] gives the sizes) */
	int n;
	struct c0_support_share s;
	int automatic, halves;     /* lambda from the data; the halves' bands needed */
	double norm, rel;          /* the image's normalisation, lambda / lambda_max */
	double *lm, *s2, *stats, *hist;   /* per tile: lambda_max (2), sigma2, stats (4); lambda's histograms */
	double *obj;               /* per tile: its objective history (res->nhist) */
};

/* This process's share of the grid (its tiles, its rows) and the subset. */
static int share_open(struct stack *k)
{
	struct c0_support_share *s = &k->s;
	c0_tiling_share(&s->tl, c0_comm_rank(), c0_comm_size(), &s->k0, &s->k1, &s->ya, &s->yb, &s->ia, &s->ib);
	s->odd = c0_alloc((size_t)(s->k1 - s->k0) + 1, sizeof *s->odd);
	s->sub = c0_alloc((size_t)s->tl.n, 1);
	if (!s->odd || !s->sub)
		return C0_ENOMEM;
	if (k->halves)
		c0_support_subset(&s->tl, s->sub);
	return C0_OK;
}

/* its bands and the subset (the grid stays) */
static void share_close(struct c0_support_share *s)
{
	c0_cov_acc_free(s->acc), s->acc = NULL;
	for (int j = 0; s->odd && j < s->k1 - s->k0; j++)
		c0_cov_acc_free(s->odd[j]), c0_cov_acc_free(s->even ? s->even[j] : NULL);
	free(s->odd), free(s->even), free(s->sub);
	s->odd = s->even = NULL, s->sub = NULL;
}

/* After the pass (its status st, collective): the bands sealed, the arrays
 * of the phases below, and the image's normalisation, its largest pixel
 * variance over every process's interiors. */
static int stack_scale(struct stack *k, int st, struct c0_support_result *res)
{
	const struct c0_support_conf *c = k->c;
	struct c0_support_share *s = &k->s;
	const int W = k->in->width, r = c->grid.srf, d = c0_support_lag(c);
	/* the tiles below only read them, some from two threads (the halves) */
	if (!st && s->acc)
		c0_cov_acc_seal(s->acc);
	for (int j = 0; !st && j < s->k1 - s->k0; j++)
		for (int h = 0; h < 2; h++)
			if (h ? s->even && s->even[j] : s->odd[j] != NULL)
				c0_cov_acc_seal(h ? s->even[j] : s->odd[j]);
	c0_mem_release();    /* the blocks and the frame */
	double norm = 0;
	for (int y = s->ia; !st && y < s->ib; y++)
		for (int x = 0; x < W; x++)
			norm = fmax(norm, c0_cov_acc_variance(s->acc, y - s->ya, x));
	const size_t nt = (size_t)s->tl.n;
	k->lm = c0_alloc(2 * nt, sizeof *k->lm), k->s2 = c0_alloc(nt, sizeof *k->s2);
	k->stats = c0_alloc(4 * nt, sizeof *k->stats);
	k->hist = k->automatic ? c0_alloc(C0_LAMBDA_HIST, sizeof *k->hist) : NULL;
	res->Ly = k->in->height * r, res->Lx = W * r, res->lag = d, res->nlag = c0_cov_lag_count(d);
	res->frames = 0;
	for (int q = 0; q < k->n; q++)
		res->frames += k->in[q].count;
	res->nhist = c->fista.maxit * (c->penalty == C0_PENALTY_CEL0 ? c->cel0_outer : 1);
	res->hist = c0_alloc((size_t)res->nhist, sizeof *res->hist);
	k->obj = c0_alloc(nt * res->nhist, sizeof *k->obj);
	if (!st && (!k->lm || !k->s2 || !k->stats || (k->automatic && !k->hist) || !res->hist || !k->obj))
		st = C0_ENOMEM;
	if (!(st = c0_comm_status(st))) {
		c0_comm_max(&norm, 1);
		st = check_norm(k->in->name, norm);
	}
	k->norm = norm;
	return st;
}

/* With fwhm_data: the PSF width from the lag 1 and 2 sums of the image's
 * rows, each process its interior rows, each row from a 3-row window of
 * the band (the sums are then the same whatever the tiles and processes),
 * used as stack_whole's data_width does (adopt_width). Collective. */
static int stack_width(struct stack *k)
{
	const struct c0_support_share *s = &k->s;
	const int W = k->in->width, H = k->in->height;
	if (!k->c->fwhm_data)
		return C0_OK;
	double *rs = c0_alloc(2 * (size_t)H, sizeof *rs), sum[2] = { 0, 0 }, fw;
	int st = rs ? C0_OK : C0_ENOMEM;
	for (int y = s->ia; !st && y < s->ib; y++) {
		struct c0_cov w = { 0 };
		st = c0_cov_acc_window(s->acc, y - s->ya, 0, s->yb - y < 3 ? s->yb - y : 3, W, &w);
		if (!st)
			c0_lambda_psf_row_sums(&w, 0, rs + 2 * y);
		c0_cov_free(&w);
	}
	if ((st = c0_comm_status(st))) {
		free(rs);
		return st;
	}
	c0_comm_sum(rs, 2 * H);   /* one process adds to each row: exact */
	for (int y = 0; y < H; y++)
		sum[0] += rs[2 * y], sum[1] += rs[2 * y + 1];
	free(rs);
	if (c0_lambda_psf_fwhm_sums(sum, k->c->grid.pixel_nm, &fw)) {
		c0_clear_error();
		return C0_OK;
	}
	k->fwd = fw;
	k->cc = *k->c;
	if (adopt_width(&k->cc, fw))
		k->c = &k->cc;
	return C0_OK;
}

/* lambda relative to the image's lambda_max: the largest of the tiles';
 * automatic: chosen from the noise of the subset's correlation images,
 * then for l1 from the peaks of a first solve, or (lambda_cv) by
 * cross-validation on the subset's halves. Collective. */
static int stack_lambda(struct stack *k, struct c0_support_result *res)
{
	const struct c0_support_conf *c = k->c;
	const int n = k->s.tl.n;
	double tn = c0_now(), l1 = 0, l0 = 0;
	k->rel = c0_support_lambda_rel(c);
	int st = c0_comm_status(c0_support_tiles_lambda(c, &k->s, k->norm, k->lm, k->hist));
	if (!st) {
		c0_comm_max(k->lm, 2 * n);
		for (int j = 0; j < n; j++)
			l1 = fmax(l1, k->lm[2 * j]), l0 = fmax(l0, k->lm[2 * j + 1]);
		res->lambda_max = c->penalty == C0_PENALTY_L1 ? l1 : l0;
	}
	if (!st && k->automatic) {
		c0_comm_sum(k->hist, C0_LAMBDA_HIST);
		if (!(l1 > 0))
			st = c0_fail(C0_EINVAL, "the stack's covariance correlates with no emitter position (lambda_max = 0)");
		else
			c0_lambda_tiles_choose(c, k->hist, l1, l0, &res->cv), k->rel = res->cv.chosen_rel, res->lambda_auto = 1;
		for (int j = 0; j < n; j++)
			res->cv.noise_tiles += k->s.sub[j];
		res->cv.seconds = c0_now() - tn;
	}
	free(k->lm), free(k->hist);
	k->lm = k->hist = NULL;
	if (!st && k->automatic && c->penalty == C0_PENALTY_L1 && (c->lambda_cv || !c->lambda_noise)) {
		tn = c0_now();
		if (c->lambda_cv)
			st = c0_support_tiles_cv(c, &k->s, k->norm, l1, res);
		else
			st = c0_support_tiles_second(c, &k->s, &(struct c0_support_scale){ k->norm, k->rel * l1 }, l1, res);
		k->rel = res->cv.chosen_rel;
		res->cv.cv_seconds = c->lambda_cv ? c0_now() - tn : 0;
		res->cv.seconds += c0_now() - tn;
	}
	return st;
}

/* The precision from the halves first, then their bands are freed before
 * the tiles' solves. Collective. */
static int stack_solve(struct stack *k, struct c0_support_result *res)
{
	const struct c0_support_conf *c = k->c;
	struct c0_support_share *s = &k->s;
	int st = C0_OK;
	res->lambda = k->rel * res->lambda_max;
	res->norm = k->norm;
	const struct c0_support_scale g = { k->norm, res->lambda };
	if (c->frc)
		st = c0_comm_status(c0_support_tiles_precision(c, s, &g, res));
	for (int j = 0; j < s->k1 - s->k0; j++) {
		c0_cov_acc_free(s->odd[j]), s->odd[j] = NULL;
		if (s->even)
			c0_cov_acc_free(s->even[j]), s->even[j] = NULL;
	}
	c0_mem_release();     /* the odd bands and the halves' solves */
	/* the results only now: the steps above fill freed memory again */
	res->mask = c0_alloc((size_t)res->Ly * res->Lx, 1);
	res->rx = c0_alloc((size_t)res->Ly * res->Lx, sizeof *res->rx);
	res->mean = c0_alloc((size_t)k->in->width * k->in->height, sizeof *res->mean);
	if (!st)
		st = c0_comm_status(res->mask && res->rx && res->mean ? c0_support_tiles_solve(c, s, &g, res, k->s2, k->stats, k->obj)
				    : C0_ENOMEM);
	return st;
}

/* Rank 0 gathers the interiors and combines the tiles' numbers (each
 * tile's come from one rank, so sums over ranks are exact and sums over
 * tiles are made in tile order, whatever the ranks and threads). Collective. */
static int stack_gather(struct stack *k, struct c0_support_result *res)
{
	const struct c0_tiling *tl = &k->s.tl;
	const int W = k->in->width, r = k->c->grid.srf, ia = k->s.ia, ib = k->s.ib;
	c0_comm_sum(k->s2, tl->n);
	c0_comm_sum(k->stats, 4 * tl->n);
	c0_comm_sum(k->obj, tl->n * res->nhist);
	int st = c0_comm_gather_rows(res->mask, (size_t)W * r, ia * r, (ib - ia) * r);
	if (!st)
		st = c0_comm_gather_rows(res->rx, (size_t)W * r * sizeof(float), ia * r, (ib - ia) * r);
	if (!st)
		st = c0_comm_gather_rows(res->mean, (size_t)W * sizeof(double), ia, ib - ia);
	if (st)
		return st;
	double area = 0;
	res->converged = 1;
	for (int j = 0; j < tl->n; j++)
		for (int i = 0; i < res->nhist; i++)
			res->hist[i] += k->obj[(size_t)j * res->nhist + i];
	for (int j = 0; j < tl->n; j++) {
		const struct c0_tile *t = &tl->t[j];
		const double *ts = k->stats + 4 * (size_t)j;
		res->sigma2 += k->s2[j] * t->ih * t->iw, area += (double)t->ih * t->iw;
		res->iters = ts[0] > res->iters ? (int)ts[0] : res->iters;
		res->converged &= ts[1] > 0;
		res->gap = fmax(res->gap, ts[2]);
	}
	res->sigma2 /= area;
	res->nhist = res->iters < res->nhist ? res->iters : res->nhist;
	for (size_t i = 0; i < (size_t)res->Ly * res->Lx; i++)
		res->support_pixels += res->mask[i];
	res->tiles = tl->n, res->tile = c0_support_tile_size(k->c, W, k->in->height);
	if (!k->c->frc)
		res->precision_nm = -1;
	return C0_OK;
}

int c0_support_stack(const struct c0_support_conf *c, struct c0_frames *in, struct c0_support_result *res)
{
	return c0_support_stacks(c, in, 1, res);
}

/* the n stacks are one field: the same size, enough frames each */
static int stacks_check(struct c0_frames *in, int n, int halves)
{
	for (int q = 0; q < n; q++) {
		if (in[q].width != in[0].width || in[q].height != in[0].height)
			return c0_fail(C0_EINVAL, "%s: %dx%d pixels, but %s has %dx%d: stacks pooled into one support share one field",
				       in[q].name, in[q].width, in[q].height, in[0].name, in[0].width, in[0].height);
		if (halves && in[q].count < 6)
			return c0_support_fail_short(&in[q]);
	}
	return C0_OK;
}

/* c: the stacks' n configurations (their drift hooks and noise maps differ) */
int c0_support_stacks(const struct c0_support_conf *c, struct c0_frames *in, int n, struct c0_support_result *res)
{
	memset(res, 0, sizeof *res);
	struct stack k = { .c = c, .in = in, .n = n };
	if (n < 1)
		return c0_fail(C0_EINVAL, "support: no stack");
	int st = c0_support_grid(c, in, &k.s.tl);
	if (st)
		return st;
	double t0 = c0_now();
	k.automatic = !(c->lambda_rel > 0), k.halves = k.automatic || c->frc;
	st = stacks_check(in, n, k.halves && k.s.tl.n > 1);
	/* one tile: every process solves the whole image, as one process does
	 * (the tiles' path normalises and chooses lambda its own way) */
	if (st || k.s.tl.n == 1) {
		c0_tiling_free(&k.s.tl);
		return st ? st : stack_whole(c, in, n, res);
	}
	/* several tiles or processes: the band of all frames, and for the
	 * automatic lambda that of the odd frames on a subset of the tiles */
	st = share_open(&k);
	if (!st && k.s.yb > k.s.ya)
		st = c0_support_stream_tiles(c, in, n, &k.s);
	res->t_cov = c0_now() - t0;
	double t1 = c0_now();
	st = stack_scale(&k, st, res);
	if (!st)
		st = stack_width(&k);
	if (!st)
		st = stack_lambda(&k, res);
	if (!st)
		st = stack_solve(&k, res);
	share_close(&k.s);
	if (!st)
		st = stack_gather(&k, res);
	res->fwhm_nm = k.c->grid.fwhm_nm;
	if (k.fwd > 0)
		res->cv.fwhm_data_nm = k.fwd;
	free(k.lm), free(k.hist), free(k.s2), free(k.stats), free(k.obj);
	c0_tiling_free(&k.s.tl);
	res->t_solve = c0_now() - t1;
	if (st)
		c0_support_result_free(res);
	return st;
}
