#include "stages/support_parts.h"
#include "ops/covpool.h"
#include "optics/psf.h"
#include "core/c0math.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"
#include "core/comm.h"
#include "stages/tiles.h"

#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <omp.h>
#include <string.h>

int c0_support_lag(const struct c0_support_conf *c)
{
	return c->lag > 0 ? c->lag : (int)ceil(6 * c0_psf_sigma_px(c->fwhm_nm, c->pixel_nm));
}

double c0_support_default_lambda(enum c0_penalty p)
{
	return p == C0_PENALTY_CEL0 ? 3e-5 : 1e-2;
}

double c0_support_tol(const struct c0_support_conf *c)
{
	if (c->fista.tol >= 0)
		return c->fista.tol;
	return c->penalty == C0_PENALTY_L1 && c->solver == C0_SUPPORT_FISTA ? 0 : C0_SUPPORT_TOL;
}

double c0_support_guard_ratio(const struct c0_support_conf *c)
{
	const double sigma = c0_psf_sigma_px(c->fwhm_nm, c->pixel_nm);
	double g = INFINITY, w[3];
	/* a source inside pixel 0 (others give larger ratios: the pixel is
	 * then on their Gaussian's flank or tail) */
	for (int k = 0; k <= 64; k++) {
		c0_psf_pixel_weights(k / 64.0, sigma, -1, 3, w);
		if (w[1] > 0)
			g = fmin(g, (w[0] + w[2]) / (2 * w[1]));
	}
	return g < 1 ? g : 1;
}

int c0_support_acc_new(const struct c0_support_conf *c, int W, int H, int d, struct c0_cov_acc **a)
{
	int st = c0_cov_acc_new(W, H, d, a);
	if (!st && c->guard)
		c0_cov_acc_set_guard(*a, c0_support_guard_ratio(c));
	return st;
}

double c0_support_lambda_rel(const struct c0_support_conf *c)
{
	return c->lambda_rel > 0 ? c->lambda_rel : c0_support_default_lambda(c->penalty);
}

int c0_support_fail_flat(void)
{
	return c0_fail(C0_EINVAL, "the stack does not fluctuate (zero temporal variance everywhere)");
}

