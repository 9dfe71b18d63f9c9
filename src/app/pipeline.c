/* 3D-COL0RME as one call: support from the support stacks, intensity and
 * background of every stack on the union of their masks, and with angles
 * the MA-TIRF volume from the (pooled) intensities, plus the standard
 * MA-TIRF baseline from the background-corrected means when asked. */
#include "app/pipeline.h"
#include "stages/bleach.h"
#include "stages/depthpool.h"
#include "stages/splat.h"
#include "optics/psf.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"
#include "core/comm.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int c0_result_new(const char *command, int n, const char *const *names, const int *is_file, struct c0_result **out)
{
	*out = NULL;
	if (n < 1 || n > C0_MAX_STACKS)
		return c0_fail(C0_EINVAL, "stacks: %d given, expected 1..%d", n, C0_MAX_STACKS);
	struct c0_result *r = c0_alloc(1, sizeof *r);
	if (!r || !(r->names = c0_alloc((size_t)n, sizeof *r->names)) || !(r->rep = c0_report_new(command, 0, NULL))) {
		c0_result_free(r);
		return C0_ENOMEM;
	}
	r->n = n;
	for (int i = 0; i < n; i++) {
		snprintf(r->names[i], sizeof r->names[i], "%s", names[i]);
		r->paths[i] = is_file[i] ? r->names[i] : NULL;
	}
	r->timings = cJSON_AddObjectToObject(r->rep, "timings_s");
	*out = r;
	return C0_OK;
}

void c0_result_set_argv(struct c0_result *r, int argc, char **argv)
{
	cJSON *a = cJSON_CreateArray();
	for (int i = 0; i < argc; i++)
		cJSON_AddItemToArray(a, cJSON_CreateString(argv[i]));
	cJSON_ReplaceItemInObject(r->rep, "argv", a);
}

void c0_result_free(struct c0_result *r)
{
	if (!r)
		return;
	for (int k = 0; r->sres && k < r->nsup; k++)
		c0_support_result_free(&r->sres[k]);
	for (int q = 0; q < r->n; q++) {
		if (r->ires)
			c0_intensity_result_free(&r->ires[q]);
		if (r->corrected)
			free(r->corrected[q]);
	}
	free(r->sres), free(r->ires), free(r->corrected), free(r->mask), free(r->names), free(r->json);
	c0_drift_free(r->drift), free(r->render), free(r->mean);
	c0_matirf_result_free(&r->vol), c0_matirf_result_free(&r->base);
	cJSON_Delete(r->rep);
	free(r);
}

int c0_stacks_open(const struct c0_stack *s, int n, struct c0_frames *f)
{
	int st = C0_OK, i;
	for (i = 0; i < n && !st; i++) {
		char name[32];
		snprintf(name, sizeof name, "array %d", i + 1);
		if (s[i].path)
			st = c0_frames_open(&f[i], s[i].path);
		else
			st = c0_frames_wrap(&f[i], s[i].data, s[i].frames, s[i].height, s[i].width, s[i].pixel_nm, name);
		if (!st && s[i].pixel_nm > 0)
			f[i].pixel_nm = s[i].pixel_nm;
		if (!st && (f[i].width != f[0].width || f[i].height != f[0].height))
			st = c0_fail(C0_EINVAL, "%s: %dx%d pixels differs from %s (%dx%d)", f[i].name, f[i].width, f[i].height,
				     f[0].name, f[0].width, f[0].height);
	}
	if (st)
		c0_stacks_close(f, i);
	return st;
}

void c0_stacks_close(struct c0_frames *f, int n)
{
	for (int i = 0; i < n; i++)
		c0_frames_close(&f[i]);
}

int c0_stacks_pixel(const struct c0_run_conf *c, const struct c0_frames *f, int n, double *pixel_nm)
{
	if (!(c->pixel_nm >= 0 && isfinite(c->pixel_nm)))
		return c0_fail(C0_EINVAL, "pixel_nm %g: must be a positive number of nm (0: the stacks' calibration)", c->pixel_nm);
	*pixel_nm = c->pixel_nm > 0 ? c->pixel_nm : f[0].pixel_nm;
	if (!(*pixel_nm > 0))
		return c0_fail(C0_EINVAL, "pixel_nm: %s has no pixel calibration; give the camera pixel size in nm", f[0].name);
	/* without the parameter, the stacks' calibrations must agree: which one is right is unknown */
	for (int i = 1; !(c->pixel_nm > 0) && i < n; i++)
		if (!(fabs(f[i].pixel_nm - f[0].pixel_nm) <= 1e-3 * f[0].pixel_nm))
			return c0_fail(C0_EINVAL, "%s: pixel size %s%.6g nm, but %s has %.6g nm (give pixel_nm to override)", f[i].name,
				       f[i].pixel_nm > 0 ? "" : "uncalibrated, not ", f[i].pixel_nm, f[0].name, f[0].pixel_nm);
	return C0_OK;
}

int c0_stacks_check(const struct c0_support_conf *sc, const struct c0_frames *f, int n)
{
	for (int i = 0; i < n; i++) {
		int st = c0_support_check(sc, f[i].width, f[i].height, f[i].count, f[i].name);
		if (st)
			return st;
	}
	return C0_OK;
}

