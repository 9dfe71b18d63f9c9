/* The intensity step (steps_intensity.h): every stack's mean and noise
 * variance, its intensity and background on the support, and with the
 * MA-TIRF stacks one smoothness, their common pattern and their noise draws. */
#include "app/steps_intensity.h"
#include "app/steps.h"
#include "app/report_json.h"
#include "stages/depthpool.h"
#include "stages/pattern.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/threads.h"
#include "core/progress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One stack's mean and noise variance: from the support step when that ran
 * on it, else one streaming pass (the covariance on the support's tiles
 * when the noise variance has to be estimated, else just the mean). */
static struct c0_support_conf stream_conf(const struct c0_support_conf *sc0, void *hook, const float *noise)
{
	struct c0_support_conf scc = *sc0;
	scc.frame_fn = hook ? c0_drift_frame_fn : NULL, scc.frame_ctx = hook;
	if (scc.noise_map)
		scc.noise_map = noise;
	return scc;
}

static int intensity_read(const struct c0_support_conf *scc, struct c0_frames *f, const uint8_t *mask, double *s2,
			  const struct c0_support_result *known, double **own, int64_t *frames, double *seconds)
{
	*own = NULL;
	if (known) {
		*frames = known->frames, *s2 = known->sigma2, *seconds = 0;
		return C0_OK;
	}
	if (*s2 > 0)
		return c0_stack_mean(scc, f, own, frames, seconds);
	return c0_stack_noise(scc, f, mask, own, frames, s2, seconds);
}

/* intensity_read, and with block the means of the frames' two block halves
 * (half, count; stages/support.h): summed in the same pass, or in a pass of
 * their own where the support step gave the mean */
static int read_stack(const struct c0_support_conf *sc, void *hook, const float *noise, struct c0_frames *f,
		      const uint8_t *mask, double *s2, const struct c0_support_result *known, int block, double **own,
		      int64_t *frames, double *seconds, float *half[2], int64_t count[2])
{
	struct c0_support_conf scc = stream_conf(sc, hook, noise);
	struct c0_block_halves bh = { 0 };
	const int tap = block > 0 && !known && f->count >= 2 * (int64_t)block;
	int st = tap ? c0_block_halves_init(&bh, block, (size_t)f->width * f->height, scc.frame_fn, scc.frame_ctx) : C0_OK;
	if (tap && !st)
		scc.frame_fn = c0_block_halves_fn, scc.frame_ctx = &bh;
	if (!st)
		st = intensity_read(&scc, f, mask, s2, known, own, frames, seconds);
	if (tap && !st)
		st = c0_block_halves_finish(&bh, half, count);
	free(bh.sum[0]), free(bh.sum[1]);
	double th = 0;
	if (!st && block > 0 && known)
		st = c0_stack_block_means(&scc, f, block, half, count, &th);
	*seconds += th;
	return st;
}

/* With the camera's read-noise map (less its median, noise): each pixel's
 * weight in the intensity fit, s2 over its own noise variance s2 + noise
 * (*w NULL without one) */
static int solve_weights(double s2, const float *noise, int H, int W, float **w)
{
	*w = noise && s2 > 0 ? malloc((size_t)H * W * sizeof **w) : NULL;
	if (noise && s2 > 0 && !*w)
		return C0_ENOMEM;
	for (size_t p = 0; *w && p < (size_t)H * W; p++)
		(*w)[p] = (float)(s2 / fmax(0.5 * s2, s2 + noise[p]));
	return C0_OK;
}

/* the mean less the background, for the corrected image */
static int solve_corrected(const double *mean, const struct c0_intensity_result *res, size_t nc, float **corrected)
{
	if (!(*corrected = c0_alloc(nc, sizeof **corrected)))
		return C0_ENOMEM;
	for (size_t p = 0; p < nc; p++)
		(*corrected)[p] = (float)(mean[p] - res->b[p]);
	return C0_OK;
}

static int intensity_solve(const struct c0_intensity_conf *ic, const double *mean, int H, int W, int64_t frames,
			   const uint8_t *mask, double s2, const float *noise, struct c0_intensity_result *res, float **corrected)
{
	struct c0_intensity_conf c = *ic;
	float *w;
	int st = solve_weights(s2, noise, H, W, &w);
	if (st)
		return st;
	c.weight = w;
	st = c0_intensity_solve(&c, mean, H, W, frames, mask, s2, res);
	free(w);
	if (!st && corrected)
		st = solve_corrected(mean, res, (size_t)H * W, corrected);
	return st;
}

