/* The steps of a run, each from its inputs in a c0_result to its outputs
 * there and its section of the report (app/report_steps.h). */
#include "app/pipeline.h"
#include "app/report_steps.h"
#include "stages/depthpool.h"
#include "stages/depthfit.h"
#include "stages/splat.h"
#include "stages/lambda.h"
#include "stages/pattern.h"
#include "optics/psf.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct c0_step_clock c0_step_begin(const char *key)
{
	c0_mem_stage(key);
	return (struct c0_step_clock){ key, c0_now(), c0_mem_peak_mb() };
}

static void add_number(cJSON *rep, const char *obj, const char *key, double v)
{
	cJSON *o = cJSON_GetObjectItem(rep, obj);
	if (!o)
		o = cJSON_AddObjectToObject(rep, obj);
	cJSON_AddNumberToObject(o, key, v);
}

void c0_step_end(struct c0_result *r, const struct c0_step_clock *k)
{
	const double peak = c0_mem_peak_mb();
	cJSON_AddNumberToObject(r->timings, k->key, c0_now() - k->t0);
	add_number(r->rep, "peak_rss_mb", k->key, round(peak));
	add_number(r->rep, "rss_rise_mb", k->key, round(peak - k->peak0));
}

/* 1: the frames were moved by a drift correction */
static int drift_moved(const struct c0_result *r)
{
	struct c0_drift_info di;
	if (!r->drift)
		return 0;
	c0_drift_get_info(r->drift, &di);
	return di.corrected[0] || di.corrected[1];
}

/* The camera's read-noise map moved and spread as each stack's frames are
 * (a noisy pixel's variance follows it), where the drift is corrected */
static int drift_noise(struct c0_result *r, const struct c0_frames *f, int n)
{
	if (!r->cal_noise || !drift_moved(r))
		return C0_OK;
	const size_t np = (size_t)f[0].width * f[0].height;
	for (int q = 0; q < n; q++) {
		if (!(r->cal_noise_q[q] = c0_alloc(np, sizeof *r->cal_noise_q[q])))
			return C0_ENOMEM;
		int st = c0_drift_variance(r->drift, q, r->cal_noise, r->cal_noise_q[q]);
		if (st)
			return st;
	}
	return C0_OK;
}

/* the read-noise map stack i's frames see (NULL: no map) */
static const float *noise_of(const struct c0_result *r, int i)
{
	return r->cal_noise_q[i] ? r->cal_noise_q[i] : r->cal_noise;
}

/* The drift follows the acquisition's clock (order, gaps, interleaving) of
 * a multi-angle run; a single stack's or the support's stacks run one
 * after another as given. */
int c0_step_drift(struct c0_result *r, const struct c0_run_conf *c, const struct c0_grid *g, struct c0_frames *f, int n)
{
	const struct c0_step_clock t = c0_step_begin("drift");
	struct c0_drift_conf dc = C0_DRIFT_DEFAULTS;
	dc.psf_sigma_px = c0_grid_sigma_px(g);
	if (c->nangles > 0 && n <= C0_DRIFT_MAX) {
		struct c0_bleach_conf bc;
		int64_t T[C0_DRIFT_MAX];
		for (int q = 0; q < n; q++)
			T[q] = f[q].count;
		c0_run_conf_bleach(c, &bc);
		c0_bleach_clock(&bc, n, T, dc.start);
		dc.nstart = n, dc.interleaved = bc.interleaved;
	}
	int st = c0_drift_estimate(&dc, f, n, &r->drift);
	if (st)
		return st;
	for (int q = 0; q < n; q++)
		r->hooks[q] = c0_drift_hook(r->drift, q);
	if ((st = drift_noise(r, f, n)))
		return st;
	const double px = r->pixel_nm > 0 ? r->pixel_nm : f[0].pixel_nm;
	if ((st = c0_report_drift(r->rep, r->drift, px)))
		return st;
	c0_step_end(r, &t);
	return C0_OK;
}

/* Rows of the render made at a time: a band of the fine grid, not n planes
 * of it (1.3 GB for 5 stacks at 2048 x 2048 camera pixels). */