int c0_step_drift(struct c0_result *r, struct c0_frames *f, int n)
{
	double t = c0_now();
	const struct c0_drift_conf dc = C0_DRIFT_DEFAULTS;
	int st = c0_drift_estimate(&dc, f, n, &r->drift);
	if (st)
		return st;
	for (int q = 0; q < n; q++)
		r->hooks[q] = c0_drift_hook(r->drift, q);
	const double px = r->pixel_nm > 0 ? r->pixel_nm : f[0].pixel_nm;
	struct c0_drift_info in;
	c0_drift_get_info(r->drift, &in);
	cJSON *j = cJSON_AddObjectToObject(r->rep, "drift");
	cJSON_AddStringToObject(j, "method", "block means cross-correlated (chained, then against the mean of all blocks), "
				"sub-pixel peak; frames shifted back by a mirrored Fourier shift");
	cJSON_AddNumberToObject(j, "block_frames", in.block);
	cJSON_AddNumberToObject(j, "blocks", in.blocks);
	cJSON_AddNumberToObject(j, "max_nm", in.max_px * px);
	double nz[2] = { in.noise_px[0] * px, in.noise_px[1] * px }, cr[2] = { in.corrected[0], in.corrected[1] };
	c0_report_add_array(j, "block_noise_nm", nz, 2);
	c0_report_add_array(j, "corrected_xy", cr, 2);
	double *b = c0_alloc(3 * (size_t)in.blocks + 1, sizeof *b);
	if (!b)
		return C0_ENOMEM;
	for (int k = 0; k < in.blocks; k++)
		b[k] = in.bt[k] + 1, b[in.blocks + k] = in.bx[k] * px, b[2 * in.blocks + k] = in.by[k] * px;
	c0_report_add_array(j, "block_centre_frame", b, in.blocks);
	c0_report_add_array(j, "block_dx_nm", b + in.blocks, in.blocks);
	c0_report_add_array(j, "block_dy_nm", b + 2 * in.blocks, in.blocks);
	free(b);
	cJSON_AddStringToObject(j, "trajectory", "drift.csv (nm per frame), drift.png");
	cJSON_AddNumberToObject(j, "seconds", in.seconds);
	cJSON_AddNumberToObject(r->timings, "drift", c0_now() - t);
	return C0_OK;
}

int c0_step_render(struct c0_result *r)
{
	const double fine = r->pixel_nm / r->srf;
	double prec = -1;
	for (int k = 0; r->sres && k < r->nsup; k++)
		prec = fmax(prec, r->sres[k].precision_nm);
	const double sd = fmax(prec, 0.5 * fine);
	const size_t L = (size_t)r->Ly * r->Lx;
	if (!(r->render = c0_alloc(L * (size_t)r->n, sizeof *r->render)))
		return C0_ENOMEM;
	for (int q = 0; q < r->n; q++) {
		int st = c0_splat(r->ires[q].x, r->Ly, r->Lx, sd / fine, r->render + q * L);
		if (st)
			return st;
	}
	r->render_sd_nm = sd;
	cJSON *j = cJSON_AddObjectToObject(r->rep, "render");
	cJSON_AddStringToObject(j, "file", "render.tif");
	cJSON_AddStringToObject(j, "content", "each stack's intensity (one plane each) splatted with a normalised Gaussian "
				"of sd max(localisation precision, half a fine pixel)");
	cJSON_AddNumberToObject(j, "gaussian_sd_nm", sd);
	cJSON_AddNumberToObject(j, "localisation_precision_nm", prec);
	cJSON_AddNumberToObject(j, "pixel_nm", fine);
	return C0_OK;
}