/* Stack i's intensity kept on the support's pixels alone, its fine grid
 * freed (268 MB at 2048 x 2048 camera pixels), unless it is not 0 off the mask */
/* x's values at the pixel list's pixels, newly allocated (NULL: no memory) */
static float *pixlist_values(const struct c0_pixlist *pl, const float *x)
{
	float *v = c0_alloc(pl->M ? pl->M : 1, sizeof *v);
	for (size_t k = 0; v && k < pl->M; k++)
		v[k] = x[pl->pix[k]];
	return v;
}

static int intensity_compact(struct c0_result *r, int i)
{
	float *x = r->ires[i].x;
	const size_t L = (size_t)r->Ly * r->Lx;
	for (size_t p = 0; p < L; p++)
		if (x[p] != 0 && !r->mask[p])
			return C0_OK;
	if (!(r->xs[i] = pixlist_values(&r->pl, x)))
		return C0_ENOMEM;
	free(x);
	r->ires[i].x = NULL;
	return C0_OK;
}

/* One smoothness for the stacks that share[] (the MA-TIRF angles), from
 * their discrepancy mu where the principle was met (a stack "above" sits at
 * the search's end, 1e8); none met, each keeps its own. The depth is read
 * from the ratios between angles, and a mu per angle smooths each angle's
 * intensities differently along the support: on sparse blinking (mu 0.1 at
 * the first angle, 1.7 at the steepest) the median depth error was 0.4-4 nm
 * larger (docs/defaults.md#mu). The shared one is the
 * geometric mean of theirs: the largest, the one the weakest stack needs,
 * over-smooths the others where the steepest angle is dim and noisy (EMCCD
 * sparse blinking, 200 frames: 26 against 21 nm). largest: the camera's
 * fixed pattern is in the means (an offset map given, or the stacks'
 * common pattern found), and intensities smoothed less would take in more
 * of what stays in every frame
 * (docs/defaults.md#mu). The stacks are solved again at that mu; the discrepancy
 * figures of their own solve stay in the report beside their own mu
 * (mu_own). */
static void share_mu(struct c0_result *r, const struct c0_intensity_conf *ic, const int *share, const double *const *mean,
		     const int64_t *frames, const double *s2, int corrected, int largest, double *mu_own, int *sts,
		     char (*msg)[256])
{
	const int n = r->n, H = r->ires[0].Ny, W = r->ires[0].Nx, one_tile = !(ic->tile > 0 && ic->tile < (H > W ? H : W));
	double mu = 0, lg = 0;
	int m = 0;
	for (int i = 0; i < n; i++) {
		mu_own[i] = r->ires[i].mu;
		if (share[i] && r->ires[i].dp_status == 0)
			mu = fmax(mu, r->ires[i].mu), lg += log(r->ires[i].mu), m++;
	}
	if (!(mu > 0))
		return;
	if (!largest && m > 1)
		mu = exp(lg / m);
	struct c0_intensity_conf c = *ic;
	c.mu = mu;
#pragma omp parallel for schedule(dynamic, 1) if (n > 1 && one_tile)
	for (int i = 0; i < n; i++) {
		if (!share[i] || r->ires[i].mu == mu)
			continue;
		struct c0_intensity_result first = r->ires[i], res;
		float *cor = NULL;
		sts[i] = intensity_solve(&c, mean[i], H, W, frames[i], r->mask, s2[i], c0_result_noise(r, i), &res, corrected ? &cor : NULL);
		if (sts[i]) {
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
			continue;
		}
		res.target2 = first.target2, res.floor2 = first.floor2, res.dp_status = first.dp_status, res.tiles_met = first.tiles_met;
		res.solves += first.solves, res.cg_iters += first.cg_iters, res.seconds += first.seconds;
		c0_intensity_result_free(&r->ires[i]);
		r->ires[i] = res;
		if (corrected)
			free(r->corrected[i]), r->corrected[i] = cor;
		free(r->xs[i]), r->xs[i] = NULL;
		if ((sts[i] = intensity_compact(r, i)))
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
	}
}

