/* The support step's part of report.json: each stack's estimates, its
 * automatic lambda (rule, curve), FRC curve and precision, and the step's parameters. */
#include "app/report_json_support.h"
#include "io/report.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdio.h>
#include <stdlib.h>

/* the path's criterion (stages/lambda.h, c0_lambda_cv) */
static void cross_validation(cJSON *l, const struct c0_lambda_result *v)
{
	cJSON *x = cJSON_AddObjectToObject(l, "cross_validation");
	cJSON_AddStringToObject(x, "what", "each half of the frames (even, odd) solved along a warm-started path of "
				"lambda, its support refitted without penalty; the error of those emitter variances "
				"predicting the other half's off-diagonal covariance lags, both directions summed, "
				"relative to the error of x = 0; chosen: the largest lambda whose error is within one "
				"standard error (paired, over blocks of lag x lag pixels) of the least (chosen_relative); the path "
				"starts at most 4 times the peaks rule's first step; the solve's lambda is the chosen over "
				"sqrt 2 (each half's covariance has twice the whole's noise variance)");
	c0_report_add_array(x, "lambda_relative", v->cv_rel, v->cv_points);
	c0_report_add_array(x, "error", v->cv_err, v->cv_points);
	cJSON_AddNumberToObject(x, "least_relative", v->cv_rel[v->cv_min]);
	cJSON_AddNumberToObject(x, "chosen_relative", v->cv_rel[v->cv_pick]);
	c0_report_add_array(x, "standard_error", v->cv_se, v->cv_pick);
	cJSON_AddNumberToObject(x, "iterations", v->cv_iters);
	cJSON_AddNumberToObject(x, "seconds", v->cv_seconds);
}