int c0_step_support(struct c0_result *r, const struct c0_support_conf *c0, struct c0_frames *f)
{
	struct c0_support_conf cc = *c0;
	const struct c0_support_conf *c = &cc;
	cJSON *arr = cJSON_AddArrayToObject(r->rep, "support");
	if (!(r->sres = c0_alloc((size_t)r->nsup, sizeof *r->sres)))
		return C0_ENOMEM;
	double t = c0_now();
	for (int k = 0; k < r->nsup; k++) {
		int i = r->sup[k];
		cc.frame_fn = r->drift ? c0_drift_frame_fn : NULL, cc.frame_ctx = r->hooks[i];
		int st = c0_support_stack(c, &f[i], &r->sres[k]);
		if (st)
			return st;
		const struct c0_support_result *s = &r->sres[k];
		cJSON *o = cJSON_CreateObject();
		cJSON_AddStringToObject(o, "stack", r->names[i]);
		cJSON_AddNumberToObject(o, "frames", (double)s->frames);
		cJSON_AddNumberToObject(o, "lag_px", s->lag);
		cJSON_AddNumberToObject(o, "lags", s->nlag);
		cJSON_AddNumberToObject(o, "lambda", s->lambda);
		cJSON_AddNumberToObject(o, "lambda_max", s->lambda_max);
		cJSON_AddNumberToObject(o, "lambda_relative", s->lambda_max > 0 ? s->lambda / s->lambda_max : 0);
		cJSON_AddNumberToObject(o, "normalisation", s->norm);
		cJSON_AddNumberToObject(o, "noise_variance", s->sigma2);
		cJSON_AddNumberToObject(o, "iterations", s->iters);
		cJSON_AddBoolToObject(o, "converged", s->converged);
		cJSON_AddNumberToObject(o, "duality_gap", s->gap);
		cJSON_AddNumberToObject(o, "tiles", s->tiles);
		cJSON_AddNumberToObject(o, "tile_px", s->tile);
		cJSON_AddNumberToObject(o, "support_pixels", s->support_pixels);
		cJSON_AddNumberToObject(o, "covariance_s", s->t_cov);
		cJSON_AddNumberToObject(o, "covariance_frames_per_s", s->t_cov > 0 ? (double)s->frames / s->t_cov : 0);
		cJSON_AddNumberToObject(o, "solve_s", s->t_solve);
		c0_report_add_array(o, "objective", s->hist, s->nhist);
		cJSON_AddStringToObject(o, "lambda_rule", s->lambda_auto ? "automatic"
					: c->lambda_rel > 0 ? "given"
					: "the penalty's fixed default");
		if (s->lambda_auto) {
			const struct c0_lambda_result *v = &s->cv;
			cJSON *l = cJSON_AddObjectToObject(o, "lambda_auto");
			cJSON_AddStringToObject(l, "rule", v->second
						? "max(share median peak, kappa sigma_C) from a first solve at max(rho q90, kappa "
						  "sigma_C); peak: x ||a||^2 at the first support's local maxima; sigma_C: noise "
						  "sd of the correlation image, from the lower quartile of the interleaved frame "
						  "halves' difference; q90: its 90th percentile over the pixels above kappa sigma_C"
						: "max(rho q90, kappa sigma_C); sigma_C: noise sd of the correlation image, from "
						  "the lower quartile of the interleaved frame halves' difference; q90: its 90th "
						  "percentile over the pixels above kappa sigma_C");
			cJSON_AddNumberToObject(l, "chosen_relative", v->chosen_rel);
			if (v->second) {
				cJSON_AddNumberToObject(l, "first_relative", v->first_rel);
				cJSON_AddNumberToObject(l, "peak_relative", v->peak_rel);
				cJSON_AddNumberToObject(l, "peaks", v->peaks);
				cJSON_AddNumberToObject(l, "share", C0_LAMBDA_PEAK_SHARE);
			}
			cJSON_AddNumberToObject(l, "rho", v->rho);
			cJSON_AddNumberToObject(l, "signal_relative", v->signal_rel);
			cJSON_AddNumberToObject(l, "kappa", v->kappa);
			cJSON_AddNumberToObject(l, "noise_relative", v->noise_rel);
			cJSON_AddStringToObject(l, "bound_by", v->noise_bound ? "noise" : "signal");
			/* tiles: sigma_C from a subset of the tiles' interiors (stages/support.c) */
			cJSON_AddNumberToObject(l, "noise_tiles", v->noise_tiles ? v->noise_tiles : s->tiles);
			cJSON_AddNumberToObject(l, "seconds", v->seconds);
			cJSON *cu = cJSON_AddObjectToObject(l, "curve");
			cJSON_AddStringToObject(cu, "what", "share of the fine pixels above lambda (l1 scale, CEL0's threshold "
						"t): of the correlation image (signal) and of the halves' noise image "
						"|C_A - C_B|/2 (noise)");
			double rel[C0_LAMBDA_CURVE];
			for (int m = 0; m < C0_LAMBDA_CURVE; m++)
				rel[m] = c0_lambda_curve_rel(m);
			c0_report_add_array(cu, "lambda_relative", rel, C0_LAMBDA_CURVE);
			c0_report_add_array(cu, "signal_above", v->curve_signal, C0_LAMBDA_CURVE);
			c0_report_add_array(cu, "noise_above", v->curve_noise, C0_LAMBDA_CURVE);
		}
		if (s->frc.n) {
			const double fine = c->pixel_nm / c->srf;
			cJSON *fr = cJSON_AddObjectToObject(o, "frc");
			cJSON_AddStringToObject(fr, "images", "emitter variances of the even and the odd frames (fine grid), Hann window");
			cJSON_AddNumberToObject(fr, "threshold", 1.0 / 7);
			cJSON_AddNumberToObject(fr, "resolution_nm", s->frc_nm);
			if (!(s->frc_nm > 0))
				cJSON_AddStringToObject(fr, "note", "stays above 1/7 up to the fine grid's Nyquist frequency: the "
							"resolution is at most 2 fine pixels");
			double *fq = c0_alloc((size_t)s->frc.n, sizeof *fq);
			if (!fq)
				return C0_ENOMEM;
			for (int m = 0; m < s->frc.n; m++)
				fq[m] = s->frc.freq[m] / fine;
			c0_report_add_array(fr, "frequency_per_nm", fq, s->frc.n);
			free(fq);
			c0_report_add_array(fr, "correlation", s->frc.corr, s->frc.n);
			cJSON_AddNumberToObject(fr, "seconds", s->t_frc);
		}
		if (c->frc)    /* tiles: the precision without the FRC (stages/support.c) */
			cJSON_AddNumberToObject(o, "precision_nm", s->precision_nm);
		cJSON_AddItemToArray(arr, o);
	}
	cJSON *p = cJSON_AddObjectToObject(r->rep, "support_parameters");
	cJSON_AddNumberToObject(p, "pixel_size_nm", c->pixel_nm);
	cJSON_AddNumberToObject(p, "fwhm_nm", c->fwhm_nm);
	cJSON_AddNumberToObject(p, "srf", c->srf);
	cJSON_AddStringToObject(p, "penalty", c->penalty == C0_PENALTY_L1 ? "l1" : "cel0");
	cJSON_AddNumberToObject(p, "max_iterations", c->fista.maxit);
	cJSON_AddNumberToObject(p, "tol", c0_support_tol(c));
	cJSON_AddStringToObject(p, "pixel_guard", c->guard ? "on" : "off");
	if (c->guard)   /* g of ops/covariance.h's c0_cov_guard */
		cJSON_AddNumberToObject(p, "pixel_guard_ratio", c0_support_guard_ratio(c));
	r->pixel_nm = c->pixel_nm, r->srf = c->srf;
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
	cJSON_AddNumberToObject(r->timings, "support", c0_now() - t);
	return C0_OK;
}

/* One stack's mean and noise variance: from the support step when that ran
 * on it, else one streaming pass (the covariance on the support's tiles
 * when the noise variance has to be estimated, else just the mean). */
static int intensity_read(const struct c0_support_conf *sc0, void *hook, struct c0_frames *f, const uint8_t *mask,
			  double *s2, const struct c0_support_result *known, double **own, int64_t *frames, double *seconds)
{
	struct c0_support_conf scc = *sc0;
	scc.frame_fn = hook ? c0_drift_frame_fn : NULL, scc.frame_ctx = hook;
	*own = NULL;
	if (known) {
		*frames = known->frames, *s2 = known->sigma2, *seconds = 0;
		return C0_OK;
	}
	if (*s2 > 0)
		return c0_stack_mean(&scc, f, own, frames, seconds);
	return c0_stack_noise(&scc, f, mask, own, frames, s2, seconds);
}

static int intensity_solve(const struct c0_intensity_conf *ic, const double *mean, int H, int W, int64_t frames,
			   const uint8_t *mask, double s2, struct c0_intensity_result *res, float **corrected)
{
	int st = c0_intensity_solve(ic, mean, H, W, frames, mask, s2, res);
	if (!st && corrected) {
		size_t nc = (size_t)H * W;
		if (!(*corrected = malloc(nc * sizeof **corrected)))
			st = C0_ENOMEM;
		for (size_t p = 0; !st && p < nc; p++)
			(*corrected)[p] = (float)(mean[p] - res->b[p]);
	}
	return st;
}