/* Stack i's first solve (its own mu) on mean, its intensity compacted */
static void solve_one(struct c0_result *r, const struct c0_intensity_conf *ic, int i, const double *mean, int H, int W,
		      const int64_t *frames, const double *s2, int corrected, int *sts, char (*msg)[256])
{
	sts[i] = intensity_solve(ic, mean, H, W, frames[i], r->mask, s2[i], c0_result_noise(r, i), &r->ires[i],
				 corrected ? &r->corrected[i] : NULL);
	if (!sts[i])
		sts[i] = intensity_compact(r, i);
	if (sts[i])
		snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
}

/* Every stack's first solve, when each is cut into tiles: all their tiles
 * in one pool (stages/intensity.h), the same numbers as solve_one's */
static void solve_pooled(struct c0_result *r, const struct c0_intensity_conf *ic, const double *const *mean, int H, int W,
			 const int64_t *frames, const double *s2, int corrected, int *sts, char (*msg)[256])
{
	const int n = r->n;
	struct c0_intensity_conf c[C0_MAX_STACKS];
	float *w[C0_MAX_STACKS] = { 0 };
	int bad = 0;
	for (int i = 0; i < n; i++) {
		c[i] = *ic;
		if ((sts[i] = solve_weights(s2[i], c0_result_noise(r, i), H, W, &w[i])))
			snprintf(msg[i], sizeof msg[i], "%s", "out of memory"), bad = 1;
		c[i].weight = w[i];
	}
	if (!bad)
		c0_intensity_solve_many(n, c, mean, H, W, frames, r->mask, s2, NULL, r->ires, sts, msg);
	for (int i = 0; i < n; i++) {
		free(w[i]);
		if (bad || sts[i])
			continue;
		if (corrected)
			sts[i] = solve_corrected(mean[i], &r->ires[i], (size_t)H * W, &r->corrected[i]);
		if (!sts[i])
			sts[i] = intensity_compact(r, i);
		if (sts[i])
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
	}
}

/* Stack i's intensity on the mask's pixels (raster order): xs[i], or its
 * fine grid's values there copied into *tmp */
static const float *mask_values(struct c0_result *r, int i, float **tmp)
{
	*tmp = NULL;
	if (r->xs[i])
		return r->xs[i];
	return *tmp = pixlist_values(&r->pl, r->ires[i].x);
}

/* stack i's residual (H x W) moved back to where the camera's pixels were,
 * for the pattern, which is the camera's, to be found in one place */
static int pattern_unmove(const struct c0_result *r, int i, double *res, int H, int W)
{
	const size_t N = (size_t)H * W;
	float *v = c0_alloc(N, sizeof *v);
	if (!v)
		return C0_ENOMEM;
	for (size_t p = 0; p < N; p++)
		v[p] = (float)res[p];
	int st = c0_drift_unmove(r->drift, i, v);
	for (size_t p = 0; !st && p < N; p++)
		res[p] = v[p];
	free(v);
	return st;
}

/* out := stack i's mean ybar less the pattern pat, moved with the drift
 * as stack i's corrected frames see it where pat is in the camera's frame */
static int pattern_less(const struct c0_result *r, int i, const double *ybar, const float *pat, int camera, int H, int W,
			double *out)
{
	const size_t N = (size_t)H * W;
	float *mv = NULL;
	int st = C0_OK;
	if (camera && !(mv = c0_alloc(N, sizeof *mv)))
		return C0_ENOMEM;
	if (camera)
		st = c0_drift_image(r->drift, i, pat, mv);
	const float *p = camera ? mv : pat;
	for (size_t k = 0; !st && k < N; k++)
		out[k] = ybar[k] - p[k];
	free(mv);
	return st;
}

/* With the frames moved by a drift correction, the camera's pattern moves
 * between the stacks and the sample's misfit does not: the residuals res
 * (the sample's frame, estimated into pat and ps) are moved back to the
 * camera's pixels and the pattern estimated again there. That one is kept
 * when the camera's frame shares at least twice the variance the sample's
 * does (the camera's part is then the larger; sCMOS stacks with 2-5 px of
 * drift 2.1-6.1x, CCD and EMCCD stacks 0.9-1.2x, docs/defaults.md#common_pattern). res
 * is left in the camera's frame. */