static void lambda_auto(cJSON *o, const struct c0_support_result *s)
{
	const struct c0_lambda_result *v = &s->cv;
	cJSON *l = cJSON_AddObjectToObject(o, "lambda_auto");
	cJSON_AddStringToObject(l, "rule", v->cv
				? "cross-validation of the interleaved frame halves along a path of lambda (cross_validation); "
				  "rho, q90, kappa and sigma_C below are the peaks rule's first step, for reference"
				: v->noise
				? "kappa sigma_C + width_share median; sigma_C: noise sd of the correlation image, "
				  "from the lower quartile of the interleaved frame halves' difference; median: of the "
				  "correlation image over the pixels above kappa sigma_C; width_share: the share of a "
				  "tube's correlation its label radius leaves beside its axis (rho and q90 below: the "
				  "peaks rule's first step, for reference)"
				: v->second
				? "max(share median peak, kappa sigma_C) from a first solve at max(rho q90, kappa "
				  "sigma_C); peak: x ||a||^2 at the first support's local maxima; sigma_C: noise "
				  "sd of the correlation image, from the lower quartile of the interleaved frame "
				  "halves' difference; q90: its 90th percentile over the pixels above kappa sigma_C"
				: "max(rho q90, kappa sigma_C); sigma_C: noise sd of the correlation image, from "
				  "the lower quartile of the interleaved frame halves' difference; q90: its 90th "
				  "percentile over the pixels above kappa sigma_C");
	cJSON_AddNumberToObject(l, "chosen_relative", v->chosen_rel);
	if (v->cv)
		cross_validation(l, v);
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
	if (v->noise) {
		cJSON_AddNumberToObject(l, "median_relative", v->median_rel);
		cJSON_AddNumberToObject(l, "width_share", v->width_share);
	}
	if (!v->cv)
		cJSON_AddStringToObject(l, "bound_by", v->noise_bound ? "noise" : v->noise ? "width" : "signal");
	/* tiles: sigma_C from a subset of the tiles' interiors (stages/support_tiles.c) */
	cJSON_AddNumberToObject(l, "noise_tiles", v->noise_tiles ? v->noise_tiles : s->tiles);
	cJSON_AddNumberToObject(l, "seconds", v->seconds);
	if (v->fwhm_data_nm > 0)   /* the PSF check (stages/lambda_psf.c); on tiles with fwhm_rule data */
		cJSON_AddNumberToObject(l, "fwhm_data_nm", v->fwhm_data_nm);
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

/* The halves' FRC as a curve only: on simulated lines a known distance apart
 * its 1/7 crossing does not follow what is resolved (docs/guide.md, section 5,
 * bench/frc_validation.py), so no resolution is drawn from it. */
static int frc(cJSON *o, const struct c0_support_result *s, const struct c0_support_conf *c)
{
	const double fine = c0_grid_fine_nm(&c->grid);
	cJSON *fr = cJSON_AddObjectToObject(o, "frc");
	cJSON_AddStringToObject(fr, "images", "emitter variances of the even and the odd frames (fine grid), Hann window");
	cJSON_AddStringToObject(fr, "note", "how far the halves agree per spatial frequency, not a resolution: the halves "
				"share the fine grid the sparse solve picks, and on two simulated lines a known distance apart "
				"the curve's 1/7 crossing does not follow which are resolved (docs/guide.md, section 5)");
	double *fq = c0_alloc((size_t)s->frc.n, sizeof *fq);
	if (!fq)
		return C0_ENOMEM;
	for (int m = 0; m < s->frc.n; m++)
		fq[m] = s->frc.freq[m] / fine;
	c0_report_add_array(fr, "frequency_per_nm", fq, s->frc.n);
	free(fq);
	c0_report_add_array(fr, "correlation", s->frc.corr, s->frc.n);
	cJSON_AddNumberToObject(fr, "seconds", s->t_frc);
	return C0_OK;
}

cJSON *c0_report_support_stack(const char *name, const struct c0_support_result *s, const struct c0_support_conf *c)
{
	cJSON *o = cJSON_CreateObject();
	cJSON_AddStringToObject(o, "stack", name);
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
	if (c->label_radius_nm > 0) {   /* the pixels the growth added: in the support, no variance of their own */
		int grown = 0;
		for (size_t i = 0; s->mask && i < (size_t)s->Ly * s->Lx; i++)
			grown += s->mask[i] && !(s->rx[i] > 0);
		cJSON_AddNumberToObject(o, "label_radius_nm", c->label_radius_nm);
		cJSON_AddNumberToObject(o, "grown_pixels", grown);
	}
	cJSON_AddNumberToObject(o, "covariance_s", s->t_cov);
	cJSON_AddNumberToObject(o, "covariance_frames_per_s", s->t_cov > 0 ? (double)s->frames / s->t_cov : 0);
	cJSON_AddNumberToObject(o, "solve_s", s->t_solve);
	c0_report_add_array(o, "objective", s->hist, s->nhist);
	cJSON_AddStringToObject(o, "lambda_rule", s->lambda_auto ? "automatic"
				: c->lambda_rel > 0 ? "given"
				: "the penalty's fixed default");
	if (s->lambda_auto)
		lambda_auto(o, s);
	if (s->frc.n && frc(o, s, c)) {
		cJSON_Delete(o);
		return NULL;
	}
	if (c->frc)    /* tiles: the precision without the FRC (stages/support_tiles.c) */
		cJSON_AddNumberToObject(o, "precision_nm", s->precision_nm);
	return o;
}

void c0_report_support_params(cJSON *rep, const struct c0_support_conf *c)
{
	cJSON *p = cJSON_AddObjectToObject(rep, "support_parameters");
	cJSON_AddNumberToObject(p, "pixel_size_nm", c->grid.pixel_nm);
	cJSON_AddNumberToObject(p, "fwhm_nm", c->grid.fwhm_nm);
	cJSON_AddNumberToObject(p, "srf", c->grid.srf);
	cJSON_AddStringToObject(p, "penalty", c->penalty == C0_PENALTY_L1 ? "l1" : "cel0");
	cJSON_AddNumberToObject(p, "max_iterations", c->fista.maxit);
	cJSON_AddNumberToObject(p, "tol", c0_support_tol(c));
	cJSON_AddStringToObject(p, "pixel_guard", c->guard ? "on" : "off");
	if (c->guard)   /* g of ops/covariance.h's c0_cov_guard */
		cJSON_AddNumberToObject(p, "pixel_guard_ratio", c0_support_guard_ratio(c));
}