int c0_step_intensity(struct c0_result *r, const struct c0_intensity_conf *ic, const struct c0_support_conf *sc,
		      struct c0_frames *f, const double *sigma2, int corrected)
{
	const int n = r->n;
	const struct c0_support_result *known[C0_MAX_STACKS] = { 0 };
	for (int k = 0; r->sres && k < r->nsup; k++)
		known[r->sup[k]] = &r->sres[k];
	if (f[0].height * sc->srf != r->Ly || f[0].width * sc->srf != r->Lx)
		return c0_fail(C0_EINVAL, "%s: %dx%d pixels at srf %d do not match the %dx%d support", f[0].name, f[0].width,
			       f[0].height, sc->srf, r->Lx, r->Ly);
	/* the stacks are independent: solve them side by side */
	int64_t frames[C0_MAX_STACKS];
	double tc[C0_MAX_STACKS], t = c0_now();
	int sts[C0_MAX_STACKS];
	char (*msg)[256] = c0_alloc((size_t)n, sizeof *msg);
	r->ires = c0_alloc((size_t)n, sizeof *r->ires);
	r->mean = c0_alloc((size_t)n * f[0].height * f[0].width, sizeof *r->mean);
	if (corrected)
		r->corrected = c0_alloc((size_t)n, sizeof *r->corrected);
	if (!msg || !r->ires || !r->mean || (corrected && !r->corrected)) {
		free(msg);
		return C0_ENOMEM;
	}
	/* the stacks' means and noise variances side by side (each reads its own
	 * file), then the solves: side by side when each is one tile, else one
	 * stack after the other with its tiles side by side (5 stacks on 2
	 * threads would leave one thread idle for the last) */
	double *own[C0_MAX_STACKS] = { 0 }, s2[C0_MAX_STACKS];
	const int H = f[0].height, W = f[0].width, one_tile = !(ic->tile > 0 && ic->tile < (H > W ? H : W));
	struct c0_progress pr;
	int done = 0;
	c0_progress_begin(&pr, "intensity (stacks)", 2 * n);
#pragma omp parallel for schedule(dynamic, 1) if (n > 1)
	for (int i = 0; i < n; i++) {
		s2[i] = sigma2 ? sigma2[i] : 0;
		sts[i] = intensity_read(sc, r->drift ? r->hooks[i] : NULL, &f[i], r->mask, &s2[i], known[i], &own[i], &frames[i], &tc[i]);
		if (sts[i])   /* error messages are per thread */
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
#pragma omp critical(c0_intensity_progress)
		c0_progress_update(&pr, ++done);
	}
	int bad = 0;
	for (int i = 0; i < n; i++)
		bad |= sts[i];
#pragma omp parallel for schedule(dynamic, 1) if (n > 1 && one_tile && !bad)
	for (int i = 0; i < n; i++) {
		if (bad)
			continue;
		sts[i] = intensity_solve(ic, known[i] ? known[i]->mean : own[i], H, W, frames[i], r->mask, s2[i], &r->ires[i],
					 corrected ? &r->corrected[i] : NULL);
		for (size_t p = 0; p < (size_t)H * W; p++)   /* kept for mean_qNN.tif and the report's error map */
			r->mean[(size_t)i * H * W + p] = (float)(known[i] ? known[i]->mean : own[i])[p];
		if (sts[i])
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
#pragma omp critical(c0_intensity_progress)
		c0_progress_update(&pr, ++done);
	}
	c0_progress_end(&pr);
	for (int i = 0; i < n; i++)
		free(own[i]);
	for (int i = 0; i < n; i++)
		if (sts[i]) {
			int st = c0_fail(sts[i], "%s", msg[i]);
			free(msg);
			return st;
		}
	free(msg);
	r->pixel_nm = ic->pixel_nm, r->srf = ic->srf;
	cJSON *arr = cJSON_AddArrayToObject(r->rep, "intensity");
	for (int i = 0; i < n; i++) {
		const struct c0_intensity_result *s = &r->ires[i];
		cJSON *j = cJSON_CreateObject();
		cJSON_AddStringToObject(j, "stack", r->names[i]);
		cJSON_AddNumberToObject(j, "frames", (double)frames[i]);
		cJSON_AddNumberToObject(j, "noise_variance", s->sigma2);
		cJSON_AddNumberToObject(j, "mu", s->mu);
		cJSON_AddNumberToObject(j, "residual2", s->residual2);
		cJSON_AddNumberToObject(j, "discrepancy_target2", s->target2);
		if (ic->relative && s->dp_status >= 0)
			cJSON_AddNumberToObject(j, "residual_floor2", s->floor2);
		static const char *dp[] = {
			"met",
			"below: even the smallest mu leaves a residual above the target, so the intensity is as little smoothed as allowed (give mu to smooth more)",
			"above: even the largest mu leaves a residual below the target, so the intensity is as smooth as allowed (lower nu or give mu for more detail)",
			"not converged: mu is the last one tried (give mu to fix it)" };
		cJSON_AddStringToObject(j, "discrepancy", s->dp_status < 0 ? "fixed mu" : dp[s->dp_status]);
		cJSON_AddNumberToObject(j, "tiles", s->tiles);
		cJSON_AddNumberToObject(j, "tiles_discrepancy_met", s->tiles_met);
		cJSON_AddNumberToObject(j, "solves", s->solves);
		cJSON_AddNumberToObject(j, "cg_iterations", s->cg_iters);
		cJSON_AddNumberToObject(j, "seconds", s->seconds + tc[i]);
		cJSON_AddItemToArray(arr, j);
	}
	cJSON *p = cJSON_AddObjectToObject(r->rep, "intensity_parameters");
	cJSON_AddNumberToObject(p, "pixel_size_nm", ic->pixel_nm);   /* the forward model, for report.html's error map */
	cJSON_AddNumberToObject(p, "fwhm_nm", ic->fwhm_nm);
	cJSON_AddNumberToObject(p, "srf", ic->srf);
	static const char *bg[] = { "none", "constant", "smooth" };
	cJSON_AddStringToObject(p, "background", bg[ic->background]);
	cJSON_AddNumberToObject(p, "beta", ic->beta);
	cJSON_AddNumberToObject(p, "nu", ic->nu);
	cJSON_AddNumberToObject(p, "fixed_mu", ic->mu);
	cJSON_AddStringToObject(p, "mu_rule", ic->mu > 0 ? "fixed" : ic->relative ? "relative discrepancy" : "plain discrepancy");
	cJSON_AddStringToObject(p, "mu_rule_meaning",
		ic->mu > 0 ? "mu as given"
		: ic->relative ? "mu is the largest smoothness whose residual exceeds the model's floor (the residual at mu = 1e-3) by no more than the noise explains (nu^2 H W sigma2 / T): smoothing that costs less than the noise is kept. The floor is the model error (continuous positions on the fine grid, background shape), larger than the noise on real data, which is why the plain principle is never met there. Larger nu smooths more; mu fixes it."
		: "mu makes the residual equal to the noise level nu^2 H W sigma2 / T; on data whose model error exceeds the noise this is never met and mu stays at its smallest value");
	cJSON_AddNumberToObject(p, "graph_radius_px", ic->graph_radius);
	cJSON_AddNumberToObject(r->timings, "intensity", c0_now() - t);
	return C0_OK;
}