static int camera_frame(const struct c0_result *r, const struct c0_grid *g, const int *idx, int m, double **res, int H,
			int W, float *pat, struct c0_pattern_stats *ps)
{
	struct c0_pattern_stats pc;
	float *pat_c = c0_alloc((size_t)H * W, sizeof *pat_c);
	int st = pat_c ? C0_OK : C0_ENOMEM;
	for (int j = 0; !st && j < m; j++)
		st = pattern_unmove(r, idx[j], res[j], H, W);
	if (!st)
		st = c0_pattern_estimate(g, m, (const double *const *)res, H, W, r->mask, pat_c, &pc);
	if (!st && pc.common_var >= 2 * ps->common_var) {
		pc.common_var_other = ps->common_var, pc.camera_frame = 1;
		*ps = pc;
		memcpy(pat, pat_c, (size_t)H * W * sizeof *pat);
	} else if (!st)
		ps->common_var_other = pc.common_var;
	free(pat_c);
	return st;
}

/* The pattern the share[] stacks have in common (stages/pattern.h) from
 * their first solves' residuals; fixed[i]: the means less it, for the
 * stacks to solve again (NULL for all where the rule does not apply). */
static int common_pattern(struct c0_result *r, const struct c0_intensity_conf *ic, const int *share, const double *const *mean,
			  double **fixed, struct c0_pattern_stats *ps)
{
	const int H = r->ires[0].Ny, W = r->ires[0].Nx;
	const size_t N = (size_t)H * W;
	int idx[C0_MAX_STACKS], m = 0, st = C0_OK;
	for (int i = 0; i < r->n; i++)
		if (share[i])
			idx[m++] = i;
	const double *yb[C0_MAX_STACKS];
	const float *xv[C0_MAX_STACKS], *bv[C0_MAX_STACKS];
	double *res[C0_MAX_STACKS] = { 0 };
	float *tmp[C0_MAX_STACKS] = { 0 }, *pat = c0_alloc(N, sizeof *pat);
	if (!pat)
		st = C0_ENOMEM;
	for (int j = 0; !st && j < m; j++) {
		yb[j] = mean[idx[j]], bv[j] = r->ires[idx[j]].b;
		if (!(xv[j] = mask_values(r, idx[j], &tmp[j])) || !(res[j] = c0_alloc(N, sizeof *res[j])))
			st = C0_ENOMEM;
	}
	if (!st)
		st = c0_pattern_residuals(&ic->grid, m, yb, xv, bv, H, W, r->mask, res);
	if (!st)
		st = c0_pattern_estimate(&ic->grid, m, (const double *const *)res, H, W, r->mask, pat, ps);
	if (!st && c0_result_drift_moved(r))
		st = camera_frame(r, &ic->grid, idx, m, res, H, W, pat, ps);
	for (int j = 0; !st && ps->applied && j < m; j++) {
		if (!(fixed[idx[j]] = c0_alloc(N, sizeof *fixed[idx[j]])))
			st = C0_ENOMEM;
		if (!st)
			st = pattern_less(r, idx[j], yb[j], pat, ps->camera_frame, H, W, fixed[idx[j]]);
	}
	for (int j = 0; j < m; j++)
		free(res[j]), free(tmp[j]);
	free(pat);
	return st;
}

/* The share[] stacks solved again on their means less the common pattern */
static void solve_again(struct c0_result *r, const struct c0_intensity_conf *ic, const int *share, double *const *fixed,
			const int64_t *frames, const double *s2, int corrected, double *mu_own, int *sts, char (*msg)[256])
{
	const int n = r->n, H = r->ires[0].Ny, W = r->ires[0].Nx, one_tile = !(ic->tile > 0 && ic->tile < (H > W ? H : W));
	int bad = 0;
#pragma omp parallel for schedule(dynamic, 1) if (n > 1 && one_tile)
	for (int i = 0; i < n; i++) {
		if (!fixed[i])
			continue;
		c0_intensity_result_free(&r->ires[i]);
		free(r->xs[i]), r->xs[i] = NULL;
		if (corrected)
			free(r->corrected[i]), r->corrected[i] = NULL;
		solve_one(r, ic, i, fixed[i], H, W, frames, s2, corrected, sts, msg);
	}
	for (int i = 0; i < n; i++)
		bad |= sts[i];
	if (!bad)
		share_mu(r, ic, share, (const double *const *)fixed, frames, s2, corrected, 1, mu_own, sts, msg);
}

