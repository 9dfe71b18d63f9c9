/* The steps of a run, each from its inputs in a c0_result to its outputs
 * there and its section of the report (app/report_json.h): drift, support
 * and bleaching here, the intensity and MA-TIRF steps in steps_intensity.c
 * and steps_matirf.c. */
#include "app/steps.h"
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "app/report_json.h"
#include "app/report_json_support.h"
#include "stages/lambda.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/order.h"

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

/* The camera's read-noise map moved and spread as each stack's frames are
 * (a noisy pixel's variance follows it), where the drift is corrected */
static int drift_noise(struct c0_result *r, const struct c0_frames *f, int n)
{
	if (!r->cal_noise || !c0_result_drift_moved(r))
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

/* The drift follows the acquisition's clock (order, gaps, interleaving) of
 * a multi-angle run; a single stack's or the support's stacks run one
 * after another as given. */
int c0_step_drift(struct c0_result *r, const struct c0_drift_conf *dc0, const struct c0_bleach_conf *clock,
		  struct c0_frames *f, int n)
{
	const struct c0_step_clock t = c0_step_begin("drift");
	struct c0_drift_conf dc = *dc0;
	if (clock && n <= C0_DRIFT_MAX) {
		int64_t T[C0_DRIFT_MAX];
		for (int q = 0; q < n; q++)
			T[q] = f[q].count;
		c0_bleach_clock(clock, n, T, dc.start);
		dc.nstart = n, dc.interleaved = clock->interleaved;
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

/* stack i's support configuration: its drift hook and noise map */
static void stack_conf(const struct c0_result *r, int i, const struct c0_support_conf *c0, struct c0_support_conf *cc)
{
	cc->frame_fn = r->drift ? c0_drift_frame_fn : NULL, cc->frame_ctx = r->hooks[i];
	if (c0->noise_map)
		cc->noise_map = c0_result_noise(r, i);
}

/* The support stacks' covariances pooled into one support (sres[0]): the
 * stacks are listed in r->pool, and nsup becomes 1 */
static int support_pooled(struct c0_result *r, const struct c0_support_conf *c0, struct c0_support_conf *cc,
			  struct c0_frames *f)
{
	struct c0_support_conf cq[C0_MAX_STACKS];
	struct c0_frames fq[C0_MAX_STACKS];   /* copies: they share the files and the frame sums */
	for (int k = 0; k < r->nsup; k++) {
		cq[k] = *cc, fq[k] = f[r->sup[k]];
		stack_conf(r, r->sup[k], c0, &cq[k]);
		r->pool[k] = r->sup[k];
	}
	r->npool = r->nsup, r->nsup = 1;
	return c0_support_stacks(cq, fq, r->npool, &r->sres[0]);
}

int c0_step_support(struct c0_result *r, const struct c0_support_conf *c0, struct c0_frames *f, int pool)
{
	struct c0_support_conf cc = *c0;
	cJSON *arr = cJSON_AddArrayToObject(r->rep, "support");
	if (!(r->sres = c0_alloc((size_t)r->nsup, sizeof *r->sres)))
		return C0_ENOMEM;
	const struct c0_step_clock t = c0_step_begin("support");
	const int pooled = pool && r->nsup > 1;
	for (int k = 0; k < r->nsup; k++) {
		int i = r->sup[k];
		stack_conf(r, i, c0, &cc);
		int st = pooled ? support_pooled(r, c0, &cc, f) : c0_support_stack(&cc, &f[i], &r->sres[k]);
		if (st)
			return st;
		char name[300];   /* a pooled support: its stacks said */
		snprintf(name, sizeof name, r->npool ? "%s (+%d stacks, pooled)" : "%s", r->names[i], r->npool - 1);
		cJSON *o = c0_report_support_stack(name, &r->sres[k], &cc);
		if (!o)
			return C0_ENOMEM;
		if (r->npool)
			cJSON_AddNumberToObject(o, "stacks_pooled", r->npool);
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

static void drift_shift(const void *d, int q, int64_t t, double *dx, double *dy)
{
	c0_drift_at(d, q, t, dx, dy);
}

/* Where the drift was corrected and the frames' profiles kept: the window
 * of the sample's frame that stays in the field in every frame (0: none) */
static int bleach_window(const struct c0_result *r, const struct c0_frames *f, struct c0_bleach_window *w)
{
	if (!c0_result_drift_moved(r) || !f[0].rows)
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

/* The depth offset one sd of the fitted fade rate leaves, to first order
 * (c0_bleach_depth_per_rate), at the depth map's median depth: every depth
 * shares it, so no pooling averages it away, and the map's signed error is
 * known no better (docs/defaults.md#bleach). In the report's bleaching object. */
int c0_report_bleach_depth(struct c0_result *r, const struct c0_angles *a, const int *tirf, const struct c0_tirf *t)
{
	cJSON *o = cJSON_GetObjectItem(r->rep, "bleaching");
	if (!o || !isfinite(r->bleach_k_sd) || !r->vol.depth || r->vol.M < 1)
		return C0_OK;
	double tau[C0_MAX_STACKS], per = 0;
	float *z = c0_alloc((size_t)r->vol.M, sizeof *z);   /* the depths are on the columns, 0 elsewhere */
	if (!z)
		return C0_ENOMEM;
	size_t m = 0;
	for (int k = 0; k < r->vol.M; k++)
		if (r->vol.depth[r->vol.pixel[k]] > 0)
			z[m++] = r->vol.depth[r->vol.pixel[k]];
	for (int i = 0; i < a->n; i++)
		tau[i] = r->bleach_tau[tirf[i]];
	int st = m ? c0_bleach_depth_per_rate(t, a->n, a->deg, a->ngains ? a->gain : NULL, tau, c0_quantile(z, m, 0.5), &per)
		   : C0_OK;
	free(z);
	if (!st && m)
		cJSON_AddNumberToObject(o, "depth_offset_sd_nm", fabs(per) * r->bleach_k_sd);
	return st;
}

int c0_step_bleach(struct c0_result *r, const struct c0_bleach_conf *bc0, struct c0_frames *f)
{
	const int n = r->n;
	const struct c0_step_clock t = c0_step_begin("bleaching");
	double B[C0_MAX_STACKS] = { 0 };
	struct c0_bleach_conf bc = *bc0;
	struct c0_bleach_window win;
	const int windowed = bleach_window(r, f, &win);
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
		r->bleach_factor[q] = br.factor[q], r->bleach_tau[q] = br.start[q] + 0.5 * (double)(f[q].count - 1);
	r->bleach_k_sd = bc.mode == C0_BLEACH_ESTIMATE ? br.k_sd : NAN;
	c0_report_bleach(r->rep, &bc, &br, n);
	if (windowed) {   /* the sample's part that stayed in the field (camera pixels of the first block) */
		const double wv[4] = { win.x0, win.x1, win.y0, win.y1 };
		cJSON_AddItemToObject(cJSON_GetObjectItem(r->rep, "bleaching"), "window_x0_x1_y0_y1_px", cJSON_CreateDoubleArray(wv, 4));
	}
	bleach_warning(r, &bc, &br);
	c0_step_end(r, &t);
	return C0_OK;
}