int c0_step_matirf(struct c0_result *r, const struct c0_run_conf *c, const struct c0_matirf_conf *m,
		   const float *const *img, const float *const *own, int ny, int nx, double pixel_nm, int baseline)
{
	struct c0_matirf_result *res = baseline ? &r->base : &r->vol;
	const char *key = baseline ? "baseline_matirf" : "matirf";
	const int nq = c->nangles;
	double t = c0_now();
	int st = c0_matirf_solve(m, nq, c->angles, c->ngains ? c->gains : NULL, img, ny, nx, res);
	if (st)
		return st;
	if (own) {
		c0_pool_rescale(res->f, res->nz, ny, nx, nq, own, img);
		for (size_t p = 0; p < (size_t)ny * nx; p++) {
			double s = 0;
			for (int j = 0; j < res->nz; j++)
				s += res->f[j * (size_t)ny * nx + p];
			res->total[p] = (float)s;
		}
	}
	if (!baseline)
		r->vol_pixel_nm = pixel_nm;
	r->z0_nm = m->z0_nm, r->dz_nm = m->dz_nm;
	cJSON *j = cJSON_AddObjectToObject(r->rep, key);
	c0_report_add_array(j, "angles_deg", c->angles, nq);
	if (c->ngains)
		c0_report_add_array(j, "gains", c->gains, c->ngains);
	double pen[C0_MAX_STACKS];
	for (int q = 0; q < nq; q++)
		c0_tirf_p(&m->tirf, c->angles[q], &pen[q]), pen[q] = 1 / pen[q];
	c0_report_add_array(j, "penetration_depth_nm", pen, nq);
	cJSON_AddNumberToObject(j, "critical_angle_deg", c0_tirf_critical_deg(&m->tirf));
	cJSON_AddNumberToObject(j, "n_glass", m->tirf.n_glass);
	cJSON_AddNumberToObject(j, "n_sample", m->tirf.n_sample);
	cJSON_AddNumberToObject(j, "wavelength_nm", m->tirf.wavelength_nm);
	cJSON_AddNumberToObject(j, "s_fraction", m->tirf.s_fraction);
	c0_report_add_array(j, "z_nm", res->z_nm, res->nz);
	if (!cJSON_GetObjectItem(r->rep, "z_nm"))
		c0_report_add_array(r->rep, "z_nm", res->z_nm, res->nz);
	cJSON_AddStringToObject(j, "regulariser", m->reg == C0_REG_TV ? "tv" : "hessian");
	cJSON_AddNumberToObject(j, "kappa", m->kappa);
	cJSON_AddNumberToObject(j, "axial_weight", m->wz);
	cJSON_AddNumberToObject(j, "sparsity", m->sparsity);
	cJSON_AddNumberToObject(j, "data_scale", res->scale);
	cJSON_AddNumberToObject(j, "iterations", res->iters);
	cJSON_AddNumberToObject(j, "coarse_iterations", res->coarse_iters);   /* on the binned grids */
	cJSON_AddBoolToObject(j, "converged", res->converged);
	cJSON_AddStringToObject(j, "solver", res->apg ? "apg" : res->exact ? "exact" : "diag");
	cJSON_AddNumberToObject(j, "final_relative_change", res->rel_change);
	cJSON_AddNumberToObject(j, "objective", res->objective);
	cJSON_AddNumberToObject(j, "seconds", res->seconds);
	cJSON_AddNumberToObject(r->timings, key, c0_now() - t);
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
	cJSON *j = cJSON_GetObjectItem(r->rep, "matirf");
	cJSON_AddNumberToObject(j, "offset", c->offset);
	if (r->vol.background) {
		cJSON_AddStringToObject(j, "background", "estimated");
		cJSON_AddNumberToObject(j, "background_mean", r->vol.background_mean);
		cJSON_AddNumberToObject(j, "background_smooth_px2", c->background_smooth);
	} else
		cJSON_AddNumberToObject(j, "background", c->matirf_background);
	cJSON_AddNumberToObject(j, "psf_fwhm_nm", c->psf_fwhm_nm);
	return C0_OK;
}

/* The support stacks: 1-based numbers, or the smallest angle (the deepest
 * penetration sees every emitter), or the first stack in 2D mode. */
static int support_stacks(const struct c0_run_conf *c, const int *only, int n, struct c0_result *r)
{
	if (!c->nsupport_stacks) {
		/* the support-only stacks (at or below the critical angle) and the smallest TIRF angle */
		int best = -1, k = 0;
		for (int i = 0; i < c->nangles; i++)
			if (only[i])
				r->sup[k++] = i;
			else if (best < 0 || c->angles[i] < c->angles[best])
				best = i;
		if (best >= 0 || !k)
			r->sup[k++] = best < 0 ? 0 : best;
		r->nsup = k;
		return C0_OK;
	}
	for (int k = 0; k < c->nsupport_stacks; k++) {
		if (c->support_stacks[k] < 1 || c->support_stacks[k] > n)
			return c0_fail(C0_EINVAL, "support_stacks: %d is not a stack number (1..%d)", c->support_stacks[k], n);
		r->sup[k] = c->support_stacks[k] - 1;
	}
	r->nsup = c->nsupport_stacks;
	return C0_OK;
}