/* The noise draw's CG tolerance: it feeds variances fitted over the
 * support's thousands of pixels, whose sampling error is far above 1 % of
 * the draw (docs/defaults.md#depth_noise_block) */
#define C0_NOISE_DRAW_TOL 1e-2

/* the draw's solve: stack i's final mu, no bounds */
static struct c0_intensity_conf noise_conf(const struct c0_intensity_conf *ic, const struct c0_result *r, int i)
{
	struct c0_intensity_conf c = *ic;
	c.mu = r->ires[i].mu, c.linear = 1, c.tol = fmax(c.tol, C0_NOISE_DRAW_TOL);
	return c;
}

/* the block halves' means' difference a - b (N pixels), or NULL */
static double *half_difference(float *const *half, size_t N)
{
	double *d = c0_alloc(N, sizeof *d);
	for (size_t p = 0; d && p < N; p++)
		d[p] = (double)half[0][p] - half[1][p];
	return d;
}

/* Stack i's draw from its solve res (freed here): on pl, scaled */
static int noise_keep(struct c0_result *r, int i, struct c0_intensity_result *res, const int64_t *count)
{
	float *x = pixlist_values(&r->pl, res->x);
	const double scale = 1 / sqrt((double)(count[0] + count[1]) * (1.0 / count[0] + 1.0 / count[1]));
	for (size_t k = 0; x && k < r->pl.M; k++)
		x[k] = (float)(x[k] * scale);
	r->xnoise[i] = x;
	c0_intensity_result_free(res);
	return x ? C0_OK : C0_ENOMEM;
}

/* Stack i's noise draw (r->xnoise[i]): the difference of its two block
 * halves' means (float, freed by the caller) solved at its final mu without
 * bounds, which is the difference of the halves' own solves (the step is
 * linear where no bound is active), on pl, scaled to the whole stack's
 * noise: var(a - b) = var(frame) (1/n_a + 1/n_b) */
static int noise_draw(struct c0_result *r, const struct c0_intensity_conf *ic, int i, float *const *half,
		      const int64_t *count, double s2)
{
	const int H = r->ires[i].Ny, W = r->ires[i].Nx;
	const struct c0_intensity_conf c = noise_conf(ic, r, i);
	double *d = half_difference(half, (size_t)H * W);
	if (!d)
		return C0_ENOMEM;
	struct c0_intensity_result res = { 0 };
	int st = intensity_solve(&c, d, H, W, count[0] + count[1], r->mask, s2, c0_result_noise(r, i), &res, NULL);
	free(d);
	if (st) {
		c0_intensity_result_free(&res);
		return st;
	}
	return noise_keep(r, i, &res, count);
}

/* noise_draws when each stack is cut into tiles: all their tiles in one
 * pool, the same numbers as noise_draw's */
static void noise_pooled(struct c0_result *r, const struct c0_intensity_conf *ic, const int *skip, float *(*half)[2],
			 int64_t (*count)[2], const double *s2, int *sts, char (*msg)[256])
{
	const int n = r->n, H = r->ires[0].Ny, W = r->ires[0].Nx;
	const size_t N = (size_t)H * W;
	struct c0_intensity_conf c[C0_MAX_STACKS];
	struct c0_intensity_result res[C0_MAX_STACKS];
	double *d[C0_MAX_STACKS] = { 0 };
	float *w[C0_MAX_STACKS] = { 0 };
	int64_t T[C0_MAX_STACKS];
	int bad = 0;
	for (int i = 0; i < n; i++) {
		c[i] = noise_conf(ic, r, i);
		T[i] = count[i][0] + count[i][1];
		if (skip[i])
			continue;
		if (solve_weights(s2[i], c0_result_noise(r, i), H, W, &w[i]) || !(d[i] = half_difference(half[i], N)))
			sts[i] = C0_ENOMEM, snprintf(msg[i], sizeof msg[i], "%s", "out of memory"), bad = 1;
		c[i].weight = w[i];
	}
	if (!bad)
		c0_intensity_solve_many(n, c, (const double *const *)d, H, W, T, r->mask, s2, skip, res, sts, msg);
	for (int i = 0; i < n; i++) {
		free(d[i]), free(w[i]);
		if (bad || skip[i] || sts[i])
			continue;
		if ((sts[i] = noise_keep(r, i, &res[i], count[i])))
			snprintf(msg[i], sizeof msg[i], "%s", "out of memory");
	}
}