#define C0_RENDER_BAND 256

/* rows y0..y1 of plane q of the render into out; xb: room for the rows of
 * x within the radius of the band */
static int render_rows(const struct c0_result *r, int q, double sigma, int y0, int y1, float *xb, float *out)
{
	const int rr = c0_splat_radius(sigma), t0 = y0 - rr < 0 ? 0 : y0 - rr, t1 = y1 + rr > r->Ly ? r->Ly : y1 + rr;
	c0_result_x_rows(r, q, t0, t1, xb);
	return c0_splat_rows(xb, t0, r->Ly, r->Lx, sigma, y0, y1, out);
}

static float *render_xbuf(const struct c0_result *r, double sigma)
{
	return c0_alloc((size_t)(C0_RENDER_BAND + 2 * c0_splat_radius(sigma)) * r->Lx, sizeof(float));
}

int c0_render_plane(const struct c0_result *r, int q, float *plane)
{
	const double sigma = r->render_sd_nm / (r->pixel_nm / r->srf);
	float *xb = render_xbuf(r, sigma);
	int st = xb ? C0_OK : C0_ENOMEM;
	for (int y0 = 0; !st && y0 < r->Ly; y0 += C0_RENDER_BAND)
		st = render_rows(r, q, sigma, y0, y0 + C0_RENDER_BAND < r->Ly ? y0 + C0_RENDER_BAND : r->Ly, xb,
				 plane + (size_t)y0 * r->Lx);
	free(xb);
	return st;
}

/* The render's planes are made when written (and when the library's caller
 * asks for them); the step fixes their Gaussian and their display range. */
int c0_step_render(struct c0_result *r)
{
	const struct c0_step_clock t = c0_step_begin("render");
	const double fine = r->pixel_nm / r->srf;
	double prec = -1;
	for (int k = 0; r->sres && k < r->nsup; k++)
		prec = fmax(prec, r->sres[k].precision_nm);
	const double sd = fmax(prec, 0.5 * fine);
	float *band = c0_alloc((size_t)C0_RENDER_BAND * r->Lx, sizeof *band), *xb = render_xbuf(r, sd / fine);
	float lo = INFINITY, hi = -INFINITY;
	int st = band && xb ? C0_OK : C0_ENOMEM;
	for (int q = 0; !st && q < r->n; q++)
		for (int y0 = 0; !st && y0 < r->Ly; y0 += C0_RENDER_BAND) {
			const int y1 = y0 + C0_RENDER_BAND < r->Ly ? y0 + C0_RENDER_BAND : r->Ly;
			st = render_rows(r, q, sd / fine, y0, y1, xb, band);
			for (size_t i = 0; !st && i < (size_t)(y1 - y0) * r->Lx; i++) {
				if (band[i] < lo) lo = band[i];
				if (band[i] > hi) hi = band[i];
			}
		}
	free(band), free(xb);
	if (st)
		return st;
	r->render_sd_nm = sd, r->render_lo = lo, r->render_hi = hi;
	c0_report_render(r->rep, sd, prec, fine);
	c0_step_end(r, &t);
	return C0_OK;
}

/* The union of the support stacks' masks into r->mask. */
static int support_union(struct c0_result *r)
{
	r->Ly = r->sres[0].Ly, r->Lx = r->sres[0].Lx;
	const size_t L = (size_t)r->Ly * r->Lx;
	if (!(r->mask = c0_alloc(L, 1)))
		return C0_ENOMEM;
	int count = 0;
	for (size_t i = 0; i < L; i++) {
		for (int k = 0; k < r->nsup; k++)
			r->mask[i] |= r->sres[k].mask[i];
		count += r->mask[i];
	}
	cJSON_AddNumberToObject(r->rep, "support_pixels_union", count);
	return C0_OK;
}

/* The PSF width check after support stack k: the first stack's decides the
 * run's width (fwhm_data), which the later stacks and the stages
 * downstream use (r->fwhm_nm), their covariances keeping the stated lag. */