/* The guide of the depth pooling: each support pixel's depth from its own
 * intensities summed over a (2 hg + 1)^2 window, one depth per pixel fitted
 * against the model's bin weights (no volume, no regulariser). */
static int depth_guide(const struct c0_run_conf *ct, const struct c0_matirf_conf *m, const uint8_t *mask,
		       const float *const *own, int Ly, int Lx, int hg, float *guide)
{
	const int nq = ct->nangles, nz = c0_matirf_nz(m);
	const size_t L = (size_t)Ly * Lx;
	float *g[C0_MAX_STACKS] = { 0 };
	double *W = c0_alloc((size_t)nq * nz, sizeof *W);
	int st = W ? c0_tirf_weights(&m->tirf, nq, ct->angles, ct->ngains ? ct->gains : NULL, nz, m->z0_nm, m->dz_nm, W)
		   : C0_ENOMEM;
	for (int i = 0; !st && hg > 0 && i < nq; i++)
		st = (g[i] = c0_alloc(L, sizeof(float))) ? c0_pool_window(own[i], mask, Ly, Lx, hg, g[i]) : C0_ENOMEM;
	if (!st)
		c0_depth_single(W, nq, nz, m->z0_nm, m->dz_nm, hg > 0 ? (const float *const *)g : own, mask, L, guide);
	for (int i = 0; i < nq; i++)
		free(g[i]);
	free(W);
	return st;
}

/* The volume from the intensities, each pooled over a window of about
 * pool_nm (odd, in fine pixels) on the support, over the pixels whose guide
 * depth is within pool_range_nm of the centre's (0: all). */
static int volume(struct c0_result *r, const struct c0_run_conf *ct, const int *tirf, const struct c0_stage_confs *s)
{
	const int nq = ct->nangles, Ly = r->Ly, Lx = r->Lx;
	const size_t L = (size_t)Ly * Lx, Nc = r->ires[0].Ny * (size_t)r->ires[0].Nx;
	float *own[C0_MAX_STACKS] = { 0 }, *pooled[C0_MAX_STACKS] = { 0 }, *base[C0_MAX_STACKS] = { 0 }, *guide = NULL;
	const double fine = s->support.pixel_nm / s->support.srf;
	const int h = (int)lround((s->pool_nm / fine - 1) / 2), guided = h > 0 && s->pool_range_nm > 0;
	const int hg = guided ? (int)lround((C0_DEPTH_GUIDE_FWHM * s->support.fwhm_nm / fine - 1) / 2) : 0;
	int st = C0_OK;
	for (int i = 0; !st && i < nq; i++) {
		const int q = tirf[i];
		const float g = (float)(1 / r->bleach_factor[q]);
		if (!(own[i] = malloc(L * sizeof(float))) || (h > 0 && !(pooled[i] = malloc(L * sizeof(float))))) {
			st = C0_ENOMEM;
			break;
		}
		for (size_t p = 0; p < L; p++)
			own[i][p] = r->ires[q].x[p] * g;
		if (ct->baseline && !(st = (base[i] = malloc(Nc * sizeof(float))) ? C0_OK : C0_ENOMEM))
			for (size_t p = 0; p < Nc; p++)
				base[i][p] = r->corrected[q][p] * g;
		if (!st && h > 0 && !guided)
			st = c0_pool_window(own[i], r->mask, Ly, Lx, h, pooled[i]);
	}
	if (!st && guided) {
		st = (guide = malloc(L * sizeof(float))) ? depth_guide(ct, &s->matirf, r->mask, (const float *const *)own, Ly, Lx,
								      hg, guide)
							 : C0_ENOMEM;
		if (!st)
			st = c0_pool_guided((const float *const *)own, nq, r->mask, guide, s->pool_range_nm, Ly, Lx, h, pooled);
	}
	free(guide);
	if (!st)
		st = c0_step_matirf(r, ct, &s->matirf, h > 0 ? (const float *const *)pooled : (const float *const *)own,
				    h > 0 ? (const float *const *)own : NULL, Ly, Lx, fine, 0);
	if (!st) {
		cJSON *j = cJSON_GetObjectItem(r->rep, "matirf");
		cJSON_AddNumberToObject(j, "depth_pool_window_px", h > 0 ? 2 * h + 1 : 0);
		cJSON_AddNumberToObject(j, "depth_pool_range_nm", guided ? s->pool_range_nm : 0);
		cJSON_AddNumberToObject(j, "depth_guide_window_px", guided ? 2 * hg + 1 : 0);
	}
	if (!st && ct->baseline)
		st = c0_step_matirf(r, ct, &s->matirf, (const float *const *)base, NULL, r->ires[0].Ny, r->ires[0].Nx,
				    s->support.pixel_nm, 1);
	for (int i = 0; i < nq; i++)
		free(own[i]), free(pooled[i]), free(base[i]);
	return st;
}

static void bleach_conf(const struct c0_run_conf *c, struct c0_bleach_conf *bc)
{
	*bc = (struct c0_bleach_conf){ .mode = c->nbleach_factors ? C0_BLEACH_KNOWN : c->bleach == C0_BLEACHING_OFF ? C0_BLEACH_OFF : C0_BLEACH_ESTIMATE,
				       .interleaved = c->acquisition == C0_ACQ_INTERLEAVED, .norder = c->nacquisition_order,
				       .ngaps = c->ngaps_frames, .nfactors = c->nbleach_factors };
	for (int i = 0; i < c->nacquisition_order && i < C0_BLEACH_MAX; i++)
		bc->order[i] = c->acquisition_order[i] - 1;
	for (int i = 0; i < c->ngaps_frames && i < C0_BLEACH_MAX; i++)
		bc->gap_frames[i] = c->gaps_frames[i];
	for (int i = 0; i < c->nbleach_factors && i < C0_BLEACH_MAX; i++)
		bc->factor[i] = c->bleach_factors[i];
}