/* The noise draws of the share[] stacks (all without share), side by side
 * when each is one tile, else their tiles in one pool */
static void noise_draws(struct c0_result *r, const struct c0_intensity_conf *ic, const int *share, float *(*half)[2],
			int64_t (*count)[2], const double *s2, int *sts, char (*msg)[256])
{
	const int n = r->n, H = r->ires[0].Ny, W = r->ires[0].Nx, one_tile = !(ic->tile > 0 && ic->tile < (H > W ? H : W));
	if (!one_tile) {
		int skip[C0_MAX_STACKS];
		for (int i = 0; i < n; i++)
			skip[i] = !half[i][0] || (share && !share[i]);
		noise_pooled(r, ic, skip, half, count, s2, sts, msg);
		return;
	}
#pragma omp parallel for schedule(dynamic, 1) if (n > 1)
	for (int i = 0; i < n; i++) {
		if (!half[i][0] || (share && !share[i]))
			continue;
		if ((sts[i] = noise_draw(r, ic, i, half[i], count[i], s2[i])))
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
	}
}

/* Every stack's mean and noise variance side by side (each reads its own
 * file; those left over by c0_threads_side after, each with every thread),
 * then the solves: side by side when each is one tile, else one
 * stack after the other with its tiles side by side (5 stacks on 2 threads
 * would leave one thread idle for the last). msg: per-stack error texts
 * (error messages are per thread). With share and no offset map, the
 * shared stacks' common pattern (ps) is taken out where it shows. */
static void intensity_all(struct c0_result *r, const struct c0_intensity_conf *ic, const struct c0_support_conf *sc,
			  struct c0_frames *f, const double *sigma2, int corrected,
			  const struct c0_support_result *const *known, int64_t *frames, double *tc, int *sts, char (*msg)[256],
			  const int *share, double *mu_own, struct c0_pattern_stats *ps)
{
	const int n = r->n;
	double *own[C0_MAX_STACKS] = { 0 }, s2[C0_MAX_STACKS], *fixed[C0_MAX_STACKS] = { 0 };
	float *half[C0_MAX_STACKS][2] = { { 0 } };
	int64_t count[C0_MAX_STACKS][2] = { { 0 } };
	const double *mean[C0_MAX_STACKS];
	const int H = f[0].height, W = f[0].width, one_tile = !(ic->tile > 0 && ic->tile < (H > W ? H : W));
	struct c0_progress pr;
	int done = 0;
	c0_progress_begin(&pr, "intensity (stacks)", 2 * n);
	const int side = c0_threads_side(n);   /* the rest one after another, each with every thread */
	for (int pass = 0; pass < 2; pass++)
#pragma omp parallel for schedule(dynamic, 1) if (!pass && side > 1)
		for (int i = pass ? side : 0; i < (pass ? n : side); i++) {
			s2[i] = sigma2 ? sigma2[i] : 0;
			sts[i] = read_stack(sc, r->drift ? r->hooks[i] : NULL, c0_result_noise(r, i), &f[i], r->mask, &s2[i],
					    known[i], !share || share[i] ? ic->noise_block : 0, &own[i], &frames[i], &tc[i], half[i],
					    count[i]);
			if (sts[i])
				snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
#pragma omp critical(c0_intensity_progress)
			c0_progress_update(&pr, ++done);
		}
	int bad = 0;
	for (int i = 0; i < n; i++)
		bad |= sts[i], mean[i] = known[i] ? known[i]->mean : own[i];
	if (!one_tile && !bad)
		solve_pooled(r, ic, mean, H, W, frames, s2, corrected, sts, msg);
#pragma omp parallel for schedule(dynamic, 1) if (n > 1 && one_tile && !bad)
	for (int i = 0; i < n; i++) {
		if (bad)
			continue;
		if (one_tile)
			solve_one(r, ic, i, mean[i], H, W, frames, s2, corrected, sts, msg);
		for (size_t p = 0; p < (size_t)H * W; p++)   /* kept for mean_qNN.tif and the report's error map */
			r->mean[(size_t)i * H * W + p] = (float)mean[i][p];
#pragma omp critical(c0_intensity_progress)
		c0_progress_update(&pr, ++done);
	}
	c0_progress_end(&pr);
	for (int i = 0; i < n; i++)
		bad |= sts[i];
	if (share && !bad)
		share_mu(r, ic, share, mean, frames, s2, corrected, r->cal_offset != NULL, mu_own, sts, msg);
	for (int i = 0; i < n; i++)
		bad |= sts[i];
	if (share && !bad && ic->common_pattern && !r->cal_offset) {
		int st = common_pattern(r, ic, share, mean, fixed, ps);
		if (st)
			sts[0] = st, snprintf(msg[0], sizeof msg[0], "%s", c0_errmsg());
		else if (ps->applied)
			solve_again(r, ic, share, fixed, frames, s2, corrected, mu_own, sts, msg);
	}
	for (int i = 0; i < n; i++)
		bad |= sts[i];
	if (!bad && ic->noise_block > 0)
		noise_draws(r, ic, share, half, count, s2, sts, msg);
	for (int i = 0; i < n; i++)
		free(own[i]), free(fixed[i]), free(half[i][0]), free(half[i][1]);
}

