#include "stages/bleach.h"
#include "io/frames.h"
#include "optics/tirf.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int c0_bleach_check(const struct c0_bleach_conf *c, int n)
{
	if (n > C0_BLEACH_MAX)
		return c0_fail(C0_EINVAL, "bleach: at most %d stacks", C0_BLEACH_MAX);
	if (c->norder) {
		if (c->norder != n)
			return c0_fail(C0_EINVAL, "acquisition_order: %d stack numbers for %d stacks (give each stack once, in recording order)",
				       c->norder, n);
		int seen[C0_BLEACH_MAX] = { 0 };
		for (int i = 0; i < n; i++) {
			if (c->order[i] < 0 || c->order[i] >= n)
				return c0_fail(C0_EINVAL, "acquisition_order: %d is not a stack number (1..%d)", c->order[i] + 1, n);
			if (seen[c->order[i]]++)
				return c0_fail(C0_EINVAL, "acquisition_order: stack %d appears twice", c->order[i] + 1);
		}
	}
	if (c->ngaps && c->interleaved)
		return c0_fail(C0_EINVAL, "gaps_frames: interleaved stacks have no gaps between them");
	if (c->ngaps > 1 && c->ngaps != n - 1)
		return c0_fail(C0_EINVAL, "gaps_frames: %d gaps for %d stacks (give one, or one between each pair of consecutive stacks: %d)",
			       c->ngaps, n, n - 1);
	for (int i = 0; i < c->ngaps; i++)
		if (!(c->gap_frames[i] >= 0))
			return c0_fail(C0_EINVAL, "gaps_frames: gap %d is negative or not a number", i + 1);
	if (c->mode == C0_BLEACH_REPEAT) {
		if (c->interleaved)
			return c0_fail(C0_EINVAL, "bleach repeat: needs stacks recorded one after another (acquisition sequential)");
		if (n < 2)
			return c0_fail(C0_EINVAL, "bleach repeat: needs the stacks and a repeat of the first angle as the last stack");
		if (c->norder && c->order[n - 1] != n - 1)
			return c0_fail(C0_EINVAL, "acquisition_order: with bleach repeat the repeat (stack %d) is recorded last", n);
	}
	if (c->mode == C0_BLEACH_KNOWN) {
		if (c->nfactors != n)
			return c0_fail(C0_EINVAL, "bleach_factors: %d factors for %d stacks", c->nfactors, n);
		for (int i = 0; i < n; i++)
			if (!(c->factor[i] > 0))
				return c0_fail(C0_EINVAL, "bleach_factors: factor %d is %g, must be > 0", i + 1, c->factor[i]);
	}
	return C0_OK;
}

/* one stack's least-squares slope c of S(t): k = -c / m with variance
 * s^2 / (m^2 sum (t - tbar)^2), s^2 the residual variance; rho the residuals'
 * lag-1 autocorrelation (a blink spans frames); NAN k without signal */
static void stack_rate(const double *S, int64_t T, double B, double *m, double *k, double *var, double *rho)
{
	const double Tq = (double)T, tbar = (Tq - 1) / 2;
	double mean = 0, stt = 0, sty = 0;
	for (int64_t t = 0; t < T; t++)
		mean += S[t];
	mean /= Tq;
	for (int64_t t = 0; t < T; t++)
		stt += (t - tbar) * (t - tbar), sty += (t - tbar) * (S[t] - mean);
	const double slope = stt > 0 ? sty / stt : 0;
	double rss = 0, lag = 0, prev = 0;
	for (int64_t t = 0; t < T; t++) {
		const double r = S[t] - mean - slope * (t - tbar);
		rss += r * r, lag += t ? r * prev : 0, prev = r;
	}
	*m = mean - B;
	*k = *var = *rho = NAN;
	if (!(*m > 0) || T < 3 || !(stt > 0))
		return;
	*k = -slope / *m;
	*var = rss / (Tq - 2) / (*m * *m * stt);
	*rho = rss > 0 ? lag / rss : 0;
}

/* res's k_fit, k, k_sd and rho from the stacks' rates k_stack (variances
 * var, lag-1 autocorrelations r) */
static int fit_rates(int n, const double *var, const double *r, const int64_t *T, struct c0_bleach_result *res)
{
	double wsum = 0, wk = 0, rho = 0, nrho = 0;
	for (int q = 0; q < n; q++)
		if (var[q] > 0) {
			wsum += 1 / var[q];
			wk += res->k_stack[q] / var[q];
			rho += r[q] * (double)T[q], nrho += (double)T[q];
		}
	if (!(wsum > 0))
		return c0_fail(C0_EINVAL, "bleaching: no stack has signal above its background to measure the fade from (set bleach off, or give bleach_factors)");
	res->k_fit = wk / wsum;
	res->k = fmax(0, res->k_fit);   /* the maximum likelihood under k >= 0 */
	/* the slopes' variance assumes independent frames; residuals correlated
	 * from frame to frame (lag-1 rho, pooled over the stacks) carry fewer
	 * independent values: the AR(1) factor (1 + rho) / (1 - rho) */
	rho = fmin(0.9, fmax(0, rho / nrho));
	res->k_sd = sqrt((1 + rho) / (1 - rho) / wsum);
	res->rho = rho;
	return C0_OK;
}