int c0_step_bleach(struct c0_result *r, const struct c0_run_conf *c, struct c0_frames *f)
{
	const int n = r->n;
	double t = c0_now(), B[C0_MAX_STACKS] = { 0 };
	struct c0_bleach_conf bc;
	bleach_conf(c, &bc);
	for (int q = 0; q < n; q++)
		for (size_t i = 0; i < (size_t)r->ires[q].Ny * r->ires[q].Nx; i++)
			B[q] += r->ires[q].b[i];
	struct c0_bleach_result br;
	int st = c0_bleach_run(&bc, n, f, B, &br);
	if (st)
		return st;
	for (int q = 0; q < n; q++)
		r->bleach_factor[q] = br.factor[q];
	static const char *modes[] = { "estimated", "given", "off" };
	cJSON *o = cJSON_AddObjectToObject(r->rep, "bleaching");
	cJSON_AddStringToObject(o, "correction", modes[bc.mode]);
	cJSON_AddStringToObject(o, "acquisition", bc.interleaved ? "interleaved" : "sequential");
	double v[C0_MAX_STACKS];
	for (int i = 0; i < n; i++)
		v[i] = bc.norder ? bc.order[i] + 1 : i + 1;
	c0_report_add_array(o, "acquisition_order", v, n);
	if (bc.ngaps)
		c0_report_add_array(o, "gaps_frames", bc.gap_frames, bc.ngaps);
	if (bc.mode == C0_BLEACH_ESTIMATE) {
		cJSON_AddNumberToObject(o, "rate_per_frame", br.k);
		cJSON_AddNumberToObject(o, "rate_sd_per_frame", br.k_sd);
		for (int q = 0; q < n; q++)
			v[q] = br.k_stack[q] == br.k_stack[q] ? br.k_stack[q] : 0;
		c0_report_add_array(o, "rate_per_frame_by_stack", v, n);
		c0_report_add_array(o, "start_frame", br.start, n);
		c0_report_add_array(o, "signal_per_frame", br.signal, n);
	}
	c0_report_add_array(o, "factors", br.factor, n);
	const int first = bc.norder ? bc.order[0] : 0, last = bc.norder ? bc.order[n - 1] : n - 1;
	cJSON_AddNumberToObject(o, "fade_last_vs_first", 1 - br.factor[last] / br.factor[first]);
	cJSON_AddStringToObject(o, "meaning",
		bc.mode == C0_BLEACH_OFF ? "no correction: a fade across the stacks would read as depth"
		: "each stack's intensity was divided by its factor (its mean population relative to the start of the acquisition) before the MA-TIRF fit; intensity_qNN.tif are the stacks' own means");
	cJSON_AddNumberToObject(r->timings, "bleaching", c0_now() - t);
	return C0_OK;
}

static int run(const struct c0_run_conf *c, const struct c0_stage_confs *sc, struct c0_frames *f, int n,
	       struct c0_result *r)
{
	const struct c0_stage_confs s = *sc;
	const int three_d = c->nangles > 0;
	int st = C0_OK;
	/* stacks at or below the critical angle (epi) only join the support:
	 * the MA-TIRF step sees ct, the TIRF stacks' angles and gains */
	int only[C0_MAX_STACKS] = { 0 }, tirf[C0_MAX_STACKS], ntirf = 0;
	struct c0_run_conf ct = *c;
	if (three_d && c->nangles != n)
		st = c0_fail(C0_EINVAL, "angles: %d angles for %d stacks (one per stack, same order)", c->nangles, n);
	if (!st && three_d && c->ngains && c->ngains != n)
		st = c0_fail(C0_EINVAL, "gains: %d gains for %d stacks", c->ngains, n);
	const double crit = c0_tirf_critical_deg(&s.matirf.tirf);
	for (int q = 0; !st && three_d && q < n; q++) {
		only[q] = c->angles[q] <= crit;
		if (!only[q])
			ct.angles[ntirf] = c->angles[q], ct.gains[ntirf] = c->gains[q], tirf[ntirf++] = q;
	}
	ct.nangles = ntirf, ct.ngains = c->ngains ? ntirf : 0;
	if (!st && three_d && ntirf < 2)
		st = c0_fail(C0_EINVAL, "angles: MA-TIRF needs at least 2 angles above the critical angle %.2f deg (got %d; stacks below it only join the support)",
			     crit, ntirf);
	if (!st && three_d)
		st = c0_run_conf_matirf_check(&ct, &s.matirf, ntirf);
	if (!st && three_d) {   /* the acquisition options, before any work */
		struct c0_bleach_conf bc;
		bleach_conf(c, &bc);
		st = c0_bleach_check(&bc, n);
	}
	if (!st && c->nnoise_variance)
		st = c0_fail(C0_EINVAL, "noise_variance: not used by the whole method (the support step estimates it)");
	if (!st)
		st = support_stacks(c, only, n, r);
	r->pixel_nm = s.support.pixel_nm, r->srf = s.support.srf;
	if (!st && c->drift)
		st = c0_step_drift(r, f, n);
	if (!st)
		st = c0_step_support(r, &s.support, f);
	if (c0_comm_rank() != 0)
		return st;      /* MPI: the other ranks share the support step; rank 0 has the result */
	int any = 0;
	for (size_t i = 0; !st && i < (size_t)r->Ly * r->Lx; i++)
		any |= r->mask[i];
	if (!st && !any)
		st = c0_fail(C0_EINVAL, "the support is empty: no emitter found (try a smaller lambda)");
	if (!st)
		st = c0_step_intensity(r, &s.intensity, &s.support, f, NULL, c->baseline && three_d);
	if (!st)
		st = c0_step_render(r);
	for (int q = 0; q < n; q++)
		r->bleach_factor[q] = 1;
	if (!st && three_d)
		st = c0_step_bleach(r, c, f);
	if (!st && three_d)
		st = volume(r, &ct, tirf, &s);
	if (st)
		return st;
	cJSON *p = cJSON_AddObjectToObject(r->rep, "parameters");
	cJSON_AddStringToObject(p, "mode", three_d ? "3D" : "2D");
	cJSON_AddNumberToObject(p, "pixel_size_nm", s.support.pixel_nm);
	cJSON_AddNumberToObject(p, "fine_pixel_nm", s.support.pixel_nm / s.support.srf);
	cJSON_AddNumberToObject(p, "fwhm_nm", s.support.fwhm_nm);
	cJSON_AddNumberToObject(p, "srf", s.support.srf);
	if (three_d) {
		cJSON_AddNumberToObject(p, "depth_pool_nm", s.pool_nm);
		cJSON_AddNumberToObject(p, "depth_pool_range_nm", s.pool_range_nm);
	}
	double s1[C0_MAX_STACKS];
	for (int k = 0; k < r->nsup; k++)
		s1[k] = r->sup[k] + 1;
	c0_report_add_array(p, "support_stacks", s1, r->nsup);
	int k = 0;
	for (int q = 0; q < n; q++)
		if (only[q])
			s1[k++] = q + 1;
	if (k) {
		c0_report_add_array(p, "support_only_stacks", s1, k);
		cJSON_AddStringToObject(p, "support_only_note",
					"stacks at or below the critical angle have no evanescent field: their supports join the union, and they are left out of the MA-TIRF fit");
	}
	if (s.psf_fitted) {
		cJSON *o = cJSON_AddObjectToObject(p, "psf_image");
		cJSON_AddStringToObject(o, "file", c->psf_image);
		cJSON_AddNumberToObject(o, "pixel_size_nm", s.psf_pixel_nm > 0 ? s.psf_pixel_nm : s.support.pixel_nm);
		cJSON_AddStringToObject(o, "pixel_size_from", s.psf_pixel_nm > 0 ? "its calibration" : "the stacks (the image has none)");
		cJSON_AddNumberToObject(o, "fwhm_px", s.psf.fwhm_px);
		cJSON_AddNumberToObject(o, "centre_x_px", s.psf.cx);
		cJSON_AddNumberToObject(o, "centre_y_px", s.psf.cy);
		cJSON_AddNumberToObject(o, "background", s.psf.background);
		cJSON_AddNumberToObject(o, "rms_residual_relative", s.psf.rel_rms);
		cJSON_AddStringToObject(o, "method", "least-squares fit of a pixel-integrated Gaussian plus a constant to the mean of its planes");
	}
	return C0_OK;
}