int c0_step_intensity(struct c0_result *r, const struct c0_intensity_conf *ic, const struct c0_support_conf *sc,
		      struct c0_frames *f, const double *sigma2, int corrected, const int *share)
{
	const int n = r->n;
	const struct c0_support_result *known[C0_MAX_STACKS] = { 0 };
	for (int k = 0; r->sres && k < r->nsup && !r->npool; k++)   /* a pooled one is no stack's own */
		known[r->sup[k]] = &r->sres[k];
	if (f[0].height * sc->grid.srf != r->Ly || f[0].width * sc->grid.srf != r->Lx)
		return c0_fail(C0_EINVAL, "%s: %dx%d pixels at srf %d do not match the %dx%d support", f[0].name, f[0].width,
			       f[0].height, sc->grid.srf, r->Lx, r->Ly);
	int64_t frames[C0_MAX_STACKS];
	double tc[C0_MAX_STACKS], mu_own[C0_MAX_STACKS];
	const struct c0_step_clock t = c0_step_begin("intensity");
	if (ic->mu > 0)
		share = NULL;   /* a given mu is every stack's already */
	int sts[C0_MAX_STACKS];
	char (*msg)[256] = c0_alloc((size_t)n, sizeof *msg);
	r->ires = c0_alloc((size_t)n, sizeof *r->ires);
	r->mean = c0_alloc((size_t)n * f[0].height * f[0].width, sizeof *r->mean);
	if (corrected)
		r->corrected = c0_alloc((size_t)n, sizeof *r->corrected);
	c0_pixlist_free(&r->pl);
	int stp = c0_pixlist_from_mask(r->mask, r->Ly, r->Lx, &r->pl);
	if (stp || !msg || !r->ires || !r->mean || (corrected && !r->corrected)) {
		free(msg);
		return stp ? stp : C0_ENOMEM;
	}
	struct c0_pattern_stats ps = { 0 };   /* stacks 0: not evaluated */
	intensity_all(r, ic, sc, f, sigma2, corrected, known, frames, tc, sts, msg, share, mu_own, &ps);
	for (int i = 0; i < n; i++)
		if (sts[i]) {
			int st = c0_fail(sts[i], "%s", msg[i]);
			free(msg);
			return st;
		}
	free(msg);
	r->pixel_nm = ic->grid.pixel_nm, r->srf = ic->grid.srf;
	double mu = -1;   /* the report says the stacks share a mu only when they do */
	for (int i = 0; share && i < n; i++)
		if (share[i] && (mu < 0 || r->ires[i].mu == mu))
			mu = r->ires[i].mu;
		else if (share[i])
			share = NULL;
	c0_report_intensity(r->rep, r, ic, frames, tc, share ? mu_own : NULL);
	c0_report_pattern(r->rep, &ps);
	c0_step_end(r, &t);
	return C0_OK;
}