static void psf_width(struct c0_result *r, int k, struct c0_support_conf *cc)
{
	const double fw = r->sres[k].cv.fwhm_data_nm, stated = k ? r->fwhm_stated_nm : cc->grid.fwhm_nm;
	if (k == 0)
		r->fwhm_stated_nm = stated, r->fwhm_data_nm = fw, r->fwhm_nm = r->sres[0].fwhm_nm;
	if (k == 0 && r->fwhm_nm != stated) {
		c0_result_warn(r, "%s: the covariance's lags say a Gaussian PSF of FWHM %.0f nm, not the given %g nm: "
			       "the solves use %.0f nm (fwhm_rule stated keeps the given one; docs/defaults.md#fwhm_rule, lambda under "
			       "model mismatch)", r->names[r->sup[0]], fw, stated, fw);
		c0_support_set_width(cc, r->fwhm_nm);
		cc->fwhm_data = 0;
	} else if (fw > 0 && fabs(fw / stated - 1) > C0_LAMBDA_PSF_WARN && !cc->fwhm_data && r->fwhm_nm == stated)
		c0_result_warn(r, "%s: the covariance's lags say a Gaussian PSF of FWHM %.0f nm, not the given %g nm "
			       "(the automatic lambda and the support assume the given one; docs/defaults.md#fwhm_rule, lambda "
			       "under model mismatch)", r->names[r->sup[k]], fw, stated);
	cc->fwhm_data = 0;   /* later stacks: the first's decision */
}

int c0_step_support(struct c0_result *r, const struct c0_support_conf *c0, struct c0_frames *f)
{
	struct c0_support_conf cc = *c0;
	cJSON *arr = cJSON_AddArrayToObject(r->rep, "support");
	if (!(r->sres = c0_alloc((size_t)r->nsup, sizeof *r->sres)))
		return C0_ENOMEM;
	const struct c0_step_clock t = c0_step_begin("support");
	for (int k = 0; k < r->nsup; k++) {
		int i = r->sup[k];
		cc.frame_fn = r->drift ? c0_drift_frame_fn : NULL, cc.frame_ctx = r->hooks[i];
		if (c0->noise_map)
			cc.noise_map = noise_of(r, i);
		int st = c0_support_stack(&cc, &f[i], &r->sres[k]);
		if (st)
			return st;
		cJSON *o = c0_report_support_stack(r->names[i], &r->sres[k], &cc);
		if (!o)
			return C0_ENOMEM;
		cJSON_AddItemToArray(arr, o);
		psf_width(r, k, &cc);
	}
	c0_report_support_params(r->rep, &cc);
	cJSON *w = cJSON_AddObjectToObject(r->rep, "psf_width");   /* docs/defaults.md#fwhm_rule */
	cJSON_AddStringToObject(w, "rule", c0->fwhm_data ? "data" : "stated");
	cJSON_AddNumberToObject(w, "stated_nm", r->fwhm_stated_nm);
	if (r->fwhm_data_nm > 0)
		cJSON_AddNumberToObject(w, "data_nm", r->fwhm_data_nm);
	cJSON_AddNumberToObject(w, "used_nm", r->fwhm_nm);
	r->pixel_nm = cc.grid.pixel_nm, r->srf = cc.grid.srf;
	int st = support_union(r);
	if (!st)
		c0_step_end(r, &t);
	return st;
}

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
 * weight in the intensity fit, s2 over its own noise variance s2 + noise */