int c0_pipe_begin(const char *command, const struct c0_run_conf *c, const struct c0_stack *stacks, int n,
		  struct c0_frames *f, struct c0_stage_confs *sc, struct c0_result **out)
{
	*out = NULL;
	if (n < 1 || n > C0_MAX_STACKS || !stacks || !c)
		return c0_fail(C0_EINVAL, "stacks: %d given, expected 1..%d", n, C0_MAX_STACKS);
	int st = c0_stacks_open(stacks, n, f);
	if (st)
		return st;
	const char *names[C0_MAX_STACKS];
	int is_file[C0_MAX_STACKS];
	double pixel_nm;
	for (int i = 0; i < n; i++)
		names[i] = f[i].name, is_file[i] = stacks[i].path != NULL;
	st = c0_stacks_pixel(c, f, n, &pixel_nm);
	if (!st)
		st = c0_run_conf_stages(c, pixel_nm, sc);
	if (!st)   /* every stack's size and frames, before the first one's work */
		st = c0_stacks_check(&sc->support, f, n);
	if (!st)
		st = c0_result_new(command, n, names, is_file, out);
	if (st)
		c0_stacks_close(f, n);
	return st;
}

int c0_run(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, struct c0_result **out)
{
	struct c0_frames f[C0_MAX_STACKS];
	struct c0_stage_confs sc;
	struct c0_result *r;
	int st = c0_pipe_begin("run", c, stacks, n, f, &sc, &r);
	if (st)
		return st;
	st = run(c, &sc, f, n, r);
	c0_stacks_close(f, n);
	if (st) {
		c0_result_free(r);
		return st;
	}
	*out = r;
	return C0_OK;
}

int c0_result_nstacks(const struct c0_result *r)
{
	return r->n;
}

static void dims(int *h, int *w, int hv, int wv)
{
	if (h)
		*h = hv;
	if (w)
		*w = wv;
}

const uint8_t *c0_result_support(const struct c0_result *r, int *h, int *w)
{
	dims(h, w, r->Ly, r->Lx);
	return r->mask;
}

const float *c0_result_intensity(const struct c0_result *r, int q, int *h, int *w)
{
	if (!r->ires || q < 0 || q >= r->n)
		return NULL;
	dims(h, w, r->ires[q].Ly, r->ires[q].Lx);
	return r->ires[q].x;
}

const float *c0_result_background(const struct c0_result *r, int q, int *h, int *w)
{
	if (!r->ires || q < 0 || q >= r->n)
		return NULL;
	dims(h, w, r->ires[q].Ny, r->ires[q].Nx);
	return r->ires[q].b;
}

static const float *vol(const struct c0_matirf_result *v, int *nz, int *h, int *w)
{
	if (nz)
		*nz = v->nz;
	dims(h, w, v->ny, v->nx);
	return v->f;
}

const float *c0_result_volume(const struct c0_result *r, int *nz, int *h, int *w)
{
	return vol(&r->vol, nz, h, w);
}

const float *c0_result_baseline_volume(const struct c0_result *r, int *nz, int *h, int *w)
{
	return vol(&r->base, nz, h, w);
}

const float *c0_result_depth(const struct c0_result *r, int *h, int *w)
{
	dims(h, w, r->vol.ny, r->vol.nx);
	return r->vol.depth;
}

const float *c0_result_render(const struct c0_result *r, int q, int *h, int *w)
{
	if (!r->render || q < 0 || q >= r->n)
		return NULL;
	dims(h, w, r->Ly, r->Lx);
	return r->render + (size_t)q * r->Ly * r->Lx;
}

const double *c0_result_z_nm(const struct c0_result *r, int *nz)
{
	if (nz)
		*nz = r->vol.nz;
	return r->vol.z_nm;
}

const char *c0_result_report_json(const struct c0_result *r)
{
	struct c0_result *m = (struct c0_result *)r;   /* the text is a cache of the report */
	if (!m->json)
		m->json = cJSON_Print(r->rep);
	return m->json;
}