/* A blinking population starts away from its steady state (every dye on
 * when the light comes on), and the first frames recorded fade faster than
 * bleaching: a start-up transient. Bleaching fades both halves of the first
 * stack alike; where its first half's rate exceeds its second's by more
 * than C0_BLEACH_TRANSIENT sds, the stack's rate is its second half's. */
static void first_transient(const double *S, int64_t T, double B, double *k, double *var, double *r,
			    struct c0_bleach_result *res)
{
	if (T < 8)
		return;
	const int64_t h = T / 2;
	double m[2], kh[2], vh[2], rh[2];
	stack_rate(S, h, B, &m[0], &kh[0], &vh[0], &rh[0]);
	stack_rate(S + h, T - h, B, &m[1], &kh[1], &vh[1], &rh[1]);
	if (!(vh[0] > 0 && vh[1] > 0))
		return;
	const double rho = fmin(0.9, fmax(0, 0.5 * (rh[0] + rh[1]))), ar = (1 + rho) / (1 - rho);
	if (kh[0] - kh[1] > C0_BLEACH_TRANSIENT * sqrt(ar * (vh[0] + vh[1])))
		*k = kh[1], *var = vh[1], *r = rh[1], res->first_left_out = 1;
}

int c0_bleach_fit(int n, const double *const *S, const int64_t *T, const double *B, int first, struct c0_bleach_result *res)
{
	double var[C0_BLEACH_MAX] = { 0 }, r[C0_BLEACH_MAX] = { 0 };
	for (int q = 0; q < n; q++)
		stack_rate(S[q], T[q], B[q], &res->signal[q], &res->k_stack[q], &var[q], &r[q]);
	if (first >= 0 && first < n && var[first] > 0)
		first_transient(S[first], T[first], B[first], &res->k_stack[first], &var[first], &r[first], res);
	return fit_rates(n, var, r, T, res);
}

void c0_bleach_clock(const struct c0_bleach_conf *c, int n, const int64_t *T, double *start)
{
	double u = 0;
	for (int i = 0; i < n; i++) {
		const int q = c->norder ? c->order[i] : i;
		if (c->interleaved)
			start[q] = (double)i / n;
		else {
			start[q] = u;
			u += (double)T[q] + (i < n - 1 && c->ngaps ? c->gap_frames[c->ngaps == 1 ? 0 : i] : 0);
		}
	}
}

void c0_bleach_factors(const struct c0_bleach_conf *c, int n, const int64_t *T, struct c0_bleach_result *res)
{
	c0_bleach_clock(c, n, T, res->start);
	for (int q = 0; q < n; q++) {
		/* mean of e^{-k (start + t)}, t = 0..T-1, in closed form */
		const double k = res->k, Tq = (double)T[q];
		res->factor[q] = k != 0 ? exp(-k * res->start[q]) * expm1(-k * Tq) / expm1(-k) / Tq : 1;
	}
}

int c0_bleach_depth_per_rate(const struct c0_tirf *t, int nq, const double *angles, const double *gain,
			     const double *tau, double z, double *per_rate)
{
	double p[C0_BLEACH_MAX], w[C0_BLEACH_MAX], ws = 0, mt = 0, mp = 0, ctp = 0, cpp = 0;
	*per_rate = 0;
	if (nq > C0_BLEACH_MAX)
		return c0_fail(C0_EINVAL, "bleaching: %d angles, at most %d", nq, C0_BLEACH_MAX);
	for (int q = 0; q < nq; q++) {
		int st = c0_tirf_p(t, angles[q], &p[q]);
		if (st)
			return st;
		const double a = (gain ? gain[q] : 1) * c0_tirf_i0(t, angles[q]) * exp(-p[q] * z);
		w[q] = a * a, ws += w[q];
	}
	for (int q = 0; q < nq && ws > 0; q++)
		mt += w[q] * tau[q] / ws, mp += w[q] * p[q] / ws;
	for (int q = 0; q < nq && ws > 0; q++)
		ctp += w[q] * (tau[q] - mt) * (p[q] - mp), cpp += w[q] * (p[q] - mp) * (p[q] - mp);
	*per_rate = cpp > 0 ? -ctp / cpp : 0;
	return C0_OK;
}