static int intensity_solve(const struct c0_intensity_conf *ic, const double *mean, int H, int W, int64_t frames,
			   const uint8_t *mask, double s2, const float *noise, struct c0_intensity_result *res, float **corrected)
{
	struct c0_intensity_conf c = *ic;
	float *w = noise && s2 > 0 ? malloc((size_t)H * W * sizeof *w) : NULL;
	if (noise && s2 > 0 && !w)
		return C0_ENOMEM;
	for (size_t p = 0; w && p < (size_t)H * W; p++)
		w[p] = (float)(s2 / fmax(0.5 * s2, s2 + noise[p]));
	c.weight = w;
	int st = c0_intensity_solve(&c, mean, H, W, frames, mask, s2, res);
	free(w);
	if (!st && corrected) {
		size_t nc = (size_t)H * W;
		if (!(*corrected = c0_alloc(nc, sizeof **corrected)))
			st = C0_ENOMEM;
		for (size_t p = 0; !st && p < nc; p++)
			(*corrected)[p] = (float)(mean[p] - res->b[p]);
	}
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
		sts[i] = intensity_solve(&c, mean[i], H, W, frames[i], r->mask, s2[i], noise_of(r, i), &res, corrected ? &cor : NULL);
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
	sts[i] = intensity_solve(ic, mean, H, W, frames[i], r->mask, s2[i], noise_of(r, i), &r->ires[i],
				 corrected ? &r->corrected[i] : NULL);
	if (!sts[i])
		sts[i] = intensity_compact(r, i);
	if (sts[i])
		snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
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
	if (!st && drift_moved(r))
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

/* Stack i's noise draw (r->xnoise[i]): the difference of its two block
 * halves' means (float, freed by the caller) solved at its final mu without
 * bounds, which is the difference of the halves' own solves (the step is
 * linear where no bound is active), on pl, scaled to the whole stack's
 * noise: var(a - b) = var(frame) (1/n_a + 1/n_b) */
static int noise_draw(struct c0_result *r, const struct c0_intensity_conf *ic, int i, float *const *half,
		      const int64_t *count, double s2)
{
	const int H = r->ires[i].Ny, W = r->ires[i].Nx;
	const size_t N = (size_t)H * W;
	struct c0_intensity_conf c = *ic;
	c.mu = r->ires[i].mu, c.linear = 1, c.tol = fmax(c.tol, C0_NOISE_DRAW_TOL);
	double *d = c0_alloc(N, sizeof *d);
	if (!d)
		return C0_ENOMEM;
	for (size_t p = 0; p < N; p++)
		d[p] = (double)half[0][p] - half[1][p];
	struct c0_intensity_result res = { 0 };
	int st = intensity_solve(&c, d, H, W, count[0] + count[1], r->mask, s2, noise_of(r, i), &res, NULL);
	float *x = st ? NULL : pixlist_values(&r->pl, res.x);
	if (!st && !x)
		st = C0_ENOMEM;
	const double scale = 1 / sqrt((double)(count[0] + count[1]) * (1.0 / count[0] + 1.0 / count[1]));
	for (size_t k = 0; !st && k < r->pl.M; k++)
		x[k] = (float)(x[k] * scale);
	if (!st)
		r->xnoise[i] = x;
	else
		free(x);
	c0_intensity_result_free(&res);
	free(d);
	return st;
}

/* The noise draws of the share[] stacks (all without share), side by side
 * when each is one tile */
static void noise_draws(struct c0_result *r, const struct c0_intensity_conf *ic, const int *share, float *(*half)[2],
			int64_t (*count)[2], const double *s2, int *sts, char (*msg)[256])
{
	const int n = r->n, H = r->ires[0].Ny, W = r->ires[0].Nx, one_tile = !(ic->tile > 0 && ic->tile < (H > W ? H : W));
#pragma omp parallel for schedule(dynamic, 1) if (n > 1 && one_tile)
	for (int i = 0; i < n; i++) {
		if (!half[i][0] || (share && !share[i]))
			continue;
		if ((sts[i] = noise_draw(r, ic, i, half[i], count[i], s2[i])))
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
	}
}

/* Every stack's mean and noise variance side by side (each reads its own
 * file), then the solves: side by side when each is one tile, else one
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
#pragma omp parallel for schedule(dynamic, 1) if (n > 1)
	for (int i = 0; i < n; i++) {
		s2[i] = sigma2 ? sigma2[i] : 0;
		sts[i] = read_stack(sc, r->drift ? r->hooks[i] : NULL, noise_of(r, i), &f[i], r->mask, &s2[i], known[i],
				    !share || share[i] ? ic->noise_block : 0, &own[i], &frames[i], &tc[i], half[i], count[i]);
		if (sts[i])
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
#pragma omp critical(c0_intensity_progress)
		c0_progress_update(&pr, ++done);
	}
	int bad = 0;
	for (int i = 0; i < n; i++)
		bad |= sts[i], mean[i] = known[i] ? known[i]->mean : own[i];
#pragma omp parallel for schedule(dynamic, 1) if (n > 1 && one_tile && !bad)
	for (int i = 0; i < n; i++) {
		if (bad)
			continue;
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
	for (int k = 0; r->sres && k < r->nsup; k++)
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

/* the single-depth fit (stages/depthfit.h) of each column into res->depth at
 * its pixel; 0 off the columns, as their volume. With the pooled
 * intensities' noise known, the fit weighs the angles by it and reads the
 * pooled intensities themselves: the solve's projections are fitted to
 * them with equal weights and smoothed across pixels, which takes back most
 * of what the weights gain
 * (docs/defaults.md#depth_noise_block). */
static int depth_fit_cols(const struct c0_matirf_conf *m, const struct c0_run_conf *c, int nq, const struct c0_pooled *pool,
			  struct c0_matirf_result *res)
{
	const int w = pool && pool->var;
	const size_t M = (size_t)res->M, L = w ? pool->pl->M : M;
	float *d = c0_alloc(L ? L : 1, sizeof *d);
	int st = d ? C0_OK : C0_ENOMEM;
	const double *gain = c->ngains ? c->gains : NULL;
	if (!st && w)
		st = c0_depth_fit_y(&m->tirf, nq, c->angles, gain, m->z0_nm, res->nz * m->dz_nm, pool->pooled, L, pool->var, d);
	else if (!st)
		st = c0_depth_fit(&m->tirf, nq, c->angles, gain, res->nz, m->z0_nm, m->dz_nm, res->f, M, d);
	for (size_t k = 0, i = 0; !st && k < M; k++) {
		while (w && i < L && pool->pl->pix[i] < res->pixel[k])   /* pixel[] and pl's pixels both increase */
			i++;
		res->depth[res->pixel[k]] = !w ? d[k] : i < L && pool->pl->pix[i] == res->pixel[k] ? d[i] : 0;
	}
	free(d);
	return st;
}

int c0_step_matirf(struct c0_result *r, const struct c0_run_conf *c, const struct c0_matirf_conf *m,
		   const float *const *img, const struct c0_pooled *pool, int ny, int nx, double pixel_nm, int baseline)
{
	struct c0_matirf_result *res = baseline ? &r->base : &r->vol;
	const char *key = baseline ? "baseline_matirf" : "matirf";
	const int nq = c->nangles;
	const struct c0_step_clock t = c0_step_begin(key);
	int st = c0_matirf_solve(m, nq, c->angles, c->ngains ? c->gains : NULL, img, ny, nx, res);
	if (st)
		return st;
	if (pool) {
		const size_t M = res->M;
		c0_pool_rescale_at(res->f, res->nz, res->pixel, M, nq, pool->pl, pool->own, pool->pooled);
		for (size_t k = 0; k < M; k++) {     /* off the columns the total stays 0 */
			double s = 0;
			for (int j = 0; j < res->nz; j++)
				s += res->f[j * M + k];
			res->total[res->pixel[k]] = (float)s;
		}
	}
	/* the fine grid's depth map: each column's single-depth fit, not its mean,
	 * which reads deep (stages/depthfit.h). The camera-grid baseline keeps the
	 * mean: its 100 nm pixels hold several depths, whose brightness-weighted
	 * mean the single fit misses (demo: -29 nm signed, the mean -8 nm) */
	const double tfit = c0_now();
	if (!baseline && (st = depth_fit_cols(m, c, nq, pool, res)))
		return st;
	if (!baseline)
		r->vol_pixel_nm = pixel_nm;
	r->z0_nm = m->z0_nm, r->dz_nm = m->dz_nm;
	c0_report_depth_readout(c0_report_matirf(r->rep, key, c, m, res), baseline, baseline ? 0 : c0_now() - tfit);
	c0_step_end(r, &t);
	return C0_OK;
}

int c0_step_matirf_raw(struct c0_result *r, const struct c0_run_conf *c, const struct c0_matirf_conf *m,
		       const float *const *img, int ny, int nx, double pixel_nm)
{
	const int nq = c->nangles;
	const size_t np = (size_t)ny * nx;
	struct c0_matirf_conf mm = *m;
	if (c->psf_fwhm_nm != 0) {
		if (!(c->psf_fwhm_nm > 0) || !(pixel_nm > 0))
			return c0_fail(C0_EINVAL, "psf_fwhm_nm %g: needs a positive FWHM and the pixel size (pixel_nm or the TIFF calibration)",
				       c->psf_fwhm_nm);
		mm.psf_sigma_px = c0_psf_sigma_px(c->psf_fwhm_nm, pixel_nm);
	}
	if (c->estimate_background) {
		if (!(c->background_smooth > 0))
			return c0_fail(C0_EINVAL, "background_smooth %g: must be > 0", c->background_smooth);
		mm.bg_smooth = c->background_smooth;
	}
	float *x[C0_MAX_STACKS] = { 0 };
	int st = C0_OK;
	for (int q = 0; q < nq && !st; q++)
		if (!(x[q] = c0_alloc(np, sizeof **x)))
			st = C0_ENOMEM;
		else
			memcpy(x[q], img[q], np * sizeof **x);
	if (!st)
		st = c0_matirf_subtract(x, nq, np, c->offset, "offset");
	if (!st)
		st = c0_matirf_subtract(x, nq, np, c->matirf_background, "matirf_background");
	if (!st)
		st = c0_step_matirf(r, c, &mm, (const float *const *)x, NULL, ny, nx, pixel_nm, 0);
	for (int q = 0; q < nq; q++)
		free(x[q]);
	if (st)
		return st;
	c0_report_matirf_raw(cJSON_GetObjectItem(r->rep, "matirf"), c, &r->vol);
	return C0_OK;
}

void c0_run_conf_bleach(const struct c0_run_conf *c, struct c0_bleach_conf *bc)
{
	*bc = (struct c0_bleach_conf){ .mode = c->nbleach_factors ? C0_BLEACH_KNOWN
					       : c->bleach == C0_BLEACHING_OFF ? C0_BLEACH_OFF
					       : c->bleach == C0_BLEACHING_REPEAT ? C0_BLEACH_REPEAT : C0_BLEACH_ESTIMATE,
				       .interleaved = c->acquisition == C0_ACQ_INTERLEAVED, .norder = c->nacquisition_order,
				       .ngaps = c->ngaps_frames, .nfactors = c->nbleach_factors };
	for (int i = 0; i < c->nacquisition_order && i < C0_BLEACH_MAX; i++)
		bc->order[i] = c->acquisition_order[i] - 1;
	for (int i = 0; i < c->ngaps_frames && i < C0_BLEACH_MAX; i++)
		bc->gap_frames[i] = c->gaps_frames[i];
	for (int i = 0; i < c->nbleach_factors && i < C0_BLEACH_MAX; i++)
		bc->factor[i] = c->bleach_factors[i];
}

static void drift_shift(const void *d, int q, int64_t t, double *dx, double *dy)
{
	c0_drift_at(d, q, t, dx, dy);
}

/* Where the drift was corrected and the frames' profiles kept: the window
 * of the sample's frame that stays in the field in every frame (0: none) */
static int bleach_window(const struct c0_result *r, const struct c0_frames *f, struct c0_bleach_window *w)
{
	if (!drift_moved(r) || !f[0].rows)
		return 0;
	double lo[2] = { 0, 0 }, hi[2] = { 0, 0 };
	for (int q = 0; q < r->n; q++)
		for (int64_t t = 0; t < f[q].count; t++) {
			double d[2];
			c0_drift_at(r->drift, q, t, &d[0], &d[1]);
			for (int a = 0; a < 2; a++)
				lo[a] = fmin(lo[a], d[a]), hi[a] = fmax(hi[a], d[a]);
		}
	*w = (struct c0_bleach_window){ -lo[0], f[0].width - hi[0], -lo[1], f[0].height - hi[1], drift_shift, r->drift };
	return w->x1 - w->x0 >= 1 && w->y1 - w->y0 >= 1;
}

/* a fade the stacks cannot show (sparse or fast blinking: the frame sums
 * carry more blinking noise than fade) leaves the factors near 1 and the
 * later, steeper angles too dim: deeper depths
 * (docs/defaults.md#bleach); a fit below 0 is held at 0. Said in the
 * report's bleaching object and its warnings (the CLI prints those). */
static void bleach_warning(struct c0_result *r, const struct c0_bleach_conf *bc, const struct c0_bleach_result *br)
{
	char msg[512];
	const char *advice = "record a repeat of the first angle at the end and run with bleach repeat, or give bleach_factors measured otherwise";
	if (br->significant && br->k_fit >= 0)
		return;
	if (br->k_fit < 0 && bc->mode == C0_BLEACH_REPEAT)
		snprintf(msg, sizeof msg, "the repeat of the first angle reads brighter than the first stack (ratio %.4g): a fade "
			 "cannot reverse, so the rate is taken as 0 and the factors as 1; the ratio carries the blinking noise of two "
			 "stacks, or the focus or illumination changed between them", bc->repeat_ratio);
	else if (br->k_fit < 0)
		snprintf(msg, sizeof msg, "the stacks' frame sums rise (fitted fade rate %.3g +- %.2g per frame): a fade cannot "
			 "reverse, so the rate is taken as 0 and the factors as 1; the rise is blinking noise (sparse or fast "
			 "blinking) or a change of focus, illumination or field; %s", br->k_fit, br->k_sd, advice);
	else
		snprintf(msg, sizeof msg, "the fade rate %.3g +- %.2g per frame is within %g sds of zero: the stacks do not show the "
			 "fade, and their factors may be off; %s", br->k, br->k_sd, (double)C0_BLEACH_SIGNIF, advice);
	cJSON_AddStringToObject(cJSON_GetObjectItem(r->rep, "bleaching"), "warning", msg);
	c0_result_warn(r, "bleaching: %s", msg);
}

int c0_step_bleach(struct c0_result *r, const struct c0_run_conf *c, struct c0_frames *f)
{
	const int n = r->n;
	const struct c0_step_clock t = c0_step_begin("bleaching");
	double B[C0_MAX_STACKS] = { 0 };
	struct c0_bleach_conf bc;
	struct c0_bleach_window win;
	const int windowed = bleach_window(r, f, &win);
	c0_run_conf_bleach(c, &bc);
	int st = C0_OK;
	for (int q = 0; !st && q < n; q++)
		if (windowed)
			st = c0_bleach_window_sum(&win, r->ires[q].b, r->ires[q].Ny, r->ires[q].Nx, &B[q]);
		else
			for (size_t i = 0; i < (size_t)r->ires[q].Ny * r->ires[q].Nx; i++)
				B[q] += r->ires[q].b[i];
	if (bc.mode == C0_BLEACH_REPEAT) {   /* intensity totals on the support: the repeat's over the first's */
		const int first = bc.norder ? bc.order[0] : 0;
		bc.repeat_ratio = c0_result_x_sum(r, n - 1) / c0_result_x_sum(r, first);
	}
	struct c0_bleach_result br;
	if (!st)
		st = c0_bleach_run(&bc, n, f, B, windowed ? &win : NULL, &br);
	if (st)
		return st;
	for (int q = 0; q < n; q++)
		r->bleach_factor[q] = br.factor[q];
	c0_report_bleach(r->rep, &bc, &br, n);
	if (windowed) {   /* the sample's part that stayed in the field (camera pixels of the first block) */
		const double wv[4] = { win.x0, win.x1, win.y0, win.y1 };
		cJSON_AddItemToObject(cJSON_GetObjectItem(r->rep, "bleaching"), "window_x0_x1_y0_y1_px", cJSON_CreateDoubleArray(wv, 4));
	}
	bleach_warning(r, &bc, &br);
	c0_step_end(r, &t);
	return C0_OK;
}