int c0_support_fail_short(const struct c0_frames *in)
{
	return c0_fail(C0_EINVAL, "%s: %lld frames is too short to choose lambda from two halves (needs >= 6; "
		       "give lambda)", in->name, (long long)in->count);
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
	if (c->fista.maxit < 1)
		return c0_fail(C0_EINVAL, "iterations %d: must be positive", c->fista.maxit);
	if (!(c->fista.tol >= 0 && c->fista.tol < 1) && c->fista.tol != -1)
		return c0_fail(C0_EINVAL, "tol %g: must be in [0, 1) (0: every iteration), or -1 for the solver's", c->fista.tol);
	if (c->penalty == C0_PENALTY_CEL0 && c->cel0_outer < 1)
		return c0_fail(C0_EINVAL, "reweightings %d: must be at least 1", c->cel0_outer);
	if (c->lag < 0 || c->lag > 1000)
		return c0_fail(C0_EINVAL, "lag %d: must be 0 (from the PSF) to 1000 pixels", c->lag);
	int d = c0_support_lag(c);
	if (c->tile && c->tile < 2 * d + 1)
		return c0_fail(C0_EINVAL, "tile %d: smaller than the PSF band (%d pixels for lag %d)", c->tile, 2 * d + 1, d);
	if (c->tile && c->tile > (W > H ? W : H))
		return c0_fail(C0_EINVAL, "tile %d: larger than the %dx%d image of %s", c->tile, W, H, name);
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

/* One pass; frames alternate between the nacc accumulators (1 or 2). */
static int stream_cov(const struct c0_support_conf *c, struct c0_frames *in, int nacc, struct c0_cov *cov,
		      double *seconds)
{
	int st = c0_support_check(c, in->width, in->height, in->count, in->name);
	if (!st && nacc == 2 && in->count < 6)
		st = c0_support_fail_short(in);
	if (st)
		return st;
	double t0 = c0_now();
	struct c0_cov_acc *acc[2] = { NULL, NULL };
	for (int k = 0; k < nacc && !st; k++)
		st = c0_support_acc_new(c, in->width, in->height, c0_support_lag(c), &acc[k]);
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

int c0_stack_noise(const struct c0_support_conf *c, struct c0_frames *in, const uint8_t *mask, double **mean,
		   int64_t *frames, double *sigma2, double *seconds)
{
	*mean = NULL, *frames = in->count, *sigma2 = 0, *seconds = 0;
	const int W = in->width, H = in->height, r = c->srf, d = c0_support_lag(c);
	int st = c0_support_check(c, W, H, in->count, in->name);
	if (st)
		return st;
	double t0 = c0_now();
	struct c0_tiling tl;
	if ((st = c0_tiling_make(H, W, c0_support_tile_size(c, W, H), 2 * d, &tl)))
		return st;
	struct c0_cov_acc *acc = NULL;
	st = c0_support_acc_new(c, W, H, d, &acc);
	float *frame = st ? NULL : c0_alloc((size_t)W * H, sizeof *frame);
	if (!st && !frame)
		st = C0_ENOMEM;
	for (int64_t t = 0; t < in->count && !st; t++) {
		st = c0_frames_read(in, t, frame);
		if (!st && c->frame_fn)
			st = c->frame_fn(c->frame_ctx, t, frame, H, W);
		if (!st)
			st = c0_cov_acc_add(acc, frame);
	}
	free(frame);
	if (!st && in->count < 3)
		st = c0_fail(C0_EINVAL, "%s: the covariance needs at least 3 frames", in->name);
	if (!st)
		c0_cov_acc_seal(acc);   /* the windows below only read */
	*seconds = c0_now() - t0;
	double *s2 = c0_alloc((size_t)tl.n, sizeof *s2);
	*mean = c0_alloc((size_t)W * H, sizeof **mean);
	if (!st && (!s2 || !*mean))
		st = C0_ENOMEM;
	struct c0_support_conf cc = *c;
	cc.fista.maxit = 100;   /* sigma2 within 0.1 % of 1000 iterations (docs/parameters.md) */
	struct c0_first_fail fail = { 0 };
#pragma omp parallel for schedule(dynamic, 1) if (tl.n > 1)
	for (int k = 0; k < (st ? 0 : tl.n); k++) {
		const struct c0_tile *t = &tl.t[k];
		struct c0_cov cov = { 0 };
		struct c0_support_result tr;
		memset(&tr, 0, sizeof tr);
		const size_t Lw = (size_t)t->w * r;
		uint8_t *m = malloc(Lw * t->h * r);
		int ts = m ? c0_cov_acc_window(acc, t->y0, t->x0, t->h, t->w, &cov) : C0_ENOMEM;
		for (int a = 0; !ts && a < t->h * r; a++)
			memcpy(m + a * Lw, mask + (size_t)(t->y0 * r + a) * W * r + (size_t)t->x0 * r, Lw);
		if (!ts)
			ts = c0_support_noise_solve(&cc, &cov, m, &tr);
		if (!ts) {
			s2[k] = tr.sigma2;
			const int oy = t->iy0 - t->y0, ox = t->ix0 - t->x0;
			for (int a = 0; a < t->ih; a++)
				memcpy(*mean + (size_t)(t->iy0 + a) * W + t->ix0, cov.mean + (size_t)(oy + a) * t->w + ox,
				       (size_t)t->iw * sizeof **mean);
		}
		c0_first_fail_note(&fail, ts);
		c0_cov_free(&cov);
		c0_support_result_free(&tr);
		free(m);
	}
	if (!st)
		st = c0_first_fail_raise(&fail);
	double area = 0;
	for (int k = 0; !st && k < tl.n; k++)   /* in tile order: the same sum on any schedule */
		*sigma2 += s2[k] * tl.t[k].ih * tl.t[k].iw, area += (double)tl.t[k].ih * tl.t[k].iw;
	if (!st)
		*sigma2 /= area;
	c0_cov_acc_free(acc);
	free(s2);
	c0_tiling_free(&tl);
	if (st)
		free(*mean), *mean = NULL;
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
		st = c0_support_solve(&cc, &half[k], &h[k]);
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

/* One tile and one process: the covariance with its two interleaved halves
 * (automatic lambda, FRC) in one pass of whole frames. */
static int stack_whole(const struct c0_support_conf *c, struct c0_frames *in, struct c0_support_result *res)
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
	double norm = 0;
	for (size_t i = 0; !st && i < (size_t)cov.W * cov.H; i++)
		norm = isfinite(cov.r[i]) ? fmax(norm, cov.r[i]) : INFINITY;
	if (!st)
		st = check_norm(in->name, norm);
	struct c0_progress ps;
	c0_progress_begin(&ps, "support", 1);
	if (!st && automatic && !(st = c0_lambda_auto(c, &half[0], &half[1], &res->cv)))
		cc.lambda_rel = res->cv.chosen_rel, res->lambda_auto = 1;
	if (!st && automatic && c->penalty == C0_PENALTY_L1)
		st = second_step(&cc, &cov, res);
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
	c0_cov_free(&cov);
	return st;
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

/* Runs fn over this process's tiles side by side (one tile per thread: the
 * solvers' own loops then run serially, so a tile's numbers do not depend
 * on how many threads or processes share the work). */
static int each_tile(const struct c0_support_conf *c, struct c0_cov_acc *acc, int ya, const struct c0_tiling *tl,
		     int k0, int k1, const struct c0_support_scale *g, struct c0_support_result *res, double *tile_s2, double *tile_stats)
{
	const int r = c->srf, Lx = tl->t[tl->n - 1].x0 + tl->t[tl->n - 1].w;
	struct c0_first_fail fail = { 0 };
	struct c0_progress pr;
	int done = 0, lo = k0;       /* the tiles before lo are done */
	uint8_t *fin = c0_alloc((size_t)(k1 - k0) + 1, 1);
	if (!fin)
		return C0_ENOMEM;
	c0_progress_begin(&pr, "support (tiles)", k1 - k0);
#pragma omp parallel for schedule(dynamic, 1) if (tl->n > 1)
	for (int k = k0; k < k1; k++) {
		const struct c0_tile *t = &tl->t[k];
		struct c0_support_result tr;
		int st = tile_solve(c, acc, ya, t, g, &tr);
		if (!st) {
			/* keep the interior: fine rows and columns inside the window */
			const int oy = t->iy0 - t->y0, ox = t->ix0 - t->x0;
			for (int y = 0; y < t->ih * r; y++) {
				const size_t src = (size_t)(oy * r + y) * tr.Lx + (size_t)ox * r;
				const size_t dst = (size_t)(t->iy0 * r + y) * (Lx * r) + (size_t)t->ix0 * r;
				memcpy(res->mask + dst, tr.mask + src, (size_t)t->iw * r);
				memcpy(res->rx + dst, tr.rx + src, (size_t)t->iw * r * sizeof(float));
			}
			for (int y = 0; y < t->ih; y++)
				memcpy(res->mean + (size_t)(t->iy0 + y) * Lx + t->ix0, tr.mean + (size_t)(oy + y) * t->w + ox,
				       (size_t)t->iw * sizeof(double));
			tile_s2[k] = tr.sigma2;
			double *ts = tile_stats + 4 * (size_t)k;
			ts[0] = tr.iters, ts[1] = tr.converged, ts[2] = tr.gap, ts[3] = tr.lambda_max;
#pragma omp critical(c0_support_hist)
			for (int i = 0; i < res->nhist; i++)      /* a finished tile keeps its last value */
				res->hist[i] += tr.nhist ? tr.hist[i < tr.nhist ? i : tr.nhist - 1] : 0;
		}
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
				c0_cov_acc_drop_rows(acc, tl->t[lo].y0 - ya);
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

/* The automatic lambda's second step on tiles (stages/lambda.h): the noise
 * subset's tiles solved at the rule's lambda (side by side, one per thread),
 * their interiors' peaks summed over tiles and ranks. Collective. */
static int tiles_second(const struct c0_support_conf *c, struct c0_cov_acc *acc, int ya, const struct c0_tiling *tl,
			int k0, int k1, const uint8_t *sub, const struct c0_support_scale *g, double lmax, struct c0_support_result *res)
{
	struct c0_first_fail fail = { 0 };
	struct c0_progress pr;
	int done = 0, nsub = 0;
	double *hist = c0_alloc(C0_LAMBDA_BINS, sizeof *hist);
	if (!hist)
		c0_first_fail_note(&fail, C0_ENOMEM);
	for (int k = k0; k < k1; k++)
		nsub += sub[k];
	c0_progress_begin(&pr, "support (lambda, first solve)", nsub);
#pragma omp parallel for schedule(dynamic, 1) if (tl->n > 1)
	for (int k = k0; k < k1; k++) {
		if (!sub[k] || !hist)
			continue;
		const struct c0_tile *t = &tl->t[k];
		struct c0_support_result tr = { 0 };
		double *h = c0_alloc(C0_LAMBDA_BINS, sizeof *h);
		int st = h ? tile_solve(c, acc, ya, t, g, &tr) : C0_ENOMEM;
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

/* Every tile's lambda_max on both scales (lm: 2 per tile); with hist, every
 * tile adds its correlation image, and the subset's halves (the even frames
 * from all and the odd ones) its noise (stages/lambda.h). */
static int each_tile_noise(const struct c0_support_conf *c, struct c0_cov_acc *acc, int ya, const struct c0_tiling *tl,
			   int k0, int k1, struct c0_cov_acc **odd, double norm, double *lm, double *hist)
{
	struct c0_first_fail fail = { 0 };
	struct c0_progress pr;
	int done = 0;
	c0_progress_begin(&pr, "support (lambda)", k1 - k0);
#pragma omp parallel for schedule(dynamic, 1) if (tl->n > 1)
	for (int k = k0; k < k1; k++) {
		const struct c0_tile *t = &tl->t[k];
		struct c0_cov all, ev, od;
		struct c0_cov_acc *o = hist ? odd[k - k0] : NULL;
		double *h = hist ? c0_alloc(C0_LAMBDA_HIST, sizeof *h) : NULL;
		int st = hist && !h ? C0_ENOMEM : c0_cov_acc_window(acc, t->y0 - ya, t->x0, t->h, t->w, &all);
		if (!st) {
			st = c0_lambda_tile_max(c, &all, norm, t->iy0 - t->y0, t->ix0 - t->x0, t->ih, t->iw, lm + 2 * (size_t)k, h);
			c0_cov_free(&all);
		}
		/* one half's band at a time: each gives its correlation image */
		double *ca = NULL, *cb = NULL, *cn = NULL;
		if (!st && o && !(st = c0_cov_acc_window_even(acc, o, t->y0 - ya, t->x0, &ev))) {
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
		tile_hist_done(hist, h, C0_LAMBDA_HIST, st, &fail, &pr, &done);
	}
	c0_progress_end(&pr);
	return c0_first_fail_raise(&fail);
}

/* The localisation precision on tiles: each subset tile's halves solved on
 * their own (at most FRC_MAXIT iterations, the image's scale and lambda),
 * their interiors' matched distances added in tile order (half_frc on one
 * tile), on part of the noise subset (PRECISION_PX). The halves are solved
 * side by side, one per thread, as the tiles are. No FRC: its
 * ring sums added over Hann-windowed tiles disagreed with the one-tile
 * value (docs/parameters.md). */
#define PRECISION_PX (256 * 256)
static int tiles_precision(const struct c0_support_conf *c, struct c0_cov_acc *acc, int ya, const struct c0_tiling *tl,
			   int k0, int k1, struct c0_cov_acc **odd, const uint8_t *sub, const struct c0_support_scale *g,
			   struct c0_support_result *res)
{
	/* which of the noise subset: spread evenly, interiors up to
	 * PRECISION_PX (all of them up to 256x256 images; each half solve costs
	 * as much as a tile's whole solve) */
	int nc = 0, *cand = c0_alloc((size_t)tl->n, sizeof *cand);
	uint8_t *use = c0_alloc((size_t)tl->n, 1);
	if (!cand || !use) {
		free(cand), free(use);
		return C0_ENOMEM;
	}
	for (int k = 0; k < tl->n; k++)
		if (sub[k])
			cand[nc++] = k;
	if (nc)
		spread(tl, cand, nc, PRECISION_PX, use);
	free(cand);
	double t0 = c0_now();
	const int r = c->srf;
	const double fine = c->pixel_nm / r;
	const int rad = (int)ceil(0.5 * c->fwhm_nm / fine);
	double *sums = c0_alloc(2 * (size_t)tl->n, sizeof *sums);   /* distance^2, matches */
	struct c0_support_conf cc = *c;
	if (cc.fista.maxit > FRC_MAXIT)
		cc.fista.maxit = FRC_MAXIT;
	/* work items: the two halves of each subset tile of this process */
	int nw = 0;
	int *item = c0_alloc(2 * (size_t)(k1 - k0) + 1, sizeof *item);
	uint8_t **m = c0_alloc((size_t)(k1 - k0) + 1, sizeof *m);     /* both halves' interior masks */
	int fail = sums && item && m ? C0_OK : C0_ENOMEM;
	struct c0_first_fail ff = { 0 };
	for (int k = k0; k < k1 && !fail; k++) {
		const struct c0_tile *t = &tl->t[k];
		if (!odd[k - k0] || !use[k])
			continue;
		if (!(m[k - k0] = c0_alloc(2 * (size_t)t->ih * r * t->iw * r, 1)))
			fail = C0_ENOMEM;
		item[nw++] = 2 * k, item[nw++] = 2 * k + 1;
	}
	/* side by side, one solve per thread (the solver's own loops then run
	 * serially, as in each_tile): two solves at a time, as there */
#pragma omp parallel for schedule(dynamic, 1) if (nw > 1 && !fail)
	for (int w = 0; w < nw; w++) {
		if (fail)
			continue;
		const int k = item[w] / 2, j = item[w] % 2;
		const struct c0_tile *t = &tl->t[k];
		struct c0_cov h;
		struct c0_support_result hr;
		memset(&hr, 0, sizeof hr);
		const int ih = t->ih * r, iw = t->iw * r, oy = (t->iy0 - t->y0) * r, ox = (t->ix0 - t->x0) * r;
		struct c0_cov_acc *o = odd[k - k0];
		int st = j ? c0_cov_acc_window(o, 0, 0, t->h, t->w, &h) : c0_cov_acc_window_even(acc, o, t->y0 - ya, t->x0, &h);
		if (!st) {
			st = c0_support_window_solve(&cc, &h, NULL, &h.r, g, &hr);
			c0_cov_free(&h);
		}
		for (int y = 0; !st && y < ih; y++)
			memcpy(m[k - k0] + ((size_t)j * ih + y) * iw, hr.mask + (size_t)(oy + y) * hr.Lx + ox, (size_t)iw);
		c0_support_result_free(&hr);
		c0_first_fail_note(&ff, st);
	}
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
	if (fail) {
		free(sums);
		return fail;
	}
	/* over ranks, then over tiles in tile order: the same sums for any split */
	c0_comm_sum(sums, 2 * tl->n);
	double s = 0, n = 0;
	for (int k = 0; k < tl->n; k++)
		s += sums[2 * k], n += sums[2 * k + 1];
	res->precision_nm = n > 0 ? sqrt(s / n / 4) * fine / sqrt(2) : -1;
	free(sums);
	res->t_frc = c0_now() - t0;
	return C0_OK;
}

int c0_support_tile_size(const struct c0_support_conf *c, int W, int H)
{
	int big = W > H ? W : H;
	return c->tile > 0 ? c->tile : C0_SUPPORT_TILE < big ? C0_SUPPORT_TILE : big;
}

int c0_support_stack(const struct c0_support_conf *c, struct c0_frames *in, struct c0_support_result *res)
{
	memset(res, 0, sizeof *res);
	const int W = in->width, H = in->height, r = c->srf, d = c0_support_lag(c);
	int st = c0_support_check(c, W, H, in->count, in->name);
	if (st)
		return st;
	double t0 = c0_now();
	/* the tile grid (halo: two lags), and this process's share of it */
	struct c0_tiling tl;
	if ((st = c0_tiling_make(H, W, c0_support_tile_size(c, W, H), 2 * d, &tl)))
		return st;
	const int rank = c0_comm_rank(), size = c0_comm_size();
	if (tl.n == 1 && size == 1) {
		c0_tiling_free(&tl);
		return stack_whole(c, in, res);
	}
	/* several tiles or processes: the band of all frames, and for the
	 * automatic lambda that of the odd frames on a subset of the tiles */
	const int automatic = !(c->lambda_rel > 0), halves = automatic || c->frc;
	if (halves && in->count < 6) {
		c0_tiling_free(&tl);
		return c0_support_fail_short(in);
	}
	int k0, k1, ya, yb, ia, ib;
	c0_tiling_share(&tl, rank, size, &k0, &k1, &ya, &yb, &ia, &ib);
	const int rows = yb - ya, block = c0_cov_block_frames((size_t)W * H);
	/* one pass over the frames, each reading only this process's rows */
	struct c0_cov_acc *acc = NULL, **odd = c0_alloc((size_t)(k1 - k0) + 1, sizeof *odd);
	uint8_t *sub = c0_alloc((size_t)tl.n, 1);
	float *frame = NULL, *win = NULL;
	if (!odd || !sub)
		st = C0_ENOMEM;
	else if (halves)
		spread(&tl, NULL, tl.n, SUBSET_PX, sub);
	if (!st && rows > 0) {
		st = c0_support_acc_new(c, W, rows, d, &acc);
		if (!st)
			st = c0_cov_acc_set_block(acc, block);
		size_t wmax = 0;
		for (int k = k0; k < k1 && !st; k++) {
			const struct c0_tile *t = &tl.t[k];
			if (sub[k] && !(st = c0_support_acc_new(c, t->w, t->h, d, &odd[k - k0])))
				st = c0_cov_acc_set_block(odd[k - k0], block);
			wmax = sub[k] && (size_t)t->w * t->h > wmax ? (size_t)t->w * t->h : wmax;
		}
		/* a frame hook (drift) needs whole frames */
		if (!st && !(frame = c0_alloc((size_t)W * (c->frame_fn ? H : rows), sizeof *frame)))
			st = C0_ENOMEM;
		if (!st && wmax && !(win = c0_alloc(wmax, sizeof *win)))
			st = C0_ENOMEM;
		struct c0_progress pr;
		c0_progress_begin(&pr, "covariance", (double)in->count);
		for (int64_t t = 0; t < in->count && !st; t++) {
			const float *mine = frame;     /* this process's rows */
			if (c->frame_fn) {
				st = c0_frames_read(in, t, frame);
				if (!st)
					st = c->frame_fn(c->frame_ctx, t, frame, H, W);
				mine = frame + (size_t)ya * W;
			} else {
				st = c0_frames_read_rows(in, t, ya, rows, frame);
			}
			if (!st)
				st = c0_cov_acc_add(acc, mine);
			for (int k = k0; k < k1 && !st && t % 2; k++) {
				const struct c0_tile *w = &tl.t[k];
				if (!odd[k - k0])
					continue;
				for (int y = 0; y < w->h; y++)
					memcpy(win + (size_t)y * w->w, mine + (size_t)(w->y0 - ya + y) * W + w->x0,
					       (size_t)w->w * sizeof *win);
				st = c0_cov_acc_add(odd[k - k0], win);
			}
			c0_progress_update(&pr, (double)t + 1);
		}
		c0_progress_end(&pr);
		free(frame), free(win);
	}
	res->t_cov = c0_now() - t0;
	double t1 = c0_now();
	/* the tiles below only read them, some from two threads (the halves) */
	if (!st && acc)
		c0_cov_acc_seal(acc);
	for (int k = 0; !st && k < k1 - k0; k++)
		if (odd[k])
			c0_cov_acc_seal(odd[k]);
	c0_mem_release();    /* the blocks and the frame */
	/* the image's normalisation: its largest pixel variance */
	double norm = 0;
	for (int y = ia; !st && y < ib; y++)
		for (int x = 0; x < W; x++)
			norm = fmax(norm, c0_cov_acc_variance(acc, y - ya, x));
	const size_t L = (size_t)W * H * r * r, nt = (size_t)tl.n;
	double *lm = c0_alloc(2 * nt, sizeof *lm), *s2 = c0_alloc(nt, sizeof *s2), *stats = c0_alloc(4 * nt, sizeof *stats);
	double *hist = automatic ? c0_alloc(C0_LAMBDA_HIST, sizeof *hist) : NULL;
	res->Ly = H * r, res->Lx = W * r, res->lag = d, res->nlag = c0_cov_lag_count(d), res->frames = in->count;
	res->nhist = c->fista.maxit * (c->penalty == C0_PENALTY_CEL0 ? c->cel0_outer : 1);
	res->hist = c0_alloc((size_t)res->nhist, sizeof *res->hist);
	if (!st && (!lm || !s2 || !stats || (automatic && !hist) || !res->hist))
		st = C0_ENOMEM;
	if (!(st = c0_comm_status(st))) {
		c0_comm_max(&norm, 1);
		st = check_norm(in->name, norm);
	}
	/* lambda relative to the image's lambda_max: the largest of the tiles';
	 * automatic: chosen from the noise of the subset's correlation images */
	struct c0_support_scale g = { norm, 0 };
	double rel = c0_support_lambda_rel(c), tn = c0_now(), l1 = 0, l0 = 0;
	if (!st)
		st = c0_comm_status(each_tile_noise(c, acc, ya, &tl, k0, k1, odd, norm, lm, hist));
	if (!st) {
		c0_comm_max(lm, 2 * tl.n);
		for (int k = 0; k < tl.n; k++)
			l1 = fmax(l1, lm[2 * k]), l0 = fmax(l0, lm[2 * k + 1]);
		res->lambda_max = c->penalty == C0_PENALTY_L1 ? l1 : l0;
	}
	if (!st && automatic) {
		c0_comm_sum(hist, C0_LAMBDA_HIST);
		if (!(l1 > 0))
			st = c0_fail(C0_EINVAL, "the stack's covariance correlates with no emitter position (lambda_max = 0)");
		else
			c0_lambda_tiles_choose(c, hist, l1, l0, &res->cv), rel = res->cv.chosen_rel, res->lambda_auto = 1;
		for (int k = 0; k < tl.n; k++)
			res->cv.noise_tiles += sub[k];
		res->cv.seconds = c0_now() - tn;
	}
	free(lm), free(hist);
	if (!st && automatic && c->penalty == C0_PENALTY_L1) {
		tn = c0_now();
		st = tiles_second(c, acc, ya, &tl, k0, k1, sub, &(struct c0_support_scale){ norm, rel * l1 }, l1, res);
		rel = res->cv.chosen_rel;
		res->cv.seconds += c0_now() - tn;
	}
	if (!st) {
		res->lambda = rel * res->lambda_max;
		res->norm = norm;
		g.lam = res->lambda;
		/* the halves first, then their bands are freed before the tiles' solves */
		if (c->frc)
			st = c0_comm_status(tiles_precision(c, acc, ya, &tl, k0, k1, odd, sub, &g, res));
		for (int k = 0; k < k1 - k0; k++)
			c0_cov_acc_free(odd[k]), odd[k] = NULL;
		c0_mem_release();     /* the odd bands and the halves' solves */
		/* the results only now: the steps above fill freed memory again */
		res->mask = c0_alloc(L, 1);
		res->rx = c0_alloc(L, sizeof *res->rx);
		res->mean = c0_alloc((size_t)W * H, sizeof *res->mean);
		if (!st)
			st = c0_comm_status(res->mask && res->rx && res->mean ? each_tile(c, acc, ya, &tl, k0, k1, &g, res, s2, stats)
					    : C0_ENOMEM);
	}
	c0_cov_acc_free(acc);
	for (int k = 0; odd && k < k1 - k0; k++)
		c0_cov_acc_free(odd[k]);
	free(odd), free(sub);
	/* rank 0 gathers the interiors (each tile's numbers come from one rank,
	 * so sums over tiles are made in tile order, whatever the ranks) */
	if (!st) {
		c0_comm_sum(s2, tl.n);
		c0_comm_sum(stats, 4 * tl.n);
		c0_comm_sum(res->hist, res->nhist);
		st = c0_comm_gather_rows(res->mask, (size_t)W * r, ia * r, (ib - ia) * r);
		if (!st)
			st = c0_comm_gather_rows(res->rx, (size_t)W * r * sizeof(float), ia * r, (ib - ia) * r);
		if (!st)
			st = c0_comm_gather_rows(res->mean, (size_t)W * sizeof(double), ia, ib - ia);
	}
	if (!st) {
		double area = 0;
		res->converged = 1;
		for (int k = 0; k < tl.n; k++) {
			const struct c0_tile *t = &tl.t[k];
			const double *ts = stats + 4 * (size_t)k;
			res->sigma2 += s2[k] * t->ih * t->iw, area += (double)t->ih * t->iw;
			res->iters = ts[0] > res->iters ? (int)ts[0] : res->iters;
			res->converged &= ts[1] > 0;
			res->gap = fmax(res->gap, ts[2]);
		}
		res->sigma2 /= area;
		res->nhist = res->iters < res->nhist ? res->iters : res->nhist;
		for (size_t i = 0; i < L; i++)
			res->support_pixels += res->mask[i];
		res->tiles = tl.n, res->tile = c0_support_tile_size(c, W, H);
		if (!c->frc)
			res->precision_nm = -1;
	}
	free(s2), free(stats);
	c0_tiling_free(&tl);
	res->t_solve = c0_now() - t1;
	if (st)
		c0_support_result_free(res);
	return st;
}