int c0_bleach_repeat(const struct c0_bleach_conf *c, int n, const int64_t *T, struct c0_bleach_result *res)
{
	const int first = c->norder ? c->order[0] : 0;
	if (!(c->repeat_ratio > 0) || !isfinite(c->repeat_ratio))
		return c0_fail(C0_EINVAL, "bleach repeat: the repeat's intensity over the first stack's is %g, not a positive number",
			       c->repeat_ratio);
	res->k = 0;
	c0_bleach_factors(c, n, T, res);   /* the starts */
	const double dt = res->start[n - 1] + 0.5 * (double)(T[n - 1] - 1) - res->start[first] - 0.5 * (double)(T[first] - 1);
	if (!(dt > 0))
		return c0_fail(C0_EINVAL, "bleach repeat: the repeat is not recorded after the first stack");
	res->k_fit = -log(c->repeat_ratio) / dt;
	res->k = fmax(0, res->k_fit);   /* a repeat brighter than the first: noise, as in c0_bleach_fit */
	res->k_sd = NAN;
	for (int q = 0; q < n; q++)
		res->k_stack[q] = NAN;
	c0_bleach_factors(c, n, T, res);
	return C0_OK;
}

/* the sums come from the passes that read the frames before (drift,
 * covariance): only frames none of them read whole are read here */
static int frame_sums(struct c0_frames *f, double **S, int64_t *T)
{
	const double *s;
	*T = f->count;
	int st = c0_frames_sums(f, &s);
	if (!st && !(*S = c0_alloc((size_t)f->count, sizeof **S)))
		st = C0_ENOMEM;
	if (!st)
		memcpy(*S, s, (size_t)f->count * sizeof **S);
	return st;
}

/* the sum of p[0..n) over [a, b), pixel i covering [i, i + 1) */
static double band(const double *p, int n, double a, double b)
{
	double s = 0;
	for (int i = a > 0 ? (int)floor(a) : 0; i < n && i < b; i++)
		s += p[i] * (fmin(b, i + 1) - fmax(a, i));
	return s;
}

static double window_of(const struct c0_bleach_window *w, const double *rows, const double *cols, double total, int H,
			int W, double dx, double dy)
{
	return band(cols, W, w->x0 + dx, w->x1 + dx) + band(rows, H, w->y0 + dy, w->y1 + dy) - total;
}

int c0_bleach_window_sum(const struct c0_bleach_window *w, const float *img, int H, int W, double *sum)
{
	double *rows = c0_alloc((size_t)H, sizeof *rows), *cols = c0_alloc((size_t)W, sizeof *cols), total = 0;
	if (!rows || !cols) {
		free(rows), free(cols);
		return C0_ENOMEM;
	}
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			rows[y] += img[(size_t)y * W + x], cols[x] += img[(size_t)y * W + x], total += img[(size_t)y * W + x];
	*sum = window_of(w, rows, cols, total, H, W, 0, 0);
	free(rows), free(cols);
	return C0_OK;
}

/* stack q's frame sums over the window */
static int window_sums(const struct c0_bleach_window *w, int q, struct c0_frames *f, double **S, int64_t *T)
{
	const double *rows, *cols, *tot;
	*T = f->count;
	int st = c0_frames_profiles(f, &tot, &rows, &cols);
	if (!st && !(*S = c0_alloc((size_t)f->count, sizeof **S)))
		st = C0_ENOMEM;
	for (int64_t t = 0; !st && t < f->count; t++) {
		double dx, dy;
		w->shift(w->ctx, q, t, &dx, &dy);
		(*S)[t] = window_of(w, rows + (size_t)t * f->height, cols + (size_t)t * f->width, tot[t], f->height, f->width,
				    dx, dy);
	}
	return st;
}

int c0_bleach_run(const struct c0_bleach_conf *c, int n, struct c0_frames *f, const double *B,
		  const struct c0_bleach_window *win, struct c0_bleach_result *res)
{
	memset(res, 0, sizeof *res);
	res->significant = 1;
	int st = c0_bleach_check(c, n);
	if (st)
		return st;
	if (c->mode == C0_BLEACH_REPEAT) {
		int64_t T[C0_BLEACH_MAX];
		for (int q = 0; q < n; q++)
			T[q] = f[q].count;
		return c0_bleach_repeat(c, n, T, res);
	}
	if (c->mode != C0_BLEACH_ESTIMATE) {
		for (int q = 0; q < n; q++)
			res->factor[q] = c->mode == C0_BLEACH_KNOWN ? c->factor[q] : 1, res->k_stack[q] = NAN;
		return C0_OK;
	}
	double *S[C0_BLEACH_MAX] = { 0 };
	int64_t T[C0_BLEACH_MAX];
	int fail = 0;
#pragma omp parallel for schedule(dynamic, 1) if (n > 1)
	for (int q = 0; q < n; q++)
		if (win ? window_sums(win, q, &f[q], &S[q], &T[q]) : frame_sums(&f[q], &S[q], &T[q]))
#pragma omp atomic write
			fail = 1;
	if (fail)   /* the per-thread messages are lost: say which step failed */
		st = c0_fail(C0_EIO, "bleach: could not read the frames of the stacks");
	if (!st)
		st = c0_bleach_fit(n, (const double *const *)S, T, B, c->interleaved ? -1 : c->norder ? c->order[0] : 0, res);
	if (!st)
		c0_bleach_factors(c, n, T, res);
	res->significant = fabs(res->k_fit) >= C0_BLEACH_SIGNIF * res->k_sd;
	for (int q = 0; q < n; q++)
		free(S[q]);
	return st;
}
